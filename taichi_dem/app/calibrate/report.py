"""What a calibration writes (its report): calibrated_material.toml (the blocks and the record),
calibration.md, calibration_response.png, calibration.json."""
from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Optional

import numpy as np

from .spec import LEVEL_TIE, Spec
from .fit import Surface, scale


def _show_point(point: dict) -> str:
    return ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                     for k, v in point.items())


# ------------------------------------------------------------------------------ outputs
def material_blocks(scene_path: str, material: str, optimum: dict) -> dict:
    """{"materials": {material: {...}}, "interactions": [...]} of the base scene with the
    optimum's overrides applied: the calibrated material and every interaction it takes part
    in."""
    from .. import overrides as ov
    doc = tomllib.loads(Path(scene_path).read_text(encoding="utf-8-sig"))
    doc = ov.apply(doc, optimum, scene_path)
    mats = doc.get("materials", {})
    return {"materials": {material: dict(mats.get(material, {}))},
            "interactions": [dict(i) for i in doc.get("interactions", [])
                             if material in i.get("pair", [])]}


def _interaction_key(doc: dict, key: str) -> dict:
    """{"pair": [a, b], "field": name} for a spec key ``interactions.N.name`` of the base
    scene ``doc`` ({} for any other key): what the key sets, in terms a scene with other
    interactions (another order, other partners) can be compared with."""
    parts = key.split(".")
    if len(parts) == 3 and parts[0] == "interactions" and parts[1].isdigit():
        items = doc.get("interactions", [])
        i = int(parts[1])
        if i < len(items) and isinstance(items[i].get("pair"), list):
            return {"pair": list(items[i]["pair"]), "field": parts[2]}
    return {}


def calibration_record(result: dict, base_scene: Optional[str] = None) -> dict:
    """The machine-readable record (TOML-ready: no None, no tuples): what a scene's
    ``materials.<name>.calibration`` table would hold. ``base_scene``: the first test's
    scene, to name the interaction pair each calibrated key sets (scene/sections/
    calibration.py compares them with the scene that claims the material)."""
    doc = {}
    if base_scene:
        try:
            doc = tomllib.loads(Path(base_scene).read_text(encoding="utf-8-sig"))
        except (OSError, tomllib.TOMLDecodeError):
            doc = {}
    parameters = [{**p, **_interaction_key(doc, p["key"])} for p in result["parameters"]]
    factors = []
    for f in result["factors"]:
        entry = {k: f[k] for k in ("keys", "levels", "value")}
        named = [_interaction_key(doc, k) for k in f["keys"]]
        if named and all(named) and len({n["field"] for n in named}) == 1:
            entry.update(pairs=[n["pair"] for n in named], field=named[0]["field"])
        factors.append(entry)
    def clean(v):
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items() if x is not None}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        if isinstance(v, (np.floating, float)):
            return float(v)
        if isinstance(v, np.integer):
            return int(v)
        return v
    tests = [{k: t[k] for k in ("name", "kind", "unit", "scene", "duration", "measured", "target",
                                "target_sd", "achieved", "achieved_mean", "achieved_sd", "achieved_sem",
                                "within_scatter", "reachable", "target_reachable", "fit")}
             for t in result["tests"]]
    rec = {"date": result["date"], "command": result["command"], "spec": result["spec"],
           "sphere_radius": result["sphere_radius"], "within_scatter": result["within_scatter"],
           "design": result["design"], "parameters": parameters, "factors": factors,
           "tests": tests,
           "rounds": [{"round": r["round"], "optimum": r["optimum"], "passed": r["passed"],
                       "achieved_mean": [t["achieved_mean"] for t in r["tests"]],
                       "achieved_sem": [t["achieved_sem"] for t in r["tests"]]}
                      for r in result.get("rounds", [])]}
    return clean(rec)


def _fmt(v, digits=4) -> str:
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.{digits}g}"
    return str(v)


def _pm(mean, sd) -> str:
    return f"{_fmt(mean)} +- {_fmt(sd, 2)}"


def write_material(result: dict, spec: Spec, path: Path) -> None:
    """``calibrated_material.toml``: a comment block with the record, the material and
    interaction blocks (paste them into a scene), then the record as the table
    ``[materials.<name>.calibration]``."""
    import tomli_w
    blocks = material_blocks(spec.tests[0].scene, spec.material, result["optimum"])
    lines = [f"# Calibrated material {spec.material!r}: {spec.title}",
             f"# {result['date']}; command: {result['command']}",
             f"# Sphere radius (as the base scenes give it): "
             f"{', '.join(map(str, result['sphere_radius'])) or 'see the scenes'} -- "
             "calibrated for this size only: another size is another material.",
             f"# Design: {result['design']['kind']}, {result['design']['design_points']} points x "
             f"{result['design']['seeds']} seeds; verified with {result['design']['verify_seeds']} "
             f"fresh seeds at the optimum; {len(result.get('rounds', [])) or 1} round(s) of at most "
             f"{result['design'].get('rounds', 1)}. Pass: |achieved mean - target| <= target sd.",
             "# Parameters (range -> calibrated value):"]
    for p in result["parameters"]:
        lines.append(f"#   {p['key']}: [{_fmt(p['range'][0])}, {_fmt(p['range'][1])}] -> {_fmt(p['value'])}")
    for f in result["factors"]:
        lines.append(f"#   {', '.join(f['keys'])}: one of {f['levels']} -> {f['value']!r}")
    lines.append("# Tests (target = measured mean +- sd; achieved = verification mean +- sd):")
    for t in result["tests"]:
        lines.append(f"#   {t['name']} ({t['scene']}): target {_pm(t['target'], t['target_sd'])} "
                     f"{t['unit']}, achieved {_pm(t['achieved_mean'], t['achieved_sd'])} {t['unit']} "
                     f"({len(t['achieved'])} runs, standard error {_fmt(t.get('achieved_sem', math.nan), 2)}) -> "
                     + ("within the measured scatter" if t["within_scatter"] else "NOT within the measured scatter")
                     + ("" if t["target_reachable"] else
                        f"; the target lies outside what the ranges reach "
                        f"({_fmt(t['reachable'][0])} - {_fmt(t['reachable'][1])} {t['unit']})"))
    if not result["within_scatter"]:
        lines.insert(1, "# NOT CALIBRATED: the verification runs miss a target by more than its measured "
                        "scatter (see the tests below and calibration.md).")
    for key in result.get("on_edge", []):
        lines.append(f"# The optimum lies on the edge of the range of {key}: the targets may need "
                     "values beyond it.")
    lines += ["#", "# Paste the [materials] and [[interactions]] blocks below into a scene (the partner",
              "# materials come from the scene). The record at the end is the value of a",
              f"# materials.{spec.material}.calibration key.", ""]
    body = tomli_w.dumps({"materials": blocks["materials"]}) + "\n"
    body += tomli_w.dumps({"interactions": blocks["interactions"]}) + "\n"
    rec = tomli_w.dumps({"materials": {spec.material: {"calibration": calibration_record(result, spec.tests[0].scene)}}})
    # tomli-w writes the record as [materials.ash.calibration] and its sub-tables; drop the
    # empty [materials] / [materials.ash] headers it may repeat
    rec_lines = [l for l in rec.splitlines() if l.strip() not in ("[materials]", f"[materials.{spec.material}]")]
    text = "\n".join(lines) + "\n" + body + "# ---- calibration record " + "-" * 60 + "\n" + \
        "\n".join(rec_lines) + "\n"
    tomllib.loads(text)          # it must read back
    path.write_text(text)


def write_report(result: dict, spec: Spec, path: Path, png: Optional[str]) -> None:
    """``calibration.md``: the tests, the design with its responses, the fits per level, the
    optimum and the verification."""
    keys = [p.key for p in spec.parameters]
    fkeys = [f.keys[0] for f in spec.factors]
    L = [f"# Calibration: {result['title']}", "", f"`{result['command']}`", "",
         f"{result['date']}. Material `{spec.material}`, spheres of radius "
         f"{', '.join(map(str, result['sphere_radius']))} (m, as the base scenes give it): the "
         "calibration holds for this size.", "", "## Bench tests", "",
         "| test | base scene | duration (s) | measured | target (mean +- sd) |", "|---|---|---|---|---|"]
    for t in result["tests"]:
        L.append(f"| {t['name']} | `{t['scene']}` | {_fmt(t['duration']) if t['duration'] else 'scene'} | "
                 f"{', '.join(_fmt(v) for v in t['measured']) or '-'} | "
                 f"{_pm(t['target'], t['target_sd'])} {t['unit']} |")
    L += ["", "## Parameters", "", "| key | range | calibrated |", "|---|---|---|"]
    for p in result["parameters"]:
        L.append(f"| `{p['key']}` | {_fmt(p['range'][0])} - {_fmt(p['range'][1])} | {_fmt(p['value'])} |")
    for f in result["factors"]:
        L.append(f"| `{'`, `'.join(f['keys'])}` | {', '.join(map(str, f['levels']))} | {f['value']} |")
    d = result["design"]
    L += ["", "## Design and responses", "",
          f"{d['kind'].replace('_', ' ')}"
          + (f" of {d['points']} points (seed {d['seed']})" if d["kind"] == "latin_hypercube" else
             f" at {' x '.join(map(str, d['levels'] or [])) or 1} levels")
          + (" per level of " + ", ".join(f['name'] for f in result["factors"]) if result["factors"] else "")
          + f"; {d['seeds']} placement seed(s) per point. Responses per seed. Later rounds add "
          "points (`source`): a failed verification joins the design with all its runs, and an "
          f"optimum on a range's edge brings {d.get('augment', 0)} new points near it (`edge`).", "",
          "| # | source | " + " | ".join(fkeys + keys) + " | " + " | ".join(
              f"{t['name']} ({t['unit']})" for t in result["tests"]) + " |",
          "|" + "---|" * (2 + len(fkeys) + len(keys) + len(result["tests"]))]
    for row in result["design_rows"]:
        o = row["overrides"]
        L.append(f"| {row['point']} | {row.get('source', 'design')} | "
                 + " | ".join(_fmt(o[k]) for k in fkeys + keys) + " | "
                 + " | ".join(", ".join(_fmt(v) for v in row[t["name"]]) for t in result["tests"]) + " |")
    L += ["", "## Response surfaces (of the round written)", "",
          "Weighted least squares in the parameters scaled to [-1, 1]: the runs at a point enter as "
          "their mean weighted by their number. The model (constant, linear or quadratic) is the one "
          "with the smallest leave-one-point-out prediction error (`LOO`; each candidate's in "
          "brackets), the simpler on a tie: no richer than the points support. R^2 and the residual "
          "standard deviation over the runs (in the response's unit; compare it with the "
          "seed-to-seed scatter) per level; `reach`: the lowest and highest value of the surface "
          "inside the ranges; chi2 = sum(((surface - target) / target_sd)^2) at that level's "
          "optimum; `predicted` +- the surface's standard error there.", "",
          "| level | test | model | runs (points) | R^2 | residual sd | LOO | reach | level's optimum | predicted | chi2 |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for lv in result["levels"]:
        for k, f in enumerate(lv["fits"]):
            cands = ", ".join(f"{m} {_fmt(v, 3)}" for m, v in f.get("candidates", {}).items())
            se = (lv.get("predicted_se") or [math.nan] * len(lv["fits"]))[k]
            L.append(f"| {', '.join(map(str, lv['level'])) or '-'} | {f['test']} | {f['model']} | "
                     f"{f['points']} ({f.get('distinct_points', '-')}) | "
                     f"{_fmt(f['r2'], 3)} | {_fmt(f['residual_sd'], 3)} | "
                     f"{_fmt(f.get('loo_rmse', math.nan), 3)}" + (f" ({cands})" if cands else "") + " | "
                     f"{_fmt(lv['reachable'][k][0])} - {_fmt(lv['reachable'][k][1])} | "
                     f"{_show_point(lv['optimum']) or '-'} | {_pm(lv['predicted'][k], se)} | {_fmt(lv['chi2'], 3)} |")
    if result.get("rounds"):
        L += ["", "## Rounds", "",
              "A sequential design: each round fits the surfaces to every run so far, verifies the "
              "optimum with fresh placements and stops when every test passes: "
              "|achieved mean - target| <= target sd. A round that fails adds its verification runs "
              "to the design (and points near an optimum on a range's edge) for the next. `SEM`: "
              "the standard error of the achieved mean (sd / sqrt(runs)).", "",
              "| round | optimum | on the edge of | test | model (LOO) | predicted | achieved (each run) | achieved mean +- sd (SEM) | distance from the target / target sd | passed |",
              "|---|---|---|---|---|---|---|---|---|---|"]
        targets = {t["name"]: t for t in result["tests"]}
        for r in result["rounds"]:
            for t in r["tests"]:
                tg = targets[t["name"]]
                L.append(f"| {r['round']} | {_show_point(r['optimum'])} | {', '.join(r['on_edge']) or '-'} | "
                         f"{t['name']} | {t['model']} ({_fmt(t['loo_rmse'], 3)}) | "
                         f"{_pm(t['predicted'], t['predicted_se'])} | "
                         f"{', '.join(_fmt(v) for v in t['achieved'])} | "
                         f"{_pm(t['achieved_mean'], t['achieved_sd'])} ({_fmt(t['achieved_sem'], 2)}) | "
                         f"{_fmt(abs(t['achieved_mean'] - tg['target']) / tg['target_sd'], 3)} | "
                         f"{'yes' if r['passed'] else 'no'} |")
    L += ["", "## Verification at the optimum", "",
          f"The optimum: {_show_point(result['optimum'])}. Fresh runs (placement seeds the design "
          "did not use):", "",
          "| test | target | predicted | achieved (each run) | achieved mean +- sd | SEM | within the measured scatter |",
          "|---|---|---|---|---|---|---|"]
    for t in result["tests"]:
        L.append(f"| {t['name']} | {_pm(t['target'], t['target_sd'])} {t['unit']} | {_fmt(t['predicted'])} | "
                 f"{', '.join(_fmt(v) for v in t['achieved'])} | {_pm(t['achieved_mean'], t['achieved_sd'])} | "
                 f"{_fmt(t.get('achieved_sem', math.nan), 2)} | {'yes' if t['within_scatter'] else 'NO'} |")
    L += ["", "Pass criterion: |achieved mean - target| <= target sd for every test (the achieved "
          "mean over the verification runs; its standard error, `SEM`, should lie below the target "
          "sd for the verdict to mean something)."]
    L.append("")
    L.append(("**Calibrated**: every verified value lies within the measured scatter of its target."
              if result["within_scatter"] else
              "**Not calibrated**: a verified value misses its target by more than the measured "
              "scatter."))
    L.append("")
    for key in result.get("on_edge", []):
        L.append(f"- The optimum lies on the edge of the range of `{key}`: the targets may need "
                 "values beyond it, and the surface is least certain there.")
    L.append("")
    if len(result.get("attempts", [])) > 1 and not result.get("rounds"):
        L += ["Levels that fit the targets equally well (chi2 within "
              f"{LEVEL_TIE:g} of the lowest) are verified in the spec's order until one meets "
              "every target within its scatter; every verified optimum:", "",
              "| optimum | " + " | ".join(f"{t['name']} achieved" for t in result["tests"])
              + " | chi2 of the achieved means | chosen |",
              "|---|" + "---|" * (len(result["tests"]) + 2)]
        for a in result["attempts"]:
            L.append(f"| {_show_point(a['optimum'])} | "
                     + " | ".join(_pm(t["achieved_mean"], t["achieved_sd"]) for t in a["tests"])
                     + f" | {_fmt(a['chi2'], 3)} | {'yes' if a['chosen'] else ''} |")
        L.append("")
    for t in result["tests"]:
        if not t["target_reachable"]:
            L.append(f"- **{t['name']}: the target {_fmt(t['target'])} {t['unit']} lies outside what the "
                     f"ranges reach at the chosen level ({_fmt(t['reachable'][0])} - "
                     f"{_fmt(t['reachable'][1])} {t['unit']}).**")
    for lv in result["levels"]:
        for k, t in enumerate(result["tests"]):
            lo, hi = lv["reachable"][k]
            if lv["level"] and math.isfinite(lo) and not lo - t["target_sd"] <= t["target"] <= hi + t["target_sd"]:
                L.append(f"- At {', '.join(map(str, lv['level']))}: {t['name']} reaches only "
                         f"{_fmt(lo)} - {_fmt(hi)} {t['unit']} inside the ranges; the target "
                         f"{_fmt(t['target'])} {t['unit']} is out of its reach.")
    c = result["cost"]
    L += ["", "## Cost", "",
          f"Design: {c['design']['finished']} of {c['design']['runs']} runs finished, "
          f"{c['design']['wall_s']:.0f} s of run wall time in all ({c['design']['cpu_s']:.0f} s stepping CPU); "
          f"verification: {c['verification']['finished']} of {c['verification']['runs']}, "
          f"{c['verification']['wall_s']:.0f} s ({c['verification']['cpu_s']:.0f} s CPU)."]
    if result["failed"]:
        L += ["", "Failed runs:", ""] + [f"- `{f['id']}`: {f['message']}" for f in result["failed"]]
    if png:
        L += ["", f"![The responses against {keys[0] if keys else 'the design'}]({png})"]
    path.write_text("\n".join(L) + "\n")


def write_plot(result: dict, spec: Spec, path: Path) -> bool:
    """PNG: each test's response against the main parameter (the first one), the design
    points per level, each level's surface through its optimum, the target band and the
    verification (mean +- sd). False when there is no continuous parameter to plot against."""
    if not spec.parameters:
        return False
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    p0 = spec.parameters[0]
    n = len(spec.tests)
    fig, axes = plt.subplots(1, n, figsize=(max(7.0, 5.2 * n), 5.0), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    grid = np.linspace(-1, 1, 101)
    for k, (ax, t) in enumerate(zip(axes[0], result["tests"])):
        ax.axhspan(t["target"] - t["target_sd"], t["target"] + t["target_sd"], color="0.85",
                   label=f"measured {_pm(t['target'], t['target_sd'])}")
        ax.axhline(t["target"], color="0.5", lw=0.8)
        for li, lv in enumerate(result["levels"]):
            c = colours[li % len(colours)]
            name = ", ".join(map(str, lv["level"])) or "design"
            xs, ys = [], []
            for row in result["design_rows"]:
                if tuple(row["overrides"][f.keys[0]] for f in spec.factors) == tuple(lv["level"]):
                    for v in row[t["name"]]:
                        xs.append(row["overrides"][p0.key])
                        ys.append(v)
            ax.plot(xs, ys, "o", color=c, label=f"{name}: runs")
            fit = lv["fits"][k]
            xopt = scale(spec, lv["optimum"])
            pts = np.tile(xopt, (len(grid), 1))
            pts[:, 0] = grid
            s = Surface(fit["model"], np.array(fit["coefficients"]), fit["r2"], fit["residual_sd"], fit["points"])
            ax.plot(p0.low + 0.5 * (grid + 1) * (p0.high - p0.low), s(pts), "-", color=c,
                    label=f"{name}: fit (R$^2$ {_fmt(fit['r2'], 2)})")
        level_names = [tuple(lv["level"]) for lv in result["levels"]]
        attempts = result.get("attempts") or [{"optimum": result["optimum"], "chosen": True,
                                               "tests": result["tests"]}]
        for ai, a in enumerate(attempts):
            at = a["tests"][k]
            lev = tuple(a["optimum"][f.keys[0]] for f in spec.factors)
            c = colours[level_names.index(lev) % len(colours)] if lev in level_names else "k"
            sd = at["achieved_sd"] if math.isfinite(at["achieved_sd"]) else 0.0
            ax.errorbar([a["optimum"][p0.key]], [at["achieved_mean"]], yerr=[sd], fmt="*", ms=13,
                        color=c, mec="k", capsize=4,
                        label=(f"round {ai + 1}, " if len(attempts) > 1 else "")
                        + f"{', '.join(map(str, lev)) or 'optimum'}: verified (mean +- sd)"
                              + (" - chosen" if a["chosen"] else ""))
        ax.set_xlabel(p0.key)
        ax.set_ylabel(f"{t['name']} ({t['unit']})")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    others = ", ".join(p.key for p in spec.parameters[1:])
    import textwrap
    fig.suptitle(textwrap.fill(f"{result['title']}" + (f" (the surfaces with {others} at each "
                                                       "level's optimum)" if others else ""),
                               width=int(15 * fig.get_figwidth())), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def write_outputs(result: dict, spec: Spec, out: Path) -> None:
    def default(o):
        if isinstance(o, (np.floating, np.integer)):
            return o.item()
        if isinstance(o, np.ndarray):
            return o.tolist()
        return str(o)
    (out / "calibration.json").write_text(json.dumps(result, indent=1, default=default))
    write_material(result, spec, out / "calibrated_material.toml")
    png = "calibration_response.png" if write_plot(result, spec, out / "calibration_response.png") else None
    write_report(result, spec, out / "calibration.md", png)
