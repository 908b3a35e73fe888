#!/usr/bin/env python3
"""Convert LAMMPS's chute benchmark (``data.chute``) into a taichi_dem scene.

The LAMMPS file is in LJ units (diameter 1, density 1, g = 1); they are read here as SI
(1 m spheres of 1 kg/m^3 under 1 m/s^2), which keeps every dimensionless number of the
benchmark. The scene has two CSV fills beside the TOML:

* ``chute_flowing.csv`` - atom type 1, header ``x,y,z,radius,vx,vy,vz,wx,wy,wz`` (the data
  file's Velocities section: the flow is already developed);
* ``chute_base.csv``    - atom type 2, the frozen rough base (``fixed = true``), ``x,y,z,radius``.

``copies`` tiles the 40 x 20 periodic box ``nx x ny`` times in x and y (copies = 4 -> 2 x 2,
128,000 particles); ``max_particles`` keeps only the particles below a cut in x (the periodic
box is shortened to the cut, and particles that would overlap their new periodic images
across the seam are dropped), e.g. 8,000 for the small end of a scaling study.

    python bench/chute_scene.py OUT_DIR [--copies 4] [--max-particles 8000] [--data PATH]

Public functions: :func:`write_chute_scene`, :func:`read_chute_data`, :func:`default_data_path`.
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parent.parent

# LAMMPS benchmark parameters (pair_style gran/hertz/history 200000.0 NULL 50.0 NULL 0.5 0).
LAMMPS_KN = 200000.0
CHUTE_ANGLE_DEG = 26.0
GRAVITY = 1.0
DT = 1e-4
POISSON = 0.3


def default_data_path() -> Path:
    """``data.chute`` beside the repository: ``<repo root>/../shared/peers/data.chute``."""
    return REPO_ROOT.parent / "shared" / "peers" / "data.chute"


@dataclass
class ChuteData:
    box_lo: np.ndarray          # (3,)
    box_hi: np.ndarray          # (3,)
    type: np.ndarray            # (n,) int
    radius: np.ndarray          # (n,)
    density: np.ndarray         # (n,)
    position: np.ndarray        # (n,3), wrapped into the periodic x, y box
    velocity: np.ndarray        # (n,3)
    angular_velocity: np.ndarray  # (n,3)


def read_chute_data(data_path=None) -> ChuteData:
    """Read a LAMMPS ``atom_style sphere`` data file (columns after ``Atoms``:
    id type diameter density x y z [ix iy iz]; after ``Velocities``: id vx vy vz wx wy wz).
    Positions are wrapped into [lo, hi) in x and y (image flags are ignored: they only record
    how many times an atom crossed the periodic faces)."""
    path = Path(data_path) if data_path is not None else default_data_path()
    lines = path.read_text().splitlines()
    natoms = None
    lo = np.zeros(3)
    hi = np.zeros(3)
    sections: dict[str, int] = {}
    for i, line in enumerate(lines):
        s = line.split("#")[0].strip()
        parts = s.split()
        if len(parts) == 2 and parts[1] == "atoms":
            natoms = int(parts[0])
        for k, ax in enumerate("xyz"):
            if len(parts) == 4 and parts[2] == f"{ax}lo" and parts[3] == f"{ax}hi":
                lo[k], hi[k] = float(parts[0]), float(parts[1])
        if s in ("Atoms", "Velocities") or s.startswith("Atoms "):
            sections[s.split()[0]] = i
    if natoms is None or "Atoms" not in sections:
        raise ValueError(f"{path}: not a LAMMPS data file with an Atoms section")

    def block(start: int, ncols: int) -> np.ndarray:
        rows = []
        for line in lines[start + 1:]:
            p = line.split("#")[0].split()
            if not p:
                if rows:
                    break
                continue
            rows.append([float(x) for x in p[:ncols]])
            if len(rows) == natoms:
                break
        arr = np.asarray(rows, dtype=np.float64)
        if arr.shape != (natoms, ncols):
            raise ValueError(f"{path}: expected {natoms} rows of >= {ncols} columns, "
                             f"got {arr.shape}")
        return arr[np.argsort(arr[:, 0], kind="stable")]

    atoms = block(sections["Atoms"], 7)
    if "Velocities" in sections:
        vel = block(sections["Velocities"], 7)
        if not np.array_equal(vel[:, 0], atoms[:, 0]):
            raise ValueError(f"{path}: Velocities ids do not match Atoms ids")
    else:
        vel = np.zeros((natoms, 7))
    pos = atoms[:, 4:7].copy()
    for k in (0, 1):   # x and y are periodic
        length = hi[k] - lo[k]
        pos[:, k] = lo[k] + np.mod(pos[:, k] - lo[k], length)
        pos[pos[:, k] >= hi[k], k] = lo[k]       # guard against rounding up to hi
    return ChuteData(box_lo=lo, box_hi=hi, type=atoms[:, 1].astype(int),
                     radius=0.5 * atoms[:, 2], density=atoms[:, 3], position=pos,
                     velocity=vel[:, 1:4].copy(), angular_velocity=vel[:, 4:7].copy())


def _tile_shape(copies: int) -> tuple[int, int]:
    """copies = nx * ny with ny the largest divisor <= sqrt(copies) (4 -> 2x2, 2 -> 2x1)."""
    if copies < 1 or int(copies) != copies:
        raise ValueError(f"copies must be a positive integer, got {copies}")
    ny = max(d for d in range(1, int(math.isqrt(copies)) + 1) if copies % d == 0)
    return copies // ny, ny


def _seam_overlaps(pos, rad, fixed, cut, ly, band) -> np.ndarray:
    """Indices of particles just below ``cut`` in x that overlap (through the new periodic
    x face at ``cut``, with y periodic of length ``ly``) a particle just above x = 0;
    fixed-fixed pairs are ignored (the engine never moves them)."""
    hi = np.nonzero(pos[:, 0] >= cut - band)[0]
    lo = np.nonzero(pos[:, 0] < band)[0]
    drop = set()
    for i in hi:
        d = pos[lo] + np.array([cut, 0.0, 0.0]) - pos[i]
        d[:, 1] -= ly * np.round(d[:, 1] / ly)
        dist = np.sqrt(np.einsum("ij,ij->i", d, d))
        hit = (dist < rad[lo] + rad[i]) & ~(fixed[lo] & fixed[i]) & (lo != i)
        if np.any(hit):
            drop.add(int(i))
    return np.asarray(sorted(drop), dtype=int)


def _fmt(v: float) -> str:
    return repr(float(v))


def write_chute_scene(out_dir, data_path=None, copies: int = 1, max_particles=None,
                      end_time: float = 0.1, precision: str = "f32", seed: int = 1,
                      name: str = "chute", skin: float = 0.1) -> Path:
    """Write ``<name>.toml`` plus ``<name>_flowing.csv`` and ``<name>_base.csv`` into
    ``out_dir`` and return the TOML's path.

    ``copies``: tile the periodic 40 x 20 box nx x ny times (4 -> 2 x 2 = 128,000 particles).
    ``max_particles``: keep only particles below an x cut and shorten the periodic box to the
    cut; particles overlapping their new periodic images across the seam are dropped and the
    cut moved out to make up for them (the count ends at or a few above ``max_particles``);
    below a tenth of the particles the box is first halved in y the same way (so that x stays
    longer than two pair cut-offs at 1,000 particles).
    ``end_time`` defaults to 0.1 s = 1000 steps of dt = 1e-4. ``skin``: the Verlet skin
    (LAMMPS's benchmark: 0.1).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    skin = float(skin)
    data = read_chute_data(data_path)
    nx, ny = _tile_shape(copies)
    lx0, ly0 = data.box_hi[0] - data.box_lo[0], data.box_hi[1] - data.box_lo[1]

    pos, vel, ang, rad, typ = [], [], [], [], []
    for ix in range(nx):
        for iy in range(ny):
            pos.append(data.position + np.array([ix * lx0, iy * ly0, 0.0]))
            vel.append(data.velocity)
            ang.append(data.angular_velocity)
            rad.append(data.radius)
            typ.append(data.type)
    pos, vel, ang = np.concatenate(pos), np.concatenate(vel), np.concatenate(ang)
    rad, typ = np.concatenate(rad), np.concatenate(typ)
    x0, y0 = data.box_lo[0], data.box_lo[1]
    lx, ly = nx * lx0, ny * ly0

    if max_particles is not None and max_particles < 1:
        raise ValueError("max_particles must be positive")
    if max_particles is not None and max_particles < 0.1 * len(pos):
        # an x cut alone would leave x shorter than two pair cut-offs (1k of 32k: 1.25 d):
        # halve y first (the same seam rule with the axes swapped), then cut x
        swap = [1, 0, 2]
        ys = np.sort(pos[:, 1])
        half = len(ys) // 2
        cut_y = 0.5 * (ys[half - 1] + ys[half])
        below = np.nonzero(pos[:, 1] < cut_y)[0]
        drop = _seam_overlaps((pos[below] - np.array([x0, y0, 0.0]))[:, swap], rad[below],
                              typ[below] == 2, cut_y - y0, lx, band=2.0 * float(rad.max()))
        keep = np.delete(below, drop)
        pos, vel, ang, rad, typ = pos[keep], vel[keep], ang[keep], rad[keep], typ[keep]
        ly = cut_y - y0
    if max_particles is not None and max_particles < len(pos):
        xs = np.sort(pos[:, 0])
        target = int(max_particles)
        for _ in range(4):   # cut further out to make up for the seam's dropped particles
            target = min(target, len(xs) - 1)
            cut = 0.5 * (xs[target - 1] + xs[target])    # exactly `target` particles below
            below = np.nonzero(pos[:, 0] < cut)[0]
            drop = _seam_overlaps(pos[below] - np.array([x0, y0, 0.0]), rad[below],
                                  typ[below] == 2, cut - x0, ly, band=2.0 * float(rad.max()))
            keep = np.delete(below, drop)
            if len(keep) >= max_particles or target == len(xs) - 1:
                break
            target += max_particles - len(keep)
        pos, vel, ang, rad, typ = pos[keep], vel[keep], ang[keep], rad[keep], typ[keep]
        lx = cut - x0

    flowing, base = typ == 1, typ == 2
    if not np.all(flowing | base):
        raise ValueError(f"unexpected atom types {sorted(set(typ.tolist()))} (expected 1 and 2)")
    densities = np.unique(data.density)
    if len(densities) != 1:
        raise ValueError(f"expected one density, got {densities}")
    density = float(densities[0])

    # Domain: periodic x, y; z from a little below the base to well above the free surface.
    zmin = math.floor(float(np.min(pos[:, 2] - rad)) - 0.5)
    zmax = math.ceil(float(np.max(pos[:, 2] + rad)) + 20.0)

    flow_csv = out_dir / f"{name}_flowing.csv"
    base_csv = out_dir / f"{name}_base.csv"
    np.savetxt(flow_csv, np.column_stack([pos[flowing], rad[flowing], vel[flowing],
                                          ang[flowing]]),
               delimiter=",", header="x,y,z,radius,vx,vy,vz,wx,wy,wz", comments="", fmt="%.9g")
    np.savetxt(base_csv, np.column_stack([pos[base], rad[base]]),
               delimiter=",", header="x,y,z,radius", comments="", fmt="%.9g")

    # Stiffness: our Hertz normal force is 4/3 E* sqrt(R*) d^1.5; LAMMPS gran/hertz/history's
    # is kn sqrt(R*) d^1.5 (its Hooke force kn d times sqrt(d R*)), so E* = 3/4 kn.
    # For two identical materials 1/E* = 2 (1 - v^2) / E, so E = 2 (1 - v^2) E*; v = 0.3.
    e_star = 0.75 * LAMMPS_KN
    youngs = 2.0 * (1.0 - POISSON ** 2) * e_star
    theta = math.radians(CHUTE_ANGLE_DEG)
    gravity = (GRAVITY * math.sin(theta), 0.0, -GRAVITY * math.cos(theta))
    n_flow, n_base = int(flowing.sum()), int(base.sum())

    toml = f"""\
# LAMMPS chute-flow benchmark (bench/in.chute, data.chute) as a taichi_dem scene.
# Generated by bench/chute_scene.py: copies = {copies} ({nx} x {ny} tiles), max_particles = {max_particles}
# {n_flow} flowing + {n_base} frozen base = {n_flow + n_base} particles.
# LJ units read as SI: diameter 1 m, density 1 kg/m^3, g = 1 m/s^2 tilted {CHUTE_ANGLE_DEG:g} degrees.

[simulation]
end_time = {_fmt(end_time)}
dt = {_fmt(DT)}                  # LAMMPS: timestep 0.0001
gravity = [{_fmt(gravity[0])}, {_fmt(gravity[1])}, {_fmt(gravity[2])}]   # fix gravity 1.0 chute 26.0
precision = "{precision}"
seed = {int(seed)}
skin = {skin!r}                 # m, Verlet skin (LAMMPS's benchmark: neighbor 0.1 bin)

[domain]
min = [{_fmt(x0)}, {_fmt(y0)}, {_fmt(zmin)}]
max = [{_fmt(x0 + lx)}, {_fmt(y0 + ly)}, {_fmt(zmax)}]
periodic = ["x", "y"]

# Normal stiffness matched to LAMMPS gran/hertz/history with kn = {LAMMPS_KN:g}:
#   ours   F = 4/3 E* sqrt(R*) d^1.5,   LAMMPS F = kn sqrt(R*) d^1.5   =>  E* = 0.75 kn = {e_star:g}
#   identical materials: 1/E* = 2 (1 - v^2) / E  =>  E = 2 (1 - v^2) E* = {youngs:g} with v = {POISSON}
# (The tangential stiffness then follows Mindlin, 8 G* sqrt(R* d), not LAMMPS's kt = 2/7 kn.)
[materials.grain]
density = {_fmt(density)}
youngs_modulus = {_fmt(youngs)}
poisson_ratio = {_fmt(POISSON)}

# LAMMPS uses gamman = 50 (damping force m_eff gamman v_n sqrt(d R*)), which gives a
# velocity-dependent restitution; we take a constant 0.5. This benchmark is about speed.
[[interactions]]
pair = ["grain", "grain"]
restitution = 0.5
friction = 0.5             # LAMMPS xmu = 0.5
rolling_friction = 0.0

[[particles]]              # atom type 1: the flowing grains, with their velocities
material = "grain"
file = "{flow_csv.name}"

[[particles]]              # atom type 2: the frozen rough base
material = "grain"
file = "{base_csv.name}"
fixed = true

[output]
interval = 1.0
"""
    toml_path = out_dir / f"{name}.toml"
    toml_path.write_text(toml)
    return toml_path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Write the LAMMPS chute benchmark as a scene.")
    ap.add_argument("out_dir", type=Path)
    ap.add_argument("--data", type=Path, default=None,
                    help=f"data.chute path (default {default_data_path()})")
    ap.add_argument("--copies", type=int, default=1, help="tiles in x and y (4 -> 2x2)")
    ap.add_argument("--max-particles", type=int, default=None,
                    help="keep about this many particles (an x cut)")
    ap.add_argument("--end-time", type=float, default=0.1)
    ap.add_argument("--precision", choices=["f32", "f64"], default="f32")
    ap.add_argument("--name", default="chute")
    args = ap.parse_args(argv)
    path = write_chute_scene(args.out_dir, args.data, copies=args.copies,
                             max_particles=args.max_particles, end_time=args.end_time,
                             precision=args.precision, name=args.name)
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
