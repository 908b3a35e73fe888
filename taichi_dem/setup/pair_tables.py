"""Device-independent pair tables derived from a Scene: equivalent moduli, damping ratios,
friction coefficients (numpy; the engine copies them to device fields).

Index convention: materials are numbered in ``sorted(scene.materials)`` order; the table has
shape (n_mat, n_mat) and is symmetric.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .restitution import damping_ratio
from ..scene.model import Material, Scene

# the ``rolling_model`` table: each interaction's rolling model (its scene value) as a code, 0
# where it has no rolling friction; the rolling effects (effects/rolling.py) act on their code
NO_ROLLING = 0
ROLLING_MODEL_CODES = {"constant_torque": 1, "epsd": 2}


def effective_youngs_modulus(a: Material, b: Material) -> float:
    """E* with 1/E* = (1 - v_a^2)/E_a + (1 - v_b^2)/E_b, Pa."""
    return 1.0 / ((1 - a.poisson_ratio ** 2) / a.youngs_modulus
                  + (1 - b.poisson_ratio ** 2) / b.youngs_modulus)


def effective_shear_modulus(a: Material, b: Material) -> float:
    """G* with 1/G* = (2 - v_a)/G_a + (2 - v_b)/G_b, Pa."""
    return 1.0 / ((2 - a.poisson_ratio) / a.shear_modulus + (2 - b.poisson_ratio) / b.shear_modulus)


def rayleigh_time(radius: float, material: Material) -> float:
    """T_R = pi R sqrt(rho/G) / (0.1631 v + 0.8766), s."""
    return (math.pi * radius * math.sqrt(material.density / material.shear_modulus)
            / (0.1631 * material.poisson_ratio + 0.8766))


def hertz_contact_time(m_eff: float, r_eff: float, e_eff: float, speed: float) -> float:
    """Hertz contact duration t_c = 2.87 (m*^2 / (R* E*^2 v))^(1/5), s (elastic impact)."""
    return 2.87 * (m_eff ** 2 / (r_eff * e_eff ** 2 * max(speed, 1e-12))) ** 0.2


@dataclass
class PairTables:
    names: list[str]
    youngs_eff: np.ndarray        # (M, M) Pa
    shear_eff: np.ndarray         # (M, M) Pa
    damping: np.ndarray           # (M, M) zeta, see restitution.py
    friction: np.ndarray          # (M, M) mu_s
    rolling_friction: np.ndarray  # (M, M) mu_r
    rolling_model: np.ndarray     # (M, M) int code
    rolling_damping: np.ndarray   # (M, M) eta_r, EPSD viscous fraction of critical
    density: np.ndarray           # (M,)

    def index(self, name: str) -> int:
        return self.names.index(name)

    @property
    def rolling_models_used(self) -> set[int]:
        return set(int(c) for c in np.unique(self.rolling_model[self.rolling_friction > 0]))


# The tables hold every pair of declared materials (M x M: 6 float64 tables and an int32 one,
# built on the host, copied to the device and indexed by material in the kernels). 140,000
# unused materials asked for 146 GiB and raised MemoryError. A cap on their size, not on what
# is used: the numbering of materials (sorted names) is shared with placement and the results'
# ``materials`` attribute. 256 MiB is about 2,200 materials, a hundred times what a scene needs.
PAIR_TABLE_BYTES_PER_PAIR = 6 * 8 + 4
MAX_PAIR_TABLE_BYTES = 2 ** 28


def pair_table_problem(scene: Scene):
    """Why the scene's pair tables are too large to build (a reason), or None."""
    m = len(scene.materials)
    need = m * m * PAIR_TABLE_BYTES_PER_PAIR
    if need > MAX_PAIR_TABLE_BYTES:
        most = int(math.isqrt(MAX_PAIR_TABLE_BYTES // PAIR_TABLE_BYTES_PER_PAIR))
        return (f"{m:,} materials need pair tables of {need / 2 ** 30:,.1f} GiB (every pair of "
                f"declared materials, {PAIR_TABLE_BYTES_PER_PAIR} bytes each); at most {most:,} "
                "materials: remove the unused ones")
    return None


def build_pair_tables(scene: Scene) -> PairTables:
    """Pair tables for every material pair that has an interaction (others stay zero and are
    never used: the loader guarantees every pair that can meet has one). SceneError (key
    ``materials``) when they would exceed MAX_PAIR_TABLE_BYTES."""
    problem = pair_table_problem(scene)
    if problem:
        from ..errors import SceneError
        raise SceneError(scene.source, "materials", problem)
    names = sorted(scene.materials)
    m = len(names)
    t = PairTables(names, *(np.zeros((m, m)) for _ in range(5)),
                   np.zeros((m, m), dtype=np.int32), np.zeros((m, m)),
                   np.array([scene.materials[n].density for n in names]))
    for a in range(m):
        for b in range(m):
            key = frozenset((names[a], names[b]))
            if key not in scene.interactions:
                continue
            inter = scene.interactions[key]
            ma, mb = scene.materials[names[a]], scene.materials[names[b]]
            t.youngs_eff[a, b] = effective_youngs_modulus(ma, mb)
            t.shear_eff[a, b] = effective_shear_modulus(ma, mb)
            t.damping[a, b] = damping_ratio(inter.restitution)
            t.friction[a, b] = inter.friction
            t.rolling_friction[a, b] = inter.rolling_friction
            t.rolling_damping[a, b] = inter.rolling_damping
            t.rolling_model[a, b] = (ROLLING_MODEL_CODES[inter.rolling_model]
                                     if inter.rolling_friction > 0 else NO_ROLLING)
    return t
