"""End-of-run summaries of process scenes: what a process engineer asks first - the shaft
torque and power, how long the material stayed, how hot it left, what went in and out."""
from __future__ import annotations

import math

import numpy as np


def _tail(a: np.ndarray, frac: float = 0.25) -> np.ndarray:
    """The last ``frac`` of a series (at least one sample)."""
    return a[-max(1, int(len(a) * frac)):]


def window_of(t: np.ndarray, frac: float = 0.25) -> tuple[float, float]:
    """(start, end) in s of the simulated time the last ``frac`` of the samples cover: each
    sample stands for the interval that ends at it, so the window opens at the sample before
    the tail (at 0 when the tail is every sample)."""
    t = np.asarray(t, float)
    n = max(1, int(len(t) * frac))
    return (float(t[-n - 1]) if len(t) > n else 0.0), float(t[-1])


def window_words(t: np.ndarray, frac: float = 0.25) -> str:
    """"mean over t = a - b s": the label every time-averaged figure of a summary carries."""
    a, b = window_of(t, frac)
    return f"mean over t = {a:.4g} - {b:.4g} s"


def error_words(values, scale: float = 1.0, fmt: str = ".2g") -> str:
    """" +- e": the standard error of the mean of ``values`` (correlated samples, by blocking:
    steady_state.block_standard_error), times ``scale``; empty with fewer than two finite
    samples. The summaries print it beside each time-averaged figure a user acts on."""
    from .steady_state import block_standard_error
    x = np.asarray(values, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return ""
    return f" +- {block_standard_error(x).standard_error * scale:{fmt}}"


def body_torque_lines(sim, frac: float = 0.25) -> dict:
    """Print one line per body: its mean axial torque (N m) and drive power (W; 0 for a body at
    rest, whose torque is the load its mounting takes) over
    the last ``frac`` of the samples (the window every summary figure uses); return them as
    {"<body>/axial_torque": N m, "<body>/power": W}."""
    s = sim.series
    out: dict = {}
    if not len(s.get("time", ())):
        return out
    words = window_words(s["time"], frac)
    for b in sim.scene.bodies:
        if f"bodies/{b.name}/axial_torque" not in s:
            continue
        torque = _tail(s[f"bodies/{b.name}/axial_torque"], frac)
        power = _tail(s[f"bodies/{b.name}/power"], frac)
        tq, pw = float(np.mean(torque)), float(np.mean(power))
        out[f"{b.name}/axial_torque"] = tq
        out[f"{b.name}/power"] = pw
        print(f"body {b.name}: axial torque {tq:.4g}{error_words(torque)} N m, drive power "
              f"{pw:.4g}{error_words(power)} W ({words}; +- the standard error of the mean)")
    return out


def process_summary(sim, window: float = 0.25) -> dict:
    """Print and return the key numbers of a run: per body the mean axial torque (N m) and
    drive power (W) over the last ``window`` fraction of the run; per residence sensor the
    mean, median and 10/90 % residence times (s); per outlet the mass removed, the mean mass
    flow (t/h) and the mean outlet temperature (K) over the window; per factory the mass fed;
    the mass balance."""
    s = sim.series
    out: dict = {}
    t = s["time"]
    start, end = window_of(t, window)
    span = end - start
    words = window_words(t, window)
    # the bodies' torque and power: computed here by the same window, printed once per body
    # by the run report (cli._drive: body_torque_lines), so no body has two torques
    for b in sim.scene.bodies:
        if b.motion.speed is None:
            continue
        out[f"{b.name}/axial_torque"] = float(np.mean(_tail(s[f"bodies/{b.name}/axial_torque"], window)))
        out[f"{b.name}/power"] = float(np.mean(_tail(s[f"bodies/{b.name}/power"], window)))
    for x in sim.scene.sensors:
        if x.kind == "residence_time":
            rec = sim.residence_times(x.name)
            if len(rec):
                rt = rec[:, 2] - rec[:, 1]
                p10, p50, p90 = np.percentile(rt, [10, 50, 90])
                out[f"{x.name}/mean"] = float(np.mean(rt))
                out[f"{x.name}/median"] = float(p50)
                print(f"summary: residence time '{x.name}' ({x.source} -> {x.target}, "
                      f"{len(rt)} particles): mean {np.mean(rt):.3g} s, median {p50:.3g} s, "
                      f"10-90 % {p10:.3g} - {p90:.3g} s")
            else:
                print(f"summary: residence time '{x.name}': no particle has made it yet")
        elif x.kind == "mass_flow":
            flows = _tail(s[f"sensors/{x.name}/mass_flow"], window)
            mf = float(np.mean(flows))
            out[f"{x.name}/mass_flow"] = mf
            print(f"summary: mass flow through '{x.name}': {mf * 3.6:.3g}"
                  f"{error_words(flows, 3.6)} t/h "
                  f"({words})")
        elif x.kind == "contact_count":
            cc = float(np.mean(_tail(s[f"sensors/{x.name}/contact_count"], window)))
            out[f"{x.name}/contact_count"] = cc
            print(f"summary: particles touching '{x.body}': {cc:.4g} ({words})")
    for o in sim.scene.outlets:
        p = f"outlets/{o.name}/"
        flow = float(np.mean(_tail(s[p + "mass_flow"], window)))
        out[f"{o.name}/mass_flow"] = flow
        line = (f"summary: outlet '{o.name}': {s[p + 'mass'][-1]:.4g} kg removed by t = {end:.4g} s, "
                f"{flow * 3.6:.3g}{error_words(_tail(s[p + 'mass_flow'], window), 3.6)} t/h "
                f"({words})")
        if p + "mean_temperature" in s:
            temps = _tail(s[p + "mean_temperature"], window)
            flows = _tail(s[p + "mass_flow"], window)
            ok = np.isfinite(temps) & (flows > 0)
            if np.any(ok):
                mean_t = float(np.sum(temps[ok] * flows[ok]) / np.sum(flows[ok]))
                out[f"{o.name}/temperature"] = mean_t
                line += f", leaving at {mean_t:.4g} K ({mean_t - 273.15:.4g} C)"
        if p + "mean_moisture" in s:
            wet = _tail(s[p + "mean_moisture"], window)
            flows = _tail(s[p + "mass_flow"], window)
            ok = np.isfinite(wet) & (flows > 0)
            if np.any(ok):
                x = float(np.sum(wet[ok] * flows[ok]) / np.sum(flows[ok]))
                out[f"{o.name}/moisture"] = x
                line += f", moisture {x:.3g} kg/kg"
        print(line)
    if "gas/outlet_temperature" in s:
        tg = float(np.mean(_tail(s["gas/outlet_temperature"], window)))
        q = float(np.mean(_tail(s["gas/heat_flow"], window)))
        out["gas/outlet_temperature"] = tg
        print(f"summary: gas leaves at {tg:.4g} K ({tg - 273.15:.4g} C), giving the solids "
              f"{q / 1e3:.3g} kW ({words})")
    if "particles/evaporated_mass" in s:
        ev = s["particles/evaporated_mass"]
        n = len(_tail(ev, window))
        before = float(ev[-n - 1]) if len(ev) > n else 0.0      # at the window's start
        rate = (ev[-1] - before) / span if span > 0 else 0.0
        print(f"summary: water evaporated: {ev[-1]:.4g} kg by t = {end:.4g} s, {rate * 3.6:.3g} t/h "
              f"({words})")
    if "thermal/particle_heat_loss" in s and len(s["time"]) > 1:
        loss = float(s["thermal/particle_heat_loss"][-1])
        walls = float(s["thermal/wall_heat"][-1])
        gas = float(s["thermal/gas_heat"][-1])
        source = float(s["thermal/source_heat"][-1]) if "thermal/source_heat" in s else 0.0
        booked = walls - gas - source
        out["heat_out_of_particles"] = loss
        out["heat_into_walls"] = walls
        scale = sim.scene.settings.get("thermal").time_scale
        when = (f" in {scale * t[-1]:.4g} s of thermal time ({t[-1]:.4g} s simulated, "
                f"time_scale {scale:g})") if scale != 1.0 else f" in {t[-1]:.4g} s"
        line = (f"summary: energy balance{when}: the particles lost {loss / 1e3:.4g} kJ; "
                f"{walls / 1e3:.4g} kJ went into isothermal walls and bodies"
                + (f", {gas / 1e3:.4g} kJ came from the gas" if gas else ""))
        for key in ("thermal/radiated_heat", "thermal/vapour_heat"):
            if key in s and len(s[key]):
                what = {"thermal/radiated_heat": "came by radiation",
                        "thermal/vapour_heat": "left with the vapour"}[key]
                line += f", {float(s[key][-1]) / 1e3:.4g} kJ {what}"

        if abs(booked) > 0 or abs(loss) > 0:
            error = (loss - booked) / max(abs(booked), abs(loss))
            out["energy_balance_error"] = error
            line += f" (difference {error:.2%}"
            if sim.scene.settings.get("thermal").gas is not None and not sim.scene.settings.get("thermal").gas.plug_flow:
                line += "; convection to the fixed gas is not booked"
            line += ")"
        print(line)
        for b in sim.scene.bodies:
            key = f"bodies/{b.name}/heat_transfer_coefficient"
            if key in s:
                h = _tail(np.asarray(s[key], float), window)
                if np.any(np.isfinite(h)):
                    mean_h = float(np.nanmean(h))
                    out[f"{b.name}/heat_transfer_coefficient"] = mean_h
                    q = float(np.mean(_tail(s[f"bodies/{b.name}/heat_flow"], window)))
                    print(f"summary: {b.name}: {q:.4g} W into it, wall-to-bed heat transfer "
                          f"coefficient {mean_h:.4g}{error_words(h)} W/(m^2 K) over "
                          f"{float(np.mean(_tail(s[f'bodies/{b.name}/covered_area'], window))):.3g} "
                          f"m^2 covered ({words})")
    for f in sim.scene.factories:
        fed = float(s[f"factories/{f.name}/mass"][-1])
        behind = float(s[f"factories/{f.name}/behind"][-1])
        out[f"{f.name}/fed"] = fed
        print(f"summary: factory '{f.name}': {fed:.4g} kg fed by t = {end:.4g} s"
              + (f", {behind:.4g} kg behind schedule (the inlet chokes)" if behind > 0.01 * max(fed, 1e-30) else ""))
    if sim.factories is not None and sim.wall_seconds > 0:
        print(f"summary: factories placed and inserted particles in "
              f"{sim.factories.wall_seconds:.3g} s wall ({sim.factories.wall_seconds / sim.wall_seconds:.1%} "
              f"of the stepping time)")
    if sim.scene.factories or sim.scene.outlets:
        b = sim.mass_balance()
        out["mass_balance_error"] = b["error"]
        print(f"summary: mass balance: {b['initial']:.4g} initial + {b['fed']:.4g} fed = "
              f"{b['inside']:.4g} inside + {b['removed']:.4g} removed + "
              f"{b['lost'] if not math.isnan(b['lost']) else 0.0:.4g} lost "
              f"(difference {b['error']:.2g} kg)")
    return out


def chute_inlet(sim) -> dict:
    """The chute scene's figures the steady-chute summary needs, read from the scene: the
    first sheet factory's depth h0 and width W (m, its face's edges), normal speed u0 (m/s) and
    mass rate (kg/s, at the end of the run), the inclination (deg, from the tilted gravity:
    x down the slope, z normal to the base) and g (m/s^2)."""
    f = next(f for f in sim.scene.factories if f.pattern == "sheet")
    w, h0 = f.sheet.extents
    u0 = float(np.asarray(f.velocity) @ np.asarray(f.sheet.normal))
    g = np.asarray(sim.scene.simulation.gravity, float)
    return {"h0": h0, "width": w, "u0": u0, "mass_rate": f.mass_rate.at(sim.time),
            "density": sim.scene.materials[f.material].density, "name": f.name,
            "inclination": math.degrees(math.atan2(g[0], -g[2])), "g": float(np.linalg.norm(g))}


def chute_summary(sim, samples: list, stations, sensor: str = "outflow", window: float = 0.1,
                  frictions=(23.0, 30.0), earth_pressure: float = 1.0) -> dict:
    """Print and return the steady chute flow against the steady depth-averaged model.

    ``samples``: (time s, {station x m: analysis.chute_station dict}) recorded at output
    samples; the profile is their mean over the last ``window`` s (at most 40 % of the run).
    The model (app/depth_averaged.py) starts from the inlet's h0 and u0 at x = 0 and is
    integrated for each basal friction angle in ``frictions`` (deg); "position" is where the
    DEM lies between the first (1) and second (0) curve. Returns the table as arrays and the
    steadiness figures (outflow vs feed, particle count drift)."""
    from . import depth_averaged as da
    inlet = chute_inlet(sim)
    s = sim.series
    t = s["time"]
    span = min(window, 0.4 * float(t[-1]))
    t0 = float(t[-1]) - span
    rows = [st for (ts, st) in samples if ts >= t0 - 1e-9]
    out: dict = {"window": (t0, float(t[-1]))}
    print(f"summary: steady chute (seed 004): {inlet['inclination']:.1f} deg, inlet "
          f"h0 = {inlet['h0'] * 1e3:.3g} mm x W = {inlet['width'] * 1e3:.3g} mm at u0 = "
          f"{inlet['u0']:.4g} m/s, fed {inlet['mass_rate']:.4g} kg/s (inflow solid fraction "
          f"{inlet['mass_rate'] / (inlet['density'] * inlet['h0'] * inlet['width'] * inlet['u0']):.3g})")
    win = t >= t0 - 1e-9
    count = s["particles/count"][win]
    fed = s[f"factories/{inlet['name']}/mass"]
    feed = float((fed[-1] - fed[win][0]) / max(t[-1] - t[win][0], 1e-30)) if win.sum() > 1 else float("nan")
    key = f"sensors/{sensor}/mass_flow"
    leaving = float(np.mean(s[key][win][1:])) if key in s and win.sum() > 1 else float("nan")
    drift = float(np.polyfit(t[win], count, 1)[0] * span / max(np.mean(count), 1.0)) if win.sum() > 2 else float("nan")
    behind = float(s[f"factories/{inlet['name']}/behind"][-1])
    out.update(feed=feed, outflow=leaving, count=float(np.mean(count)), count_drift=drift,
               behind=behind)
    print(f"  over t = {t0:.3g} - {t[-1]:.3g} s: {np.mean(count):,.0f} spheres in the chute "
          f"(drift {drift:+.1%} over the window), mass flow leaving {leaving:.4g} kg/s against "
          f"{feed:.4g} kg/s fed ({leaving / feed - 1.0:+.1%}; the inlet is {behind * 1e3:.3g} g "
          f"behind its schedule)")
    if sim.factories is not None and sim.wall_seconds > 0:
        n_fed = float(s[f"factories/{inlet['name']}/count"][-1])
        print(f"  the sheet inlet inserted {n_fed:,.0f} spheres in {sim.factories.wall_seconds:.3g} s "
              f"wall ({sim.factories.wall_seconds / sim.wall_seconds:.1%} of the run; "
              f"{n_fed / max(sim.factories.wall_seconds, 1e-9):,.0f} spheres per wall second)")
    if not rows:
        print("  no profile samples in the window (run longer)")
        return out
    xs = np.array(sorted(stations))
    keys = ("h", "u_mean", "u_surface", "u_base", "flux", "phi")
    table = {k: np.array([np.nanmean([r[x][k] for r in rows if r.get(x)]) if any(r.get(x) for r in rows)
                          else np.nan for x in xs]) for k in keys}
    models = {}
    for delta in frictions:
        try:
            models[delta] = da.steady_profile(np.concatenate([[0.0], xs]), inlet["h0"], inlet["u0"],
                                              inlet["inclination"], delta, gravity=inlet["g"],
                                              earth_pressure=earth_pressure)
        except ValueError as e:
            print(f"  depth-averaged model, delta = {delta:g} deg: {e}")
    phi_in = inlet["mass_rate"] / (inlet["density"] * inlet["h0"] * inlet["width"] * inlet["u0"])
    # the depth the DEM's solid would fill at the inflow's solid fraction: the model carries the
    # inlet's bulk density unchanged, the DEM compacts or dilates along the chute
    table["h_inflow_density"] = table["h"] * table["phi"] / phi_in
    out.update(x=xs, **table, models={d: {"h": m["h"][1:], "u": m["u"][1:]} for d, m in models.items()})
    d1, d2 = frictions
    print(f"  profile (mean of {len(rows)} samples) beside the steady depth-averaged model (K = "
          f"{earth_pressure:g}) from the inlet state, basal friction delta = {d1:g} and {d2:g} deg:")
    print("    x mm | h mm DEM  d=%g  d=%g | u_mean m/s DEM  d=%g  d=%g | u_surf  u_base | flux kg/s  phi"
          "  h phi/phi0 mm" % (d1, d2, d1, d2))
    for i, x in enumerate(xs):
        m1 = models.get(d1, {"h": [np.nan] * (len(xs) + 1), "u": [np.nan] * (len(xs) + 1)})
        m2 = models.get(d2, m1)
        print(f"  {x * 1e3:6.0f} | {table['h'][i] * 1e3:8.2f} {m1['h'][i + 1] * 1e3:5.2f} "
              f"{m2['h'][i + 1] * 1e3:5.2f} | {table['u_mean'][i]:14.3f} {m1['u'][i + 1]:5.3f} "
              f"{m2['u'][i + 1]:5.3f} | {table['u_surface'][i]:6.3f} {table['u_base'][i]:7.3f} | "
              f"{table['flux'][i]:9.4f} {table['phi'][i]:5.3f} {table['h_inflow_density'][i] * 1e3:8.2f}")
    if d1 in models and d2 in models:
        lo = {k: models[d2][k][1:] for k in ("h", "u")}
        hi = {k: models[d1][k][1:] for k in ("h", "u")}
        pos = {"u_mean": da.position_between(table["u_mean"], lo["u"], hi["u"]),
               "u_surface": da.position_between(table["u_surface"], lo["u"], hi["u"]),
               "h": da.position_between(table["h"], lo["h"], hi["h"]),
               "h_inflow_density": da.position_between(table["h_inflow_density"], lo["h"], hi["h"])}
        out["position"] = pos
        for k, label in (("u_mean", "depth-averaged velocity"), ("u_surface", "free-surface velocity"),
                         ("h", "flow depth"),
                         ("h_inflow_density", f"flow depth at the inflow's solid fraction {phi_in:.2f}")):
            p = pos[k]
            print(f"  {label}: position between delta = {d2:g} (0) and {d1:g} deg (1) curves "
                  f"{np.nanmin(p):.2f} - {np.nanmax(p):.2f} along x (mean {np.nanmean(p):.2f})")
    return out
