"""The calibration itself: the design run on Dask, fitted, verified with fresh seeds, in
rounds (a sequential design), and its result assembled."""
from __future__ import annotations

import datetime as _dt
import itertools
import math
import sys
import tomllib
from pathlib import Path

import numpy as np

from ...errors import SceneError
from .spec import AUGMENT_WIDTH, EDGE, LEVEL_TIE, Spec
from .design import (_plan, _round, design_points, design_seeds, level_of, response,
                     verification_offset)
from .fit import _stats, choose_surface, optimise, reachable, scale, unscale
from .report import _show_point, write_outputs


def _responses(spec: Spec, planned, records, out: Path) -> dict:
    """{(test index, combo index): [response per seed]} from the finished runs."""
    res: dict = {}
    for (ti, ci, s), rec in zip(planned, records):
        val = math.nan
        if rec.get("status") == "done":
            try:
                val = response(spec.tests[ti], str(out / "runs" / s.id / "results.h5"), spec.material)
            except (OSError, KeyError, ValueError) as err:
                print(f"calibrate: cannot read {spec.tests[ti].name} from run {s.id}: {err}",
                      file=sys.stderr)
        res.setdefault((ti, ci), []).append(val)
    return res


def _dedupe(planned):
    seen, uniq = set(), []
    for _, _, s in planned:
        if s.id not in seen:
            seen.add(s.id)
            uniq.append(s)
    return uniq


def fit_design(spec: Spec, points: list[dict], design_resp: dict,
               failed: frozenset = frozenset()) -> tuple[list, dict, dict]:
    """The response surfaces and the optimum of each level of the categorical factors, from
    ``design_resp`` ({(test index, point index): [response per seed]}). Returns (per level:
    {level, fits, x (scaled optimum), chi2, reach, predicted}; the best level's entry; the
    optimum as overrides, continuous values rounded to 3 significant digits). The factors'
    levels are in order of preference: the first level whose chi2 lies within LEVEL_TIE of the
    lowest is taken, passing over the levels in ``failed`` (those whose verified optimum
    already missed a target: the preference is for ties, and a failed verification is evidence
    against the tie); when every tied level has failed, the lowest chi2 among them."""
    d = len(spec.parameters)
    prefer = np.array([2.0 * (p.prefer - p.low) / (p.high - p.low) - 1.0 for p in spec.parameters])
    per_level = []
    for lev in itertools.product(*(f.levels for f in spec.factors)):
        idx = [ci for ci, pt in enumerate(points) if level_of(pt, spec) == lev]
        fits = []
        for ti in range(len(spec.tests)):
            xs, ys = [], []
            for ci in idx:
                for v in design_resp.get((ti, ci), []):
                    xs.append(scale(spec, points[ci]))
                    ys.append(v)
            fits.append(choose_surface(np.array(xs).reshape(len(xs), d), np.array(ys)))
        if all(np.all(np.isfinite(s.coef)) for s in fits):
            xopt, chi2 = optimise(fits, [t.target for t in spec.tests],
                                  [t.target_sd for t in spec.tests], d, prefer)
            reach = [reachable(s, d) for s in fits]
            pred = [float(s(xopt.reshape(1, d))[0]) for s in fits]
            pred_se = [float(s.se(xopt.reshape(1, d))[0]) for s in fits]
        else:
            xopt, chi2 = np.zeros(d), math.inf
            reach, pred = [(math.nan, math.nan)] * len(fits), [math.nan] * len(fits)
            pred_se = [math.nan] * len(fits)
        per_level.append({"level": lev, "fits": fits, "x": xopt, "chi2": chi2, "reach": reach,
                          "predicted": pred, "predicted_se": pred_se})
    lowest = min(r["chi2"] for r in per_level)
    # levels within one unit of chi2 of the lowest fit the targets equally well (a target sd
    # apart at most): the first of them in the spec's order is taken
    tied = [r for r in per_level if r["chi2"] <= lowest + LEVEL_TIE]
    fresh = [r for r in tied if tuple(r["level"]) not in failed]
    best = fresh[0] if fresh else min(tied, key=lambda r: r["chi2"])
    if not math.isfinite(best["chi2"]):
        raise RuntimeError("no level of the design gave responses to fit (did every run fail? "
                           "see the runs' log.txt)")
    return per_level, best, optimum_of(spec, best)


def optimum_of(spec: Spec, level_entry: dict) -> dict:
    """A level's optimum as overrides: the factors' keys at the level, the continuous values
    rounded to 3 significant digits."""
    optimum = {k: lv for f, lv in zip(spec.factors, level_entry["level"]) for k in f.keys}
    optimum.update({k: _round(v, 3) for k, v in unscale(spec, level_entry["x"]).items()})
    return optimum


def candidates(per_level: list) -> list:
    """The levels that fit the targets equally well (chi2 within LEVEL_TIE of the lowest), in
    the spec's order: verified in turn until one meets every target within its scatter."""
    lowest = min(r["chi2"] for r in per_level)
    return [r for r in per_level if math.isfinite(r["chi2"]) and r["chi2"] <= lowest + LEVEL_TIE]


def verified_chi2(spec: Spec, vresp: dict) -> float:
    """sum(((achieved mean - target) / target_sd)^2) of a verification."""
    return float(sum(((_stats(vresp.get((ti, 0), []))[0] - t.target) / t.target_sd) ** 2
                     for ti, t in enumerate(spec.tests)))


def _sweep(specs, out: Path, state: dict, progress: bool, timeout) -> list[dict]:
    """sweep.run_sweep on the client in ``state`` (made on first need: a command started again
    with every run finished starts no cluster)."""
    from .. import sweep
    if state.get("client") is None and any(not (out / "runs" / s.id / "done.json").exists()
                                           for s in specs):
        state["client"] = sweep.make_client(state["scheduler"], state["workers"])
    return sweep.run_sweep(specs, str(out), state.get("client"), progress=progress, timeout=timeout)


def calibrate(spec: Spec, out_dir: str, *, scheduler=None, workers=None, threads=None,
              arch: str = "cpu", progress: bool = True, command: str = "") -> dict:
    """Run the design, fit, optimise, verify and write the outputs (module docstring); returns
    the result dict also written to ``calibration.json``."""
    from .. import sweep
    out = Path(out_dir)
    points = design_points(spec)
    nthreads = sweep.threads_per_run(workers, threads)
    planned = _plan(spec, points, spec.seeds, nthreads, arch)
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / "runs").mkdir(exist_ok=True)
    except OSError as e:
        raise SceneError("--out", str(out), f"cannot make the output directory: {e.strerror or e}") from None
    if progress:
        print(f"calibrate: {len(points)} design points x {len(spec.tests)} tests x {spec.seeds} "
              f"seeds = {len(planned)} runs ({len(_dedupe(planned))} distinct), then "
              f"{spec.verify_seeds} verification runs per test, in {out}", file=sys.stderr)
    state = {"client": None, "scheduler": scheduler, "workers": workers}
    offsets = design_seeds(spec, len(points))
    sources = ["design"] * len(points)
    base_offset, stride = verification_offset(spec, len(points)), round_stride(spec)
    rounds = []                 # per round: (per_level, best, optimum, vplanned, vrecords, vresp)
    vall_planned, vall_records = [], []
    try:
        recs = {r["id"]: r for r in _sweep(_dedupe(planned), out, state, progress, spec.timeout)}
        records = [recs[s.id] for _, _, s in planned]
        design_resp = _responses(spec, planned, records, out)
        for rnd in range(spec.rounds):
            failed = frozenset(tuple(r[1]["level"]) for r in rounds)   # every earlier round failed
            per_level, best, optimum = fit_design(spec, points, design_resp, failed)
            first = base_offset + stride * rnd
            vplanned = _plan(spec, [optimum], spec.verify_seeds, nthreads, arch,
                             offsets=[[first + k for k in range(spec.verify_seeds)]])
            if progress:
                print(f"calibrate: round {rnd + 1} of at most {spec.rounds}: the optimum "
                      f"{_show_point(optimum)} (predicted "
                      + ", ".join(f"{t.name} {p:.4g} +- {se:.2g} {t.unit}" for t, p, se in
                                  zip(spec.tests, best["predicted"], best["predicted_se"]))
                      + f"); verifying with {len(_dedupe(vplanned))} runs", file=sys.stderr)
            vrecs = {r["id"]: r for r in _sweep(_dedupe(vplanned), out, state, progress, spec.timeout)}
            vrecords = [vrecs[s.id] for _, _, s in vplanned]
            vresp = _responses(spec, vplanned, vrecords, out)
            vall_planned += vplanned
            vall_records += vrecords
            rounds.append((per_level, best, optimum, vplanned, vrecords, vresp))
            if passes(spec, vresp):
                break
            if rnd + 1 == spec.rounds:
                if progress:
                    print("calibrate: not within the measured scatter; no rounds left", file=sys.stderr)
                break
            # the verification joins the design (its runs weigh by their number in the fit)
            ci = len(points)
            points.append(dict(optimum))
            offsets.append([first + k for k in range(spec.verify_seeds)])
            sources.append(f"verification {rnd + 1}")
            for ti in range(len(spec.tests)):
                design_resp[(ti, ci)] = list(vresp.get((ti, 0), []))
            # an optimum on a range's edge: new points near it, inside the ranges
            extra = augment_points(spec, optimum, rnd) if on_edge(spec, optimum) else []
            if progress:
                print("calibrate: not within the measured scatter; the verification joins the "
                      "design" + (f", with {len(extra)} points near the optimum on the edge of "
                                  f"{', '.join(on_edge(spec, optimum))}" if extra else ""),
                      file=sys.stderr)
            if extra:
                eoff = [[first + spec.verify_seeds + j * spec.seeds + k for k in range(spec.seeds)]
                        for j in range(len(extra))]
                eplanned = _plan(spec, extra, spec.seeds, nthreads, arch, offsets=eoff)
                erecs = {r["id"]: r for r in _sweep(_dedupe(eplanned), out, state, progress, spec.timeout)}
                erecords = [erecs[s.id] for _, _, s in eplanned]
                eresp = _responses(spec, eplanned, erecords, out)
                for j, pt in enumerate(extra):
                    for ti in range(len(spec.tests)):
                        design_resp[(ti, len(points) + j)] = eresp.get((ti, j), [])
                planned += [(ti, len(points) + cj, r) for ti, cj, r in eplanned]
                records += erecords
                points += extra
                offsets += eoff
                sources += [f"edge {rnd + 1}"] * len(extra)
    finally:
        if state["client"] is not None:
            sweep.close_client(state["client"])
    # the first round within the scatter (the loop stopped there), else the closest one
    chosen = rounds[-1] if passes(spec, rounds[-1][5]) else min(
        rounds, key=lambda r: verified_chi2(spec, r[5]))
    per_level, best, optimum, vplanned, vrecords, vresp = chosen
    result = assemble(spec, points, planned, records, design_resp, per_level, best, optimum,
                      vplanned, vrecords, vresp, command, out,
                      attempts=[(r[2], r[5]) for r in rounds],
                      extra_records=[x for r in rounds if r is not chosen for x in r[4]],
                      rounds=[_round_summary(spec, i, r) for i, r in enumerate(rounds)],
                      sources=sources, seed_offsets=offsets)
    write_outputs(result, spec, out)
    return result


def passes(spec: Spec, vresp: dict) -> bool:
    """The pass criterion: every test's achieved mean (over the verification runs) within one
    target standard deviation of the target, |mean - target| <= target_sd."""
    return all(abs(_stats(vresp.get((ti, 0), []))[0] - t.target) <= t.target_sd
               for ti, t in enumerate(spec.tests))


def round_stride(spec: Spec) -> int:
    """Seed offsets per round: the verification's ``verify_seeds`` and the edge points'
    ``augment x seeds``, rounded up to a multiple of 100."""
    return 100 * math.ceil((spec.verify_seeds + spec.augment_points * spec.seeds + 1) / 100)


def on_edge(spec: Spec, point: dict) -> list:
    """The parameters whose value in ``point`` lies within 1 % of its range from an end."""
    return [p.key for p in spec.parameters
            if min(point[p.key] - p.low, p.high - point[p.key]) <= EDGE * (p.high - p.low)]


def augment_points(spec: Spec, optimum: dict, round_index: int) -> list[dict]:
    """``augment`` new design points near ``optimum`` at its level: a seeded Latin hypercube
    in a box of AUGMENT_WIDTH of each range (scaled width 2 x AUGMENT_WIDTH) centred on the
    optimum and shifted inside the ranges, so that an optimum on an edge gets points between
    it and the edge's neighbourhood, where a surface fitted to the first design extrapolates.
    Values rounded to 4 significant digits."""
    d, n = len(spec.parameters), spec.augment_points
    if d == 0 or n == 0:
        return []
    from scipy.stats import qmc
    x = scale(spec, optimum)
    h = AUGMENT_WIDTH
    lo = np.clip(x - h, -1.0, 1.0 - 2 * h)
    u = qmc.LatinHypercube(d=d, seed=spec.design_seed + 1000 * (round_index + 1)).random(n)
    level = {k: optimum[k] for f in spec.factors for k in f.keys}
    return [{**level, **{k: _round(v) for k, v in unscale(spec, lo + 2 * h * row).items()}}
            for row in u]


def _round_summary(spec: Spec, index: int, rnd) -> dict:
    per_level, best, optimum, vplanned, vrecords, vresp = rnd
    tests = []
    for ti, t in enumerate(spec.tests):
        v = vresp.get((ti, 0), [])
        mean, sd = _stats(v)
        n = int(np.sum(np.isfinite(v))) if len(v) else 0
        f = best["fits"][ti]
        tests.append({"name": t.name, "model": f.model, "loo_rmse": f.loo_rmse,
                      "candidates": dict(f.tried), "residual_sd": f.residual_sd,
                      "points": f.points, "runs": f.n,
                      "predicted": best["predicted"][ti], "predicted_se": best["predicted_se"][ti],
                      "achieved": v, "achieved_mean": mean, "achieved_sd": sd,
                      "achieved_sem": sd / math.sqrt(n) if n > 1 else math.nan,
                      "within_scatter": bool(abs(mean - t.target) <= t.target_sd)})
    return {"round": index + 1, "optimum": optimum, "level": list(best["level"]),
            "on_edge": on_edge(spec, optimum), "tests": tests, "passed": passes(spec, vresp),
            "chi2_verified": verified_chi2(spec, vresp)}


def _run_cost(records) -> dict:
    done = [r for r in records if r.get("status") == "done"]
    return {"runs": len(records), "finished": len(done),
            "wall_s": float(sum(r.get("wall_s", 0.0) for r in done)),
            "cpu_s": float(sum(r.get("cpu_s", 0.0) for r in done))}


def _sphere_sizes(spec: Spec) -> list:
    """The radii the base scenes give the calibrated material's particles, as written."""
    sizes = []
    for t in spec.tests:
        doc = tomllib.loads(Path(t.scene).read_text(encoding="utf-8-sig"))
        for p in doc.get("particles", []):
            if p.get("material") == spec.material and "radius" in p and p["radius"] not in sizes:
                sizes.append(p["radius"])
    return sizes


def assemble(spec, points, planned, records, design_resp, per_level, best, optimum, vplanned,
             vrecords, vresp, command, out, attempts=None, extra_records=(), rounds=None,
             sources=None, seed_offsets=None) -> dict:
    """The result: everything the outputs show (written as ``calibration.json``). ``planned``
    and ``vplanned``: (test index, point index, RunSpec) of the design and the verification;
    ``records`` / ``vrecords``: their sweep records; ``vresp``: {(test index, 0): [response]}.
    ``attempts``: every verified optimum as (overrides, vresp), the chosen one among them;
    ``extra_records``: the runs of the attempts not chosen (for the cost); ``rounds``: the
    sequential design's rounds (:func:`_round_summary`); ``sources``: per design point where it
    came from ("design", "verification N", "edge N"); ``seed_offsets``: its placement seeds'
    offsets from the scene's seed."""
    tests = []
    for ti, t in enumerate(spec.tests):
        achieved = vresp.get((ti, 0), [])
        mean, sd = _stats(achieved)
        n_ok = int(np.sum(np.isfinite(achieved))) if len(achieved) else 0
        fit = best["fits"][ti]
        lo, hi = best["reach"][ti]
        reach_ok = lo - t.target_sd <= t.target <= hi + t.target_sd
        tests.append({
            "name": t.name, "kind": t.kind, "unit": t.unit,
            "scene": _rel(t.scene), "duration": t.duration,
            "measured": list(t.measured), "target": t.target, "target_sd": t.target_sd,
            "predicted": best["predicted"][ti], "achieved": achieved, "achieved_mean": mean,
            "achieved_sd": sd, "achieved_sem": sd / math.sqrt(n_ok) if n_ok > 1 else math.nan,
            "predicted_se": best.get("predicted_se", [math.nan] * len(spec.tests))[ti],
            "within_scatter": bool(abs(mean - t.target) <= t.target_sd),
            "reachable": [lo, hi], "target_reachable": bool(reach_ok),
            "fit": {"model": fit.model, "points": fit.n, "r2": fit.r2, "residual_sd": fit.residual_sd,
                    "loo_rmse": fit.loo_rmse},
        })
    levels = []
    for r in per_level:
        levels.append({
            "level": list(r["level"]), "chi2": r["chi2"],
            "optimum": {k: _round(v, 3) for k, v in unscale(spec, r["x"]).items()},
            "fits": [{"test": t.name, "model": s.model, "points": s.n, "r2": s.r2,
                      "distinct_points": s.points, "residual_sd": s.residual_sd,
                      "loo_rmse": s.loo_rmse, "candidates": dict(s.tried), "pure_sd": s.pure_sd,
                      "coefficients": [float(c) for c in s.coef]}
                     for t, s in zip(spec.tests, r["fits"])],
            "reachable": [list(x) for x in r["reach"]], "predicted": r["predicted"],
            "predicted_se": r.get("predicted_se", [math.nan] * len(spec.tests))})
    design_rows = []
    for ci, pt in enumerate(points):
        row = {"point": ci, "overrides": pt,
               "source": sources[ci] if sources else "design"}
        if seed_offsets:
            row["seed_offsets"] = list(seed_offsets[ci])
        for ti, t in enumerate(spec.tests):
            row[t.name] = design_resp.get((ti, ci), [])
        design_rows.append(row)
    failed = [{"id": s.id, "message": r.get("message", "")} for (_, _, s), r in
              zip(list(planned) + list(vplanned), list(records) + list(vrecords))
              if r.get("status") != "done"]
    return {
        "title": spec.title, "material": spec.material, "spec": _rel(spec.path),
        "command": command, "date": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        "sphere_radius": _sphere_sizes(spec),
        "design": {"kind": spec.design, "points": spec.points if spec.design == "latin_hypercube" else None,
                   "levels": ([len(p.values) or spec.levels for p in spec.parameters]
                              if spec.design == "full_factorial" else None),
                   "seed": spec.design_seed, "seeds": spec.seeds, "verify_seeds": spec.verify_seeds,
                   "rounds": spec.rounds, "augment": spec.augment_points,
                   "design_points": len(points)},
        "parameters": [{"key": p.key, "range": [p.low, p.high], "value": optimum[p.key]}
                       for p in spec.parameters],
        "factors": [{"name": f.name, "keys": list(f.keys), "levels": list(f.levels),
                     "value": optimum[f.keys[0]]} for f in spec.factors],
        "optimum": optimum, "chi2": best["chi2"], "tests": tests, "levels": levels,
        "on_edge": on_edge(spec, optimum),
        "design_rows": design_rows,
        "verification": [{"id": s.id, "test": spec.tests[ti].name, "seed": s.seed,
                          "status": r.get("status")} for (ti, _, s), r in zip(vplanned, vrecords)],
        "within_scatter": all(t["within_scatter"] for t in tests),
        "cost": {"design": _run_cost(records),
                 "verification": _run_cost(list(vrecords) + list(extra_records))},
        "attempts": [{"optimum": o, "tests": [
            {"name": t.name, "achieved": r.get((ti, 0), []),
             "achieved_mean": _stats(r.get((ti, 0), []))[0],
             "achieved_sd": _stats(r.get((ti, 0), []))[1]} for ti, t in enumerate(spec.tests)],
            "chi2": verified_chi2(spec, r), "chosen": o == optimum}
            for o, r in (attempts or [(optimum, vresp)])],
        "rounds": rounds or [],
        "pass_criterion": "|achieved mean - target| <= target sd, for every test",
        "failed": failed, "out": str(out),
    }


def _rel(path: str) -> str:
    try:
        return str(Path(path).resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)
