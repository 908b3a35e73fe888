"""``taichi-dem machine``: its arguments, the command and its report (the march itself is
app/machine.py)."""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..scene import catalog  # noqa: F401 (the effects' dimensions: a temperature)
from ..errors import SceneError
from .machine import (MachineMap, choice_differences, choices_report, feed_entered,
                      parse_holdup, substituted, with_errors)


def add_arguments(p) -> None:
    """The ``taichi-dem machine`` arguments."""
    p.add_argument("map", help="a map.json written by `taichi-dem map` (or its folder); or a "
                               "dryer design (TOML with [drum], [solids], [gas]: "
                               "demos/dryers/*.toml), marched as `taichi-dem dryer` does")
    p.add_argument("--length", default=None, help="the machine's length ('6 m', or metres; "
                                                  "required with a map, a dryer design has its own)")
    p.add_argument("--feed", nargs="+", default=None,
                   help="feed rates ('6.5 t/h', or kg/s): the answers at each (required with a "
                        "map; for a dryer design, dry feeds instead of the design's)")
    p.add_argument("--flow", choices=("counter", "co"), default=None,
                   help="a dryer design only: the gas against the solids or with them "
                        "(default: the design's)")
    p.add_argument("--incline", type=float, default=None,
                   help="the machine's incline (deg, the +axis end raised; default: the map's "
                        "only incline; with several mapped, any incline between them)")
    p.add_argument("--inlet-temperature", default=None,
                   help="the feed's temperature ('450 C'): the outlet temperature from the map's "
                        "shell conductance per metre")
    p.add_argument("--discharge-depth", default=None,
                   help="the bed's depth at the discharge ('20 mm': a dam's height; default one "
                        "particle diameter, a free discharge)")
    p.add_argument("--feed-over", nargs=2, metavar=("FROM", "TO"), default=None,
                   help="the feed enters evenly between these distances from the inlet end "
                        "('0.03 m' '0.25 m': a chute's or a factory's spread; default at the "
                        "inlet end)")
    p.add_argument("--overflow", default=None,
                   help="the hold-up at which the inlet end overflows ('90 kg/m', or a fill "
                        "fraction '40 %%'; default the largest mapped hold-up)")
    p.add_argument("--inlet-section", nargs=2, action="append", metavar=("MAP", "LENGTH"),
                   default=[], help="a section at the inlet end with its own map (an inlet "
                   "screw before the paddles): the map and its length ('1 m'); repeat for more, "
                   "in order from the inlet; the main map covers the rest, at the discharge end")
    p.add_argument("--choice", nargs=2, action="append", metavar=("LABEL", "MAP"), default=[],
                   help="a map of the same slice with one modelling choice changed ('f64', "
                   "'20 mm spheres'), at the main map's hold-ups and at one or all of its "
                   "inclines: the machine is marched again with it and each answer's change "
                   "reported beside the noise; repeat for more")
    p.add_argument("--draws", type=int, default=40,
                   help="re-marches with the map drawn from its standard errors (the errors)")
    p.add_argument("--out", default=None, help="folder for machine.md, machine.json and "
                                               "profile.png (default: beside the map)")


def _quantity(text, dimension, key):
    from ..scene.units import parse_quantity
    return parse_quantity(text if not _is_number(text) else float(text), dimension,
                          file="taichi-dem machine", key=key)


def _is_number(text) -> bool:
    try:
        float(text)
        return True
    except (TypeError, ValueError):
        return False


def cmd_machine(args) -> int:
    """``taichi-dem machine``: the whole machine from its map (module docstring)."""
    import sys
    if _is_dryer_design(args.map):
        return _dryer_machine(args)
    if args.flow is not None:
        raise SceneError("taichi-dem machine", "--flow", "is for a dryer design (a TOML file), "
                         "not for a map")
    for key, value in (("--length", args.length), ("--feed", args.feed)):
        if value is None:
            raise SceneError("taichi-dem machine", key, "is required with a map (a dryer "
                             "design file gives its own)")
    m = MachineMap.load(args.map)
    map_path = Path(args.map)
    length = _quantity(args.length, "length", "--length")
    feeds = [_quantity(f, "mass_rate", "--feed") for f in args.feed]
    if length <= 0.0 or any(f <= 0.0 for f in feeds):
        raise SceneError("taichi-dem machine", "--length/--feed", "must be > 0")
    inclines = sorted({round(-math.degrees(math.atan(r.axial_slope)), 9) for r in m.rows})
    if args.incline is None:
        if len(inclines) > 1:
            raise SceneError("taichi-dem machine", "--incline", "the map has several inclines "
                             f"({inclines} deg): say which the machine has")
        incline = inclines[0]
    else:
        incline = args.incline
        if len(inclines) > 1 and not inclines[0] - 1e-9 <= incline <= inclines[-1] + 1e-9:
            print(f"warning: incline {incline} deg is outside the mapped {inclines[0]} - "
                  f"{inclines[-1]} deg: the law is extrapolated", file=sys.stderr)
    slope = -math.tan(math.radians(incline))
    t_in = (_quantity(args.inlet_temperature, "temperature", "--inlet-temperature")
            if args.inlet_temperature is not None else None)
    depth0 = (_quantity(args.discharge_depth, "length", "--discharge-depth")
              if args.discharge_depth is not None else None)
    overflow = None
    if args.overflow is not None:
        try:
            kind, value = parse_holdup(args.overflow)
        except ValueError as err:
            raise SceneError("taichi-dem machine", "--overflow", str(err)) from None
        full = float(m.section.holdup(2.0 * m.section.shell_radius))
        overflow = value if kind == "kg/m" else value * full
    feed_over = (tuple(_quantity(v, "length", "--feed-over") for v in args.feed_over)
                 if args.feed_over else None)
    if feed_over is not None:
        feed_entered(1.0, length, feed_over)        # refused here when outside the machine
    inlet = [(MachineMap.load(path), _quantity(size, "length", "--inlet-section"))
             for path, size in args.inlet_section]
    for (path, _), (section_map, size) in zip(args.inlet_section, inlet):
        if size <= 0.0:
            raise SceneError("taichi-dem machine", "--inlet-section", f"{path}: the length must "
                             "be > 0")
        mapped = sorted({round(-math.degrees(math.atan(r.axial_slope)), 9) for r in section_map.rows})
        if len(mapped) == 1 and abs(mapped[0] - incline) > 1e-6:
            raise SceneError(str(path), "rows", f"mapped at {mapped[0]} deg only, not at the "
                             f"machine's {incline} deg: map it at both, or at this incline")
    out = with_errors(m, length, feeds, slope, depth0, overflow, t_in, draws=args.draws,
                      inlet_sections=inlet, feed_over=feed_over)
    report = machine_report(m, out, length, incline, t_in,
                            sections=[(p, l) for (p, _), (_, l) in zip(args.inlet_section, inlet)])
    if args.choice:
        differences = {}
        for label, path in args.choice:
            other = substituted(m, MachineMap.load(path), source=str(path))
            other_out = with_errors(other, length, feeds, slope, depth0, overflow, t_in,
                                    draws=args.draws, inlet_sections=inlet,
                                    feed_over=feed_over)
            differences[label] = choice_differences(out, other_out)
        report["text"] += "\n\n" + choices_report(differences)
        report["json"]["choices"] = {label: {"map": str(path), **differences[label]}
                                     for label, path in args.choice}
    folder = Path(args.out) if args.out else (map_path if map_path.is_dir() else map_path.parent)
    folder.mkdir(parents=True, exist_ok=True)
    if not inlet:       # the RTD where the map has D_ax (app/dispersion.py; one map only)
        from .dispersion import rtd_report
        text, rtd_rows = rtd_report(m, out, slope, t_in, plot=folder / "rtd.png",
                                    inlet=feed_over)
        if text:
            report["text"] += "\n\n" + text
            report["json"]["residence_time_distributions"] = rtd_rows
    print(report["text"])
    (folder / "machine.md").write_text(report["text"] + "\n")
    (folder / "machine.json").write_text(json.dumps(report["json"], indent=1, default=float))
    _plot_profiles(out, folder / "profile.png")
    print(f"wrote {folder / 'machine.md'}, {folder / 'machine.json'}, {folder / 'profile.png'}",
          file=sys.stderr)
    return 0


def _is_dryer_design(path) -> bool:
    """The machine file is a dryer design (TOML), not a slice's map (map.json or its folder)."""
    return Path(path).suffix.lower() == ".toml"


def _dryer_machine(args) -> int:
    """``taichi-dem machine DESIGN.toml``: a dryer, marched along its axis by app/dryer.py (its
    closures from the design's [closure] map or the correlations), at the design's feed or at
    each ``--feed``; the report and files are those of ``taichi-dem dryer``."""
    from types import SimpleNamespace
    from .dryer_command import cmd_dryer
    refused = [key for key, value in (("--length", args.length), ("--incline", args.incline),
                                      ("--inlet-temperature", args.inlet_temperature),
                                      ("--discharge-depth", args.discharge_depth),
                                      ("--overflow", args.overflow),
                                      ("--inlet-section", args.inlet_section),
                                      ("--choice", args.choice)) if value]
    if refused:
        raise SceneError(str(args.map), refused[0], "a dryer design gives its drum, incline "
                         "and feed in the file ([drum], [solids]); this option is for a map")
    feeds = [None] if not args.feed else [_quantity(f, "mass_rate", "--feed") for f in args.feed]
    if any(f is not None and f <= 0.0 for f in feeds):
        raise SceneError("taichi-dem machine", "--feed", "must be > 0")
    for i, feed in enumerate(feeds):
        out = args.out
        if out and len(feeds) > 1:
            out = str(Path(out) / f"feed_{i + 1}")
        code = cmd_dryer(SimpleNamespace(design=args.map, flow=args.flow, out=out, feed=feed))
        if code:
            return code
    return 0


def machine_report(m: MachineMap, out: dict, length: float, incline: float, t_in,
                   sections=()) -> dict:
    """The answers as a Markdown table and a JSON-ready dict (values with their errors).
    ``sections``: the inlet sections' (map path, length m), in order from the inlet."""
    bodies = list(m.bodies)
    for ans in out["feeds"]:
        bodies += [b for b in ans.torques if b not in bodies]
    m = MachineMap(m.rows, m.section, m.angular_speeds, m.particle_diameter, m.heat_capacity,
                   m.wall_temperatures, bodies)
    lines = [f"# The machine from its map: {length:g} m at {incline:.3g} deg", ""]
    if sections:
        lines += ["sections from the inlet end: " + ", then ".join(
            f"{l:g} m mapped in {path}" for path, l in sections)
            + f", then {length - sum(l for _, l in sections):g} m of the main map", ""]
    lines += [
             f"capacity (the inlet end at the overflow hold-up): {out['capacity'] * 3.6:.4g} "
             f"+- {out['capacity_error'] * 3.6:.2g} t/h", "",
             "| feed (t/h) | inlet-end hold-up (kg/m) | hold-up (kg) | mean residence (s) | "
             + " | ".join(f"{b} torque (N m) | {b} power (W)" for b in m.bodies)
             + (" | outlet temperature (C) |" if t_in is not None else " |"),
             "|---" * (4 + 2 * len(m.bodies) + (1 if t_in is not None else 0)) + "|"]
    rows = []
    for ans, err in zip(out["feeds"], out["errors"]):
        cells = [f"{ans.feed * 3.6:.4g}", f"{ans.inlet_holdup:.4g}"
                 + (" (overflows)" if ans.overflows else ""),
                 f"{ans.holdup:.4g} +- {err.get('holdup', math.nan):.2g}",
                 f"{ans.residence_time:.4g} +- {err.get('residence_time', math.nan):.2g}"]
        row = {"feed_kg_per_s": ans.feed, "inlet_holdup_kg_per_m": ans.inlet_holdup,
               "holdup_kg": ans.holdup, "holdup_kg_error": err.get("holdup"),
               "residence_time_s": ans.residence_time,
               "residence_time_s_error": err.get("residence_time"), "overflows": ans.overflows,
               "profile_x_m": ans.profile.x.tolist(),
               "profile_holdup_kg_per_m": ans.profile.holdup.tolist()}
        for b in m.bodies:
            t, p = ans.torques.get(b, math.nan), ans.powers.get(b, math.nan)
            cells += [f"{t:.4g} +- {err.get(f'{b}/torque', math.nan):.2g}",
                      f"{p:.4g} +- {err.get(f'{b}/power', math.nan):.2g}"]
            row[f"{b}/torque_N_m"], row[f"{b}/power_W"] = t, p
            row[f"{b}/torque_N_m_error"] = err.get(f"{b}/torque")
            row[f"{b}/power_W_error"] = err.get(f"{b}/power")
        if t_in is not None:
            t = ans.outlet_temperature
            cells.append("n/a (no conductance in the map)" if t is None else
                         f"{t - 273.15:.4g} +- {err.get('outlet_temperature', math.nan):.2g}")
            row["outlet_temperature_K"] = t
            row["outlet_temperature_K_error"] = err.get("outlet_temperature")
        lines.append("| " + " | ".join(cells) + " |")
        rows.append(row)
    lines += ["", f"errors: one standard deviation over {out['draws']} re-marches of the map "
              "drawn from its standard errors (noise only: not the particle size or precision)"]
    mapped = sorted(r.holdup for r in m.rows)
    outside = [a.feed * 3.6 for a in out["feeds"]
               if a.profile.holdup.max() < mapped[0] * 0.999 or a.overflows]
    if outside:
        lines.append(f"note: at {', '.join(f'{f:.3g}' for f in outside)} t/h the bed lies "
                     f"outside the mapped hold-ups ({mapped[0]:.4g} - {mapped[-1]:.4g} kg/m): "
                     "below them the law is extrapolated as Saeman's (chord cubed); map lower "
                     "or higher hold-ups to be sure")
    doc = {"length_m": length, "incline_deg": incline, "capacity_kg_per_s": out["capacity"],
           "inlet_sections": [{"map": str(path), "length_m": l} for path, l in sections],
           "capacity_kg_per_s_error": out["capacity_error"], "feeds": rows,
           "inlet_temperature_K": t_in}
    return {"text": "\n".join(lines), "json": doc}


def _plot_profiles(out: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for ans in out["feeds"]:
        ax.plot(ans.profile.x, ans.profile.holdup, label=f"{ans.feed * 3.6:.3g} t/h")
    ax.set_xlabel("distance from the inlet end (m)")
    ax.set_ylabel("hold-up (kg/m)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
