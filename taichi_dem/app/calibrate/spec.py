"""The calibration spec (``taichi-dem calibrate SPEC.toml``): its tables read strictly, a bad
key a SceneError naming the spec file, the dotted key and the reason."""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from ...errors import SceneError


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


# ------------------------------------------------------------------------------ the fit
def _n_coefficients(d: int, model: str) -> int:
    return {"quadratic": 1 + 2 * d + d * (d - 1) // 2, "linear": 1 + d, "constant": 1}[model]
