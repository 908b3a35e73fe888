"""``taichi-dem sweep``: many runs of one scene with keys changed, on Dask distributed.

The plan (:func:`plan`) turns ``--set`` overrides (cross product or ``--zip``) and ``--seeds``
into :class:`RunSpec` s, each validated by the loader before anything runs (bad input exits 2
naming the file and key). :func:`run_sweep` submits one Dask task per run that has not
finished yet; the task (:func:`execute_run`, on a worker) starts the run in a fresh Python
process (``python -m taichi_dem.app.sweep --run-dir DIR``: its own Taichi runtime, arch,
precision and thread count; a crash takes down that process only) and returns its record.

Each run lives in ``OUT/runs/<id>/``: ``spec.json`` (what to run), ``scene.toml`` (the
overridden scene), ``results.h5``, ``checkpoint.h5``, ``log.txt`` (its output), ``running``
while it runs, and ``done.json`` (the finished marker with its record) or ``failed.json``.
The id is a readable slug of the overrides and seed plus a hash of the scene text and run
length, so the same sweep started again finds its finished runs and skips them; a run killed
after a checkpoint continues from it (``resumed`` in the table). Failed runs are run again.

With ``--scheduler tcp://HOST:PORT`` the workers must see OUT on a shared file system and have
taichi_dem installed; the scene's relative paths (meshes, particle files) resolve against the
scene file's directory, which they must see too.
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import re
import subprocess
import sys
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Optional

from ..errors import SceneError
from . import overrides as ov

RESULTS_CSV = "results.csv"
RESULTS_MD = "sweep.md"
FIXED_COLUMNS = ("id", "status", "seed", "wall_s", "build_s", "compile_s", "step_s", "cpu_s",
                 "dt", "particles", "particle_steps_per_s", "resumed")


@dataclass
class RunSpec:
    """One run of a sweep. ``overrides`` are the user's (the table's columns); ``text`` is the
    scene actually run (overrides, seed, duration and checkpoint interval applied); relative
    paths in it resolve against ``source``'s directory. ``until``: simulated time to run to, s.
    ``threads``: CPU threads of the run. ``labels``: extra columns (tradeoffs: knob, setting)."""
    id: str
    overrides: dict
    seed: int
    text: str
    source: str
    until: float
    threads: int = 1
    arch: str = "cpu"
    labels: dict = field(default_factory=dict)


def _slug(overrides: dict, seed: int) -> str:
    parts = []
    for k, v in overrides.items():
        leaf = k.split(".")[-1]
        shown = f"{v:.4g}" if isinstance(v, float) else ov._show(v)
        parts.append(f"{leaf}={shown}")
    parts.append(f"seed={seed}")
    s = re.sub(r"[^A-Za-z0-9_.=+-]+", "-", "_".join(parts)).strip("-")
    return s[:60]


def run_id(overrides: dict, seed: int, text: str, until: float, arch: str) -> str:
    """Readable and stable: ``<slug of overrides and seed>-<8 hex of scene text, until, arch>``."""
    h = hashlib.sha1(f"{text}\n{until!r}\n{arch}".encode()).hexdigest()[:8]
    return f"{_slug(overrides, seed)}-{h}"


def scene_seed(doc: dict) -> int:
    """The seed a scene file gives (``simulation.seed``; 1 when it gives none)."""
    seed = doc.get("simulation", {}).get("seed", 1)
    return int(seed) if isinstance(seed, int) else 1


def plan(scene_path: str, combos: list[dict], seeds: int = 1, *, duration: Optional[float] = None,
         threads: int = 1, arch: str = "cpu", checkpoint_interval: Optional[float] = None,
         labels: Optional[list[dict]] = None) -> list[RunSpec]:
    """The runs: every override combination in ``combos`` times ``seeds`` placement seeds
    (the scene's ``simulation.seed``, +1, +2, ...). ``duration`` (s) overrides
    ``simulation.end_time``. Each scene is validated here: a SceneError names the scene file,
    the key and the ``--set`` it came from."""
    source = str(Path(scene_path).resolve())
    try:
        text = Path(scene_path).read_text(encoding="utf-8-sig")
    except OSError as e:
        raise SceneError(scene_path, "", f"cannot read the scene file: {e.strerror or e}") from None
    from ..scene.loader import read_toml
    doc = read_toml(text, scene_path)       # a syntax error or deep nesting: SceneError
    if seeds < 1:
        raise SceneError("--seeds", "", f"must be >= 1, got {seeds}")
    base_seed = scene_seed(doc)
    specs = []
    for i, combo in enumerate(combos):
        if seeds > 1 and "simulation.seed" in combo:
            raise SceneError("--set", "simulation.seed", "cannot be set together with --seeds N")
        for k in range(seeds):
            seed = int(combo.get("simulation.seed", base_seed + k))
            full = dict(combo)
            full["simulation.seed"] = seed
            if duration is not None:
                full["simulation.end_time"] = float(duration)
            if checkpoint_interval is not None:
                full["output.checkpoint_interval"] = float(checkpoint_interval)
            new_doc = ov.apply(doc, full, scene_path)
            new_text = ov.to_text(new_doc)
            scene = ov.check(new_text, full, scene_path, base_dir=Path(source).parent)
            until = scene.simulation.end_time
            specs.append(RunSpec(id=run_id(combo, seed, new_text, until, arch),
                                 overrides=dict(combo), seed=seed, text=new_text, source=source,
                                 until=until, threads=threads, arch=arch,
                                 labels=dict(labels[i]) if labels else {}))
    ids = [s.id for s in specs]
    if len(set(ids)) != len(ids):
        dup = next(x for x in ids if ids.count(x) > 1)
        raise SceneError("--set", "", f"two runs come out identical ({dup}): a value is given twice")
    return specs


# ------------------------------------------------------------------------------ one run
def _write_json(path: Path, data: dict) -> None:
    """Atomically: a temporary file moved over ``path``."""
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=1, default=float))
    os.replace(tmp, path)


def _last_message(log: Path) -> str:
    """The reason a run failed: its last ``taichi-dem:`` line, else the log's last lines."""
    try:
        lines = [l.strip() for l in log.read_text(errors="replace").splitlines() if l.strip()]
    except OSError:
        return "(no log)"
    msgs = [l for l in lines if l.startswith("taichi-dem:")]
    if msgs:
        return msgs[-1][len("taichi-dem:"):].strip()
    return " | ".join(lines[-3:]) if lines else "(empty log)"


def execute_run(spec: dict, run_dir: str, timeout: Optional[float] = None) -> dict:
    """The Dask task: run ``spec`` (a :class:`RunSpec` as a dict) in a new Python process in
    ``run_dir`` and return its record (``status`` "done" or "failed" with ``message``).
    A run whose ``done.json`` exists is not run again."""
    d = Path(run_dir)
    d.mkdir(parents=True, exist_ok=True)
    done = d / "done.json"
    if done.exists():
        rec = json.loads(done.read_text())
        rec["reused"] = True
        return rec
    _write_json(d / "spec.json", spec)
    (d / "scene.toml").write_text(spec["text"])
    (d / "failed.json").unlink(missing_ok=True)
    (d / "running").write_text(f"{os.uname().nodename} {time.time()}\n")
    t0 = time.perf_counter()
    try:
        with open(d / "log.txt", "ab") as log:
            proc = subprocess.run([sys.executable, "-m", "taichi_dem.app.sweep", "--run-dir",
                                   str(d)], stdout=log, stderr=subprocess.STDOUT, timeout=timeout,
                                  env={**os.environ, "PYTHONUNBUFFERED": "1"})
        rc = proc.returncode
    except subprocess.TimeoutExpired:
        rc = -1
    finally:
        (d / "running").unlink(missing_ok=True)
    if rc == 0 and done.exists():
        return json.loads(done.read_text())
    message = (f"ran past the time limit of {timeout:g} s" if rc == -1 else _last_message(d / "log.txt"))
    rec = {"id": spec["id"], "status": "failed", "rc": rc, "message": message,
           "overrides": spec["overrides"], "seed": spec["seed"], "labels": spec.get("labels", {}),
           "wall_s": time.perf_counter() - t0}
    _write_json(d / "failed.json", rec)
    return rec


def _run_here(run_dir: str) -> int:
    """The body of one run, in its own process: build (or continue from the run's checkpoint),
    run to ``until``, checkpoint, read the key outputs back from the results file, write
    ``done.json``. Exit 2 on bad input, 3 on divergence (message on stderr)."""
    from ..errors import DivergenceError
    from ..run.simulation import Simulation
    from ..scene.loader import parse_scene
    from .outputs import key_outputs, run_facts

    d = Path(run_dir)
    spec = json.loads((d / "spec.json").read_text())
    h5, ckpt, wall_file = d / "results.h5", d / "checkpoint.h5", d / "wall.json"
    t0 = time.perf_counter()
    prior = json.loads(wall_file.read_text()) if wall_file.exists() and ckpt.exists() else None
    try:
        if prior is not None:
            sim = Simulation.from_checkpoint(str(ckpt), arch=spec["arch"], threads=spec["threads"],
                                             h5=str(h5), checkpoint=str(ckpt))
        else:
            scene = parse_scene(spec["text"], source=spec["source"])
            sim = Simulation(scene, arch=spec["arch"], threads=spec["threads"], h5=str(h5))
            sim.checkpointer.path = str(ckpt)
    except SceneError as err:
        print(f"taichi-dem: {err}", file=sys.stderr)
        return 2
    except DivergenceError as err:
        print(f"taichi-dem: {err} (at the start)", file=sys.stderr)
        return 3
    build_s = time.perf_counter() - t0
    prior_step = prior["step_s"] if prior else 0.0
    prior_cpu = prior.get("cpu_s", 0.0) if prior else 0.0
    ck = sim.checkpointer
    start_steps = sim.step_count
    state = {"written": ck.written, "first": None}
    t_step, c_step = time.perf_counter(), time.process_time()

    def rates(now_wall, now_cpu, steps_now):
        """(stepping wall s, stepping CPU s) of this segment's steps so far, kernel compilation
        left out: Taichi compiles the step's kernels at their first launch, and dt and the
        pair constants are compile-time constants, so a run whose dt no other run used pays
        seconds of compilation inside its first output interval. The rate measured after the
        first sample is applied to all of the segment's steps."""
        n = steps_now - start_steps
        first = state["first"]
        if first is None or steps_now <= first[2]:
            return now_wall - t_step, now_cpu - c_step
        k = n / (steps_now - first[2])
        ck_after = ck.write_seconds + ck.snapshot_seconds - first[3]
        return (max(now_wall - first[0] - ck_after, 0.0) * k, max(now_cpu - first[1], 0.0) * k)

    def after_sample(sim):
        if state["first"] is None and sim.step_count > start_steps:
            state["first"] = (time.perf_counter(), time.process_time(), sim.step_count,
                              ck.write_seconds + ck.snapshot_seconds)
        # after each periodic checkpoint: the stepping time so far, for a resumed run's total
        if ck.written != state["written"]:
            state["written"] = ck.written
            w, c = rates(time.perf_counter(), time.process_time(), sim.step_count)
            _write_json(wall_file, {"step_s": prior_step + w, "cpu_s": prior_cpu + c,
                                    "time": sim.time})
    sim.after_sample.append(after_sample)
    try:
        sim.run(spec["until"])
        sim.sample_now()         # as `taichi-dem run`: the results end at the run's last instant
    except DivergenceError as err:
        sim.close()
        print(f"taichi-dem: {err}", file=sys.stderr)
        return 3
    run_s = time.perf_counter() - t_step
    w, c = rates(time.perf_counter(), time.process_time(), sim.step_count)
    step_s, cpu_s = prior_step + w, prior_cpu + c
    ck_s = ck.write_seconds + ck.snapshot_seconds
    steps = sim.step_count               # from t = 0, also when continued from a checkpoint
    ck.save(sim=sim)                 # the final state: `taichi-dem resume` continues the run
    _write_json(wall_file, {"step_s": step_s, "cpu_s": cpu_s, "time": sim.time})
    sim.close()
    facts = run_facts(str(h5))
    outputs = key_outputs(str(h5))
    rec = {"id": spec["id"], "status": "done", "overrides": spec["overrides"], "seed": spec["seed"],
           "labels": spec.get("labels", {}), "wall_s": prior_step + time.perf_counter() - t0,
           "build_s": build_s, "compile_s": max(run_s - w - ck_s, 0.0), "step_s": step_s,
           "cpu_s": cpu_s, "checkpoint_s": ck_s, "steps": steps, "dt": facts["dt"],
           "particles": facts["mean_particles"],
           "particle_steps_per_s": steps * facts["mean_particles"] / max(step_s, 1e-9),
           "precision": facts["precision"], "resumed": prior is not None, "outputs": outputs}
    _write_json(d / "done.json", rec)
    return 0


# ------------------------------------------------------------------------------ the sweep
def make_client(scheduler: Optional[str] = None, workers: Optional[int] = None):
    """A Dask client: to ``scheduler`` (tcp://HOST:PORT), else on a new LocalCluster of
    ``workers`` processes (default: the number of cores), one thread each."""
    from distributed import Client, LocalCluster
    if scheduler:
        try:
            return Client(scheduler, timeout="20s")
        except (OSError, TimeoutError, ValueError) as err:
            raise SceneError("--scheduler", scheduler,
                             f"cannot reach the Dask scheduler ({type(err).__name__}: {err})") from None
    n = workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    client._taichi_dem_cluster = cluster       # closed with the client by close_client
    return client


def close_client(client) -> None:
    cluster = getattr(client, "_taichi_dem_cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


def _progress_line(done: int, running: int, left: int, failed: int, eta: float) -> str:
    eta_s = "?" if not math.isfinite(eta) else (f"{eta:.0f} s" if eta < 120 else f"{eta / 60:.1f} min")
    return (f"sweep: {done} done, {running} running, {left} left"
            + (f" ({failed} failed)" if failed else "") + f"; ETA {eta_s}")


def run_sweep(specs: list[RunSpec], out_dir: str, client=None, *, scheduler: Optional[str] = None,
              workers: Optional[int] = None, progress: bool = True,
              timeout: Optional[float] = None) -> list[dict]:
    """Run every spec not finished yet under ``out_dir/runs/`` on Dask and return all records
    in the order of ``specs`` (finished ones from their ``done.json``, marked ``reused``).
    A failed run gives a record with ``status`` "failed" and its ``message``; the others go on.
    Progress on stderr: runs done / running / left and an ETA from the mean run time."""
    from distributed import wait
    runs = Path(out_dir) / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    records: dict[str, dict] = {}
    todo = []
    for s in specs:
        marker = runs / s.id / "done.json"
        if marker.exists():
            rec = json.loads(marker.read_text())
            rec["reused"] = True
            records[s.id] = rec
        else:
            (runs / s.id / "running").unlink(missing_ok=True)    # left by a killed sweep
            todo.append(s)
    if progress and records:
        print(f"sweep: {len(records)} of {len(specs)} runs already finished in {runs} (skipped)",
              file=sys.stderr)
    own = client is None and todo
    if own:
        client = make_client(scheduler, workers)
    try:
        if todo:
            slots = max(sum(client.nthreads().values()), 1)
            futures = {client.submit(execute_run, asdict(s), str(runs / s.id), timeout,
                                     key=f"taichi-dem-run-{s.id}", pure=False): s for s in todo}
            pending = set(futures)
            t0 = time.perf_counter()
            durations: list[float] = []
            failed = 0
            shown = ""
            while pending:
                try:
                    finished, pending = wait(pending, timeout=1.0, return_when="FIRST_COMPLETED")
                except TimeoutError:                 # none finished in that second
                    finished = set()
                for fut in finished:
                    s = futures[fut]
                    try:
                        rec = fut.result()
                    except Exception as err:         # the task itself failed (worker lost, ...)
                        rec = {"id": s.id, "status": "failed", "message": f"{type(err).__name__}: {err}",
                               "overrides": s.overrides, "seed": s.seed, "labels": s.labels}
                    records[s.id] = rec
                    if rec["status"] == "done":
                        durations.append(float(rec.get("wall_s", 0.0)))
                    else:
                        failed += 1
                        print(f"\nsweep: run {s.id} failed: {rec.get('message', '')}", file=sys.stderr)
                if progress:
                    running = sum(1 for f in pending if (runs / futures[f].id / "running").exists())
                    left = len(pending) - running
                    mean = (sum(durations) / len(durations)) if durations else math.nan
                    elapsed = time.perf_counter() - t0
                    eta = mean * (left + 0.5 * running) / slots if durations else math.nan
                    line = _progress_line(len(records), running, left, failed, eta)
                    if line != shown or not pending:
                        print(f"\r{line}   (wall {elapsed:.0f} s)", end="", file=sys.stderr, flush=True)
                        shown = line
            if progress:
                print(file=sys.stderr)
    finally:
        if own:
            close_client(client)
    return [records[s.id] for s in specs]


# ------------------------------------------------------------------------------ the table
def output_names(records: list[dict]) -> list[str]:
    """Every output name that any finished run reported, in first-seen order."""
    names: list[str] = []
    for r in records:
        for k in r.get("outputs", {}):
            if k not in names:
                names.append(k)
    return names


def table_rows(records: list[dict]) -> tuple[list[str], list[list]]:
    """(header, rows) of the results table: labels, overrides, fixed columns, outputs
    (``name [unit]``), message."""
    from .outputs import unit
    label_keys = list(dict.fromkeys(k for r in records for k in r.get("labels", {})))
    keys = list(dict.fromkeys(k for r in records for k in r.get("overrides", {})))
    outs = output_names(records)
    header = (label_keys + keys + list(FIXED_COLUMNS)
              + [f"{o} [{unit(o)}]" if unit(o) else o for o in outs] + ["message"])
    rows = []
    for r in records:
        row = [r.get("labels", {}).get(k, "") for k in label_keys]
        row += [r.get("overrides", {}).get(k, "") for k in keys]
        row += [r.get(c, "") if c != "resumed" else bool(r.get("resumed", False)) for c in FIXED_COLUMNS]
        row += [r.get("outputs", {}).get(o, "") for o in outs]
        row.append(r.get("message", ""))
        rows.append(row)
    return header, rows


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "yes" if v else ""
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.4g}"
    if isinstance(v, (list, dict)):
        return json.dumps(v)
    return str(v)


def write_table(records: list[dict], out_dir: str, title: str, command: str) -> tuple[Path, Path]:
    """``results.csv`` (full precision) and ``sweep.md`` (4 significant digits) in ``out_dir``."""
    out = Path(out_dir)
    header, rows = table_rows(records)
    csv_path = out / RESULTS_CSV
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for row in rows:
            w.writerow([json.dumps(v) if isinstance(v, (list, dict)) else v for v in row])
    md = [f"# {title}", "", f"`{command}`", "",
          f"{sum(r['status'] == 'done' for r in records)} of {len(records)} runs finished"
          f" ({sum(bool(r.get('reused')) for r in records)} from an earlier sweep). "
          "wall_s: the whole run (start-up, building, stepping, reading the outputs back); "
          "build_s: building the simulation; compile_s: kernel compilation at the first "
          "steps (a new dt compiles anew); step_s, cpu_s: stepping wall and CPU seconds, "
          "compilation left out (the rate after the first output sample times all steps); "
          "particle-steps/s over step_s; outputs: means over the last 25 % of the run "
          "(taichi_dem/app/outputs.py).", "",
          "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(_fmt(v).replace("|", "/") for v in row) + " |" for row in rows]
    fails = [r for r in records if r["status"] != "done"]
    if fails:
        md += ["", "Failed runs:", ""] + [f"- `{r['id']}`: {r.get('message', '')}" for r in fails]
    md_path = out / RESULTS_MD
    md_path.write_text("\n".join(md) + "\n")
    return csv_path, md_path


# ------------------------------------------------------------------------------ CLI
def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="the base scene file (TOML); each run changes keys of it")
    p.add_argument("--set", action="append", default=[], metavar="KEY=V1,V2,...", dest="sets",
                   help="a dotted scene key and its values, e.g. interactions.0.friction=0.3,0.5 "
                        "(repeat for more keys: their cross product is run)")
    p.add_argument("--zip", action="store_true",
                   help="pair the i-th values of every --set instead of the cross product")
    p.add_argument("--seeds", type=int, default=1, metavar="N",
                   help="repeat each combination with N placement seeds (simulation.seed, +1, ...)")
    p.add_argument("--out", default="sweep", help="directory for runs/ and the tables (default sweep)")
    p.add_argument("--duration", type=float, metavar="S", help="simulated time per run, s (sets "
                                                               "simulation.end_time)")
    p.add_argument("--checkpoint-interval", type=float, metavar="S",
                   help="s of simulated time between each run's checkpoints (default the scene's; "
                        "a killed run continues from its latest one)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="an existing Dask scheduler "
                                                                  "(default: a LocalCluster here)")
    p.add_argument("--workers", type=int, metavar="N", help="LocalCluster workers (default: cores)")
    p.add_argument("--threads", type=int, metavar="N",
                   help="CPU threads per run (default cores / workers, at least 1)")
    p.add_argument("--arch", default="cpu", choices=["cpu", "gpu", "cuda", "vulkan", "metal"],
                   help="where the kernels run: cpu, or a GPU backend (gpu picks one; default cpu)")
    p.add_argument("--timeout", type=float, metavar="S", help="wall-clock limit per run, s")
    p.add_argument("--quiet", action="store_true", help="no progress output")


def threads_per_run(workers: Optional[int], threads: Optional[int]) -> int:
    if threads:
        return threads
    cores = os.cpu_count() or 1
    return max(1, cores // (workers or cores))


def cmd_sweep(args) -> int:
    """Run the sweep the arguments describe; exit 0 when every run finished, 1 when some
    failed (the table lists them with their messages), 2 on bad input."""
    sets = [ov.parse_set(a) for a in args.sets]
    combos = ov.combinations(sets, zip_=args.zip)
    specs = plan(args.scene, combos, args.seeds, duration=args.duration,
                 threads=threads_per_run(args.workers, args.threads), arch=args.arch,
                 checkpoint_interval=args.checkpoint_interval)
    if not args.quiet:
        print(f"sweep: {len(specs)} runs of {args.scene} ({len(combos)} combinations x "
              f"{args.seeds} seeds) in {args.out}", file=sys.stderr)
    records = run_sweep(specs, args.out, scheduler=args.scheduler, workers=args.workers,
                        progress=not args.quiet, timeout=args.timeout)
    command = "taichi-dem sweep " + " ".join(sys.argv[2:]) if sys.argv[1:2] == ["sweep"] else \
        f"taichi-dem sweep {args.scene} " + " ".join(f"--set {a}" for a in args.sets)
    csv_path, md_path = write_table(records, args.out, f"Sweep of {args.scene}", command)
    _print_summary(records)
    print(f"results: {csv_path}, {md_path}")
    return 0 if all(r["status"] == "done" for r in records) else 1


def _print_summary(records: list[dict]) -> None:
    for r in records:
        o = " ".join(f"{k}={ov._show(v)}" for k, v in r.get("overrides", {}).items())
        if r["status"] == "done":
            outs = ", ".join(f"{k} {v:.4g}" for k, v in r.get("outputs", {}).items())
            print(f"{r['id']}: {o} seed {r['seed']}: {r['step_s']:.2f} s stepping "
                  f"({r.get('cpu_s', math.nan):.2f} s CPU), {outs}")
        else:
            print(f"{r['id']}: {o} seed {r['seed']}: FAILED: {r.get('message', '')}")


def _main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m taichi_dem.app.sweep",
                                description="run one planned sweep run (used by the workers)")
    p.add_argument("--run-dir", required=True)
    args = p.parse_args(argv)
    from ..run import checkpoint
    checkpoint.KEEP_LAST_GOOD = False
    return _run_here(args.run_dir)


if __name__ == "__main__":
    sys.exit(_main())
