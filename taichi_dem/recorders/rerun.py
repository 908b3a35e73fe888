"""Rerun recorder: a simulation observer that writes a ``.rrd`` file or streams to a viewer.

    rec = RerunRecorder("out/pile.rrd")          # headless; or spawn=True / connect=URL
    sim.add_observer(rec)                        # logs at every output sample
    sim.run(1.0); sim.close()                    # close() flushes and closes the file

What is logged (CONTRACT.md, "Rerun"), all on the ``sim_time`` timeline (a duration, s):

- ``particles``: ``Points3D`` (positions, radii, colours). Coloured by the first field the
  effects name for it that the particles carry (scene/catalog.py colour_fields: the
  temperature, with heat transfer), else by speed, through a fixed viridis ramp. The ramp's
  range only ever widens (so colours stay comparable along the run); its ends are logged as
  the scalars ``colour_scale/min`` and ``colour_scale/max`` and described in the text
  document ``colour_scale/legend``.
  ``every_nth`` and ``region`` decimate what is drawn (not what is simulated).
- ``bodies/<name>``: a ``Mesh3D`` of the body at t = 0, logged once (static), moved by a
  ``Transform3D`` at each sample: rotation by the body's angle about its axis through its axis
  point, and its translation (x(t) = R (x0 - p) + p + v t).
- ``series/<name>``: every /series quantity as ``Scalars``; a vector quantity as one scalar per
  component, ``series/<name>/x|y|z``.
- A blueprint: the 3D view beside plots of body torque, mass flow, the effects' views
  (scene/catalog.py series_views: the temperatures) and kinetic energy (those present).

Each recorder has a recording stream of its own, so several simulations can record side by side.
"""
from __future__ import annotations

import fnmatch
import time as _time
from pathlib import Path
from typing import Optional, Sequence

import numpy as np

from ..scene import catalog


# viridis at eleven evenly spaced points (matplotlib's values, rounded); interpolated linearly
_VIRIDIS = np.array([
    [68, 1, 84], [72, 36, 117], [65, 68, 135], [53, 95, 141], [42, 120, 142], [33, 145, 140],
    [34, 168, 132], [68, 191, 112], [122, 209, 81], [189, 223, 38], [253, 231, 37]], float)

_COMPONENTS = ("x", "y", "z")


def colormap(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """(N, 3) uint8 viridis colours of ``values`` on the scale [lo, hi] (clipped)."""
    span = hi - lo
    u = np.clip((np.asarray(values, float) - lo) / span, 0.0, 1.0) if span > 0 else \
        np.zeros(np.shape(values))
    x = u * (len(_VIRIDIS) - 1)
    i = np.minimum(x.astype(np.int64), len(_VIRIDIS) - 2)
    f = (x - i)[:, None]
    return (_VIRIDIS[i] * (1.0 - f) + _VIRIDIS[i + 1] * f + 0.5).astype(np.uint8)


class RerunRecorder:
    """Observer ``(sim, values)`` logging a simulation to rerun (see the module doc).

    path: ``.rrd`` file to write (headless). spawn: start a viewer and stream to it.
    connect: URL of a running viewer to stream to (e.g. "rerun+http://127.0.0.1:9876/proxy").
    every_nth: draw every Nth particle (by id order). region: ((xmin, ymin, zmin), (xmax, ymax,
    zmax)), draw only particles inside it. color_range: (lo, hi) fixes the colour scale instead
    of widening it to the values seen.
    """

    def __init__(self, path: Optional[str] = None, spawn: bool = False, every_nth: int = 1,
                 application_id: str = "taichi_dem", *, connect: Optional[str] = None,
                 region: Optional[Sequence[Sequence[float]]] = None,
                 color_range: Optional[Sequence[float]] = None, recording_id=None):
        import rerun as rr

        if every_nth < 1:
            raise ValueError("every_nth must be 1 or more")
        self.rr = rr
        self.path = str(path) if path else None
        self.spawn = bool(spawn)
        self.connect = connect
        self.every_nth = int(every_nth)
        self.region = None if region is None else (np.asarray(region[0], float),
                                                   np.asarray(region[1], float))
        self.fixed_range = None if color_range is None else (float(color_range[0]),
                                                             float(color_range[1]))
        self.stream = rr.RecordingStream(application_id, recording_id=recording_id)
        self.stream.set_log_tick_enabled(False)
        self.stream.set_log_time_enabled(False)
        self.wall_seconds = 0.0      # time spent in this observer, s
        self.samples = 0
        self._started = False
        self._closed = False
        self._range: Optional[list] = None
        self._quantity: Optional[str] = None

    # ------------------------------------------------------------------ setup
    def _blueprint(self, sim, names):
        import rerun.blueprint as rrb

        plots = []
        torque = [f"+ /series/bodies/{b.name}/axial_torque" for b in sim.scene.bodies]
        if torque:
            plots.append(rrb.TimeSeriesView(name="axial torque (N m)", origin="/series",
                                            contents=torque))
        flow = sorted(f"+ /series/{n}" for n in names if n.endswith("/mass_flow"))
        if flow:
            plots.append(rrb.TimeSeriesView(name="mass flow (kg/s)", origin="/series",
                                            contents=flow))
        sensors = getattr(sim.scene, "sensors", ())
        residence = sorted(f"+ /series/sensors/{x.name}/{k}" for x in sensors
                           if x.kind == "residence_time" for k in ("median", "p10", "p90"))
        if residence:
            plots.append(rrb.TimeSeriesView(name="residence time (s)", origin="/series",
                                            contents=residence))
        # the views the effects ask for (scene/catalog.py series_views: the temperatures)
        for title, patterns in catalog.series_views().items():
            chosen = sorted(f"+ /series/{n}" for n in names
                            if any(fnmatch.fnmatchcase(n, p) for p in patterns))
            if chosen:
                plots.append(rrb.TimeSeriesView(name=title, origin="/series", contents=chosen))
        if "particles/kinetic_energy" in names:
            plots.append(rrb.TimeSeriesView(name="kinetic energy (J)", origin="/series",
                                            contents=["+ /series/particles/kinetic_energy"]))
        plots.append(rrb.TimeSeriesView(name="colour scale", origin="/colour_scale",
                                        contents=["+ /colour_scale/min", "+ /colour_scale/max"]))
        left = rrb.Vertical(
            rrb.Spatial3DView(name="particles and bodies", origin="/",
                              contents=["+ /**", "- /series/**", "- /colour_scale/**"]),
            rrb.TextDocumentView(name="colour scale", origin="/colour_scale/legend"),
            row_shares=[6, 1])
        return rrb.Blueprint(rrb.Horizontal(left, rrb.Vertical(*plots), column_shares=[3, 2]),
                             collapse_panels=True)

    def _start(self, sim, values):
        rr = self.rr
        blueprint = self._blueprint(sim, values)
        sinks = []
        if self.path:
            Path(self.path).parent.mkdir(parents=True, exist_ok=True)
            sinks.append("file")
        if self.spawn or self.connect:
            sinks.append("grpc")
        if sinks == ["file"]:
            self.stream.save(self.path, default_blueprint=blueprint)
        elif sinks == ["grpc"] and self.connect:
            self.stream.connect_grpc(self.connect, default_blueprint=blueprint)
        elif sinks == ["grpc"]:
            self.stream.spawn(default_blueprint=blueprint)
        elif sinks:
            if self.spawn:
                self.stream.spawn(connect=False)
            grpc = rr.GrpcSink(self.connect) if self.connect else rr.GrpcSink()
            self.stream.set_sinks(rr.FileSink(self.path), grpc, default_blueprint=blueprint)
        else:
            # no sink: keep the data in memory (tests, notebooks: self.stream.memory_recording())
            self.stream.send_blueprint(blueprint)
        self.stream.log("/", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        for body in sim.scene.bodies:
            self.stream.log(f"bodies/{body.name}", rr.Mesh3D(
                vertex_positions=np.asarray(body.vertices, np.float32),
                triangle_indices=np.asarray(body.faces, np.uint32),
                albedo_factor=[150, 150, 160, 255]), static=True)
        self._started = True

    # ------------------------------------------------------------------ every sample
    def __call__(self, sim, values):
        if self._closed:
            return
        t0 = _time.perf_counter()
        rr = self.rr
        if not self._started:
            self._start(sim, values)
        stream = self.stream
        t = float(values.get("time", sim.time))
        stream.set_time("sim_time", duration=t)
        self._log_particles(sim, values)
        self._log_bodies(sim, t)
        for name, v in values.items():
            if name == "time":
                continue
            a = np.asarray(v, np.float64)
            if a.ndim == 0:
                stream.log(f"series/{name}", rr.Scalars(a.reshape(1)))
            else:
                flat = a.reshape(-1)
                labels = _COMPONENTS if len(flat) == 3 else [str(i) for i in range(len(flat))]
                for c, x in zip(labels, flat):
                    stream.log(f"series/{name}/{c}", rr.Scalars([x]))
        self.samples += 1
        self.wall_seconds += _time.perf_counter() - t0

    @staticmethod
    def _colour_field(p):
        """(name, unit, values) of the first field the effects colour particles by that the
        frame ``p`` has (scene/catalog.py colour_fields: the temperature), or None."""
        fields = catalog.frame_fields()
        for name in catalog.colour_fields():
            if name in p:
                return name, fields[name][0], np.asarray(p[name], float)
        return None

    def _log_particles(self, sim, values):
        rr = self.rr
        p = sim.particles()
        pos = p["position"]
        keep = np.zeros(len(pos), bool)
        keep[::self.every_nth] = True
        if self.region is not None:
            lo, hi = self.region
            keep &= np.all((pos >= lo) & (pos <= hi), axis=1)
        coloured = self._colour_field(p)
        if coloured is not None:
            quantity, unit, field = coloured[0], coloured[1], coloured[2][keep]
        else:
            quantity, unit = "speed", "m/s"
            field = np.linalg.norm(p["velocity"][keep], axis=1)
        changed = quantity != self._quantity
        if changed:
            self._quantity, self._range = quantity, None
        if self.fixed_range is not None:
            if self._range is None:
                self._range = list(self.fixed_range)
        elif len(field):
            lo, hi = float(np.min(field)), float(np.max(field))
            if self._range is None:
                self._range = [lo, hi]
                changed = True
            elif lo < self._range[0] or hi > self._range[1]:
                self._range = [min(lo, self._range[0]), max(hi, self._range[1])]
                changed = True
        lo, hi = self._range if self._range is not None else (0.0, 1.0)
        self.stream.log("particles", rr.Points3D(
            pos[keep].astype(np.float32), radii=p["radius"][keep].astype(np.float32),
            colors=colormap(field, lo, hi)))
        self.stream.log("colour_scale/min", rr.Scalars([lo]))
        self.stream.log("colour_scale/max", rr.Scalars([hi]))
        if changed:
            shown = int(np.count_nonzero(keep))
            self.stream.log("colour_scale/legend", rr.TextDocument(
                f"**particles coloured by {quantity}** (viridis): dark purple = {lo:.4g} {unit}, "
                f"green = {(lo + hi) / 2:.4g} {unit}, yellow = {hi:.4g} {unit}. "
                f"Showing {shown} of {len(pos)} particles"
                + (f" (every {self.every_nth}th)" if self.every_nth > 1 else "")
                + (" inside the region" if self.region is not None else "") + ".",
                media_type=rr.MediaType.MARKDOWN))

    def _log_bodies(self, sim, t):
        rr = self.rr
        kin = getattr(sim.engine, "kinematics", None)
        for k, body in enumerate(sim.scene.bodies):
            axis = np.asarray(body.motion.axis_direction, float)
            angle = float(kin.angle(k, t)) if kin is not None else 0.0
            # the pose the results file records too (BodyKinematics.pose): x = R x0 + T
            translation = kin.pose(k, t)[1] if kin is not None else np.zeros(3)
            self.stream.log(f"bodies/{body.name}", rr.Transform3D(
                translation=translation,
                rotation_axis_angle=rr.RotationAxisAngle(axis=axis, radians=angle)))

    # ------------------------------------------------------------------ end
    def close(self):
        """Flush and close the file or connection (called by ``sim.close()``)."""
        if self._closed:
            return
        self._closed = True
        t0 = _time.perf_counter()
        if self._started:
            try:
                self.stream.flush()
            except RuntimeError as err:     # a viewer that went away must not fail the run
                import sys
                print(f"taichi-dem: warning: rerun: {err}", file=sys.stderr)
            if self.path or self.spawn or self.connect:
                self.stream.disconnect()
        self.wall_seconds += _time.perf_counter() - t0
