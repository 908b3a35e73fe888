"""``taichi-dem calibrate SPEC.toml --out DIR``: contact parameters fitted to bench tests.

A calibration spec (its own small TOML format, validated strictly: a bad key exits 2 naming the
spec file, the dotted key and the reason) names the material, the bench tests users measure
with their measured values, the contact parameters to vary (dotted scene keys, as ``taichi-dem
sweep --set`` takes them) with their ranges, categorical factors (the rolling model) and the
design. The command

1. runs the design of experiments (every design point x bench test x placement seed) as sweep
   runs on Dask (:mod:`taichi_dem.app.sweep`: one fresh process per run, ``DIR/runs/<id>/``,
   finished runs are skipped when the command is started again, a LocalCluster unless
   ``--scheduler`` names one);
2. reads each bench test's response from each run's results file (:func:`response`);
3. fits one response surface per test and per level of the categorical factors (weighted
   least squares in the continuous parameters scaled to [-1, 1], repeated runs at a point
   entering as their mean weighted by their number; the model - constant, linear or quadratic
   - no richer than the points support: the one with the smallest leave-one-point-out
   prediction error, :func:`choose_surface`) and finds the parameters that minimise
   sum(((response - target) / target_sd)^2) inside the ranges (:func:`optimise`); a target
   the surface cannot reach inside the ranges is said so, with the reachable interval;
4. verifies the optimum with ``verify_seeds`` fresh runs (new placement seeds) and reports the
   achieved mean, its scatter and its standard error against the targets. The pass criterion:
   |achieved mean - target| <= target sd for every test (:func:`passes`). A sequential design:
   when the verification fails and ``rounds`` allows another round, its runs join the design,
   an optimum on a range's edge brings ``augment`` new points near it (:func:`augment_points`),
   the surfaces are refitted and the new optimum verified; the round that passes (else the one
   whose achieved means come closest, in chi2) is written;
5. writes ``DIR/calibrated_material.toml`` (the material and interaction blocks, ready to paste
   into a scene, with the calibration record as comments and as a machine-readable table),
   ``DIR/calibration.md`` (design, responses, fits, verification), ``DIR/calibration.json``
   and ``DIR/calibration_response.png``.

Bench tests (``kind``), each read from the last frame(s) of a run's results file:

==================  ======  ==================================================================
``angle_of_repose``  deg    the flank of a heap on z = 0 around ``centre`` (default [0, 0]),
                            fitted by :func:`taichi_dem.app.analysis.heap_angle`; particles
                            that never moved (a fixed rough base) are left out
``discharge_rate``   kg/s   a hopper: the outputs' ``particles/discharge_rate`` (1/s, while
                            15 - 60 % has left) times the mean particle mass
``bulk_density``     kg/m3  the mass of the spheres whose centres lie in the vertical cylinder
                            ``region = {radius, z_min, z_max, centre}`` over its volume
``dynamic_angle``    deg    a rotating drum's free surface (:func:`analysis.drum_dynamic_angle`)
                            averaged over the frames in the last ``window`` (default 0.5) of
                            the run; the axis is the first rotating body's unless given
==================  ======  ==================================================================
"""
from __future__ import annotations

import argparse
import datetime as _dt
import itertools
import json
import math
import shlex
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from ..errors import SceneError

KINDS = {"angle_of_repose": "deg", "discharge_rate": "kg/s", "bulk_density": "kg/m3",
         "dynamic_angle": "deg"}
DESIGNS = ("latin_hypercube", "full_factorial")
REGULARISATION = 1e-4      # weight of the pull towards `prefer` when many optima fit equally
LEVEL_TIE = 1.0            # chi2 within which levels count as equally good (the first wins)
EDGE = 0.01                # an optimum this close to a range's end (fraction of the range) is on its edge
AUGMENT_WIDTH = 0.25       # half-width (scaled units: 1/8 of the range) of the box of edge points


# ------------------------------------------------------------------------------ the spec
@dataclass
class Parameter:
    """A continuous parameter: a dotted scene key varied over [low, high]; ``prefer`` is the
    value chosen among equally good optima (default the middle of the range)."""
    key: str
    low: float
    high: float
    prefer: float
    values: tuple = ()          # full factorial: the levels (default ``levels`` evenly spaced)


@dataclass
class Factor:
    """A categorical factor: every key in ``keys`` is set to the same level."""
    name: str
    keys: tuple
    levels: tuple


@dataclass
class BenchTest:
    """A measured bench test: its base scene (absolute path), the simulated time per run (s;
    None: the scene's end_time), the measured values and their mean and standard deviation."""
    name: str
    kind: str
    scene: str
    duration: Optional[float]
    measured: tuple
    target: float
    target_sd: float
    options: dict = field(default_factory=dict)

    @property
    def unit(self) -> str:
        return KINDS[self.kind]


@dataclass
class Spec:
    path: str
    material: str
    title: str
    parameters: list
    factors: list
    tests: list
    design: str = "latin_hypercube"
    points: int = 8
    levels: int = 3
    design_seed: int = 1
    seeds: int = 1
    verify_seeds: int = 3
    timeout: Optional[float] = None
    rounds: int = 1
    augment: Optional[int] = None      # points added near an edge optimum (None: parameters + 1)

    @property
    def augment_points(self) -> int:
        return len(self.parameters) + 1 if self.augment is None else self.augment


def _err(spec: str, key: str, reason: str) -> SceneError:
    return SceneError(spec, key, reason)


def _table(doc, where: str, spec: str, allowed: dict, required=()) -> dict:
    """``doc`` checked as a table whose keys are in ``allowed`` ({key: type or tuple})."""
    if not isinstance(doc, dict):
        raise _err(spec, where, f"must be a table, got {type(doc).__name__}")
    for k in doc:
        if k not in allowed:
            raise _err(spec, f"{where}.{k}" if where else k,
                       f"unknown key (allowed here: {', '.join(sorted(allowed))})")
    for k in required:
        if k not in doc:
            raise _err(spec, f"{where}.{k}" if where else k, "is required")
    for k, v in doc.items():
        types = allowed[k]
        key = f"{where}.{k}" if where else k
        if types is float:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise _err(spec, key, f"must be a finite number, got {v!r}")
        elif types is int:
            if isinstance(v, bool) or not isinstance(v, int):
                raise _err(spec, key, f"must be an integer, got {v!r}")
        elif not isinstance(v, types):
            names = types.__name__ if isinstance(types, type) else " or ".join(t.__name__ for t in types)
            raise _err(spec, key, f"must be a {names}, got {v!r}")
    return doc


def _numbers(v, key: str, spec: str, n: Optional[int] = None) -> tuple:
    if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, (int, float))
                                      or not math.isfinite(x) for x in v):
        raise _err(spec, key, f"must be a list of finite numbers, got {v!r}")
    if n is not None and len(v) != n:
        raise _err(spec, key, f"must have {n} numbers, got {len(v)}")
    return tuple(float(x) for x in v)


def load_spec(path: str) -> Spec:
    """Read and validate a calibration spec; every problem is a SceneError naming the spec
    file, the dotted key and the reason. Base scenes resolve against the spec's directory."""
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as e:
        raise _err(path, "", f"cannot read the calibration spec: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise _err(path, "", f"not UTF-8 text: {e}") from None
    try:
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as e:
        raise _err(path, "", f"not valid TOML: {e}") from None
    _table(doc, "", path, {"calibration": dict, "design": dict, "parameters": list,
                           "factors": list, "tests": list}, required=("calibration", "tests"))
    cal = _table(doc["calibration"], "calibration", path, {"material": str, "title": str},
                 required=("material",))
    design = _table(doc.get("design", {}), "design", path,
                    {"kind": str, "points": int, "levels": int, "seed": int, "seeds": int,
                     "verify_seeds": int, "timeout": float, "rounds": int, "augment": int})
    kind = design.get("kind", "latin_hypercube")
    if kind not in DESIGNS:
        raise _err(path, "design.kind", f"must be one of {', '.join(DESIGNS)}, got {kind!r}")
    for k, lo in (("points", 1), ("levels", 2), ("seeds", 1), ("verify_seeds", 1), ("rounds", 1),
                  ("augment", 0)):
        if k in design and design[k] < lo:
            raise _err(path, f"design.{k}", f"must be >= {lo}, got {design[k]}")
    if "timeout" in design and design["timeout"] <= 0:
        raise _err(path, "design.timeout", f"must be > 0 s, got {design['timeout']}")

    params = []
    for i, p in enumerate(doc.get("parameters", [])):
        w = f"parameters.{i}"
        _table(p, w, path, {"key": str, "range": list, "prefer": float, "values": list},
               required=("key", "range"))
        lo, hi = _numbers(p["range"], f"{w}.range", path, 2)
        if not lo < hi:
            raise _err(path, f"{w}.range", f"the low end must be below the high end, got [{lo}, {hi}]")
        prefer = float(p.get("prefer", 0.5 * (lo + hi)))
        if not lo <= prefer <= hi:
            raise _err(path, f"{w}.prefer", f"{prefer} lies outside the range [{lo}, {hi}]")
        values = _numbers(p["values"], f"{w}.values", path) if "values" in p else ()
        if any(not lo <= v <= hi for v in values):
            raise _err(path, f"{w}.values", f"every value must lie in the range [{lo}, {hi}]")
        if "values" in p and len(values) < 2:
            raise _err(path, f"{w}.values", "give at least two values")
        _check_key(p["key"], f"{w}.key", path)
        params.append(Parameter(p["key"], lo, hi, prefer, values))
    factors = []
    for i, fc in enumerate(doc.get("factors", [])):
        w = f"factors.{i}"
        _table(fc, w, path, {"name": str, "keys": list, "levels": list}, required=("keys", "levels"))
        keys = fc["keys"]
        if not keys or any(not isinstance(k, str) for k in keys):
            raise _err(path, f"{w}.keys", "must be a non-empty list of dotted scene keys")
        for j, k in enumerate(keys):
            _check_key(k, f"{w}.keys.{j}", path)
        levels = fc["levels"]
        if len(levels) < 1 or any(isinstance(v, (list, dict)) for v in levels):
            raise _err(path, f"{w}.levels", "must be a non-empty list of values")
        if len(set(map(repr, levels))) != len(levels):
            raise _err(path, f"{w}.levels", "a level is given twice")
        factors.append(Factor(fc.get("name", keys[0]), tuple(keys), tuple(levels)))
    all_keys = [p.key for p in params] + [k for f in factors for k in f.keys]
    dup = next((k for k in all_keys if all_keys.count(k) > 1), None)
    if dup:
        raise _err(path, "parameters", f"the key {dup} is varied twice")

    tests = []
    names = set()
    base = Path(path).resolve().parent
    if not doc["tests"]:
        raise _err(path, "tests", "give at least one bench test")
    for i, t in enumerate(doc["tests"]):
        w = f"tests.{i}"
        _table(t, w, path, {"name": str, "kind": str, "scene": str, "duration": float,
                            "measured": list, "mean": float, "sd": float, "centre": list,
                            "region": dict, "axis_point": list, "axis_direction": list,
                            "window": float}, required=("kind", "scene"))
        if t["kind"] not in KINDS:
            raise _err(path, f"{w}.kind", f"must be one of {', '.join(KINDS)}, got {t['kind']!r}")
        name = t.get("name", t["kind"])
        if name in names:
            raise _err(path, f"{w}.name", f"two tests are called {name!r}")
        names.add(name)
        scene = (base / t["scene"]).resolve()
        if not scene.is_file():
            raise _err(path, f"{w}.scene", f"no such scene file: {scene}")
        if "duration" in t and t["duration"] <= 0:
            raise _err(path, f"{w}.duration", f"must be > 0 s, got {t['duration']}")
        measured = _numbers(t["measured"], f"{w}.measured", path) if "measured" in t else ()
        if measured and ("mean" in t or "sd" in t):
            raise _err(path, f"{w}.measured", "give either measured (the repeats) or mean and sd")
        if measured:
            if len(measured) < 2:
                raise _err(path, f"{w}.measured", "give at least two repeats (their scatter "
                                                  "weights the fit), or mean and sd")
            target, sd = float(np.mean(measured)), float(np.std(measured, ddof=1))
        elif "mean" in t and "sd" in t:
            target, sd = float(t["mean"]), float(t["sd"])
        else:
            raise _err(path, f"{w}.measured", "give the measured values (measured = [...]) or "
                                              "their mean and sd")
        if not sd > 0:
            raise _err(path, f"{w}.sd" if not measured else f"{w}.measured",
                       f"the standard deviation must be > 0, got {sd}")
        opts = {}
        if "centre" in t:
            opts["centre"] = _numbers(t["centre"], f"{w}.centre", path, 2)
        if "region" in t:
            r = _table(t["region"], f"{w}.region", path,
                       {"radius": float, "z_min": float, "z_max": float, "centre": list},
                       required=("radius", "z_min", "z_max"))
            if not r["radius"] > 0 or not r["z_min"] < r["z_max"]:
                raise _err(path, f"{w}.region", "needs radius > 0 and z_min < z_max")
            opts["region"] = {"radius": float(r["radius"]), "z_min": float(r["z_min"]),
                              "z_max": float(r["z_max"]),
                              "centre": _numbers(r.get("centre", [0, 0]), f"{w}.region.centre", path, 2)}
        elif t["kind"] == "bulk_density":
            raise _err(path, f"{w}.region", "a bulk density needs its region "
                                            "{radius, z_min, z_max} (m)")
        for k in ("axis_point", "axis_direction"):
            if k in t:
                opts[k] = _numbers(t[k], f"{w}.{k}", path, 3)
        if "window" in t:
            if not 0 < t["window"] <= 1:
                raise _err(path, f"{w}.window", f"must be in (0, 1], got {t['window']}")
            opts["window"] = float(t["window"])
        tests.append(BenchTest(name, t["kind"], str(scene), t.get("duration"), measured, target,
                               sd, opts))
    n_par = len(params)
    points = design.get("points", 8)
    if kind == "latin_hypercube" and n_par and points < _n_coefficients(n_par, "linear") + 1:
        raise _err(path, "design.points", f"{points} points cannot fit even a linear surface in "
                                          f"{n_par} parameters: give at least {n_par + 2}")
    return Spec(path=str(path), material=cal["material"], title=cal.get("title", Path(path).stem),
                parameters=params, factors=factors, tests=tests, design=kind, points=points,
                levels=design.get("levels", 3), design_seed=design.get("seed", 1),
                seeds=design.get("seeds", 1), verify_seeds=design.get("verify_seeds", 3),
                timeout=design.get("timeout"), rounds=design.get("rounds", 1),
                augment=design.get("augment"))


def _check_key(key: str, where: str, spec: str) -> None:
    if not key or any(not part for part in key.split(".")):
        raise _err(spec, where, f"not a dotted scene key: {key!r}")


# ------------------------------------------------------------------------------ the design
def _round(v: float, digits: int = 4) -> float:
    return float(f"{v:.{digits}g}")


def design_points(spec: Spec) -> list[dict]:
    """The design: a list of {key: value} override dicts, the continuous points (seeded Latin
    hypercube of ``points`` or the full factorial) crossed with every level combination of
    the categorical factors. Values are rounded to 4 significant digits."""
    params = spec.parameters
    if not params:
        cont = [{}]
    elif spec.design == "full_factorial":
        axes = [p.values or tuple(np.linspace(p.low, p.high, spec.levels)) for p in params]
        cont = [{p.key: _round(v) for p, v in zip(params, row)} for row in itertools.product(*axes)]
    else:
        from scipy.stats import qmc
        u = qmc.LatinHypercube(d=len(params), seed=spec.design_seed).random(spec.points)
        cont = [{p.key: _round(p.low + x * (p.high - p.low)) for p, x in zip(params, row)} for row in u]
    out = []
    for combo in itertools.product(*(f.levels for f in spec.factors)):
        lev = {k: v for f, v in zip(spec.factors, combo) for k in f.keys}
        out += [{**lev, **c} for c in cont]
    return out


def level_of(point: dict, spec: Spec) -> tuple:
    """The categorical level combination of a design point (one value per factor)."""
    return tuple(point[f.keys[0]] for f in spec.factors)


def design_seeds(spec: Spec, n_points: int) -> list[list[int]]:
    """The placement seeds (offsets from the scene's seed) of each design point: ``seeds`` per
    point, different from one continuous point to the next (a seed shared by every point would
    shift the whole surface by that one placement's offset; measured on the fly-ash heap: 1.2
    - 2.6 deg), the same for a continuous point at every level of the factors (the levels compared
    on the same placements)."""
    n_levels = max(1, math.prod(len(f.levels) for f in spec.factors))
    n_cont = max(1, n_points // n_levels)
    return [[(ci % n_cont) * spec.seeds + k for k in range(spec.seeds)] for ci in range(n_points)]


def verification_offset(spec: Spec, n_points: int) -> int:
    """The first verification seed's offset from the scene's seed: past every design seed, a
    multiple of 100."""
    used = max((max(s) for s in design_seeds(spec, n_points)), default=0) + 1
    return 100 * math.ceil(max(used, 1) / 100)


def _plan(spec: Spec, combos: list[dict], seeds: int, threads: int, arch: str,
          seed_offset: int = 0, offsets: Optional[list] = None) -> list:
    """(test index, combo index, RunSpec) for every test x combo x seed: the design's seeds
    (:func:`design_seeds`) or, with ``seed_offset`` > 0, the scene's seed + offset + k for
    k < ``seeds`` (fresh placements for the verification), or ``offsets`` (per combo, the
    seeds' offsets from the scene's seed) when given."""
    from . import sweep
    out = []
    if offsets is None:
        offsets = (design_seeds(spec, len(combos)) if not seed_offset else
                   [[seed_offset + k for k in range(seeds)] for _ in combos])
    for ti, test in enumerate(spec.tests):
        try:
            base_seed = sweep.scene_seed(tomllib.loads(Path(test.scene).read_text(encoding="utf-8-sig")))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, RecursionError) as err:
            raise _err(spec.path, f"tests.{ti}.scene", f"cannot read the base scene "
                                                      f"{test.scene}: {err}") from None
        for ci, combo in enumerate(combos):
            try:
                # the scene's own seed is left implicit (the run is the plain sweep's run)
                runs = sweep.plan(test.scene, [{**combo, "simulation.seed": base_seed + k} if k else combo
                                               for k in offsets[ci]], 1, duration=test.duration,
                                  threads=threads, arch=arch)
            except SceneError as err:
                raise _err(spec.path, _culprit(spec, err, ti),
                           f"the design does not give a valid scene in tests.{ti}'s base scene: "
                           f"{err}") from None
            except tomllib.TOMLDecodeError as err:
                raise _err(spec.path, f"tests.{ti}.scene", f"not valid TOML: {err}") from None
            for r in runs:
                r.labels = {"test": test.name}
                out.append((ti, ci, r))
    return out


def _culprit(spec: Spec, err: SceneError, test_index: int) -> str:
    """The spec key a scene's SceneError comes from: a parameter's or factor's key (the scene
    format does not know it, or the index is past the end), its range or its levels (a value
    the loader refuses); else the test."""
    for i, p in enumerate(spec.parameters):
        if f"--set {p.key}=" in err.reason or err.key == p.key:
            return f"parameters.{i}.key" if _is_key_problem(err) else f"parameters.{i}.range"
    for i, f in enumerate(spec.factors):
        for j, k in enumerate(f.keys):
            if f"--set {k}=" in err.reason or err.key == k:
                return f"factors.{i}.keys.{j}" if _is_key_problem(err) else f"factors.{i}.levels"
    return f"tests.{test_index}"


def _is_key_problem(err: SceneError) -> bool:
    return any(w in err.reason for w in ("unknown key", "past the end", "index it", "not a table"))


# ------------------------------------------------------------------------------ responses
def _frames(h5_path: str):
    import h5py
    f = h5py.File(h5_path, "r")
    keys = sorted(f["frames"], key=int) if "frames" in f else []
    return f, keys


def _moving(first, last) -> np.ndarray:
    """Mask over the last frame's particles: those that moved since the first frame (a fixed
    rough base never does)."""
    ids0, pos0 = first["id"][()], first["position"][()]
    ids1, pos1 = last["id"][()], last["position"][()]
    where = {int(i): k for k, i in enumerate(ids0)}
    idx = np.array([where.get(int(i), -1) for i in ids1])
    still = np.zeros(len(ids1), bool)
    ok = idx >= 0
    still[ok] = np.all(pos1[ok] == pos0[idx[ok]], axis=1)
    return ~still


def _material_density(doc: dict, name: str) -> float:
    v = doc.get("materials", {}).get(name, {}).get("density")
    if isinstance(v, (int, float)):
        return float(v)
    from ..scene.units import parse_quantity      # a quantity string such as "870 kg/m3"
    return float(parse_quantity(v, "density"))


def response(test: BenchTest, h5_path: str, material: str) -> float:
    """The bench test's measured quantity (its unit: ``KINDS``) from one run's results file;
    NaN when the run does not show it (e.g. a hopper that did not empty to 60 %)."""
    if test.kind == "discharge_rate":
        from .outputs import key_outputs
        rate = key_outputs(h5_path).get("particles/discharge_rate", math.nan)
        f, keys = _frames(h5_path)
        with f:
            doc = tomllib.loads(str(f.attrs.get("scene", "")))
            r = f["frames"][keys[0]]["radius"][()]
        mass = float(np.mean(4.0 / 3.0 * math.pi * r ** 3)) * _material_density(doc, material)
        return rate * mass
    f, keys = _frames(h5_path)
    with f:
        if not keys:
            return math.nan
        doc = tomllib.loads(str(f.attrs.get("scene", "")))
        first, last = f["frames"][keys[0]], f["frames"][keys[-1]]
        if test.kind == "angle_of_repose":
            from .analysis import heap_angle
            m = _moving(first, last)
            p = {"position": last["position"][()][m], "radius": last["radius"][()][m]}
            if len(p["radius"]) < 10:
                return math.nan
            return heap_angle(p, centre=test.options.get("centre", (0.0, 0.0)))[0]
        if test.kind == "bulk_density":
            reg = test.options["region"]
            x = last["position"][()]
            r = last["radius"][()]
            c = reg["centre"]
            sel = ((np.hypot(x[:, 0] - c[0], x[:, 1] - c[1]) < reg["radius"])
                   & (x[:, 2] > reg["z_min"]) & (x[:, 2] < reg["z_max"]))
            vol = math.pi * reg["radius"] ** 2 * (reg["z_max"] - reg["z_min"])
            return float(np.sum(4.0 / 3.0 * math.pi * r[sel] ** 3)) / vol * _material_density(doc, material)
        if test.kind == "dynamic_angle":
            from .analysis import drum_dynamic_angle
            point, direction = test.options.get("axis_point"), test.options.get("axis_direction")
            if point is None or direction is None:
                rot = next((b["motion"]["rotate"] for b in doc.get("bodies", [])
                            if isinstance(b.get("motion"), dict) and "rotate" in b["motion"]), None)
                if rot is None:
                    return math.nan
                point = point or rot.get("axis_point", [0, 0, 0])
                direction = direction or rot.get("axis_direction", [1, 0, 0])
            window = test.options.get("window", 0.5)
            use = keys[-max(1, int(round(len(keys) * window))):]
            angles = [drum_dynamic_angle(f["frames"][k]["position"][()], f["frames"][k]["radius"][()],
                                         point, direction) for k in use]
            return float(np.nanmean(angles)) if angles else math.nan
    raise ValueError(test.kind)


# ------------------------------------------------------------------------------ the fit
def _n_coefficients(d: int, model: str) -> int:
    return {"quadratic": 1 + 2 * d + d * (d - 1) // 2, "linear": 1 + d, "constant": 1}[model]


def design_matrix(x: np.ndarray, model: str) -> np.ndarray:
    """Columns of the response surface at scaled points ``x`` (n, d): 1, x_i, and for
    ``quadratic`` also x_i^2 and x_i x_j (i < j)."""
    x = np.atleast_2d(np.asarray(x, float))
    n, d = x.shape
    cols = [np.ones(n)]
    if model in ("linear", "quadratic"):
        cols += [x[:, i] for i in range(d)]
    if model == "quadratic":
        cols += [x[:, i] ** 2 for i in range(d)]
        cols += [x[:, i] * x[:, j] for i in range(d) for j in range(i + 1, d)]
    return np.column_stack(cols)


MODELS = ("constant", "linear", "quadratic")   # from the simplest: ties go to the simpler


@dataclass
class Surface:
    """A least-squares response surface in scaled parameters (each range mapped to [-1, 1]).
    ``r2``: coefficient of determination; ``residual_sd``: sqrt(SS_res / (n - p)) over the
    individual runs, in the response's unit (NaN with no residual degrees of freedom); ``n``:
    runs; ``points``: distinct points; ``loo_rmse``: the leave-one-point-out prediction error
    (weighted by each point's runs; NaN when not computed); ``pure_sd``: the run-to-run scatter
    at repeated points (NaN without repeats); ``cov``: the coefficients' covariance (None
    without residual degrees of freedom)."""
    model: str
    coef: np.ndarray
    r2: float
    residual_sd: float
    n: int
    points: int = 0
    loo_rmse: float = math.nan
    pure_sd: float = math.nan
    cov: Optional[np.ndarray] = None
    tried: dict = field(default_factory=dict)     # {model: leave-one-out rmse} of the candidates

    def __call__(self, x) -> np.ndarray:
        return design_matrix(x, self.model) @ self.coef

    def se(self, x) -> np.ndarray:
        """The standard error of the surface's value at scaled points ``x`` (the response's
        unit): sqrt(a^T cov a); NaN without a covariance."""
        a = design_matrix(x, self.model)
        if self.cov is None:
            return np.full(len(a), math.nan)
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", a, self.cov, a), 0.0))


def _group(x: np.ndarray, y: np.ndarray):
    """Repeated runs at one point pooled: (distinct points (m, d), mean response, runs per
    point, pure-error sum of squares, its degrees of freedom). NaN responses left out."""
    ok = np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(y) == 0:
        return x, y, np.zeros(0), 0.0, 0
    keys = [tuple(np.round(r, 9)) for r in x]
    order = {}
    for k in keys:
        order.setdefault(k, len(order))
    idx = np.array([order[k] for k in keys])
    m = len(order)
    w = np.bincount(idx, minlength=m).astype(float)
    ybar = np.bincount(idx, weights=y, minlength=m) / w
    xs = np.zeros((m, x.shape[1]))
    xs[idx] = x
    ss_pure = float(np.sum((y - ybar[idx]) ** 2))
    return xs, ybar, w, ss_pure, int(len(y) - m)


def _wls(xs, ybar, w, model):
    a = design_matrix(xs, model)
    sw = np.sqrt(w)
    coef, *_ = np.linalg.lstsq(a * sw[:, None], ybar * sw, rcond=None)
    return a, coef


def loo_rmse(xs: np.ndarray, ybar: np.ndarray, w: np.ndarray, model: str) -> float:
    """Leave-one-point-out prediction error of ``model``: each distinct point (with all its
    runs) left out in turn, the weighted surface refitted on the others and its error there;
    the root of the mean squared error weighted by the points' runs. NaN when the others cannot
    determine the model (fewer points than coefficients + 1)."""
    m, d = xs.shape
    p = _n_coefficients(d, model)
    if m < p + 1:
        return math.nan
    err = np.empty(m)
    for i in range(m):          # m is a design's size (tens): a refit per point is cheap
        keep = np.arange(m) != i
        a, coef = _wls(xs[keep], ybar[keep], w[keep], model)
        if np.linalg.matrix_rank(a) < p:
            return math.nan
        err[i] = ybar[i] - float((design_matrix(xs[i:i + 1], model) @ coef)[0])
    return float(math.sqrt(np.sum(w * err ** 2) / np.sum(w)))


def fit_surface(x: np.ndarray, y: np.ndarray, model: Optional[str] = None) -> Surface:
    """Weighted least squares of the responses ``y`` at scaled points ``x`` (n, d): repeated
    runs at a point enter as their mean weighted by their number (the same coefficients as
    every run on its own). ``model``: "constant", "linear" or "quadratic"; None: the richest
    the points allow (quadratic when the distinct points leave it residual degrees of freedom,
    else linear when they determine it, else the mean). NaN responses are left out."""
    x = np.atleast_2d(np.asarray(x, float)).reshape(len(y), -1)
    y = np.asarray(y, float)
    d = x.shape[1]
    xs, ybar, w, ss_pure, df_pure = _group(x, y)
    m, n = len(ybar), int(np.sum(w))
    if m == 0:
        return Surface("constant", np.array([math.nan]), math.nan, math.nan, 0)
    if model is None:
        if d > 0 and m > _n_coefficients(d, "quadratic"):
            model = "quadratic"
        elif d > 0 and m >= _n_coefficients(d, "linear"):
            model = "linear"
        else:
            model = "constant"
    a, coef = _wls(xs, ybar, w, model)
    p = a.shape[1]
    ss_lack = float(np.sum(w * (ybar - a @ coef) ** 2))
    ss_res = ss_lack + ss_pure                       # over the individual runs
    ymean = float(np.sum(w * ybar) / n)
    ss_tot = float(np.sum(w * (ybar - ymean) ** 2)) + ss_pure
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else math.nan
    sd = math.sqrt(ss_res / (n - p)) if n > p else math.nan
    cov = None
    if n > p and np.linalg.matrix_rank(a) == p:
        cov = sd ** 2 * np.linalg.pinv(a.T @ (a * w[:, None]))
    pure = math.sqrt(ss_pure / df_pure) if df_pure > 0 else math.nan
    return Surface(model, coef, r2, sd, n, m, loo_rmse(xs, ybar, w, model), pure, cov)


def choose_surface(x: np.ndarray, y: np.ndarray) -> Surface:
    """The surface no richer than the points support: among constant, linear and quadratic
    (each fitted by :func:`fit_surface`), the one with the smallest leave-one-point-out
    prediction error (:func:`loo_rmse`), the simpler on a tie; a model the points cannot
    cross-validate (fewer distinct points than its coefficients + 1) is not a candidate.
    With too few points for any cross-validation, the richest model they allow."""
    x = np.atleast_2d(np.asarray(x, float)).reshape(len(y), -1)
    d = x.shape[1]
    fits = {m: fit_surface(x, y, m) for m in (MODELS if d > 0 else ("constant",))}
    scored = {m: s.loo_rmse for m, s in fits.items() if math.isfinite(s.loo_rmse)}
    if not scored:
        return fit_surface(x, y)
    best = min(scored, key=lambda m: (round(scored[m], 12), MODELS.index(m)))
    out = fits[best]
    out.tried = scored
    return out


def _starts(d: int, rng_seed: int = 0) -> np.ndarray:
    if d == 0:
        return np.zeros((1, 0))
    if d <= 3:
        g = np.linspace(-1, 1, 5)
        return np.array(list(itertools.product(*([g] * d))))
    return np.random.default_rng(rng_seed).uniform(-1, 1, (60, d))


def _minimise(fun, d: int) -> tuple[np.ndarray, float]:
    from scipy.optimize import minimize
    if d == 0:
        x = np.zeros(0)
        return x, float(fun(x))
    best = (None, math.inf)
    for s in _starts(d):
        r = minimize(fun, s, method="L-BFGS-B", bounds=[(-1.0, 1.0)] * d)
        if r.fun < best[1]:
            best = (np.clip(r.x, -1, 1), float(r.fun))
    return best


def optimise(surfaces: list[Surface], targets: list[float], sds: list[float], d: int,
             prefer: Optional[np.ndarray] = None) -> tuple[np.ndarray, float]:
    """The scaled point in [-1, 1]^d minimising sum(((surface - target) / sd)^2), and that sum.
    Among points that fit equally (more parameters than tests) the one nearest ``prefer``
    (scaled) is taken: a pull of weight REGULARISATION per unit squared distance."""
    prefer = np.zeros(d) if prefer is None else np.asarray(prefer, float)

    def chi2(x):
        x = np.asarray(x, float).reshape(1, d)
        return float(sum(((s(x)[0] - t) / sd) ** 2 for s, t, sd in zip(surfaces, targets, sds)))

    x, _ = _minimise(lambda x: chi2(x) + REGULARISATION * float(np.sum((x - prefer) ** 2)), d)
    return x, chi2(x)


def reachable(surface: Surface, d: int) -> tuple[float, float]:
    """(lowest, highest) value of ``surface`` inside [-1, 1]^d."""
    lo = _minimise(lambda x: float(surface(np.reshape(x, (1, d)))[0]), d)[1]
    hi = -_minimise(lambda x: -float(surface(np.reshape(x, (1, d)))[0]), d)[1]
    return lo, hi


def scale(spec: Spec, point: dict) -> np.ndarray:
    """A design point's continuous parameters mapped to [-1, 1]."""
    return np.array([2.0 * (point[p.key] - p.low) / (p.high - p.low) - 1.0 for p in spec.parameters])


def unscale(spec: Spec, x: np.ndarray) -> dict:
    return {p.key: p.low + 0.5 * (xi + 1.0) * (p.high - p.low) for p, xi in zip(spec.parameters, x)}


# ------------------------------------------------------------------------------ running
def _stats(values) -> tuple[float, float]:
    v = np.asarray([x for x in values if np.isfinite(x)], float)
    if len(v) == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if len(v) > 1 else math.nan


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
    from . import sweep
    if state.get("client") is None and any(not (out / "runs" / s.id / "done.json").exists()
                                           for s in specs):
        state["client"] = sweep.make_client(state["scheduler"], state["workers"])
    return sweep.run_sweep(specs, str(out), state.get("client"), progress=progress, timeout=timeout)


def calibrate(spec: Spec, out_dir: str, *, scheduler=None, workers=None, threads=None,
              arch: str = "cpu", progress: bool = True, command: str = "") -> dict:
    """Run the design, fit, optimise, verify and write the outputs (module docstring); returns
    the result dict also written to ``calibration.json``."""
    from . import sweep
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


def _show_point(point: dict) -> str:
    return ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                     for k, v in point.items())


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


# ------------------------------------------------------------------------------ outputs
def material_blocks(scene_path: str, material: str, optimum: dict) -> dict:
    """{"materials": {material: {...}}, "interactions": [...]} of the base scene with the
    optimum's overrides applied: the calibrated material and every interaction it takes part
    in."""
    from . import overrides as ov
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


# ------------------------------------------------------------------------------ CLI
def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("spec", help="the calibration spec (TOML): material, bench tests with their "
                                "measured values, parameters and ranges, design")
    p.add_argument("--out", default="calibration", help="directory for the runs and the results "
                                                        "(default calibration)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="an existing Dask scheduler "
                                                                  "(default: a LocalCluster here)")
    p.add_argument("--workers", type=int, metavar="N", help="LocalCluster workers (default: cores)")
    p.add_argument("--threads", type=int, metavar="N", help="CPU threads per run (default cores / workers)")
    p.add_argument("--arch", default="cpu", choices=["cpu", "gpu", "cuda", "vulkan", "metal"],
                   help="where each run's kernels run (default cpu)")
    p.add_argument("--quiet", action="store_true", help="no progress output")


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``calibrate`` subcommand to an argparse ``subparsers``; returns its parser."""
    p = subparsers.add_parser("calibrate", help="fit contact parameters to measured bench tests "
                                                "(angle of repose, discharge rate, bulk density, "
                                                "dynamic angle) by a design of experiments on Dask")
    add_arguments(p)
    return p


def run(args) -> int:
    """The command: 0 when calibrated (even when a target is out of reach: the report says so),
    1 when the runs gave nothing to fit, 2 on bad input (one paragraph: file, key, reason)."""
    try:
        if args.workers is not None and args.workers < 1:
            raise SceneError("--workers", "", f"must be >= 1, got {args.workers}")
        spec = load_spec(args.spec)
        argv = sys.argv[1:]
        command = ("taichi-dem calibrate " + " ".join(map(shlex.quote, argv[1:]))
                   if argv[:1] == ["calibrate"] else
                   "taichi-dem calibrate " + " ".join(map(shlex.quote, [args.spec, "--out", args.out]
                                                     + (["--workers", str(args.workers)] if args.workers else []))))
        result = calibrate(spec, args.out, scheduler=args.scheduler, workers=args.workers,
                           threads=args.threads, arch=args.arch, progress=not args.quiet,
                           command=command)
    except SceneError as err:
        print(f"taichi-dem: {err}", file=sys.stderr)
        return 2
    except RuntimeError as err:
        print(f"taichi-dem: calibrate: {err}", file=sys.stderr)
        return 1
    for t in result["tests"]:
        print(f"{t['name']}: target {_pm(t['target'], t['target_sd'])} {t['unit']}, achieved "
              f"{_pm(t['achieved_mean'], t['achieved_sd'])} ({len(t['achieved'])} runs, standard error "
              f"{_fmt(t.get('achieved_sem', math.nan), 2)}): "
              + ("within the measured scatter" if t["within_scatter"] else "NOT within the measured scatter")
              + ("" if t["target_reachable"] else " (the target is out of the ranges' reach)"))
    if result.get("rounds"):
        print(f"rounds: {len(result['rounds'])} of at most {result['design']['rounds']}; pass criterion: "
              f"{result['pass_criterion']}")
    print(f"{'calibrated' if result['within_scatter'] else 'NOT calibrated; the closest verified'}: "
          f"{_show_point(result['optimum'])}")
    print(f"results: {Path(args.out) / 'calibrated_material.toml'}, {Path(args.out) / 'calibration.md'}")
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m taichi_dem.app.calibrate",
                                description=add_parser.__doc__)
    add_arguments(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
