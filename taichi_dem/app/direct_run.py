"""A whole machine run directly, inlet to outlet, against the machine the march assembles from
its slices' map (issue 31 item 4): the check that the map and the march are the machine.

``DirectObserver`` (Simulation.add_observer) records at each output sample the hold-up in
axial bins (kg/m), the mass inside (kg), each body's axial torque (N m) and the discharge's
mass and temperature. ``reduce_direct`` takes the run's steady part - where the mass inside
has settled (MSER-5, app/steady_state.py) - and gives each figure with a standard error from
blocking: the hold-up profile and its total, the mean residence time (both as the mean of the
particles' own times from the residence sensor and as hold-up over discharge rate, Little's
law), the bodies' torques, the discharge rate and its mass-weighted temperature.
``compare`` sets them beside the march's answer (app/machine.py) with each tolerance.

Pure numpy apart from the observer's reading of the simulation; nothing here changes it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .steady_state import block_standard_error, steady_start


class DirectObserver:
    """Records a direct run's axial hold-up profile and loads (module docstring): ``bins``
    equal bins over [x0, x0 + length] (m) along the unit ``axis``."""

    def __init__(self, axis, x0: float, length: float, bins: int, outlet: str):
        self.axis = np.asarray(axis, float) / np.linalg.norm(axis)
        self.edges = x0 + np.linspace(0.0, length, bins + 1)
        self.outlet = outlet
        self.time: list[float] = []
        self.profile: list[np.ndarray] = []
        self.inside: list[float] = []
        self.loads: dict[str, list[float]] = {}
        self.discharged: list[float] = []
        self.discharge_temperature: list[float] = []

    def __call__(self, sim, values: dict):
        p = sim.particles()
        x = p["position"] @ self.axis
        mass, _ = np.histogram(x, self.edges, weights=p["mass"])
        self.time.append(float(values.get("time", sim.time)))
        self.profile.append(mass / np.diff(self.edges))
        self.inside.append(float(np.sum(p["mass"])))
        for key, value in values.items():
            if key.startswith("bodies/") and key.endswith(("/axial_torque", "/power")):
                self.loads.setdefault(key[len("bodies/"):], []).append(float(value))
        self.discharged.append(float(values.get(f"outlets/{self.outlet}/mass", math.nan)))
        self.discharge_temperature.append(float(values.get(
            f"outlets/{self.outlet}/mean_temperature", math.nan)))


def save_record(obs: DirectObserver, residence, path) -> None:
    """Write a direct run's observer and residence times to ``path`` (.npz), for a bench to
    reduce again without running (load_record)."""
    np.savez(path, time=obs.time, profile=np.asarray(obs.profile), inside=obs.inside,
             discharged=obs.discharged, temperature=obs.discharge_temperature,
             edges=obs.edges, residence=np.asarray(residence, float),
             **{f"load:{k}": v for k, v in obs.loads.items()})


def load_record(path) -> tuple[DirectObserver, np.ndarray]:
    """(observer, residence times s) as save_record wrote them to ``path``."""
    z = np.load(path)
    obs = DirectObserver([1.0, 0.0, 0.0], 0.0, 1.0, 1, "discharge")
    obs.edges = z["edges"]
    obs.time, obs.profile, obs.inside = list(z["time"]), list(z["profile"]), list(z["inside"])
    obs.discharged, obs.discharge_temperature = list(z["discharged"]), list(z["temperature"])
    obs.loads = {k[5:]: list(z[k]) for k in z.files if k.startswith("load:")}
    return obs, z["residence"]


def shorter_machine(text: str, rows: int, row_length: float, end_time: float,
                    source: str = "<direct scene>") -> str:
    """A direct cooler scene (bench/direct_check/cooler_direct.toml's layout: bodies 0 the
    shell and 1 the paddle shaft along +x from 0, outlet 0 a box beyond the discharge end)
    cut to ``rows`` paddle rows ``row_length`` m apart and run to ``end_time`` s."""
    import tomllib
    from .overrides import overridden_text
    doc = tomllib.loads(text)
    length = rows * row_length
    box = doc["outlets"][0]["region"]["box"]
    shift = length - float(doc["bodies"][1]["mesh"]["length"])
    return overridden_text(text, {
        "bodies.0.mesh.length": length, "bodies.1.mesh.length": length,
        "bodies.1.mesh.rows": rows, "simulation.end_time": end_time,
        "outlets.0.region.box.min": [box["min"][0] + shift] + box["min"][1:],
        "domain.max": [doc["domain"]["max"][0] + shift] + doc["domain"]["max"][1:],
        "outlets.0.region.box.max": [box["max"][0] + shift] + box["max"][1:]}, source)


def run_direct(text: str, *, base_dir, source: str, seconds: float, length: float, bins: int,
               outlet: str, residence_sensor: str | None, arch: str = "cpu"):
    """Run the direct scene ``text`` for ``seconds`` s observed in ``bins`` axial bins over
    [0, ``length``] m along +x; (observer, residence rows or None, wall s)."""
    import time
    from ..run.simulation import Simulation
    t0 = time.perf_counter()
    with Simulation.from_text(text, base_dir=base_dir, source=source, h5="", arch=arch) as sim:
        obs = DirectObserver([1.0, 0.0, 0.0], 0.0, length, bins, outlet)
        sim.add_observer(obs, now=False)
        sim.run(seconds)
        residence = sim.residence_times(residence_sensor) if residence_sensor else None
    return obs, residence, time.perf_counter() - t0


@dataclass
class Figure:
    """A figure of the direct run: ``value`` and its ``error`` (one standard error)."""
    value: float
    error: float


@dataclass
class DirectResult:
    """A direct run's steady figures (module docstring); ``steady_from`` (s) where the steady
    part starts, ``steady`` False when the mass inside never settled (the figures are then of
    the second half, to be looked at, not trusted)."""
    steady_from: float
    steady: bool
    x: np.ndarray                     # bin centres (m)
    holdup_profile: np.ndarray        # kg/m
    holdup_profile_error: np.ndarray
    holdup: Figure                    # kg
    discharge_rate: Figure            # kg/s
    residence_time: Figure            # s, the particles' own times
    little_residence_time: Figure     # s, hold-up over discharge rate
    torques: dict = field(default_factory=dict)       # body -> Figure (N m)
    outlet_temperature: Figure | None = None           # K
    particles_out: int = 0


def _mean_error(values) -> Figure:
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    if len(values) < 2:
        return Figure(float(values[0]) if len(values) else math.nan, math.nan)
    return Figure(float(np.mean(values)), block_standard_error(values).standard_error)


def reduce_direct(obs: DirectObserver, residence: np.ndarray | None = None) -> DirectResult:
    """The steady figures of a direct run observed by ``obs``; ``residence`` the (id, t_in,
    t_out) rows of its residence sensor (Simulation.residence_times)."""
    t = np.asarray(obs.time)
    inside = np.asarray(obs.inside)
    start = steady_start(inside)
    steady = start is not None
    if start is None:
        start = len(t) // 2
    t0, t1 = t[start], t[-1]
    prof = np.asarray(obs.profile)[start:]
    errors = np.array([block_standard_error(prof[:, k]).standard_error
                       for k in range(prof.shape[1])])
    holdup = _mean_error(inside[start:])
    out = np.asarray(obs.discharged)
    # the discharge rate: the outlet's mass over the steady window, its error from the
    # scatter of the per-sample rates (blocked)
    per_sample = np.diff(out[start:]) / np.diff(t[start:])
    rate = Figure((out[-1] - out[start]) / (t1 - t0),
                  block_standard_error(per_sample).standard_error if len(per_sample) > 1
                  else math.nan)
    little = Figure(holdup.value / rate.value,
                    holdup.value / rate.value * math.hypot(holdup.error / holdup.value,
                                                           rate.error / rate.value))
    res = Figure(math.nan, math.nan)
    count = 0
    if residence is not None and len(residence):
        rows = np.asarray(residence, float)
        rows = rows[(rows[:, 2] >= t0) & (rows[:, 2] <= t1)]
        rows = rows[np.argsort(rows[:, 2])]
        count = len(rows)
        if count >= 2:
            times = rows[:, 2] - rows[:, 1]
            res = Figure(float(np.mean(times)), block_standard_error(times).standard_error)
    torques = {}
    for key, values in obs.loads.items():
        if key.endswith("/axial_torque"):
            torques[key[:-len("/axial_torque")]] = _mean_error(np.asarray(values)[start:])
    t_out = None
    temps = np.asarray(obs.discharge_temperature)[start + 1:]
    weights = np.diff(out[start:])
    ok = np.isfinite(temps) & (weights > 0)
    if np.any(ok):
        value = float(np.sum(temps[ok] * weights[ok]) / np.sum(weights[ok]))
        t_out = Figure(value, block_standard_error(temps[ok]).standard_error
                       if np.sum(ok) > 1 else math.nan)
    centres = 0.5 * (obs.edges[1:] + obs.edges[:-1])
    return DirectResult(float(t0), steady, centres, prof.mean(axis=0), errors, holdup, rate,
                        res, little, torques, t_out, count)


@dataclass
class Comparison:
    """One figure of the direct run beside the march's: ``ratio`` = march / direct, its
    ``ratio_error`` (one standard error of both), and whether it lies within ``tolerance``
    (a fraction: |ratio - 1| <= tolerance)."""
    name: str
    unit: str
    direct: Figure
    march: Figure
    tolerance: float

    @property
    def ratio(self) -> float:
        return self.march.value / self.direct.value if self.direct.value else math.nan

    @property
    def ratio_error(self) -> float:
        d, m = self.direct, self.march
        rel = [e / abs(v) for v, e in ((d.value, d.error), (m.value, m.error))
               if v and math.isfinite(e)]
        return abs(self.ratio) * math.sqrt(sum(r * r for r in rel)) if rel else math.nan

    @property
    def within(self) -> bool:
        return bool(math.isfinite(self.ratio) and abs(self.ratio - 1.0) <= self.tolerance)


def compare(direct: DirectResult, answer, errors: dict, tolerances: dict,
            inlet_temperature: float | None = None) -> list[Comparison]:
    """The march's ``answer`` (machine.MachineAnswer, its ``errors`` from machine.with_errors)
    beside the direct run's figures, each with ``tolerances[name]`` (fraction; a figure not
    named there is not compared): "holdup", "residence_time", "<body>/torque",
    "outlet_temperature_drop" (the cooling, ``inlet_temperature`` K minus T_out, compared
    rather than the absolute temperature, which hides a wrong cooling behind the inlet
    temperature)."""
    if "outlet_temperature_drop" in tolerances and inlet_temperature is None:
        raise ValueError("the cooling is compared from the inlet temperature: give it")
    rows = []
    nan = math.nan
    if "holdup" in tolerances:
        rows.append(Comparison("hold-up", "kg", direct.holdup,
                               Figure(answer.holdup, errors.get("holdup", nan)),
                               tolerances["holdup"]))
    if "residence_time" in tolerances:
        rows.append(Comparison("mean residence time", "s", direct.residence_time,
                               Figure(answer.residence_time, errors.get("residence_time", nan)),
                               tolerances["residence_time"]))
    for body, fig in direct.torques.items():
        key = f"{body}/torque"
        if key in tolerances and body in answer.torques:
            rows.append(Comparison(f"{body} torque", "N m", fig,
                                   Figure(answer.torques[body], errors.get(key, nan)),
                                   tolerances[key]))
    if ("outlet_temperature_drop" in tolerances and direct.outlet_temperature is not None
            and answer.outlet_temperature is not None):
        t_in = inlet_temperature
        rows.append(Comparison(
            "cooling T_in - T_out", "K",
            Figure(t_in - direct.outlet_temperature.value, direct.outlet_temperature.error),
            Figure(t_in - answer.outlet_temperature, errors.get("outlet_temperature", nan)),
            tolerances["outlet_temperature_drop"]))
    return rows


def profile_difference(direct: DirectResult, answer) -> tuple[float, float]:
    """(RMS, largest) difference (kg/m) between the march's hold-up profile, read at the
    direct run's bin centres, and the direct run's."""
    prof = answer.profile
    marched = np.interp(direct.x, prof.x, prof.holdup)
    diff = marched - direct.holdup_profile
    return float(np.sqrt(np.mean(diff ** 2))), float(np.max(np.abs(diff)))


def table(rows: list[Comparison]) -> str:
    """A Markdown table of ``rows``."""
    lines = ["| figure | direct run | march from the map | march / direct | tolerance | |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r.name} ({r.unit}) | {r.direct.value:.4g} +- {r.direct.error:.2g} | "
            f"{r.march.value:.4g} +- {r.march.error:.2g} | {r.ratio:.3f} +- "
            f"{r.ratio_error:.2g} | {r.tolerance:.0%} | {'ok' if r.within else 'OUTSIDE'} |")
    return "\n".join(lines)
