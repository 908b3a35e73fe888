"""What a scene asks of the machine's memory, checked before anything is allocated (issue 43:
``max_particles = 2147483647`` printed "estimated device memory 2105344 MiB", said OK, and the
run crashed; 200 million particles in one fill raised MemoryError in placement).

Plain Python and numpy: ``check`` uses it without starting the Taichi runtime.
"""
from __future__ import annotations

import math
import os
import shutil
import subprocess
from typing import Optional

import numpy as np

# particle slots are indexed with 32-bit integers, so the estimate below never needs more
LIST_ENTRIES_PER_PARTICLE = 8      # neighbour entries per particle the lists start with
CELLS_PER_PARTICLE = 8             # engine/grid.py MAX_CELLS_PER_PARTICLE: a start and a count
GPU_ARCHS = ("gpu", "cuda")        # archs whose device memory nvidia-smi reports


def host_memory_bytes() -> int:
    """The machine's physical memory, bytes (os.sysconf); 0 when the system does not say."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 0


def device_memory_bytes(arch: str) -> tuple[int, str]:
    """(bytes, what they are) the kernels of ``arch`` can use: host RAM for cpu; for a CUDA GPU
    the first device's memory as nvidia-smi reports it (cheap, no Taichi runtime), else host
    RAM (vulkan and metal do not say cheaply; their memory is rarely more than the host's)."""
    if arch in GPU_ARCHS and shutil.which("nvidia-smi"):
        try:
            out = subprocess.run(["nvidia-smi", "--query-gpu=memory.total",
                                  "--format=csv,noheader,nounits"], capture_output=True,
                                 text=True, timeout=10, check=True).stdout.split()
            if out:
                return int(float(out[0]) * 2 ** 20), "the GPU's memory"
        except (OSError, ValueError, subprocess.SubprocessError):
            pass
    return host_memory_bytes(), "the machine's memory"


def estimated_device_bytes(slots: int, precision: str, bodies: bool = False) -> int:
    """Device memory (bytes) for ``slots`` particle slots: per particle 6 vectors and 4 reals
    of state, 15 ints of shadows and rows, 4 reals more, and the reorder's shadows of the
    state (engine/state.py: 4 vectors, 3 reals and 2 ints beyond those ints); the neighbour
    entries the first list
    is allocated with (SETTLED_ENTRIES_PER_PARTICLE per slot, in a bucket; more than
    LIST_ENTRIES_PER_PARTICLE with the growth headroom) of 3 ints and 5 vectors each; and
    CELLS_PER_PARTICLE grid cells of 2 ints. With mesh ``bodies``, their candidate entries
    too (bodies/mesh_contacts.py: one per slot to start with, each ~3 ints, 2 reals and up to
    11 vectors: the contact, the history now and before, the candidate placed this step)."""
    from .tuning import LIST_GROWTH, SETTLED_ENTRIES_PER_PARTICLE
    real_bytes = 8 if precision == "f64" else 4
    per_particle = ((6 * 3 + 4) * real_bytes + 15 * 4 + 4 * real_bytes
                    + (4 * 3 + 3) * real_bytes + 2 * 4)
    per_entry = 3 * 4 + 5 * 3 * real_bytes
    # the first list has room for every slot settled (engine/broadphase.py), in a bucket
    entries = bucket(int(max(LIST_GROWTH * LIST_ENTRIES_PER_PARTICLE,
                             SETTLED_ENTRIES_PER_PARTICLE) * slots))
    mesh = slots * (3 * 4 + (2 + 11 * 3) * real_bytes) if bodies else 0
    return (slots * per_particle + entries * per_entry + CELLS_PER_PARTICLE * slots * 2 * 4
            + mesh)


def factory_capacity(scene) -> int:
    """Slots for factory particles: what the schedules insert until end_time plus 10 %, but
    no more than the domain could hold at random close packing (0.64); or max_particles."""
    if not scene.factories:
        return 0
    if scene.simulation.max_particles is not None:
        return max(scene.simulation.max_particles - scene.expected_particle_count, 0)
    total = 0.0
    smallest = math.inf
    for f in scene.factories:
        mass = f.mass_rate.mass_until(scene.simulation.end_time)
        total += mass / (scene.materials[f.material].density * f.mean_particle_volume())
        smallest = min(smallest, 4.0 / 3.0 * math.pi * f.smallest_radius ** 3)
    span = np.asarray(scene.domain.max) - np.asarray(scene.domain.min)
    packing = 0.64 * float(np.prod(span)) / smallest
    return int(min(1.1 * total + 64, packing))


def bucket(n: int, floor: int = 64) -> int:
    """The capacity an array of ``n`` entries is allocated with: the next of 64, 96, 128, 192,
    256, 384, ... (powers of two and 1.5 times them), so that scenes whose counts differ a
    little share their arrays' shapes, and so their compiled kernels, for at most 1.5x the
    memory (2x below the floor of 64)."""
    n = max(int(n), 1)
    if n <= floor:
        return floor
    p = 1 << (n - 1).bit_length()          # the power of two at or above n
    three_quarters = 3 * p // 4
    return three_quarters if three_quarters >= n else p


def allocated_slots(n: int) -> int:
    """The particle slots the engine allocates for ``n`` particles: their bucket, no fewer
    than the floor MIN_PARTICLE_SLOTS (setup/tuning.py)."""
    from .tuning import MIN_PARTICLE_SLOTS
    return max(bucket(n), MIN_PARTICLE_SLOTS)


def triangle_slots(n: int) -> int:
    """The triangle slots the bodies' arrays are allocated with for ``n`` triangles: their
    bucket, no fewer than the floor MIN_TRIANGLE_SLOTS (setup/tuning.py)."""
    from .tuning import MIN_TRIANGLE_SLOTS
    return max(bucket(n), MIN_TRIANGLE_SLOTS)


def particle_slots(scene) -> int:
    """Slots the engine allocates: the fills' particles plus the factories' capacity
    (``factory_capacity``, which honours max_particles)."""
    return scene.expected_particle_count + factory_capacity(scene)


def _blamed_key(scene) -> str:
    """The key that sets the slot count: max_particles when given, else the largest source."""
    if scene.simulation.max_particles is not None and scene.factories:
        return "simulation.max_particles"
    if scene.factories:
        return f"{scene.factories[0].key}.mass_rate"
    if scene.fills:
        biggest = max(scene.fills, key=lambda f: f.expected_count)
        return f"{biggest.key}.count" if biggest.file is None else f"{biggest.key}.file"
    return "particles"


def memory_problem(scene, arch: str = "cpu", precision: Optional[str] = None):
    """(key, reason) when the scene's estimated device memory exceeds what ``arch`` has (the
    estimate and the machine's figure in the reason), else None. Nothing is allocated."""
    precision = precision or scene.simulation.precision
    slots = particle_slots(scene)
    need = estimated_device_bytes(allocated_slots(slots), precision,    # as allocated
                                  bool(scene.bodies))
    have, what = device_memory_bytes(arch)
    if have and need > have:
        return (_blamed_key(scene),
                f"{slots:,} particle slots need an estimated {need / 2 ** 20:,.0f} MiB of "
                f"device memory ({precision}), more than {what} ({have / 2 ** 20:,.0f} MiB); "
                "use fewer particles (or a smaller max_particles)")
    return None
