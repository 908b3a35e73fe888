"""``taichi-dem tradeoffs``: what accuracy costs in time, one knob at a time, on the sweep.

The **reference** is the scene as written at the most accurate precision (``simulation.precision
= "f64"``), run with ``--seeds N`` placement seeds; its seed-to-seed scatter says how large a
difference the study can resolve at all. Each **variant** is the reference with one knob
changed, run with the same seeds. Per variant: the median stepping wall time over the seeds
(``step_s``: kernel compilation and start-up left out, they do not grow with the run) and
CPU time (``cpu_s``, likewise), the speed-up in CPU time against the reference's median (CPU
seconds of a one-thread run are what its wall time would be on an idle core; on a shared
machine the wall time also counts the other jobs' turns), and per key output (``outputs.py``) the relative
error of the variant's median against the reference's median. The recommended setting of a
knob is its fastest setting (the reference's included) whose error stays within
``--tolerance`` on every output.

Knobs (``--knobs``, default all; a knob whose keys the loader refuses for this scene, or that
does not apply, is skipped and the report says why):

``timestep``    explicit ``simulation.dt`` at 0.5, 1.5, 2 and 2.4 times the automatic dt of the
                reference (whichever bound set it: Rayleigh fraction, 20 steps per contact, a
                body's surface speed); the label gives the steps per Hertz contact at the
                expected speed. A dt the engine refuses (under 8 steps per contact, over half
                the Rayleigh time) is skipped with its message.
``precision``   f32 against the f64 reference.
``modulus``     Young's modulus of every particle material (those of fills and factories)
                divided by 10, 100, 1000 (the automatic time step grows with it; an explicit
                dt is scaled as the Hertz contact time, by factor^0.4). In a thermal
                scene each twice: with the conduction correction (``real_youngs_modulus`` =
                the unsoftened value, the scene's own when it gives one, else the reference's
                modulus; ``contact_radius_correction`` as the scene has it) and without it
                (``thermal.contact_radius_correction = "none"``).
``skin``        ``simulation.skin`` 0.5x and 2x the default skin the engine picks for the scene.
``size``        coarse graining: every fill's and factory's radii (constant, distribution, or
                sizes table) times 1.5 and 2; fill counts divided by the factor cubed (same
                fill mass); factory mass rates unchanged (the particle rate falls by the cube),
                so the mass flows match; an explicit dt is scaled by the factor (the contact
                time grows as the radius). Interactions, materials and geometry are unchanged.
``mobility``    ``mobility.enabled = true`` (mobility skipping, issue 12: the contacts and
                integration of immobile particles skipped).
``time_scale``  ``thermal.time_scale`` 10, 100 (thermal scenes: heat capacities divided by S,
                issue 10).
"""
from __future__ import annotations

import argparse
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from ..errors import SceneError
from . import overrides as ov

REFERENCE_OVERRIDES = {"simulation.precision": "f64"}
KNOB_NAMES = ("timestep", "precision", "modulus", "skin", "size", "mobility", "time_scale")
DEFAULT_TOLERANCE = 0.05
MIN_SPEEDUP = 1.05     # a setting must beat the reference by this factor to be recommended


@dataclass
class Variant:
    """One setting of one knob: ``overrides`` on top of the reference's."""
    knob: str
    setting: str
    overrides: dict


# ------------------------------------------------------------------------------ knobs
def _particle_materials(doc: dict) -> list[str]:
    names = []
    for section in ("particles", "factories"):
        for t in doc.get(section, []):
            m = t.get("material") if isinstance(t, dict) else None
            if isinstance(m, str) and m not in names:
                names.append(m)
    return names


def knob_timestep(doc: dict, info: dict):
    """Explicit dt at multiples of the reference's automatic dt (whichever bound set it:
    Rayleigh fraction, steps per contact or a body's surface speed; changing only
    rayleigh_fraction would leave a contact-limited dt where it is)."""
    out = []
    for f in (0.5, 1.5, 2.0, 2.4):
        dt = f * info["dt"]
        out.append(Variant("timestep", f"dt x{f:g} ({info['contact_time'] / dt:.3g} steps/contact)",
                           {"simulation.dt": dt}))
    return out


def knob_precision(doc: dict, info: dict):
    return [Variant("precision", "f32", {"simulation.precision": "f32"})]


def _explicit_dt(doc: dict) -> Optional[float]:
    """The scene's explicit ``simulation.dt`` (s), or None when it is automatic."""
    from ..scene.units import parse_quantity
    dt = doc.get("simulation", {}).get("dt")
    if dt is None or (isinstance(dt, str) and dt.strip().lower() == "auto"):
        return None
    return parse_quantity(dt, "time")


def knob_modulus(doc: dict, info: dict):
    from ..scene.units import parse_quantity
    mats = _particle_materials(doc)
    fixed_dt = _explicit_dt(doc)
    if not mats:
        return "no particle material (no fill and no factory)"
    materials = doc.get("materials", {})
    thermal = "thermal" in doc
    out = []
    for factor in (10, 100, 1000):
        base, real = {}, {}
        for m in mats:
            e = parse_quantity(materials[m]["youngs_modulus"], "pressure")
            base[f"materials.{m}.youngs_modulus"] = e / factor
            given = materials[m].get("real_youngs_modulus")
            real[f"materials.{m}.real_youngs_modulus"] = (parse_quantity(given, "pressure")
                                                          if given is not None else e)
        if fixed_dt is not None:
            # an explicit dt would not follow the softer contacts: scale it as the Hertz
            # contact time, t_c ~ E*^(-2/5), so the steps per contact stay the scene's
            base["simulation.dt"] = fixed_dt * factor ** 0.4
        if thermal:
            out.append(Variant("modulus", f"E/{factor}, corrected", {**base, **real}))
            out.append(Variant("modulus", f"E/{factor}, uncorrected",
                               {**base, "thermal.contact_radius_correction": "none"}))
        else:
            out.append(Variant("modulus", f"E/{factor}", base))
    return out


def step_info(scene) -> dict:
    """The time step the engine picks for ``scene`` and why, without compiling anything (as
    ``taichi-dem check``): {"dt" s, "skin" m, "contact_time" s (Hertz, at the expected speed),
    "rayleigh_time" s, "limited_by"}. An explicit dt the engine refuses is a SceneError."""
    from ..run.simulation import _check_periodic_axes, _sizes_to_expect
    from ..setup.pair_tables import build_pair_tables
    from ..setup.placement import place_fills
    from ..setup.timestep import choose_step_and_skin
    placed = place_fills(scene, np.random.default_rng(scene.simulation.seed))
    tables = build_pair_tables(scene)
    radii, mats, speeds, fixed = _sizes_to_expect(scene, placed, tables.names)
    ts, skin = choose_step_and_skin(scene, radii, mats, tables.names, speeds, fixed)
    _check_periodic_axes(scene, float(np.max(radii)))
    return {"dt": ts.dt, "skin": skin, "contact_time": ts.contact_time,
            "rayleigh_time": ts.rayleigh_time, "limited_by": ts.limited_by}


def knob_skin(doc: dict, info: dict):
    skin = info["skin"]
    return [Variant("skin", f"{f:g} x default ({f * skin * 1e3:.3g} mm)", {"simulation.skin": f * skin})
            for f in (0.5, 2.0)]


def _scaled_radius(value, f: float):
    from ..scene.units import parse_quantity
    if isinstance(value, dict):
        return {k: (parse_quantity(v, "length") * f if k in ("mean", "std", "min", "max") else v)
                for k, v in value.items()}
    return parse_quantity(value, "length") * f


def knob_size(doc: dict, info: dict):
    from ..scene.units import parse_quantity
    fills, factories = doc.get("particles", []), doc.get("factories", [])
    if any("file" in t for t in fills):
        return "a fill is read from a particle file (its positions cannot be coarse-grained here)"
    if not fills and not factories:
        return "no fill and no factory"
    fixed_dt = _explicit_dt(doc)
    out = []
    for f in (1.5, 2.0):
        o = {} if fixed_dt is None else {"simulation.dt": fixed_dt * f}   # t_c ~ R
        for i, t in enumerate(fills):
            o[f"particles.{i}.radius"] = _scaled_radius(t["radius"], f)
            o[f"particles.{i}.count"] = max(1, int(round(int(t["count"]) / f ** 3)))
        for i, t in enumerate(factories):
            if "radius" in t:
                o[f"factories.{i}.radius"] = _scaled_radius(t["radius"], f)
            if "sizes" in t:
                o[f"factories.{i}.sizes"] = [[parse_quantity(r, "length") * f, w] for r, w in t["sizes"]]
        out.append(Variant("size", f"radius x{f:g}", o))
    return out


def knob_mobility(doc: dict, info: dict):
    return [Variant("mobility", "enabled", {"mobility.enabled": True})]


def knob_time_scale(doc: dict, info: dict):
    if "thermal" not in doc:
        return "the scene has no [thermal] section"
    return [Variant("time_scale", f"x{s}", {"thermal.time_scale": s}) for s in (10, 100)]


KNOBS: dict[str, Callable] = {"timestep": knob_timestep, "precision": knob_precision,
                              "modulus": knob_modulus, "skin": knob_skin, "size": knob_size,
                              "mobility": knob_mobility, "time_scale": knob_time_scale}


def parse_knobs(values: Optional[list[str]]) -> list[str]:
    """``--knobs a,b c`` -> names, in the order of KNOB_NAMES; unknown names exit 2."""
    if not values:
        return list(KNOB_NAMES)
    names = [n.strip() for v in values for n in v.split(",") if n.strip()]
    for n in names:
        if n not in KNOBS:
            raise SceneError("--knobs", n, f"unknown knob; choose from {', '.join(KNOB_NAMES)}")
    return [n for n in KNOB_NAMES if n in names]


# ------------------------------------------------------------------------------ planning
def plan_study(scene_path: str, knobs: list[str], seeds: int, duration: Optional[float],
               threads: int = 1, arch: str = "cpu"):
    """(reference specs, variant specs, skipped {knob or variant: reason}). Every variant is
    validated by the loader; one it refuses is skipped with the loader's message."""
    from .sweep import plan
    from ..scene.loader import read_toml
    text = Path(scene_path).read_text(encoding="utf-8-sig")
    doc = read_toml(text, scene_path)       # a syntax error or deep nesting: SceneError
    ref_specs = plan(scene_path, [dict(REFERENCE_OVERRIDES)], seeds, duration=duration,
                     threads=threads, arch=arch, labels=[{"knob": "reference", "setting": "reference"}])
    info = step_info(ov.check(ref_specs[0].text, {}, scene_path))
    variants, skipped = [], {}
    for name in knobs:
        try:
            got = KNOBS[name](doc, info)
        except (KeyError, ValueError, TypeError, SceneError) as err:
            got = f"cannot be applied to this scene ({type(err).__name__}: {err})"
        if isinstance(got, str):
            skipped[name] = got
            continue
        for v in got:
            combo = {**REFERENCE_OVERRIDES, **v.overrides}
            try:
                specs = plan(scene_path, [combo], seeds, duration=duration, threads=threads,
                             arch=arch, labels=[{"knob": v.knob, "setting": v.setting}])
                step_info(ov.check(specs[0].text, combo, scene_path))   # dt the engine refuses
                variants += specs
            except SceneError as err:
                skipped[f"{name}: {v.setting}"] = str(err)
    return ref_specs, variants, skipped


# ------------------------------------------------------------------------------ analysis
@dataclass
class Row:
    """One setting of a knob, aggregated over its seeds."""
    knob: str
    setting: str
    runs: int
    failed: list
    dt: float
    particles: float
    step_s: float            # median stepping wall time over the seeds, s (compilation left out)
    wall_s: float            # median whole-run wall time, s
    speedup: float           # reference cpu_s / this cpu_s
    values: dict             # output -> median over seeds
    errors: dict             # output -> (median - reference median) / |reference median|
    cpu_s: float = math.nan  # median stepping CPU time over the seeds, s (compilation left out)

    @property
    def worst(self) -> float:
        e = [abs(x) for x in self.errors.values() if math.isfinite(x)]
        return max(e) if e else math.nan


def _median(xs) -> float:
    xs = [x for x in xs if isinstance(x, (int, float)) and math.isfinite(x)]
    return float(np.median(xs)) if xs else math.nan


def aggregate(records: list[dict], outputs: Optional[list[str]] = None) -> tuple[Row, list[Row], dict]:
    """(reference row, variant rows in planned order, reference scatter {output: relative
    sample standard deviation over the seeds, NaN with one seed}) from sweep records, over
    ``outputs`` (default every output the reference reported; a name it did not report is a
    SceneError listing those it did)."""
    groups: dict[tuple, list[dict]] = {}
    for r in records:
        lab = r.get("labels", {})
        groups.setdefault((lab.get("knob", "?"), lab.get("setting", "?")), []).append(r)
    ref_recs = groups.pop(("reference", "reference"), [])
    ref_ok = [r for r in ref_recs if r["status"] == "done"]
    if not ref_ok:
        msgs = "; ".join(r.get("message", "") for r in ref_recs)
        raise RuntimeError(f"the reference runs failed: {msgs}")
    outs = list(dict.fromkeys(k for r in ref_ok for k in r["outputs"]))
    if outputs:
        for o in outputs:
            if o not in outs:
                raise SceneError("--outputs", o, f"not an output of this scene; it has: "
                                                 f"{', '.join(outs)}")
        outs = list(outputs)
    ref_vals = {o: _median([r["outputs"].get(o, math.nan) for r in ref_ok]) for o in outs}
    scatter = {}
    for o in outs:
        xs = np.array([r["outputs"].get(o, math.nan) for r in ref_ok], float)
        xs = xs[np.isfinite(xs)]
        m = abs(float(np.mean(xs))) if len(xs) else math.nan
        scatter[o] = float(np.std(xs, ddof=1) / m) if len(xs) > 1 and m > 0 else math.nan
    ref_cpu = _median([r.get("cpu_s", math.nan) for r in ref_ok])

    def row(knob, setting, recs):
        ok = [r for r in recs if r["status"] == "done"]
        vals = {o: _median([r["outputs"].get(o, math.nan) for r in ok]) for o in outs}
        errs = {o: ((vals[o] - ref_vals[o]) / abs(ref_vals[o])
                    if ref_vals[o] and math.isfinite(ref_vals[o]) else math.nan) for o in outs}
        step = _median([r["step_s"] for r in ok])
        cpu = _median([r.get("cpu_s", math.nan) for r in ok])
        return Row(knob=knob, setting=setting, runs=len(ok),
                   failed=[r.get("message", "") for r in recs if r["status"] != "done"],
                   dt=_median([r.get("dt") for r in ok]),
                   particles=_median([r.get("particles") for r in ok]), step_s=step,
                   wall_s=_median([r.get("wall_s") for r in ok]),
                   speedup=ref_cpu / cpu if cpu and math.isfinite(cpu) else math.nan,
                   values=vals, errors=errs, cpu_s=cpu)
    ref = row("reference", "reference", ref_recs)
    return ref, [row(k, s, recs) for (k, s), recs in groups.items()], scatter


def recommend(ref: Row, rows: list[Row], tolerance: float, min_speedup: float = MIN_SPEEDUP) -> Row:
    """The fastest of ``rows`` whose worst relative error over the outputs is within
    ``tolerance`` and which is at least ``min_speedup`` times faster than the reference (in
    CPU time; a smaller gain is within the timing noise); the reference itself when none is."""
    best = ref
    for r in rows:
        if (r.runs and not r.failed and r.worst <= tolerance and r.speedup >= min_speedup
                and r.cpu_s < best.cpu_s):
            best = r
    return best


# ------------------------------------------------------------------------------ report
def _pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100 * x:+.1f} %"


def _g(x: float, digits: int = 4) -> str:
    return "n/a" if not (isinstance(x, (int, float)) and math.isfinite(x)) else f"{x:.{digits}g}"


def write_report(out_dir: str, scene_path: str, command: str, ref: Row, rows: list[Row],
                 scatter: dict, skipped: dict, tolerance: float, seeds: int,
                 plots: list[str]) -> Path:
    """``tradeoffs.md``: the reference, then per knob a table (setting, dt, particles, step
    time, speed-up, error per output) and its recommended setting; skipped knobs with why."""
    from .outputs import unit
    outs = list(ref.values)
    lines = [f"# What accuracy costs in time: {Path(scene_path).name}", "",
             f"`{command}`", "",
             f"Reference: the scene's own settings at f64 (`simulation.precision = \"f64\"`), "
             f"{seeds} seed(s). Every variant changes one knob from the reference and runs with "
             f"the same seeds. Times are medians over the seeds of the stepping CPU and wall "
             f"time (start-up and kernel compilation left out); speed-ups are in CPU time "
             f"(one thread per run: an idle core's wall time); errors compare the median of each "
             f"output over the seeds with the reference's median. Scatter: the reference's "
             f"seed-to-seed relative standard deviation; an error below it is not resolved. "
             f"Recommended: the fastest setting within {tolerance:.0%} of the reference on "
             f"every output and at least {MIN_SPEEDUP:g}x faster than it (less is timing noise). Runs share the machine's cores (one run per worker at a time), so "
             f"times carry the noise of whatever else runs.", "",
             "## Reference", "",
             f"dt {_g(ref.dt)} s, {_g(ref.particles)} particles (mean over the run), stepping "
             f"{_g(ref.cpu_s, 3)} s CPU, {_g(ref.step_s, 3)} s wall (whole run "
             f"{_g(ref.wall_s, 3)} s), {ref.runs} run(s)", "",
             "| output | reference (median) | seed-to-seed scatter |", "|---|---|---|"]
    for o in outs:
        u = unit(o)
        lines.append(f"| {o} | {_g(ref.values[o])} {u} | {_pct(scatter.get(o, math.nan)).lstrip('+')} |")
    header = (["setting", "dt [s]", "particles", "cpu [s]", "wall [s]", "speed-up"]
              + [f"{o} error" for o in outs])
    for knob in dict.fromkeys(r.knob for r in rows):
        krows = [r for r in rows if r.knob == knob]
        lines += ["", f"## {knob}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        lines.append("| reference | " + " | ".join([_g(ref.dt), _g(ref.particles, 5), _g(ref.cpu_s, 3),
                                                    _g(ref.step_s, 3), "1"]
                                                   + ["0" for _ in outs]) + " |")
        for r in krows:
            if not r.runs:
                lines.append(f"| {r.setting} | failed: {'; '.join(r.failed)[:300]} |" + " |" * (len(header) - 2))
                continue
            cells = [r.setting, _g(r.dt), _g(r.particles, 5), _g(r.cpu_s, 3), _g(r.step_s, 3),
                     _g(r.speedup, 3)]
            cells += [_pct(r.errors[o]) for o in outs]
            lines.append("| " + " | ".join(cells) + " |")
        best = recommend(ref, krows, tolerance)
        if best is ref:
            lines += ["", f"Recommended: the reference setting (no {knob} setting is at least "
                          f"{MIN_SPEEDUP:g}x faster within {tolerance:.0%} on every output)."]
        else:
            lines += ["", f"Recommended: **{best.setting}**, {best.speedup:.3g}x faster, worst "
                          f"error {100 * best.worst:.1f} % (within {tolerance:.0%})."]
        unresolved = [o for o in outs if scatter.get(o, 0) > tolerance]
        if unresolved:
            lines.append(f"Note: the reference's own scatter exceeds {tolerance:.0%} for "
                         f"{', '.join(unresolved)}: more seeds or a longer run are needed to "
                         f"tell its errors from noise.")
        fails = [r for r in krows if r.failed and r.runs]
        for r in fails:
            lines.append(f"Note: {r.setting}: {len(r.failed)} run(s) failed: {'; '.join(r.failed)[:300]}")
    if skipped:
        lines += ["", "## Skipped", ""] + [f"- **{k}**: {v}" for k, v in skipped.items()]
    if plots:
        lines += ["", "## Plots", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in plots]
    path = Path(out_dir) / "tradeoffs.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def plot(out_dir: str, ref: Row, rows: list[Row], scatter: dict, tolerance: float) -> list[str]:
    """Per output a PNG ``tradeoffs_<output>.png``: |relative error| (%) against the stepping
    CPU time (s), one curve per knob through its settings in the knob's order, the reference
    as a star at zero error, its seed-to-seed scatter as a band, the tolerance as a line."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .outputs import unit
    paths = []
    for o in ref.values:
        fig, ax = plt.subplots(figsize=(7, 4.5))
        sc = scatter.get(o, math.nan)
        if math.isfinite(sc):
            ax.axhspan(0, 100 * sc, color="0.85", label="reference seed-to-seed scatter")
        ax.axhline(100 * tolerance, color="0.4", ls="--", lw=1, label=f"tolerance {tolerance:.0%}")
        ax.plot([ref.cpu_s], [0.0], "k*", ms=12, label="reference", zorder=5)
        for knob in dict.fromkeys(r.knob for r in rows):
            # in the knob's own order (dt x0.5, x1.5, ...), not sorted by time
            pts = [(r.cpu_s, 100 * abs(r.errors[o]), r.setting) for r in rows
                   if r.knob == knob and r.runs and math.isfinite(r.errors[o])
                   and math.isfinite(r.cpu_s)]
            if not pts:
                continue
            line, = ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=knob)
            for x, y, s in pts:
                ax.annotate(s.split(" (")[0], (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7,
                            color=line.get_color())
        ax.set_xscale("log")
        ax.set_xlabel("stepping CPU time per run, s (median over seeds; compilation left out; log)")
        ax.set_ylabel(f"|relative error| of {o}, %")
        ax.set_title(f"{o} [{unit(o)}]: error against cost, one knob at a time")
        ax.legend(fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()
        name = "tradeoffs_" + re.sub(r"[^A-Za-z0-9]+", "_", o).strip("_") + ".png"
        path = str(Path(out_dir) / name)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


# ------------------------------------------------------------------------------ CLI
def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="the scene file (TOML) whose knobs are measured")
    p.add_argument("--knobs", nargs="+", metavar="KNOB",
                   help=f"knobs to vary (default all): {', '.join(KNOB_NAMES)}")
    p.add_argument("--out", default="tradeoffs", help="directory (default tradeoffs)")
    p.add_argument("--seeds", type=int, default=2, metavar="N",
                   help="placement seeds per setting (default 2; the reference's scatter needs >= 2)")
    p.add_argument("--duration", type=float, metavar="S", help="simulated time per run, s "
                                                               "(default the scene's end_time)")
    p.add_argument("--outputs", nargs="+", metavar="NAME",
                   help="the outputs the errors and the recommendation are about (default all "
                        "the scene reports, e.g. drum/axial_torque particles/kinetic_energy)")
    p.add_argument("--tolerance", type=float, default=DEFAULT_TOLERANCE,
                   help=f"relative error a recommended setting may have (default {DEFAULT_TOLERANCE})")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                   help="an existing Dask scheduler (default: a LocalCluster on this machine)")
    p.add_argument("--workers", type=int, metavar="N", help="LocalCluster workers (default: cores)")
    p.add_argument("--threads", type=int, metavar="N", help="CPU threads per run (default cores / workers, at least 1)")
    p.add_argument("--arch", default="cpu", choices=["cpu", "gpu", "cuda", "vulkan", "metal"],
                   help="where the kernels run: cpu, or a GPU backend (gpu picks one; default cpu)")
    p.add_argument("--timeout", type=float, metavar="S", help="wall-clock limit per run, s")
    p.add_argument("--quiet", action="store_true", help="no progress output")


def run_tradeoffs(scene_path: str, out_dir: str, knobs: list[str], seeds: int,
                  duration: Optional[float], tolerance: float, client=None, *, command: str = "",
                  outputs: Optional[list[str]] = None,
                  scheduler=None, workers=None, threads: int = 1, arch: str = "cpu",
                  progress: bool = True, timeout=None) -> dict:
    """Plan, run (on the sweep), aggregate, write ``tradeoffs.md``, the sweep's tables and the
    plots in ``out_dir``. Returns {"reference", "rows", "scatter", "skipped", "report", "plots"}."""
    from .sweep import run_sweep, write_table
    ref_specs, variants, skipped = plan_study(scene_path, knobs, seeds, duration, threads, arch)
    if progress:
        print(f"tradeoffs: {len(ref_specs)} reference runs + {len(variants)} variant runs"
              + (f"; skipped: {', '.join(skipped)}" if skipped else ""), file=sys.stderr)
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    records = run_sweep(ref_specs + variants, out_dir, client, scheduler=scheduler,
                        workers=workers, progress=progress, timeout=timeout)
    write_table(records, out_dir, f"Tradeoff runs of {scene_path}", command)
    ref, rows, scatter = aggregate(records, outputs)
    plots = plot(out_dir, ref, rows, scatter, tolerance)
    report = write_report(out_dir, scene_path, command, ref, rows, scatter, skipped, tolerance,
                          seeds, plots)
    return {"reference": ref, "rows": rows, "scatter": scatter, "skipped": skipped,
            "report": report, "plots": plots, "records": records}


def cmd_tradeoffs(args) -> int:
    from .sweep import threads_per_run
    knobs = parse_knobs(args.knobs)
    if args.seeds < 1:
        raise SceneError("--seeds", "", f"must be >= 1, got {args.seeds}")
    command = "taichi-dem " + " ".join(sys.argv[1:]) if sys.argv[1:2] == ["tradeoffs"] else \
        f"taichi-dem tradeoffs {args.scene}"
    try:
        res = run_tradeoffs(args.scene, args.out, knobs, args.seeds, args.duration, args.tolerance,
                            command=command, outputs=args.outputs, scheduler=args.scheduler,
                            workers=args.workers,
                            threads=threads_per_run(args.workers, args.threads), arch=args.arch,
                            progress=not args.quiet, timeout=args.timeout)
    except RuntimeError as err:
        print(f"taichi-dem: {err}", file=sys.stderr)
        return 1
    ref = res["reference"]
    print(f"reference: stepping {ref.cpu_s:.3g} s CPU; " + ", ".join(f"{o} {v:.4g}" for o, v in ref.values.items()))
    for r in res["rows"]:
        print(f"{r.knob:10s} {r.setting:28s} speed-up {_g(r.speedup, 3):>6s}  worst error "
              f"{_pct(r.worst).lstrip('+')}" + (f"  ({len(r.failed)} failed)" if r.failed else ""))
    for k, v in res["skipped"].items():
        print(f"skipped {k}: {v}")
    print(f"report: {res['report']}; plots: {', '.join(res['plots'])}")
    return 0
