"""``taichi-dem dryer DESIGN.toml``: a rotary dryer's design file, read and checked, marched
(app/dryer.py) and reported (dryer.md, dryer.json, dryer_profile.png)."""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from ..scene import catalog  # noqa: F401 (the effects' dimensions: a temperature)
from ..errors import SceneError
from .dryer import Dryer, answer, sensitivity

# section -> key -> (Dryer field, dimension, default (None: required), lower bound, upper bound,
# description). A dimension of None: a plain number in the unit the description gives. A lower
# bound of 0.0 means > 0; GE0 means >= 0.
GE0 = "nonnegative"
KEYS = {
    "drum": {
        "diameter": ("diameter", "length", None, 0.0, None, "the drum's inside diameter"),
        "length": ("length", "length", None, 0.0, None, "the drum's length"),
        "incline": ("incline", "angle", None, 0.0, math.radians(45.0),
                    "the drum's incline, the discharge end lower"),
        "speed": ("rpm", "angular_speed", None, 0.0, None, "the drum's speed"),
    },
    "solids": {
        "feed": ("feed", "mass_rate", None, 0.0, None, "the feed of dry solids"),
        "moisture": ("feed_moisture", "dimensionless", 0.0, GE0, 10.0,
                     "the feed's moisture, kg water per kg dry solid"),
        "critical_moisture": ("critical_moisture", "dimensionless", 0.0, GE0, 10.0,
                              "the falling-rate period below it, kg/kg (0: none)"),
        "temperature": ("feed_temperature", "temperature", None, 0.0, None,
                        "the feed's temperature"),
        "target_moisture": ("target_moisture", "dimensionless", 0.005, GE0, 10.0,
                            "the product's moisture aimed at, kg/kg (the report says if met)"),
        "particle_diameter": ("particle_diameter", "length", None, 0.0, 1.0,
                              "the particles' diameter (Friedman-Marshall's gas term)"),
        "heat_capacity": ("solids_heat_capacity", "specific_heat", None, 0.0, None,
                          "the dry solid's specific heat"),
        "bulk_density": ("bulk_density", "density", None, 0.0, None,
                         "the dry bulk density (the fill fraction)"),
    },
    "gas": {
        "mass_flow": ("gas_flow", "mass_rate", None, 0.0, None, "the dry gas's flow"),
        "temperature": ("gas_temperature", "temperature", None, 0.0, None,
                        "the gas's inlet temperature"),
        "humidity": ("gas_humidity", "dimensionless", 0.0, GE0, 10.0,
                     "the inlet gas's humidity, kg water per kg dry gas"),
        "heat_capacity": ("gas_heat_capacity", "specific_heat", 1100.0, 0.0, None,
                          "the dry gas's specific heat"),
        "density": ("gas_density", "density", 0.52, 0.0, None,
                    "the gas's density (a map's closure; default air at 400 C)"),
        "viscosity": ("gas_viscosity", "viscosity", 3.3e-5, 0.0, None,
                      "the gas's viscosity (a map's closure)"),
        "conductivity": ("gas_conductivity", "thermal_conductivity", 0.051, 0.0, None,
                         "the gas's conductivity (a map's closure)"),
        "flow": ("counter_current", None, "counter", None, None,
                 "\"counter\" (against the solids) or \"co\""),
    },
    "water": {
        "evaporation_temperature": ("evaporation_temperature", "temperature", 373.15, 0.0, None,
                                    "the temperature at which the parcel dries"),
        "latent_heat": ("latent_heat", "specific_energy", 2.26e6, 0.0, None,
                        "the latent heat at the evaporation temperature"),
        "heat_capacity": ("water_heat_capacity", "specific_heat", 4186.0, 0.0, None,
                          "liquid water's specific heat"),
        "vapour_heat_capacity": ("vapour_heat_capacity", "specific_heat", 1900.0, 0.0, None,
                                 "steam's specific heat"),
    },
    "shell": {
        "loss_coefficient": ("shell_loss_coefficient", None, 0.0, GE0, 1e4,
                             "W/(m2 K) from the gas through the shell"),
        "ambient_temperature": ("ambient_temperature", "temperature", 288.15, 0.0, None,
                                "the surroundings' temperature"),
    },
    "closure": {
        "residence_time": ("residence_time", "time", "friedman_marshall", 0.0, None,
                           "the solids' mean residence time, or \"friedman_marshall\""),
        "conductance_per_metre": ("conductance_per_metre", None, "perry", 0.0, None,
                                  "gas-solids W/(m K) per metre of drum, or \"perry\""),
        "map": ("map", None, "", None, None, "a map.json of this drum's slices (taichi-dem "
                "map), relative to this file, or a list of maps at several gas speeds: the "
                "residence, conductance and torque from it"),
        "exposure": ("exposure", None, "curtains", None, None,
                     "what of a map's solids meets the gas: \"curtains\" (the airborne "
                     "particles) or \"surface\" (those and the surface of the bed and of the "
                     "flights' loads open to the gas, each at its own speed against it)"),
        "perry_k": ("perry_k", None, 0.5, 0.0, 100.0, "K in Perry's Ua = K G^0.67 / D, "
                                                      "Btu/(h ft3 F)"),
        "uncertainty": ("uncertainty", None, 0.25, GE0, 0.9,
                        "each closure's relative uncertainty, for the sensitivity"),
        "cells": ("cells", None, 800, 9.0, 1e4, "cells along the drum in the march"),
    },
}
ABOUT = "about"          # free text: what the design is and where its numbers come from


def load(path, feed: float | None = None, exposure: str | None = None) -> Dryer:
    """A dryer design file (TOML; the sections and keys of KEYS) as a Dryer (at ``feed`` kg/s
    of dry solids and with closure.exposure ``exposure`` instead of the file's, when given: a
    map's closures follow them); bad input is a SceneError naming the file, key and reason."""
    from ..scene.loader import read_toml
    from ..scene.units import parse_quantity
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(str(p), "", f"cannot read the dryer file: {getattr(e, 'strerror', None) or e}") from None
    data = read_toml(text, str(p))
    for section in data:
        if section not in KEYS and section != ABOUT:
            raise SceneError(str(p), section, "unknown section; known: " + ", ".join(KEYS))
    if not isinstance(data.get(ABOUT, ""), str):
        raise SceneError(str(p), ABOUT, f"expected text, got {data[ABOUT]!r}")
    kw = {}
    for section, keys in KEYS.items():
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise SceneError(str(p), section, "expected a table")
        for key in table:
            if key not in keys:
                raise SceneError(str(p), f"{section}.{key}", "unknown key; known: "
                                 + ", ".join(keys))
        for key, (attr, dimension, default, low, high, _) in keys.items():
            name = f"{section}.{key}"
            if key not in table:
                if default is None:
                    raise SceneError(str(p), name, "required")
                continue
            value = table[key]
            if attr == "map":
                paths = [value] if isinstance(value, str) else value
                if (not isinstance(paths, list) or not paths
                        or not all(isinstance(v, str) and v for v in paths)):
                    raise SceneError(str(p), name, "expected a path to a map.json or a list of "
                                     f"them (maps at several gas speeds), got {value!r}")
                resolved = [str((p.parent / v).resolve()) for v in paths]
                kw["map"] = resolved[0] if isinstance(value, str) else resolved
                continue
            if attr == "exposure":
                if value not in ("curtains", "surface"):
                    raise SceneError(str(p), name, "expected \"curtains\" or \"surface\", "
                                     f"got {value!r}")
                kw[attr] = value
                continue
            if attr == "counter_current":
                if value not in ("counter", "co"):
                    raise SceneError(str(p), name, f"expected \"counter\" or \"co\", got {value!r}")
                kw[attr] = value == "counter"
                continue
            if isinstance(default, str) and value == default:
                continue
            if dimension is None:
                if isinstance(value, bool) or not isinstance(value, (int, float)) \
                        or not math.isfinite(value):
                    raise SceneError(str(p), name, f"expected a number ({keys[key][5]}), "
                                     f"got {value!r}")
                number = float(value)
            else:
                number = parse_quantity(value, dimension, file=str(p), key=name)
            if low == GE0 and number < 0.0:
                raise SceneError(str(p), name, f"must be >= 0, got {number:g}")
            if isinstance(low, float) and not number > low:
                raise SceneError(str(p), name, f"must be > {low:g}, got {number:g}")
            if high is not None and number > high:
                raise SceneError(str(p), name, f"must be <= {high:g}, got {number:g}")
            if attr == "rpm":
                number *= 60.0 / (2.0 * math.pi)       # rad/s -> rev/min
            kw[attr] = int(number) if attr == "cells" else number
    if feed is not None:
        kw["feed"] = feed
    if exposure is not None:
        kw["exposure"] = exposure
    map_path = kw.pop("map", None)
    if map_path is None and kw.get("exposure", "curtains") != "curtains":
        raise SceneError(str(p), "closure.exposure", "the surface open to the gas is measured "
                         "by a map of the drum's slices: give closure.map")
    if map_path is not None:
        if "residence_time" in kw or "conductance_per_metre" in kw:
            raise SceneError(str(p), "closure.map", "a map gives the residence time and the "
                             "conductance: leave residence_time and conductance_per_metre out")
        from dataclasses import fields
        from .dryer_map import closures_over_gas
        base = Dryer(source=str(p), **kw)
        design = {f.name: getattr(base, f.name) for f in fields(base)}
        found = closures_over_gas(map_path, design, str(p))
        kw.update({k: found[k] for k in ("residence_time", "residence_uncertainty",
                                         "conductance_per_metre", "conductance_uncertainty",
                                         "drive_torque")})
        kw["map_info"] = found
    return Dryer(source=str(p), **kw)


def add_arguments(p) -> None:
    """The ``taichi-dem dryer`` arguments."""
    p.add_argument("design", help="a dryer design file (TOML: [drum], [solids], [gas], "
                                  "[water], [shell], [closure]; demos/dryers/*.toml)")
    p.add_argument("--flow", choices=("counter", "co"), default=None,
                   help="the gas against the solids or with them (default: the file's)")
    p.add_argument("--feed", default=None,
                   help="a feed of dry solids ('45 t/h', or kg/s) instead of the design's")
    p.add_argument("--exposure", choices=("curtains", "surface"), default=None,
                   help="with a map: what of the solids meets the gas (default: the file's "
                        "closure.exposure)")
    p.add_argument("--out", default=None, help="folder for dryer.md, dryer.json and "
                                               "dryer_profile.png (default: print only)")


# name, unit, scale, format: the figures of the report, in SI scaled for reading
ROWS = (("residence_time", "min", 1 / 60.0, ".3g"),
        ("holdup", "t (dry)", 1e-3, ".3g"),
        ("fill_fraction", "% of the drum", 100.0, ".3g"),
        ("solids_outlet_temperature", "C", None, ".1f"),
        ("solids_outlet_moisture", "% (dry basis)", 100.0, ".3g"),
        ("gas_outlet_temperature", "C", None, ".1f"),
        ("gas_outlet_humidity", "kg/kg dry gas", 1.0, ".4f"),
        ("gas_outlet_dew_point", "C", None, ".1f"),
        ("evaporation", "t/h of water", 3.6, ".3g"),
        ("heat_to_solids", "MW", 1e-6, ".4g"),
        ("shell_loss", "MW", 1e-6, ".3g"),
        ("burner_duty", "MW (the gas heated from ambient)", 1e-6, ".4g"),
        ("thermal_efficiency", "(heat to the solids / burner duty)", 1.0, ".3f"),
        ("drive_torque", "kN m (from the map)", 1e-3, ".3g"),
        ("drying_capacity", "t/h of dry solids dried to the target moisture", 3.6, ".3g"),
        ("energy_closure", "of the burner duty", 1.0, ".1e"))


def _shown(value: float, scale) -> float:
    return value - 273.15 if scale is None else value * scale


def report(d: Dryer, a: dict, spread: dict, title: str = "") -> str:
    """The answers as Markdown: each figure with its sensitivity to the closures."""
    flow = "counter-current" if d.counter_current else "co-current"
    lines = [f"# {title or 'Rotary dryer'}: {flow} march", "",
             f"Drum {d.diameter:g} m x {d.length:g} m at {math.degrees(d.incline):.3g} deg and "
             f"{d.rpm:g} rpm; feed {d.feed * 3.6:.4g} t/h dry solids at "
             f"{d.feed_moisture * 100:.3g} % moisture and {d.feed_temperature - 273.15:.1f} C; "
             f"gas {d.gas_flow:g} kg/s dry at {d.gas_temperature - 273.15:.0f} C.", "",
             ("Closures from the slices' map " + d.map_info["map_source"]
              + f": the hold-up marched from the discharge (as `taichi-dem machine` does) "
              f"averages {d.map_info['map_holdup']:.4g} kg/m (dry; "
              f"{d.map_info['map_uniform_holdup']:.4g} kg/m where the slice alone carries the "
              "feed), "
              f"{d.map_info['map_airborne_fraction']:.1%} of it airborne, the curtains' "
              f"coefficient h = {d.map_info['map_heat_transfer_coefficient']:.3g} W/(m^2 K)"
              + (f"; the gas also meets the surface of the bed and the flights' loads: "
                 f"{d.map_info['map_surface_conductance_per_metre']:.4g} of the "
                 f"{d.conductance_per_metre:.4g} W/(m K) per metre (closure.exposure)"
                 if d.map_info.get("map_surface_conductance_per_metre") is not None else "")
              + "; the +- column is each figure's change with the closures moved by the map's "
              "standard errors (added in quadrature)." if d.map_info else
             "Closures: residence "
             + (f"given ({d.residence_time:g} s)" if d.residence_time is not None
                else "from Friedman & Marshall (1949)")
             + ", gas-solids conductance "
             + (f"given ({d.conductance_per_metre:g} W/(m K) per metre)"
                if d.conductance_per_metre is not None
                else f"from Perry's Ua = {d.perry_k:g} G^0.67/D ({a['conductance_per_metre']:.4g} "
                     "W/(m K) per metre at the inlet gas flow)")
             + f". The +- column is each figure's change when each closure moves by "
               f"+-{d.uncertainty * 100:.0f} % (root sum of squares), a sensitivity, not a "
               "measured scatter."), "",
             "| figure | value | +- | unit |", "|---|---|---|---|"]
    for name, unit, scale, fmt in ROWS:
        if not math.isfinite(a.get(name, math.nan)):
            continue
        value = _shown(a[name], scale)
        err = spread["combined"].get(name)
        err_text = format(err * (1.0 if scale is None else abs(scale)), ".2g") if err is not None else ""
        shown = format(value, fmt)
        if name == "drying_capacity" and a.get("drying_capacity_bound"):
            shown = {"above": "> ", "below": "< "}[a["drying_capacity_bound"]] + shown
            err_text = ""
        lines.append(f"| {name.replace('_', ' ')} | {shown} | {err_text} | {unit} |")
    notes = []
    if not 0.03 <= a["fill_fraction"] <= 0.08 and d.residence_time is None:
        notes.append(f"the fill ({a['fill_fraction'] * 100:.2g} %) is outside the 3-8 % of drum "
                     "volume Friedman and Marshall fitted")
    if a["gas_outlet_temperature"] < a["gas_outlet_dew_point"] + 10.0:
        notes.append("the gas leaves within 10 K of its dew point: water may condense in the "
                     "ducts and filter")
    if d.map_info:
        notes += d.map_info.get("map_notes", [])
    bound = a.get("drying_capacity_bound")
    if bound:
        notes.append(f"the drying capacity is {bound} the feeds searched "
                     + ("(the map's)" if d.map_info else "(0.05 - 5x the design's)"))
    if a["solids_outlet_moisture"] > d.target_moisture:
        notes.append(f"the product leaves wetter than the {d.target_moisture * 100:.3g} % aimed "
                     "at: more gas, a hotter gas or a longer drum")
    if notes:
        lines += [""] + [f"- Note: {n}." for n in notes]
    return "\n".join(lines)


def _plot(a: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    p = a["profile"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    top.plot(p.x, p.solids_temperature - 273.15, label="solids")
    top.plot(p.x, p.gas_temperature - 273.15, label="gas")
    top.set_ylabel("temperature (C)")
    top.legend()
    bottom.plot(p.x, p.moisture * 100.0, label="solids' moisture (% dry basis)")
    bottom.plot(p.x, p.humidity * 100.0, label="gas humidity (% of dry gas)")
    bottom.set_xlabel("distance from the feed end (m)")
    bottom.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run(path, flow: str | None = None, capacity: bool = True,
        feed: float | None = None, exposure: str | None = None) -> tuple[Dryer, dict, dict]:
    """Load, march and measure the sensitivity of the dryer in ``path`` (at ``feed`` kg/s of
    dry solids and with closure.exposure ``exposure`` instead of the file's, when given); with
    ``capacity`` also its drying capacity (the largest dry feed it dries to the target
    moisture) and that figure's sensitivity to the closures."""
    from dataclasses import replace
    d = load(path, feed=feed, exposure=exposure)
    if flow is not None:
        d = replace(d, counter_current=flow == "counter")
    a = answer(d)
    spread = sensitivity(d, a)
    if capacity:
        a["drying_capacity"], a["drying_capacity_bound"], moved = _capacity(path, d)
        spread["combined"]["drying_capacity"] = moved
    return d, a, spread


CAPACITY_RESOLUTION = 0.01           # drying_capacity's bisection tolerance (relative)


def _capacity(path, d: Dryer):
    """(capacity kg/s, "" or "above"/"below" the searched range, its sensitivity kg/s)."""
    from dataclasses import replace
    from .dryer import drying_capacity
    if d.map_info:
        low, high = d.map_info["map_feed_range"]
    else:
        low, high = 0.05 * d.feed, 5.0 * d.feed

    def at_feed(feed, residence=1.0, conductance=1.0):
        return replace(load(path, feed=feed, exposure=d.exposure),
                       counter_current=d.counter_current, residence_factor=residence,
                       conductance_factor=conductance)
    value, bound = drying_capacity(at_feed, low, high, d.target_moisture,
                                   tolerance=CAPACITY_RESOLUTION)
    own = {"residence": d.residence_uncertainty, "conductance": d.conductance_uncertainty}
    moves = []
    for name in ("residence", "conductance"):
        u = d.uncertainty if own[name] is None else own[name]
        moved = 0.0
        for f in (1.0 + u, 1.0 - u):
            kw = {name: f}
            other, _ = drying_capacity(lambda feed: at_feed(feed, **kw), low, high,
                                       d.target_moisture, tolerance=CAPACITY_RESOLUTION)
            moved = max(moved, abs(other - value))
        moves.append(moved)
    # never below the bisection's resolution (drying_capacity's 1 %): closures that move the
    # capacity by less land in the same bracket, which read as an exact "+- 0"
    return value, bound, max(math.hypot(*moves), CAPACITY_RESOLUTION * value)


def cmd_dryer(args) -> int:
    """``taichi-dem dryer``: the module docstring."""
    feed = getattr(args, "feed", None)
    if isinstance(feed, str):
        from ..scene.units import parse_quantity
        try:
            feed = float(feed)                  # plain kg/s
        except ValueError:
            pass                                # a quantity ('45 t/h')
        feed = parse_quantity(feed, "mass_rate",
                              file="taichi-dem dryer", key="--feed")
        if feed <= 0.0:
            raise SceneError("taichi-dem dryer", "--feed", "must be > 0")
    d, a, spread = run(args.design, args.flow, feed=feed,
                       exposure=getattr(args, "exposure", None))
    text = report(d, a, spread, Path(args.design).stem.replace("_", " "))
    print(text)
    if args.out:
        folder = Path(args.out)
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "dryer.md").write_text(text + "\n")
        figures = {k: v for k, v in a.items() if k != "profile"}
        p = a["profile"]
        figures["profile"] = {"x": p.x.tolist(), "solids_temperature": p.solids_temperature.tolist(),
                              "moisture": p.moisture.tolist(),
                              "gas_temperature": p.gas_temperature.tolist(),
                              "humidity": p.humidity.tolist()}
        figures["sensitivity"] = spread
        (folder / "dryer.json").write_text(json.dumps(figures, indent=1, default=float))
        _plot(a, folder / "dryer_profile.png")
        print(f"wrote {folder / 'dryer.md'}, {folder / 'dryer.json'}, "
              f"{folder / 'dryer_profile.png'}", file=sys.stderr)
    return 0
