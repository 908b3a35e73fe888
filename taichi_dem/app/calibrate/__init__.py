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
import math
import shlex
import sys
from pathlib import Path

from ...errors import SceneError
from .spec import (  # noqa: F401 (the package's names: tests and users)
    AUGMENT_WIDTH,
    BenchTest,
    DESIGNS,
    EDGE,
    Factor,
    KINDS,
    LEVEL_TIE,
    Parameter,
    REGULARISATION,
    Spec,
    _check_key,
    _err,
    _n_coefficients,
    _numbers,
    _table,
    load_spec)
from .design import (  # noqa: F401 (the package's names: tests and users)
    _culprit,
    _frames,
    _is_key_problem,
    _material_density,
    _moving,
    _plan,
    _round,
    design_points,
    design_seeds,
    level_of,
    response,
    verification_offset)
from .fit import (  # noqa: F401 (the package's names: tests and users)
    MODELS,
    Surface,
    _group,
    _minimise,
    _starts,
    _stats,
    _wls,
    choose_surface,
    design_matrix,
    fit_surface,
    loo_rmse,
    optimise,
    reachable,
    scale,
    unscale)
from .report import (  # noqa: F401 (the package's names: tests and users)
    _fmt,
    _interaction_key,
    _pm,
    _show_point,
    calibration_record,
    material_blocks,
    write_material,
    write_outputs,
    write_plot,
    write_report)
from .rounds import (  # noqa: F401 (the package's names: tests and users)
    _dedupe,
    _rel,
    _responses,
    _round_summary,
    _run_cost,
    _sphere_sizes,
    _sweep,
    assemble,
    augment_points,
    calibrate,
    candidates,
    fit_design,
    on_edge,
    optimum_of,
    passes,
    round_stride,
    verified_chi2)


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
