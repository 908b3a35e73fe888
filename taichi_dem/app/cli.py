"""taichi-dem: discrete element simulations of drums, dryers and coolers, with heat transfer.

Exit status: 0 success; 2 bad input (one paragraph naming file, key and reason, never a
traceback); 3 the simulation diverged; ``sweep``: 1 when some of its runs failed (the table
lists them with their messages).
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from ..errors import BackendError, CheckpointError, DivergenceError, SceneError, WindowError
from ..run import interrupt

def _fail(message: str, code: int = 2) -> int:
    print(f"taichi-dem: {message}", file=sys.stderr)
    return code


def _common_outputs(p: argparse.ArgumentParser):
    p.add_argument("--until", type=float, help="simulated time to stop at, s (default end_time)")
    p.add_argument("--out", help="directory for results, the checkpoint and the recording "
                                 "(default: the scene's [output] paths, in the scene file's "
                                 "folder); ~ is expanded")
    p.add_argument("--h5", help="HDF5 results file, anywhere (a path in the scene stays in its "
                                "folder); an existing file not of taichi_dem is never overwritten")
    p.add_argument("--rrd", help="rerun recording file (headless), anywhere")
    p.add_argument("--spawn", action="store_true", help="stream to a rerun viewer")
    p.add_argument("--every-nth", type=int, default=1, metavar="N",
                   help="rerun: draw every Nth particle only (default 1: all)")
    p.add_argument("--arch", default="cpu", choices=["cpu", "gpu", "cuda", "vulkan", "metal"],
                   help="where the kernels run: cpu, or a GPU backend (gpu picks one; default cpu)")
    p.add_argument("--precision", choices=["f32", "f64"],
                   help="floating-point precision of the state (default: the scene's [simulation] precision, else f32)")
    p.add_argument("--threads", type=int, help="CPU threads (default: all cores)")
    p.add_argument("--parallel-from", type=int, metavar="N", dest="parallel_from",
                   help="particles from which the CPU runs the step on all threads; below, one "
                        "thread and several steps per launch (default 5000; 0: always "
                        "parallel; BENCHMARKS.md 'Small scenes')")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--window", "--gui", action="store_true", dest="window",
                   help="a live window (Taichi GGUI): space pauses, up/down change the speed "
                        "of the first rotating body, Esc stops; needs a display")
    p.add_argument("--plots", action=argparse.BooleanOptionalAction, default=None,
                   help="write PNG plots of the results (as `taichi-dem plot`) into "
                        "<results stem>_plots/ beside the results file (default: on for "
                        "`demo`, off for `run` and `resume`)")


def _parser() -> argparse.ArgumentParser:
    from .._version import __version__
    p = argparse.ArgumentParser(prog="taichi-dem", description=__doc__.splitlines()[0] + "\n\n"
                                + "\n".join(__doc__.splitlines()[2:5]))
    p.add_argument("--version", action="version", version=f"taichi-dem {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND",
                           help="one of the commands below; `taichi-dem COMMAND --help` for its options")
    r = sub.add_parser("run", help="run a scene")
    r.add_argument("scene", help="the scene file (TOML)")
    _common_outputs(r)
    c = sub.add_parser("check", help="validate a scene and print derived figures")
    c.add_argument("scene", nargs="?", help="the scene file (TOML) to validate")
    c.add_argument("--builders", action="store_true", help="list the mesh builders")
    c.add_argument("--preview", metavar="PNG", help="also draw the scene at t = 0 into this PNG: "
                   "the placed particles, the bodies, the factories' and outlets' regions, "
                   "the domain (a perspective view and a section along the first body's axis)")
    rs = sub.add_parser("resume", help="continue from a checkpoint")
    rs.add_argument("checkpoint", help="a checkpoint (<scene stem>.checkpoint.h5) a run wrote beside its results")
    _common_outputs(rs)
    d = sub.add_parser("demo", help="run a bundled demo (no NAME: list them)")
    d.add_argument("name", nargs="?", help="the demo to run (leave out to list them)")
    d.add_argument("--copy", metavar="DIR", default=None,
                   help="copy the demo's (or a tutorial's) scene file into DIR to edit, and the "
                        "files it names beside it; run nothing")
    _common_outputs(d)
    b = sub.add_parser("bench", help="the chute performance benchmark")
    b.add_argument("--steps", type=int, default=1000, help="time steps per timed run (default 1000)")
    b.add_argument("--copies", type=float, default=1.0, help="chute size in units of 32k particles")
    b.add_argument("--threads", type=int, help="CPU threads (default: all cores)")
    b.add_argument("--precision", default="f32", choices=["f32", "f64"],
                   help="floating-point precision (default f32, as the LAMMPS peer)")
    from . import sweep, tradeoffs
    sw = sub.add_parser("sweep", help="many runs of a scene with keys changed, on Dask")
    sweep.add_arguments(sw)
    tr = sub.add_parser("tradeoffs", help="what accuracy costs in time: one knob at a time")
    tradeoffs.add_arguments(tr)
    sc = sub.add_parser("schema", help="print the JSON Schema of every scene key (type, unit, "
                                       "default, range, description), generated from the "
                                       "declarations")
    sc.add_argument("--keys", action="store_true",
                    help="a plain table instead: one line per key (path, unit, default, "
                         "description)")
    from . import slice_map
    mp = sub.add_parser("map", help="a periodic slice at several hold-ups: its steady transport, "
                                    "torque and heat per metre (the machine's map)")
    slice_map.add_arguments(mp)
    from . import machine_command
    mc = sub.add_parser("machine", help="the whole machine from its map: hold-up profile, "
                                        "residence, torque, outlet temperature and capacity")
    machine_command.add_arguments(mc)
    from . import dryer_command
    dr = sub.add_parser("dryer", help="a whole rotary dryer marched along its axis: outlet "
                                      "temperatures and moisture, gas outlet, heat duty")
    dryer_command.add_arguments(dr)
    from . import plots
    pl = sub.add_parser("plot", help="PNG plots of a results file (torque, residence time, "
                                     "mass flows, temperatures, heat flows)")
    plots.add_arguments(pl)
    from . import export
    ex = sub.add_parser("export", help="a results file's series or one particle frame as CSV")
    export.add_arguments(ex)
    from . import analyse
    an = sub.add_parser("analyse", help="profiles in bins, particle tracks, residence records "
                                        "and a video, from a results file's frames")
    analyse.add_arguments(an)
    from . import calibrate
    calibrate.add_parser(sub)
    p.epilog = "examples:\n  taichi-dem demo pile\n  taichi-dem check my_drum.toml\n" \
               "  taichi-dem run my_drum.toml --out results\n\n" \
               "`taichi-dem COMMAND --help` shows each command's options and examples."
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    for name, command in sub.choices.items():
        command.epilog = "examples:\n" + "\n".join(f"  {line}" for line in EXAMPLES[name])
        command.formatter_class = argparse.RawDescriptionHelpFormatter
    return p


# shown under each command's --help (tests/unit/test_cli_help.py runs every one through the parser)
EXAMPLES = {
    "run": ["taichi-dem run demos/pile.toml --out results",
            "taichi-dem run drum.toml --until 2 --precision f64 --rrd drum.rrd",
            "taichi-dem run cooler.toml --arch gpu --quiet"],
    "check": ["taichi-dem check drum.toml", "taichi-dem check drum.toml --preview drum.png",
              "taichi-dem check --builders"],
    "resume": ["taichi-dem resume out/pile.checkpoint.h5 --until 1.0"],
    "demo": ["taichi-dem demo", "taichi-dem demo pile", "taichi-dem demo paddle_cooler --until 10 --no-plots",
             "taichi-dem demo first_drum --copy ."],
    "bench": ["taichi-dem bench --steps 500", "taichi-dem bench --copies 0.25 --precision f64"],
    "sweep": ["taichi-dem sweep drum.toml --set \"bodies.0.speed=2 rpm,6 rpm\" --seeds 2 --out sweep",
              "taichi-dem sweep drum.toml --set simulation.dt=2e-5,4e-5 --scheduler tcp://10.0.0.5:8786"],
    "tradeoffs": ["taichi-dem tradeoffs demos/small_drum.toml --duration 1 --out tradeoffs",
                  "taichi-dem tradeoffs cooler.toml --knobs precision timestep --seeds 3"],
    "schema": ["taichi-dem schema > scene.schema.json", "taichi-dem schema --keys | grep thermal"],
    "map": ["taichi-dem map demos/cooler_slice.toml --holdup \"10 %\" \"25 %\" --time 10 --out map",
            "taichi-dem map slice.toml --holdup \"30 kg/m\" \"60 kg/m\" --time 8 --incline 5 2 --dask",
            "taichi-dem map slice.toml --holdup \"45 kg/m\" --time 8 --incline 5 2 --out map --add",
            "taichi-dem map slice.toml --holdup 30 60 90 --time 6 --incline 5 --set simulation.precision=f64 --out map_f64"],
    "machine": ["taichi-dem machine map --length \"6 m\" --feed \"4.6 t/h\" \"6.5 t/h\"",
                "taichi-dem machine map --length \"6 m\" --feed \"5 t/h\" --incline 5 --inlet-temperature \"450 C\"",
                "taichi-dem machine map --length \"6 m\" --feed \"6.5 t/h\" --incline 5 --choice f64 map_f64"],
    "dryer": ["taichi-dem dryer demos/dryers/aggregate_dryer.toml",
              "taichi-dem dryer my_dryer.toml --flow co --out dryer"],
    "plot": ["taichi-dem plot out/paddle_cooler.h5", "taichi-dem plot results.h5 --out figures --dpi 150"],
    "export": ["taichi-dem export out/pile.h5 --series --out pile_series.csv",
               "taichi-dem export out/pile.h5 --frame -1 --out last_frame.csv",
               "taichi-dem export out/pile.h5 --xdmf   # then open out/pile.xdmf in ParaView"],
    "analyse": ["taichi-dem analyse out/paddle_cooler.h5 profile --axis x --bins 20 --from 40 --plot profile.png",
                "taichi-dem analyse out/drum.h5 profile --axis y --origin 0 0 0 --radial 0.1 --bins 10 --material glass",
                "taichi-dem analyse out/pile.h5 track --ids 3 17 --out tracks.csv",
                "taichi-dem analyse out/paddle_cooler.h5 residence --out residence.csv",
                "taichi-dem analyse out/pile.h5 video --view xz --out pile.gif"],
    "calibrate": ["taichi-dem calibrate demos/calibration/fly_ash_seed001.toml --out calibration --workers 2",
                  "taichi-dem calibrate spec.toml --out cal --scheduler tcp://10.0.0.5:8786"],
}


def main(argv=None) -> int:
    from ..run import checkpoint
    # a run from the command line keeps its last good state for a divergence (exit 3)
    saved, checkpoint.KEEP_LAST_GOOD = checkpoint.KEEP_LAST_GOOD, True
    try:
        return _main(argv)
    finally:
        checkpoint.KEEP_LAST_GOOD = saved


# commands whose stdout is a report to read or parse: Taichi's import banner stays off it
QUIET_IMPORT = ("check", "schema", "machine", "dryer", "map", "export", "analyse")


def _main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.command in QUIET_IMPORT:
        os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "False")
    try:
        if args.command == "check":
            return cmd_check(args)
        if args.command == "run":
            return cmd_run(args, args.scene)
        if args.command == "demo":
            return cmd_demo(args)
        if args.command == "resume":
            return cmd_resume(args)
        if args.command == "bench":
            return cmd_bench(args)
        if args.command == "sweep":
            from .sweep import cmd_sweep
            return cmd_sweep(args)
        if args.command == "tradeoffs":
            from .tradeoffs import cmd_tradeoffs
            return cmd_tradeoffs(args)
        if args.command == "schema":
            return cmd_schema(args)
        if args.command == "plot":
            from .plots import cmd_plot
            return cmd_plot(args)
        if args.command == "map":
            from .slice_map import cmd_map
            return cmd_map(args)
        if args.command == "machine":
            from .machine_command import cmd_machine
            return cmd_machine(args)
        if args.command == "dryer":
            from .dryer_command import cmd_dryer
            return cmd_dryer(args)
        if args.command == "export":
            from .export import cmd_export
            return cmd_export(args)
        if args.command == "analyse":
            from .analyse import cmd_analyse
            return cmd_analyse(args)
        if args.command == "calibrate":
            from .calibrate import run as cmd_calibrate
            return cmd_calibrate(args)
    except SceneError as err:
        return _fail(str(err), 2)
    except BackendError as err:       # the runtime cannot be had as asked (bad input: exit 2)
        return _fail(str(err), 2)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)
    except BrokenPipeError:
        # stdout piped into a reader that stopped (`taichi-dem plot ... | head`): not an error;
        # later writes (and the flush at exit) go nowhere instead of raising again
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    return 0


# ---------------------------------------------------------------------------------- schema
def cmd_schema(args) -> int:
    """Print the scene schema (JSON) or, with --keys, one line per key."""
    from ..scene import schema
    if not args.keys:
        text = schema.dumps()
    else:
        lines = []
        for path, node in schema.every_key():
            default = ("required" if node.get("x-required")
                       else node.get("x-default", node.get("default", "")))
            choices = node.get("enum")
            allowed = (" (one of: " + ", ".join(json.dumps(c) for c in choices) + ")"
                       if choices else "")
            lines.append(f"{path:52s} {node.get('x-unit', ''):10s} {str(default):20s} "
                         f"{node.get('description', '')}{allowed}")
        text = "\n".join(lines)
    try:
        print(text)
    except BrokenPipeError:       # `taichi-dem schema | head`
        sys.stderr.close()
    return 0


# ---------------------------------------------------------------------------------- check
def describe_scene(scene) -> str:
    """The effect list and derived figures of a scene, without compiling anything."""
    from ..effects import enabled_effects
    from ..setup.pair_tables import build_pair_tables
    from ..setup.placement import place_fills
    from ..setup.memory import (allocated_slots, estimated_device_bytes, memory_problem,
                                particle_slots)
    from ..setup.timestep import choose_step_and_skin

    # before anything the size of the scene is allocated (placement, the tables)
    problem = memory_problem(scene)
    if problem:
        raise SceneError(scene.source, *problem)
    placed = place_fills(scene, np.random.default_rng(scene.simulation.seed))
    tables = build_pair_tables(scene)
    from ..run.simulation import _check_periodic_axes, _factory_capacity, _sizes_to_expect
    n = len(placed.radius)
    if n == 0 and not scene.factories:
        raise SceneError(scene.source, "particles", "the scene has no particles")
    radii, mats, speeds, fixed = _sizes_to_expect(scene, placed, tables.names)
    ts, skin = choose_step_and_skin(scene, radii, mats, tables.names, speeds, fixed)
    if not (ts.dt > 0.0 and math.isfinite(ts.dt)) or not ts.rayleigh_time > 0.0:
        raise SceneError(scene.source, "simulation.dt",
                         f"the time step comes out as {ts.dt:g} s (set by {ts.limited_by}; "
                         f"Rayleigh time {ts.rayleigh_time:g} s): the scene's sizes, speeds "
                         "and material properties are absurd together")
    _check_periodic_axes(scene, float(np.max(radii)))
    n_initial = n
    n = n + _factory_capacity(scene)
    # setup/memory.py: state, neighbour lists, cells (memory_problem refused more than the
    # machine has above, from the same estimate)
    memory = estimated_device_bytes(allocated_slots(particle_slots(scene)),
                                    scene.simulation.precision, bool(scene.bodies))
    steps = scene.simulation.end_time / ts.dt
    lines = [f"scene: {scene.source}", "effects (compiled and run, in step order):"]
    for e in enabled_effects(scene):
        lines.append(f"  - {e.name:24s} {e.description}")
    lines += [
        f"particles: {n_initial} initially ({', '.join(f'{c} {m}' for m, c in zip(tables.names, np.bincount(placed.material, minlength=len(tables.names))) if c) or 'none'})"
        + (f"; up to {n} with the factories (the particle-step estimate below assumes them all)"
           if scene.factories else "")
        + f", radius {radii.min():.4g} - {radii.max():.4g} m",
        f"Rayleigh time (smallest particle): {ts.rayleigh_time:.4g} s",
        f"Hertz contact time at {ts.expected_speed:.3g} m/s: {ts.contact_time:.4g} s",
        f"time step: {ts.dt:.4g} s ({ts.dt / ts.rayleigh_time:.1%} of Rayleigh; set by {ts.limited_by})",
        f"steps to end_time {scene.simulation.end_time:g} s: {steps:,.0f}"
        f" ({steps * n / 1e9:.3g} G particle-steps)",
        f"Verlet skin: {skin:.4g} m",
        f"precision: {scene.simulation.precision}; estimated device memory: {memory / 2**20:.1f} MiB",
    ]
    if scene.bodies:
        from ..setup.timestep import body_surface_speed
        for b in scene.bodies:
            w = max((abs(p[1]) for p in b.motion.speed.points), default=0.0) if b.motion.speed else 0.0
            lines.append(f"body {b.name}: {len(b.faces)} triangles, material {b.material}, "
                         f"up to {w * 60 / (2 * math.pi):.3g} rpm")
        lines.append(f"fastest body surface: {body_surface_speed(scene):.3g} m/s "
                     f"({body_surface_speed(scene) * ts.dt / float(np.min(radii)):.3f} "
                     f"of the smallest radius per step)")
        for note in narrow_gap_notes(scene, float(np.max(radii))):
            ts.notes.append(note)
    if scene.simulation.max_particles is not None and not scene.factories:
        ts.notes.append(f"simulation.max_particles = {scene.simulation.max_particles:,} is not "
                        "used: a scene without factories allocates exactly the particles its "
                        f"fills place ({n_initial:,})")
    lines += [f"note: {note}" for note in ts.notes]
    from ..scene.sections.calibration import describe_calibration
    lines += describe_calibration(scene)
    return "\n".join(lines)


def narrow_gap_notes(scene, largest_radius: float) -> list:
    """Warnings for each pair of bodies, one turning about an axis the other shares or is
    swept round, whose narrowest radial gap (geometry/gaps.py) the largest sphere cannot pass:
    spheres wedge between paddle tips and the shell there (a jam, a torque spike)."""
    from taichi_dem.geometry.gaps import radial_gap, surface_points
    notes = []
    bodies = list(scene.bodies)
    for i, a in enumerate(bodies):
        for b in bodies[i + 1:]:
            turning = [x for x in (a, b) if x.motion.speed is not None]
            if not turning:
                continue
            axis_point = np.asarray(turning[0].motion.axis_point, float)
            axis = np.asarray(turning[0].motion.axis_direction, float)
            if len(turning) == 2:
                other = np.asarray(turning[1].motion.axis_direction, float)
                offset = np.asarray(turning[1].motion.axis_point, float) - axis_point
                if (abs(abs(other @ axis) - 1.0) > 1e-6
                        or np.linalg.norm(offset - (offset @ axis) * axis) > 1e-6):
                    continue        # not coaxial: no swept annulus to speak of
            pa, pb = (surface_points(x.vertices, x.faces) for x in (a, b))
            if not len(pa) or not len(pb):
                continue

            def median_radius(points):
                rel = points - axis_point
                return float(np.median(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)))
            inner, outer, p_in, p_out = ((a, b, pa, pb) if median_radius(pa) < median_radius(pb)
                                         else (b, a, pb, pa))
            gap, where = radial_gap(p_in, p_out, axis_point, axis, slab=largest_radius)
            if 2.0 * largest_radius >= gap:
                notes.append(f"the largest sphere (diameter {2e3 * largest_radius:.3g} mm) cannot "
                             f"pass the narrowest gap between bodies {inner.name!r} and "
                             f"{outer.name!r} ({1e3 * gap:.3g} mm, {where:.3g} m along the axis): "
                             "spheres wedge there (jams, torque spikes); smaller spheres or a "
                             "wider clearance")
    return notes


def cmd_check(args) -> int:
    if args.builders:
        from taichi_dem import geometry
        print(geometry.describe_builders())
        if not args.scene:
            return 0
    if not args.scene:
        return _fail("check: give a scene file (or --builders)")
    from ..scene.loader import load_scene
    scene = load_scene(args.scene)
    _refuse_bad_outputs(args.scene, scene, *_resolve_outputs(args.scene, scene))
    _note_ignored(args.scene, scene)
    print(describe_scene(scene))
    if args.preview:
        from .preview import write_preview
        try:
            print(f"preview: {write_preview(scene, args.preview)}")
        except OSError as err:
            return _fail(f"--preview: cannot write {args.preview} ({err.strerror or err})")
    print("scene OK")
    return 0


# ---------------------------------------------------------------------------------- run
def _resolve_outputs(scene_path, scene, args=None):
    """(results file, recording file, checkpoint file) a run of ``scene`` writes: absolute
    paths or None (consistency.resolve_output_path: the scene's [output] paths inside its
    folder, or their names in --out DIR; --h5 and --rrd as the user gave them; the checkpoint
    beside the results, in --out DIR, or beside the scene)."""
    from ..run.checkpoint import default_path
    from ..scene.sections.consistency import resolve_output_path
    explicit_h5 = getattr(args, "h5", None)
    explicit_rrd = getattr(args, "rrd", None)
    out_dir = getattr(args, "out", None)
    h5_name = scene.output.h5
    if out_dir and not h5_name:
        h5_name = Path(scene_path).stem + ".h5"      # --out DIR alone: <scene stem>.h5 there
    h5 = resolve_output_path(scene_path, "output.h5", h5_name, explicit_h5, out_dir, "--h5")
    rrd = resolve_output_path(scene_path, "output.rrd", scene.output.rrd, explicit_rrd,
                              out_dir, "--rrd")
    checkpoint = default_path(scene, h5, os.path.expanduser(out_dir) if out_dir else None)
    return h5, rrd, checkpoint


def _refuse_bad_outputs(scene_path, scene, h5, rrd, checkpoint, args=None) -> None:
    """SceneError (file: key: reason) for an output that cannot be written, or an existing
    file in its place that is not ours (consistency.foreign_file_problem): never overwritten."""
    from ..scene.sections.consistency import foreign_file_problem
    h5_key = "--h5" if getattr(args, "h5", None) else "output.h5"
    rrd_key = "--rrd" if getattr(args, "rrd", None) else "output.rrd"
    _refuse_unwritable(scene_path, ((h5_key, h5), (rrd_key, rrd)))
    # the checkpoint (periodic, or the last good state of a diverged run) goes beside the
    # results: blamed on the key that puts it there
    checkpoint_key = ("output.checkpoint_interval" if scene.output.checkpoint_interval
                      else "--out" if getattr(args, "out", None) else h5_key)
    for key, path, kind in ((h5_key, h5, "results"), (rrd_key, rrd, "recording"),
                            (checkpoint_key, checkpoint, "checkpoint")):
        problem = foreign_file_problem(path, kind)
        if problem:
            raise SceneError(str(scene_path), key, problem)


def _window_problem(args):
    """A one-line reason why --window cannot work here, or None."""
    if not getattr(args, "window", False):
        return None
    from .window import display_problem
    return display_problem()


def _note_ignored(source, scene) -> None:
    """A note on stderr for each key the scene gives that nothing will read, and for each
    way it departs from a material's calibration record."""
    from ..scene.sections.calibration import calibration_notes
    from ..scene.sections.consistency import ignored_keys
    for key, reason in ignored_keys(scene) + calibration_notes(scene):
        print(f"note: {source}: {key}: {reason}", file=sys.stderr)


def _refuse_unwritable(source, paths) -> None:
    """SceneError (file: key: reason) for the first of (key, path) that cannot be written."""
    from ..scene.sections.consistency import output_path_problem
    for key, path in paths:
        problem = output_path_problem(path)
        if problem:
            raise SceneError(str(source), key, f"cannot write the results there: {problem}")


def cmd_run(args, scene_path: str, summary=None, setup=None) -> int:
    from ..run.simulation import Simulation
    from ..scene.loader import load_scene

    problem = _window_problem(args)
    if problem:
        return _fail(problem, 2)
    scene = load_scene(scene_path)
    h5, rrd, checkpoint_path = _resolve_outputs(scene_path, scene, args)
    _refuse_bad_outputs(scene_path, scene, h5, rrd, checkpoint_path, args)
    _note_ignored(scene_path, scene)
    from ..setup.memory import memory_problem
    problem = memory_problem(scene, args.arch, args.precision)   # before anything is allocated
    if problem:
        raise SceneError(scene_path, *problem)
    every_nth = getattr(args, "every_nth", 1) or 1
    if every_nth < 1:
        return _fail(f"--every-nth: {every_nth} is not a positive whole number")
    t0 = time.perf_counter()
    try:
        sim = Simulation(scene, arch=args.arch, precision=args.precision, threads=args.threads,
                         h5=h5 or "", parallel_from=getattr(args, "parallel_from", None))
    except DivergenceError as err:       # at the first sample: there is no good state
        return _fail(f"{err} (at the start: no checkpoint written)", 3)
    # beside the results, or in --out DIR (CONTRACT.md); also where a divergence leaves the
    # last good state
    sim.checkpointer.path = checkpoint_path
    if summary is None and (scene.factories or scene.outlets or scene.sensors):
        # a process scene of the user's own gets the engineer's numbers the process demos print
        from .summaries import process_summary
        summary = process_summary
    return _drive(sim, args, scene_path, rrd, h5, t0, summary, setup)


def cmd_resume(args) -> int:
    """Continue a checkpointed run: results appended to its results file (or --h5/--out)."""
    from ..run.checkpoint import resume as resume_checkpoint
    from ..run.simulation import Simulation

    problem = _window_problem(args)
    if problem:
        return _fail(problem, 2)
    path = args.checkpoint
    if not Path(path).is_file():
        return _fail(f"{path}: no such checkpoint file")
    t0 = time.perf_counter()
    try:
        import h5py
        with h5py.File(path, "r") as f:
            stored_results = str(f.attrs.get("results", ""))
    except OSError as err:
        return _fail(f"{path}: cannot open as an HDF5 checkpoint ({err})")
    if args.h5:
        h5 = args.h5
    elif args.out:
        args.out = os.path.expanduser(args.out)
        h5 = str(Path(args.out) / (Path(stored_results).name if stored_results
                                   else Path(path).name.replace(".checkpoint.h5", ".h5")))
    else:
        h5 = stored_results if stored_results and Path(stored_results).exists() else ""
    checkpoint = str(Path(args.out) / Path(path).name) if args.out else path
    try:
        build = functools.partial(Simulation, parallel_from=args.parallel_from)
        sim = resume_checkpoint(path, build=build, arch=args.arch, threads=args.threads, h5=h5,
                                checkpoint=checkpoint)
    except CheckpointError as err:
        return _fail(str(err))
    if args.precision and args.precision != sim.precision:
        print(f"taichi-dem: note: the checkpoint is {sim.precision}; --precision "
              f"{args.precision} ignored", file=sys.stderr)
    rrd = args.rrd
    if not args.quiet:
        print(f"{path}: resumed at t = {sim.time:.6g} s (step {sim.step_count:,})", file=sys.stderr)
    return _drive(sim, args, path, rrd, h5, t0, None)


def _drive(sim, args, label: str, rrd, h5, t0: float, summary, setup=None) -> int:
    """Run ``sim`` to --until (or end_time) with progress, a window or quietly, and print the
    summary; exit 3 on divergence (the last good state checkpointed)."""
    scene = sim.scene
    every_nth = getattr(args, "every_nth", 1) or 1
    recorder = None
    if rrd or args.spawn:
        from ..recorders.rerun import RerunRecorder
        recorder = RerunRecorder(rrd, spawn=args.spawn, every_nth=every_nth)
        sim.add_observer(recorder)
    if setup:
        setup(sim)
    if not args.quiet:
        print(f"{label}: {sim.particle_count} particles, dt = {sim.dt:.4g} s, "
              f"{len(sim.effects)} effects: {', '.join(e.name for e in sim.effects)}",
              file=sys.stderr)
    until = scene.simulation.end_time if args.until is None else args.until
    steps0, time0 = sim.step_count, sim.time
    try:
        if args.window:
            from .window import run_window
            try:
                run_window(sim, until)
            except WindowError as err:
                sim.close()
                return _fail(str(err), 2)
        else:
            # Ctrl-C stops at the next chunk of steps, where the state is whole (run/interrupt.py)
            with interrupt.deferred():
                sim.run(until, progress=not args.quiet)
        # a sample at the run's last instant: the report below reads the final state and the
        # series, which must describe the same moment (the last regular sample may be earlier)
        sim.sample_now()
    except DivergenceError as err:
        sim.close()
        return _fail(str(err), 3)
    except KeyboardInterrupt:
        return _interrupted(sim, args, label, until, h5, recorder, t0, time0, steps0)
    if sim.checkpointer.interval:
        sim.checkpointer.save(sim=sim)       # the final state, to continue with `resume`
    _report(sim, args, h5, rrd, recorder, summary, t0, time0, steps0)
    sim.close()
    if h5 and getattr(args, "plots", None):
        _write_plots(h5)
    return 0


def _interrupted(sim, args, label: str, until: float, h5, recorder, t0: float, time0: float,
                 steps0: int) -> int:
    """Ctrl-C during a run: the summary so far, the state checkpointed where it can be resumed,
    the results file closed (its .xdmf written); exit 130. A second Ctrl-C stops at once."""
    print(f"taichi-dem: interrupted at t = {sim.time:.6g} s of {until:g} s", file=sys.stderr)
    try:
        sim.sample_now()                     # the series and a frame at the moment it stopped
        ck = sim.checkpointer
        if ck.path:
            ck.save(sim=sim)
            print(f"taichi-dem: the state at t = {sim.time:.6g} s is in {ck.path}; continue "
                  f"with: taichi-dem resume {ck.path}"
                  + (f" --until {until:g}" if args.until is not None else ""), file=sys.stderr)
        _report(sim, args, h5, None, recorder, None, t0, time0, steps0)
    finally:
        sim.close()                          # (closes the results file: its .xdmf is written)
    return 130


def _report(sim, args, h5, rrd, recorder, summary, t0: float, time0: float, steps0: int):
    """The run's summary on stdout: time, rate, particles, wall forces, body torques, the
    demo's own figures (``summary``), where the results and checkpoints went."""
    scene = sim.scene
    wall = time.perf_counter() - t0
    s = sim.series
    steps = sim.step_count - steps0
    # particles that leave (outlets, the domain) make the final count too small a measure
    mean_count = float(np.mean(s["particles/count"])) if len(s["particles/count"]) else sim.particle_count
    # the particle-steps the progress counted block by block, when it ran (else the mean count)
    particle_steps = getattr(sim, "progress_particle_steps", None) or steps * mean_count
    print(f"simulated {sim.time - time0:.4g} s (to t = {sim.time:.4g} s) in {wall:.1f} s wall "
          f"({sim.wall_seconds:.1f} s stepping); {steps:,} steps, "
          f"{particle_steps / max(sim.wall_seconds, 1e-9) / 1e6:.2f} M particle-steps/s "
          "over the stepping time")
    print(f"particles: {sim.particle_count} (lost {int(s['particles/lost'][-1])}); "
          f"kinetic energy {s['particles/kinetic_energy'][-1]:.4g} J")
    for w in scene.walls:
        f = s[f"walls/{w.name}/force"][-1]
        print(f"wall {w.name}: force [{f[0]:.4g}, {f[1]:.4g}, {f[2]:.4g}] N")
    # one torque per body, over the window every summary figure uses (the last quarter)
    from .summaries import body_torque_lines
    body_torque_lines(sim)
    if summary:
        summary(sim)
    if h5:
        print(f"results: {h5}")
    ck = sim.checkpointer
    if ck.written:
        print(f"checkpoint: {ck.path} ({ck.written} written, {ck.write_seconds:.2f} s; "
              f"state captures {ck.snapshot_seconds:.2f} s, divergence checks "
              f"{sim.divergence.seconds:.2f} s)")
    if recorder is not None:
        recorder.close()
        print(f"rerun: {recorder.samples} samples in {recorder.wall_seconds:.2f} s wall "
              f"({recorder.wall_seconds / max(wall, 1e-9):.1%} of the run)"
              + (f" -> {rrd}" if rrd else ""))


def _write_plots(h5: str) -> None:
    """The PNGs of ``h5`` beside it (plots.default_dir); a failure is a note, not an error:
    the run's results are written already."""
    from .plots import PlotError, default_dir, plot_results
    t0 = time.perf_counter()
    try:
        made = plot_results(h5)
    except (PlotError, OSError, ValueError) as err:
        print(f"taichi-dem: note: no plots ({err})", file=sys.stderr)
        return
    print(f"plots: {default_dir(h5)}/ ({len(made)} PNG{'s' if len(made) != 1 else ''}: "
          f"{', '.join(Path(f.path).name for f in made)}; {time.perf_counter() - t0:.1f} s)")


# ---------------------------------------------------------------------------------- demo
def cmd_demo(args) -> int:
    from . import demos
    if not args.name:
        print("demos (taichi-dem demo NAME; taichi-dem demo NAME --copy DIR: its scene to edit):")
        for name in demos.DEMOS:
            print(f"  {name:16s} {demos.get(name).description}")
        print("tutorial scenes (taichi-dem demo NAME --copy DIR; docs: Tutorials):")
        for name, path in demos.tutorial_scenes().items():
            print(f"  {name:16s} {demos.first_line(path)}")
        return 0
    if args.copy is not None:
        return _copy_scene(args.name, Path(args.copy))
    if args.name not in demos.DEMOS:
        hint = (f"; '{args.name}' is a tutorial's scene: taichi-dem demo {args.name} --copy DIR"
                if args.name in demos.tutorial_scenes() else "")
        return _fail(f"demo '{args.name}' not found; available: {', '.join(demos.DEMOS)}{hint}")
    demo = demos.get(args.name)
    if not demo.path.exists():
        return _fail(f"{demo.path}: the scene of demo '{args.name}' is missing (run from a "
                     f"source checkout)")
    if not args.out and not args.h5:
        args.out = "out"
    if args.plots is None:
        args.plots = True        # cheap next to the run; `--no-plots` skips them
    return cmd_run(args, str(demo.path), summary=demo.summary, setup=demo.attach)


def _copy_scene(name: str, folder: Path) -> int:
    """``taichi-dem demo NAME --copy DIR``: the scene file of a demo or tutorial into DIR, with
    the files it names that lie beside it (CSV fills, STL meshes); nothing is overwritten."""
    from . import demos
    try:
        made = demos.copy_scene(name, folder)
    except FileExistsError as e:
        return _fail(f"{e.filename}: exists already; not overwritten (remove it, or copy into "
                     f"another folder)")
    except KeyError:
        names = list(demos.DEMOS) + list(demos.tutorial_scenes())
        return _fail(f"demo '{name}' not found; available: {', '.join(names)}")
    except OSError as e:
        return _fail(f"{folder}: cannot copy into it ({e.strerror or e})")
    for source, target in made:
        print(f"copied {source.name} to {target}")
    print(f"run it: taichi-dem run {made[0][1]}", file=sys.stderr)
    return 0


# ---------------------------------------------------------------------------------- bench
def cmd_bench(args) -> int:
    bench = Path(__file__).resolve().parents[2] / "bench" / "chute.py"
    if not bench.exists():
        return _fail("bench/chute.py not found (run from a source checkout)")
    import runpy
    sys.argv = [str(bench), "--steps", str(args.steps), "--copies", str(args.copies),
                "--precision", args.precision] + (["--threads", str(args.threads)] if args.threads else [])
    runpy.run_path(str(bench), run_name="__main__")
    return 0
