"""The design of experiments: its points, seeds and runs (sweep specs), and each bench test's
response read from a run's results file."""
from __future__ import annotations

import itertools
import math
import tomllib
from pathlib import Path
from typing import Optional

import numpy as np

from ...errors import SceneError
from .spec import BenchTest, Spec, _err


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
    from .. import sweep
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
    from ...scene.units import parse_quantity      # a quantity string such as "870 kg/m3"
    return float(parse_quantity(v, "density"))


def response(test: BenchTest, h5_path: str, material: str) -> float:
    """The bench test's measured quantity (its unit: ``KINDS``) from one run's results file;
    NaN when the run does not show it (e.g. a hopper that did not empty to 60 %)."""
    if test.kind == "discharge_rate":
        from ..outputs import key_outputs
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
            from ..analysis import heap_angle
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
            from ..analysis import drum_dynamic_angle
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
