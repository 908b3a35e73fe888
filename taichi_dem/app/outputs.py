"""The key outputs of a run, read back from its HDF5 results file: the numbers a demo summary
prints (``summaries.process_summary``), by the same definitions, so a sweep's table agrees
with what ``taichi-dem run`` / ``demo`` print.

Every time-averaged output is the mean over the last ``window`` fraction of the samples (25 %,
as the summaries use). Names and units:

=====================================  =====  ===============================================
``<body>/axial_torque``                N m    rotating bodies: torque along the axis
``<body>/power``                       W      rotating bodies: drive power
``<body>/heat_flow``                   W      thermal, into the body
``<wall>/load``                        N      plane walls: force pressed into the wall along
                                              its normal (the weight a floor carries)
``<sensor>/mass_flow``                 kg/s   mass-flow sensors
``<sensor>/residence_mean``, ``_median``  s   residence-time sensors, over every particle
                                              that completed the path during the run
``<outlet>/mass_flow``                 kg/s   outlets
``<outlet>/temperature``               K      outlets, mass-flow-weighted over the window
``gas/outlet_temperature``             K      plug-flow gas leaving the domain
``particles/mean_temperature``         K      at the end of the run (thermal)
``particles/kinetic_energy``           J      every scene
``particles/discharge_rate``           1/s    particles leaving the domain (a hopper's
                                              orifice): the slope of the lost count while 15 -
                                              60 % of the initial count has left, as the hopper
                                              demo fits its rate (only once 60 % has left)
``periodic_<axis>/mass_flow``          kg/s   a periodic slice: the mass flow along its
                                              periodic axis, sum m v_axis / L over the frames
                                              in the window (the flow through any section)
``periodic_<axis>/holdup``             kg/m   a periodic slice: the mass per metre of axis
=====================================  =====  ===============================================
"""
from __future__ import annotations

import math
import tomllib

import numpy as np

UNITS = {"axial_torque": "N m", "power": "W", "heat_flow": "W", "load": "N", "mass_flow": "kg/s",
         "residence_mean": "s", "residence_median": "s", "temperature": "K",
         "outlet_temperature": "K", "mean_temperature": "K", "kinetic_energy": "J",
         "discharge_rate": "1/s", "holdup": "kg/m"}


def unit(name: str) -> str:
    """The SI unit of output ``name`` (by its last part)."""
    return UNITS.get(name.rpartition("/")[2], "")


def _tail(a: np.ndarray, window: float) -> np.ndarray:
    return a[-max(1, int(len(a) * window)):]


def key_outputs(h5_path: str, window: float = 0.25) -> dict[str, float]:
    """{output name: value} of the results file ``h5_path`` (names and units in the module
    docstring). A quantity without samples is NaN."""
    import h5py
    out: dict[str, float] = {}
    with h5py.File(h5_path, "r") as f:
        s = f["series"]
        try:
            doc = tomllib.loads(str(f.attrs.get("scene", "")))
        except tomllib.TOMLDecodeError:
            doc = {}

        def tail_mean(name):
            if name not in s or s[name].shape[0] == 0:
                return math.nan
            return float(np.mean(_tail(s[name][()], window), axis=0))

        for name in sorted(s["bodies"]) if "bodies" in s else ():
            g = s["bodies"][name]
            w = g["angular_speed"][()] if "angular_speed" in g else np.zeros(1)
            if np.any(w != 0.0):
                out[f"{name}/axial_torque"] = tail_mean(f"bodies/{name}/axial_torque")
                out[f"{name}/power"] = tail_mean(f"bodies/{name}/power")
            if "heat_flow" in g:
                out[f"{name}/heat_flow"] = tail_mean(f"bodies/{name}/heat_flow")
        normals = {w.get("name"): w.get("plane", {}).get("normal")
                   for w in doc.get("walls", []) if isinstance(w, dict)}
        for name in sorted(s["walls"]) if "walls" in s else ():
            force = s[f"walls/{name}/force"][()]
            n = normals.get(name)
            if len(force) and isinstance(n, list) and len(n) == 3:
                n = np.asarray(n, float) / np.linalg.norm(np.asarray(n, float))
                out[f"{name}/load"] = float(-np.mean(_tail(force, window) @ n))
            if f"walls/{name}/heat_flow" in s:
                out[f"{name}/heat_flow"] = tail_mean(f"walls/{name}/heat_flow")
        for name in sorted(s["sensors"]) if "sensors" in s else ():
            if "mass_flow" in s["sensors"][name]:
                out[f"{name}/mass_flow"] = tail_mean(f"sensors/{name}/mass_flow")
        for name in sorted(f["residence"]) if "residence" in f else ():
            g = f["residence"][name]
            rt = g["t_out"][()] - g["t_in"][()]
            out[f"{name}/residence_mean"] = float(np.mean(rt)) if len(rt) else math.nan
            out[f"{name}/residence_median"] = float(np.median(rt)) if len(rt) else math.nan
        for name in sorted(s["outlets"]) if "outlets" in s else ():
            p = f"outlets/{name}/"
            out[f"{name}/mass_flow"] = tail_mean(p + "mass_flow")
            if p + "mean_temperature" in s:
                temps = _tail(s[p + "mean_temperature"][()], window)
                flows = _tail(s[p + "mass_flow"][()], window)
                ok = np.isfinite(temps) & (flows > 0)
                out[f"{name}/temperature"] = (float(np.sum(temps[ok] * flows[ok]) / np.sum(flows[ok]))
                                              if np.any(ok) else math.nan)
        if "gas/outlet_temperature" in s:
            out["gas/outlet_temperature"] = tail_mean("gas/outlet_temperature")
        if "particles/mean_temperature" in s and s["particles/mean_temperature"].shape[0]:
            out["particles/mean_temperature"] = float(s["particles/mean_temperature"][-1])
        out["particles/kinetic_energy"] = tail_mean("particles/kinetic_energy")
        if "particles/lost" in s and "particles/count" in s and s["particles/count"].shape[0]:
            t = s["time"][()]
            lost = s["particles/lost"][()].astype(float)
            initial = float(s["particles/count"][0])
            if initial > 0 and lost[-1] >= 0.6 * initial:
                window_ = (lost >= 0.15 * initial) & (lost <= 0.6 * initial)
                if np.count_nonzero(window_) >= 3:
                    out["particles/discharge_rate"] = float(np.polyfit(t[window_], lost[window_], 1)[0])
        out.update(_periodic_flows(f, doc, window))
    return out


def _periodic_flows(f, doc: dict, window: float) -> dict[str, float]:
    """A periodic slice's transport from its frames: per periodic axis, the mean over the last
    ``window`` of the frames of the mass flow sum(m v_axis) / L (kg/s) and the hold-up
    sum(m) / L (kg/m), L the domain's length along the axis."""
    domain = doc.get("domain", {}) if isinstance(doc.get("domain"), dict) else {}
    axes = [a for a in domain.get("periodic", ()) if a in ("x", "y", "z")]
    if not axes or "frames" not in f or not len(f["frames"]):
        return {}
    keys = sorted(f["frames"], key=int)
    keys = keys[-max(1, int(len(keys) * window)):]
    out: dict[str, float] = {}
    for axis in axes:
        k = "xyz".index(axis)
        try:
            length = float(domain["max"][k]) - float(domain["min"][k])
        except (KeyError, IndexError, TypeError, ValueError):
            continue                    # (a quantity string: the loader's job, not read here)
        flows, holdups = [], []
        for key in keys:
            g = f["frames"][key]
            if "mass" not in g or "velocity" not in g:
                return out
            m = g["mass"][()]
            flows.append(float(np.sum(m * g["velocity"][()][:, k])) / length)
            holdups.append(float(np.sum(m)) / length)
        out[f"periodic_{axis}/mass_flow"] = float(np.mean(flows))
        out[f"periodic_{axis}/holdup"] = float(np.mean(holdups))
    return out


def run_facts(h5_path: str) -> dict[str, float]:
    """What a run was, from its results file: dt (s), samples, simulated time (s), mean
    particle count over the samples."""
    import h5py
    with h5py.File(h5_path, "r") as f:
        t = f["series/time"][()]
        count = f["series/particles/count"][()] if "series/particles/count" in f else np.zeros(1)
        return {"dt": float(f.attrs["dt"]), "samples": int(len(t)),
                "simulated": float(t[-1]) if len(t) else 0.0,
                "mean_particles": float(np.mean(count)) if len(count) else 0.0,
                "precision": str(f.attrs.get("precision", ""))}
