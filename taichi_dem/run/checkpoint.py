"""Checkpoints: the whole state of a Simulation in one HDF5 file, and resuming from it.

What is saved (enough to continue bit for bit on the same arch, precision and thread count):

* every Taichi field of every ``FieldTree`` the engine owns (``engine.trees`` and the pair
  arrays' tree), by tree label (the tree's first field name) and field name, so fields other
  modules add later are saved without touching this file. Fields placed in a builder
  directly, not through ``FieldTree.add``, are not seen (``MeshContacts.rotation`` is one:
  it is recomputed from the time before every use);
* the sizes the arrays had (pair capacity, candidate scratch widths, mesh entry capacities),
  so a resumed run re-allocates them before loading;
* host state: the attributes in ``HOST_ATTRIBUTES`` (time, step count, alive count, the
  mesh re-binning time, warned-once flags ...), each body's speed schedule (``set_speed``
  changes it), every ``numpy.random.Generator`` held by the simulation or the engine, the
  /series sampled so far, the scene TOML text and its path, dt, precision, arch;
* the state of every host-side component in ``sim.checkpointables`` (factories, outlets,
  sensors, ...): ``{name: obj}`` with ``obj.state_dict() -> {key: numpy array | float | int |
  str}`` and ``obj.load_state_dict(d)``, under ``/host/<name>/`` (arrays as datasets, scalars
  and strings as attributes).

A checkpoint is written to a temporary file in the same directory, flushed and fsync'ed, then
moved over the old one with ``os.replace`` (atomic on POSIX): a reader, or a run killed at
any moment, sees either the previous checkpoint or the new one, never half of one.

Layout: / attrs (format, taichi_dem version, scene, source, dt, precision, arch, time,
step_count, count, capacities, host attributes, schedules, rng states, results file);
/fields/<tree label>/<field name>; /series/<name> (as in the results file);
/host/<component>/<key>.
"""
from __future__ import annotations

import json
import math
import os
import sys
import time as _time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import h5py
import numpy as np

from .._version import __version__
from ..errors import CheckpointError
from ..files import remove_stale_side_files, side_path

# 2: f32 scenes with heat keep f64 residuals of temperature and moisture (engine/precision.py);
# a version-1 file lacks them, and would resume with temperatures off by up to half an f32 step
FORMAT = "taichi_dem checkpoint 2"

# Keep the last good state in memory at every sample (Checkpointer.keep_last_good) by
# default? The copy itself is cheap (36 ms per sample at 20,000 particles, BENCHMARKS.md),
# but the first copy of a new simulation compiles one copy kernel per field (1-8 s), which a
# script or test building many small simulations should not pay. The CLI turns it on.
KEEP_LAST_GOOD = False

# host attributes saved and restored by name, (owner, attribute); a missing one is skipped
HOST_ATTRIBUTES = (
    ("sim", "time"), ("sim", "step_count"), ("sim", "_warned_thermal"), ("sim", "_warned_speed"),
    ("sim", "_last_sample_time"), ("sim", "_next_frame_time"), ("sim", "_interval_tail"),
    ("engine", "time"), ("engine", "count"),
    ("broadphase", "rebuilds"), ("broadphase", "entries"),
    # (the lists' age: an effect's forced rebuilds, Model.rebuild_within_steps, keep their
    # schedule across a resume; a file without it resumes with the age at 0)
    ("broadphase", "list_age"),
    ("mesh", "binned_time"), ("mesh", "interval_steps"),
)


@dataclass
class Snapshot:
    """One captured state, in host memory (numpy); ``write`` puts it in a file."""
    time: float
    attrs: dict
    fields: dict[str, dict[str, np.ndarray]]
    host: dict[str, dict]
    series: dict[str, list]            # references to the live lists ...
    series_len: dict[str, int] = field(default_factory=dict)   # ... and their length then

    def series_arrays(self) -> dict[str, np.ndarray]:
        return {k: np.array(v[: self.series_len[k]], dtype=np.float64) for k, v in self.series.items()}


# ------------------------------------------------------------------------------ engine walk
# the per-triangle arrays (bodies/frames.py BodyTriangles, bodies/surface_survey.py), allocated
# with more slots than triangles since setup/tuning.py MIN_TRIANGLE_SLOTS
TRIANGLE_SLOT_FIELDS = frozenset({"tri_a", "tri_b", "tri_c", "tri_body", "tri_normal",
                                  "touched_triangle"})


def field_trees(engine) -> dict:
    """Live FieldTrees of an engine by label (first field name; unique by construction)."""
    # (the run-time scene values are the scene's, not state: rebuilt, never saved)
    trees = [t for t in engine.trees if t is not getattr(engine.values, "tree", None)]
    if engine.pairs is not None:
        trees.append(engine.pairs.tree)
    out, seen = {}, set()
    for t in trees:
        if id(t) in seen or not t.fields:
            continue
        seen.add(id(t))
        label = next(iter(t.fields))
        while label in out:
            label += "+"
        out[label] = t
    return out


def capacities(engine) -> dict[str, int]:
    """Sizes of the arrays that grow during a run."""
    c = {"particles": int(engine.state.capacity), "pairs": int(engine.pairs.capacity),
         "scratch_width": int(engine.broadphase.scratch_width)}
    m = engine.mesh
    if m is not None:
        c.update(mesh_items=int(m.items_capacity), mesh_scratch_width=int(m.scratch_width),
                 mesh_entries=int(m.entries_capacity))
    return c


def reallocate(engine, caps: dict) -> None:
    """Give the growable arrays the sizes ``caps`` (and recompile what uses them)."""
    # a checkpoint written before the slots came in buckets (engine/values.py) holds fewer:
    # its rows fill the first slots (restore pads them)
    if caps["particles"] > engine.state.capacity:
        raise CheckpointError(f"the checkpoint holds {caps['particles']} particle slots, this "
                              f"scene allocates {engine.state.capacity}")
    m = engine.mesh
    if m is not None:
        if m.items_capacity != caps["mesh_items"]:
            m._alloc_items(caps["mesh_items"])
            m._compile_binning()
        rows = False
        if m.scratch_width != caps["mesh_scratch_width"]:
            m._alloc_scratch(caps["mesh_scratch_width"])
            rows = True
        if m.entries_capacity != caps["mesh_entries"]:
            m._alloc_entries(caps["mesh_entries"])
            rows = True
        if rows:
            m._compile_rows()
    bp = engine.broadphase
    if bp.scratch_width != caps["scratch_width"]:
        bp._compile_search(caps["scratch_width"])
    # new pair arrays of the saved size; recompiles every kernel that touches pairs or mesh
    # entries (compiled lazily on first use)
    engine.grow_pairs(caps["pairs"])


def _owners(sim) -> dict:
    e = sim.engine
    return {"sim": sim, "engine": e, "broadphase": e.broadphase, "mesh": e.mesh}


def _generators(sim) -> dict:
    out = {}
    for owner_name, owner in _owners(sim).items():
        if owner is None:
            continue
        for attr, value in vars(owner).items():
            if isinstance(value, np.random.Generator):
                out[f"{owner_name}.{attr}"] = value
    return out


# ------------------------------------------------------------------------------ capture/write
def capture(sim) -> Snapshot:
    """The simulation's whole state now, copied to host memory."""
    from ..engine import transfer      # (here: the CLI imports this module without Taichi)
    e = sim.engine
    fields = {label: dict(zip(tree.kept(), transfer.read(tree.kept().values())))
              for label, tree in field_trees(e).items()}
    host_attrs = {}
    for owner_name, attr in HOST_ATTRIBUTES:
        owner = _owners(sim).get(owner_name)
        if owner is not None and hasattr(owner, attr):
            value = getattr(owner, attr)
            host_attrs[f"{owner_name}.{attr}"] = value.item() if isinstance(value, np.generic) else value
    kin = getattr(e, "kinematics", None)
    schedules = [[list(r) for r in rows] for rows in kin.schedules] if kin is not None else []
    rngs = {k: g.bit_generator.state for k, g in _generators(sim).items()}
    recorder = getattr(sim, "recorder", None)
    attrs = {
        "format": FORMAT, "taichi_dem_version": _version(), "scene": sim.scene.text,
        "source": _abs_source(sim.scene.source), "dt": float(sim.dt),
        "precision": sim.precision, "arch": sim.arch, "time": float(sim.time),
        "step_count": int(sim.step_count), "count": int(e.count),
        "capacities": json.dumps(capacities(e)), "host_attributes": json.dumps(host_attrs),
        "schedules": json.dumps(schedules), "rng_states": json.dumps(rngs),
        "results": os.path.abspath(recorder.path) if recorder is not None else "",
    }
    host = {name: dict(obj.state_dict()) for name, obj in getattr(sim, "checkpointables", {}).items()}
    series = dict(sim._series)
    return Snapshot(float(sim.time), attrs, fields, host, series,
                    {k: len(v) for k, v in series.items()})


def write(path: str, snap: Snapshot) -> None:
    """Write ``snap`` to ``path`` atomically (temp file, fsync, os.replace)."""
    path = os.path.abspath(path)
    directory = os.path.dirname(path)
    os.makedirs(directory, exist_ok=True)
    tmp = side_path(path, "tmp")
    remove_stale_side_files(path)
    try:
        with h5py.File(tmp, "w") as f:
            for k, v in snap.attrs.items():
                f.attrs[k] = v
            g = f.create_group("fields")
            for label, arrays in snap.fields.items():
                gl = g.create_group(label)
                for name, a in arrays.items():
                    gl.create_dataset(name, data=a)
            gs = f.create_group("series")
            for name, a in snap.series_arrays().items():
                gs.create_dataset(name, data=a)
            gh = f.create_group("host")
            for name, d in snap.host.items():
                _write_state_dict(gh.create_group(name), name, d)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    try:            # make the rename itself durable
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
    except OSError:
        pass


def _write_state_dict(group, name, d: dict):
    for key, value in d.items():
        if "/" in key:
            raise ValueError(f"checkpointable '{name}': key '{key}' may not contain '/'")
        if isinstance(value, (str, bool, int, float, np.generic)):
            group.attrs[key] = value
        else:
            group.create_dataset(key, data=np.asarray(value))


def _read_state_dict(group) -> dict:
    d = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in group.attrs.items()}
    for key, ds in group.items():
        d[key] = ds[()]
    return d


def load(path: str) -> Snapshot:
    """Read a checkpoint file into memory (CheckpointError when it is not one)."""
    try:
        f = h5py.File(path, "r")
    except (OSError, ValueError) as err:
        raise CheckpointError(f"{path}: cannot open as an HDF5 checkpoint ({err})") from None
    with f:
        found = f.attrs.get("format")
        if isinstance(found, str) and found.startswith("taichi_dem checkpoint ") and found != FORMAT:
            raise CheckpointError(f"{path}: written by an older taichi_dem ({found!r}; this "
                                  f"version reads {FORMAT!r}): rerun the scene from its start")
        if found != FORMAT:
            raise CheckpointError(f"{path}: not a taichi_dem checkpoint (format "
                                  f"{found!r}, expected {FORMAT!r})")
        attrs = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in f.attrs.items()}
        fields = {label: {name: ds[()] for name, ds in g.items()} for label, g in f["fields"].items()}
        series: dict[str, list] = {}

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                series[name] = list(obj[()])
        f["series"].visititems(visit)
        host = {name: _read_state_dict(g) for name, g in f["host"].items()}
    return Snapshot(float(attrs["time"]), attrs, fields, host, series,
                    {k: len(v) for k, v in series.items()})


# ------------------------------------------------------------------------------ restore
def restore(sim, snap: Snapshot) -> None:
    """Load ``snap`` into ``sim`` (built from the same scene text, arch and precision)."""
    a = snap.attrs
    if a["precision"] != sim.precision:
        raise CheckpointError(f"the checkpoint is {a['precision']}, the simulation {sim.precision}")
    e = sim.engine
    reallocate(e, json.loads(a["capacities"]))
    from ..engine import transfer
    missing = []
    writes = []
    zero_between_steps = e.state.ZERO_BETWEEN_STEPS
    for label, tree in field_trees(e).items():
        saved = snap.fields.get(label, {})
        for name, f in tree.kept().items():
            if name not in saved:
                if tree is e.state.tree and name in zero_between_steps:
                    f.fill(0)          # (a checkpoint from before these sums existed)
                else:
                    missing.append(f"{label}/{name}")
                continue
            arr = saved[name]
            shape = transfer.host_shape(f)
            saved_slots = json.loads(a["capacities"])["particles"]
            if (arr.shape != shape and arr.shape[1:] == shape[1:] and arr.ndim >= 1
                    and arr.shape[0] in (saved_slots, saved_slots + 1)
                    and shape[0] - arr.shape[0] == e.state.capacity - saved_slots):
                # per-slot rows of a checkpoint with fewer slots: the rest stay empty
                padded = np.zeros(shape, arr.dtype)
                padded[:arr.shape[0]] = arr
                arr = padded
            if (name in TRIANGLE_SLOT_FIELDS and arr.shape[1:] == shape[1:]
                    and arr.shape[0] < shape[0]):
                # the bodies' triangles of a checkpoint from before their slots had a floor
                # (one row per triangle): the same triangles, the other slots empty
                padded = np.zeros(shape, arr.dtype)
                padded[:arr.shape[0]] = arr
                arr = padded
            if arr.shape != shape:
                raise CheckpointError(f"field {label}/{name}: saved shape {arr.shape}, "
                                      f"allocated {shape}")
            writes.append((f, arr))
    transfer.write(writes)
    if missing:
        print(f"taichi-dem: warning: the checkpoint has no values for {', '.join(missing)}; "
              f"they keep their freshly built values", file=sys.stderr)
    owners = _owners(sim)
    for key, value in json.loads(a["host_attributes"]).items():
        owner_name, attr = key.split(".", 1)
        if owners.get(owner_name) is not None:
            setattr(owners[owner_name], attr, value)
    kin = getattr(e, "kinematics", None)
    if kin is not None:
        kin.schedules = [[tuple(r) for r in rows] for rows in json.loads(a["schedules"])]
        e.mesh.upload_schedules()
    generators = _generators(sim)
    for key, state in json.loads(a["rng_states"]).items():
        if key in generators:
            generators[key].bit_generator.state = state
    sim._series = {k: list(v) for k, v in snap.series_arrays().items()}
    host = getattr(sim, "checkpointables", {})
    for name, d in snap.host.items():
        if name in host:
            host[name].load_state_dict(d)
        else:
            print(f"taichi-dem: warning: the checkpoint holds state for '{name}', which this "
                  f"simulation does not have; ignored", file=sys.stderr)
    for name in host:
        if name not in snap.host:
            print(f"taichi-dem: warning: the checkpoint has no state for '{name}'; it starts "
                  f"afresh", file=sys.stderr)


def resume(path: str, *, build, arch: Optional[str] = None, threads: Optional[int] = None,
           h5: Optional[str] = None, checkpoint: Optional[str] = None, configure=None):
    """A Simulation continuing from checkpoint ``path`` (``Simulation.from_checkpoint``).

    ``build`` makes the simulation, called as ``build(scene, arch=, precision=, threads=,
    h5="")``: the Simulation class, passed in because this module does not import the run
    driver (which attaches the checkpoint writer as one of its observers). Results: ``h5``
    (default the results file the checkpointed run wrote, when it still exists; "" for none)
    is continued: its series and frames after the checkpoint time are dropped and the run
    appends from there. Further checkpoints go to ``checkpoint`` (default ``path`` itself).
    ``configure(sim)``, if given, runs after the simulation is built and before the state is
    loaded (to register checkpointables that a script adds)."""
    from ..scene.loader import parse_scene

    snap = load(path)
    a = snap.attrs
    source = a["source"]
    base_dir = None if source.startswith("<") else str(Path(source).parent)
    scene = parse_scene(a["scene"], source=source, base_dir=base_dir)
    sim = build(scene, arch=arch or a["arch"], precision=a["precision"], threads=threads, h5="")
    if configure is not None:
        configure(sim)
    restore(sim, snap)
    sim.checkpointer.restart(sim, checkpoint or path)
    if h5 is None:
        h5 = a.get("results") or ""
        if h5 and not os.path.exists(h5):
            h5 = ""
    if h5:
        from ..recorders.hdf5 import HDF5Recorder
        sim.recorder = HDF5Recorder.continue_at(h5, sim.time, sim.dt, sim._series,
                                                scene_text=scene.text, arch=sim.arch,
                                                precision=sim.precision)
        sim.recorder.write_bodies(scene.bodies, sim.tables.names)
    return sim


def _abs_source(source: str) -> str:
    return source if source.startswith("<") else os.path.abspath(source)


def _version() -> str:
    return __version__


def default_path(scene, h5: Optional[str] = None, out_dir: Optional[str] = None) -> str:
    """``<scene stem>.checkpoint.h5`` in ``out_dir``, else beside the results file, else beside
    the scene file (the working directory for a scene given as text)."""
    is_file = not scene.source.startswith("<")
    stem = Path(scene.source).stem if is_file else "scene"
    if out_dir:
        directory = Path(os.path.expanduser(out_dir))
    elif h5:
        directory = Path(h5).resolve().parent
    elif is_file:
        directory = Path(scene.source).resolve().parent
    else:
        directory = Path.cwd()
    return str(directory / f"{stem}.checkpoint.h5")


# ------------------------------------------------------------------------------ the hook
class Checkpointer:
    """Writes the periodic checkpoints of one simulation (``sim.checkpointer``) and keeps the
    last good state in memory for a divergence. An observer of the run: the Simulation calls
    ``after_sample(sim)`` once a sample is recorded and ``diverged(sim, err)`` when a step
    raised DivergenceError (``sim.after_sample``, ``sim.on_divergence``).

    ``path``: where checkpoints go; ``interval``: s of simulated time between them (None:
    none; the scene's ``[output] checkpoint_interval``); ``keep_last_good``: capture the state
    at every output sample that passed the divergence check (costs a host copy of all fields
    per sample, measured in BENCHMARKS.md), so a diverged run can write the last good state;
    default ``KEEP_LAST_GOOD``: on in the CLI, off from Python)."""

    def __init__(self, sim):
        self.path = default_path(sim.scene, sim.recorder.path if sim.recorder else None)
        self.interval = sim.scene.output.checkpoint_interval
        self.keep_last_good = KEEP_LAST_GOOD
        self.last_good: Optional[Snapshot] = None
        self.written = 0
        self.write_seconds = 0.0
        self.snapshots = 0
        self.snapshot_seconds = 0.0
        self.next_due = self.interval if self.interval else math.inf

    def restart(self, sim, path: str):
        """After a resume: write to ``path``; the next checkpoint one interval later."""
        self.path = path
        self.last_good = None
        self._schedule(sim)
        if self.keep_last_good:
            self.last_good = capture(sim)

    def _schedule(self, sim):
        if self.interval:
            self.next_due = (math.floor(sim.time / self.interval + 0.5 * sim.output_every
                                        * sim.dt / self.interval) + 1) * self.interval
        else:
            self.next_due = math.inf

    def after_sample(self, sim):
        """Called at the end of every output sample (the state passed the checks)."""
        # samples fall every output_every steps, not exactly at multiples of the interval:
        # the sample nearest to the due time takes the checkpoint
        due = sim.time >= self.next_due - 0.5 * sim.output_every * sim.dt
        if not (due or self.keep_last_good):
            return
        t0 = _time.perf_counter()
        snap = capture(sim)
        self.snapshots += 1
        self.snapshot_seconds += _time.perf_counter() - t0
        if self.keep_last_good:
            self.last_good = snap
        if due:
            self.save(snap)
            self._schedule(sim)

    def save(self, snap: Optional[Snapshot] = None, sim=None):
        """Write ``snap`` (or the state of ``sim`` now) to ``self.path``."""
        if snap is None:
            snap = capture(sim)
        t0 = _time.perf_counter()
        write(self.path, snap)
        self.written += 1
        self.write_seconds += _time.perf_counter() - t0
        return self.path

    def diverged(self, sim, err: Exception) -> Exception:
        """Write the last good state; returns the error with the checkpoint named."""
        if getattr(err, "checkpoint", None) is not None:
            return err
        if self.last_good is None:
            if self.written and os.path.exists(self.path):
                note = (f" The last good state was not kept (sim.checkpointer.keep_last_good "
                        f"is off); the latest periodic checkpoint is {self.path}.")
                err.checkpoint = self.path
            else:
                note = (" No checkpoint was written: the last good state was not kept "
                        "(sim.checkpointer.keep_last_good is off) or no sample passed.")
                err.checkpoint = ""
        else:
            self.save(self.last_good)
            note = (f" The last good state (t = {self.last_good.time:.6g} s) is in "
                    f"{self.path}; `taichi-dem resume {self.path}` continues from it.")
            err.checkpoint = self.path
        err.args = (str(err.args[0]) + note,) + tuple(err.args[1:])
        return err

