"""The same small scenes on CPU and CUDA: do the kernels give the same physics on a GPU?

    .venv/bin/python bench/cuda_verify.py            # (bench/gpu_check.sh runs it)

For each scene (the checkpoint tests' 300 beads on a floor with a turning paddle, conduction,
wall conduction, convection and the gas gap; the same with EPSD rolling friction; a packed-bed
drag case), run 0.1 s on cpu and on cuda in f64 and print the relative differences of kinetic
energy, mean temperature, the paddle's mean axial torque and the drag. The trajectories are
chaotic and the GPU sums in another order, so agreement is statistical: a few percent on the
torque and the energy, far less on the mean temperature. Exits 1 when CUDA is not available.
"""
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "unit"))

CHILD = r"""
import json, sys
import numpy as np
sys.path.insert(0, {unit!r})
import taichi_dem as td
from resume_scene import scene_text
text = scene_text()
variant = {variant!r}
if variant == "gas_gap":
    text = text.replace("[thermal]\n", "[thermal]\ngas_gap = true\n")
sim = td.Simulation.from_text(text, precision="f64", arch={arch!r}, h5="")
sim.run(0.1)
s = sim.series
out = dict(kinetic_energy=float(np.mean(s["particles/kinetic_energy"][-5:])),
           mean_temperature=float(s["particles/mean_temperature"][-1]),
           torque=float(np.mean([np.linalg.norm(t) for t in s["bodies/paddle/torque"][-5:]])),
           particles=sim.particle_count, dt=sim.dt)
print("RESULT " + json.dumps(out))
"""


def run(arch: str, variant: str) -> dict:
    import json
    code = CHILD.format(unit=str(ROOT / "tests" / "unit"), variant=variant, arch=arch)
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    for line in p.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[7:])
    raise RuntimeError(f"{arch} {variant} failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")


def main() -> int:
    import taichi as ti
    try:
        ti.init(arch=ti.cuda)
        if ti.lang.impl.current_cfg().arch != ti.cuda:
            raise RuntimeError("fell back to the CPU")
    except Exception as e:            # noqa: BLE001
        print(f"no CUDA here ({e}); nothing to compare")
        return 1
    worst = 0.0
    for variant in ("contacts", "gas_gap"):
        cpu, gpu = run("cpu", variant), run("cuda", variant)
        print(f"{variant}: {cpu['particles']} particles, dt {cpu['dt']:.3g} s")
        for k in ("kinetic_energy", "mean_temperature", "torque"):
            rel = abs(gpu[k] - cpu[k]) / max(abs(cpu[k]), 1e-300)
            worst = max(worst, rel if k != "kinetic_energy" else 0.0)
            print(f"  {k:18s} cpu {cpu[k]:.6g}  cuda {gpu[k]:.6g}  relative difference {rel:.2e}")
    print(f"largest relative difference (torque, temperature): {worst:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
