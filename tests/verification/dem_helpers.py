"""Shared helpers for the physics verification tests: scene-text builders, CSV initial states
and the closed-form Hertz results the tests compare against.

Hertz elastic impact (Johnson, Contact Mechanics, sec. 11.1), relative normal speed v:
    K      = 4/3 E* sqrt(R*)                       F = K d^(3/2)
    d_max  = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5)
    F_max  = K d_max^(3/2)
    t_c    = 2 (d_max / v) int_0^1 du / sqrt(1 - u^(5/2)) = 2.943275 d_max / v
The integral is (2/5) B(2/5, 1/2), evaluated exactly here (the 2.87 of PHYSICS.md is its
rounded form 2.943275 * (15/16)^(2/5) = 2.8683).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

RIGID_E = 1.0e20        # Pa: a "rigid" wall (E* changes by 1e-9 relative; still finite)


def _fmt(x) -> str:
    return repr(float(x))


def vec(v) -> str:
    return "[" + ", ".join(_fmt(c) for c in v) + "]"


def material(name, density, youngs_modulus, poisson_ratio) -> str:
    return (f"[materials.{name}]\ndensity = {_fmt(density)}\nyoungs_modulus = {_fmt(youngs_modulus)}\n"
            f"poisson_ratio = {_fmt(poisson_ratio)}\n\n")


def interaction(a, b, restitution, friction, rolling_friction=0.0, model=None) -> str:
    s = (f"[[interactions]]\npair = [\"{a}\", \"{b}\"]\nrestitution = {_fmt(restitution)}\n"
         f"friction = {_fmt(friction)}\n")
    if rolling_friction:
        s += f"rolling_friction = {_fmt(rolling_friction)}\n"
    if model:
        s += f"model = \"{model}\"\n"
    return s + "\n"


def wall(name, point, normal, material_name) -> str:
    return (f"[[walls]]\nname = \"{name}\"\nplane = {{ point = {vec(point)}, normal = {vec(normal)} }}\n"
            f"material = \"{material_name}\"\n\n")


def header(dt=None, gravity=(0.0, 0.0, 0.0), lo=(-1, -1, -1), hi=(1, 1, 1), periodic=(),
           output_interval=None, skin=None, rayleigh_fraction=None) -> str:
    s = "[simulation]\nend_time = 1.0\nprecision = \"f64\"\n"
    s += f"gravity = {vec(gravity)}\n"
    if dt is not None:
        s += f"dt = {_fmt(dt)}\n"
    if skin is not None:
        s += f"skin = {_fmt(skin)}\n"
    if rayleigh_fraction is not None:
        s += f"rayleigh_fraction = {_fmt(rayleigh_fraction)}\n"
    s += (f"\n[domain]\nmin = {vec(lo)}\nmax = {vec(hi)}\n"
          f"periodic = [{', '.join(chr(34) + a + chr(34) for a in periodic)}]\n\n")
    if output_interval is not None:
        s += f"[output]\ninterval = {_fmt(output_interval)}\n\n"
    return s


def csv_fill(tmp_path: Path, filename: str, material_name: str, positions, radii,
             velocities=None, angular_velocities=None) -> str:
    """Write a CSV initial state and return the [[particles]] table that loads it."""
    positions = np.atleast_2d(np.asarray(positions, float))
    n = len(positions)
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    v = np.zeros((n, 3)) if velocities is None else np.broadcast_to(np.asarray(velocities, float), (n, 3))
    w = np.zeros((n, 3)) if angular_velocities is None else np.broadcast_to(
        np.asarray(angular_velocities, float), (n, 3))
    lines = ["x,y,z,radius,vx,vy,vz,wx,wy,wz"]
    for k in range(n):
        row = list(positions[k]) + [radii[k]] + list(v[k]) + list(w[k])
        lines.append(",".join(repr(float(c)) for c in row))
    (Path(tmp_path) / filename).write_text("\n".join(lines) + "\n")
    return f"[[particles]]\nmaterial = \"{material_name}\"\nfile = \"{filename}\"\n\n"


def all_interactions(names, restitution=1.0, friction=0.0) -> str:
    """Interactions for every pair of ``names`` (required by the loader even when the
    particles never meet)."""
    out = ""
    for i, a in enumerate(names):
        for b in names[i:]:
            out += interaction(a, b, restitution, friction)
    return out


# ------------------------------------------------------------------------------ Hertz theory
def youngs_eff(e1, v1, e2=None, v2=None) -> float:
    if e2 is None:
        e2, v2 = e1, v1
    return 1.0 / ((1 - v1 ** 2) / e1 + (1 - v2 ** 2) / e2)


def sphere_mass(radius, density) -> float:
    return 4.0 / 3.0 * math.pi * radius ** 3 * density


def _contact_time_integral() -> float:
    """int_0^1 du / sqrt(1 - u^(5/2)) = (2/5) B(2/5, 1/2), exactly."""
    a = 2.5
    return (1.0 / a) * math.gamma(1.0 / a) * math.gamma(0.5) / math.gamma(1.0 / a + 0.5)


CONTACT_TIME_FACTOR = 2.0 * _contact_time_integral()     # 2.943275...


def hertz_impact(m_eff, r_eff, e_eff, speed) -> dict:
    """Elastic Hertz impact at relative normal speed ``speed``: max overlap (m), peak force (N),
    contact duration (s)."""
    k = 4.0 / 3.0 * e_eff * math.sqrt(r_eff)
    d_max = (15.0 * m_eff * speed ** 2 / (16.0 * e_eff * math.sqrt(r_eff))) ** 0.4
    return {"overlap": d_max, "force": k * d_max ** 1.5,
            "time": CONTACT_TIME_FACTOR * d_max / speed}
