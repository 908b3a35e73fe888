"""End-of-run summaries of process scenes: what a process engineer asks first - the shaft
torque and power, how long the material stayed, how hot it left, what went in and out."""
from __future__ import annotations

import math

import numpy as np


def _tail(a: np.ndarray, frac: float = 0.25) -> np.ndarray:
    """The last ``frac`` of a series (at least one sample)."""
    return a[-max(1, int(len(a) * frac)):]


def process_summary(sim, window: float = 0.25) -> dict:
    """Print and return the key numbers of a run: per body the mean axial torque (N m) and
    drive power (W) over the last ``window`` fraction of the run; per residence sensor the
    mean, median and 10/90 % residence times (s); per outlet the mass removed, the mean mass
    flow (t/h) and the mean outlet temperature (K) over the window; per factory the mass fed;
    the mass balance."""
    s = sim.series
    out: dict = {}
    t = s["time"]
    span = t[-1] - _tail(t, window)[0]
    for b in sim.scene.bodies:
        if b.motion.speed is None:
            continue
        tq = float(np.mean(_tail(s[f"bodies/{b.name}/axial_torque"], window)))
        pw = float(np.mean(_tail(s[f"bodies/{b.name}/power"], window)))
        out[f"{b.name}/axial_torque"] = tq
        out[f"{b.name}/power"] = pw
        print(f"summary: {b.name}: axial torque {tq:.4g} N m, drive power {pw:.4g} W "
              f"(mean of the last {span:.3g} s)")
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
            mf = float(np.mean(_tail(s[f"sensors/{x.name}/mass_flow"], window)))
            out[f"{x.name}/mass_flow"] = mf
            print(f"summary: mass flow through '{x.name}': {mf * 3.6:.3g} t/h "
                  f"(mean of the last {span:.3g} s)")
        elif x.kind == "contact_count":
            cc = float(np.mean(_tail(s[f"sensors/{x.name}/contact_count"], window)))
            out[f"{x.name}/contact_count"] = cc
            print(f"summary: particles touching '{x.body}': {cc:.4g} (mean of the last {span:.3g} s)")
    for o in sim.scene.outlets:
        p = f"outlets/{o.name}/"
        flow = float(np.mean(_tail(s[p + "mass_flow"], window)))
        out[f"{o.name}/mass_flow"] = flow
        line = (f"summary: outlet '{o.name}': {s[p + 'mass'][-1]:.4g} kg removed, "
                f"{flow * 3.6:.3g} t/h over the last {span:.3g} s")
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
              f"{q / 1e3:.3g} kW (mean of the last {span:.3g} s)")
    if "particles/evaporated_mass" in s:
        ev = s["particles/evaporated_mass"]
        rate = (ev[-1] - _tail(ev, window)[0]) / span if span > 0 else 0.0
        print(f"summary: water evaporated: {ev[-1]:.4g} kg in all, {rate * 3.6:.3g} t/h lately")
    if "thermal/particle_heat_loss" in s and len(s["time"]) > 1:
        loss = float(s["thermal/particle_heat_loss"][-1])
        walls = float(s["thermal/wall_heat"][-1])
        gas = float(s["thermal/gas_heat"][-1])
        booked = walls - gas
        out["heat_out_of_particles"] = loss
        out["heat_into_walls"] = walls
        scale = sim.scene.thermal.time_scale
        when = (f" in {scale * t[-1]:.4g} s of thermal time ({t[-1]:.4g} s simulated, "
                f"time_scale {scale:g})") if scale != 1.0 else f" in {t[-1]:.4g} s"
        line = (f"summary: energy balance{when}: the particles lost {loss / 1e3:.4g} kJ; "
                f"{walls / 1e3:.4g} kJ went into isothermal walls and bodies"
                + (f", {gas / 1e3:.4g} kJ came from the gas" if gas else ""))
        if abs(booked) > 0 or abs(loss) > 0:
            error = (loss - booked) / max(abs(booked), abs(loss))
            out["energy_balance_error"] = error
            line += f" (difference {error:.2%}"
            if sim.scene.thermal.gas is not None and not sim.scene.thermal.gas.plug_flow:
                line += "; convection to the fixed gas is not booked"
            if sim.scene.thermal.radiation:
                line += "; radiation is not booked"
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
                          f"coefficient {mean_h:.4g} W/(m^2 K) over "
                          f"{float(np.mean(_tail(s[f'bodies/{b.name}/covered_area'], window))):.3g} "
                          f"m^2 covered (mean of the last {span:.3g} s)")
    for f in sim.scene.factories:
        fed = float(s[f"factories/{f.name}/mass"][-1])
        behind = float(s[f"factories/{f.name}/behind"][-1])
        out[f"{f.name}/fed"] = fed
        print(f"summary: factory '{f.name}': {fed:.4g} kg fed"
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
