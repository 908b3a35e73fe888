"""The first layer's transient ratio G(t) / G(0) of the "schlunder" wall law (thermal/
particle_transient.py) for 2 mm beads of glass, steel, alumina and a k_s = 0.3 solid in air at
1 bar, and each pair law's steady share: a table on stdout and
docs/verification/first_layer_ratio.png.

    .venv/bin/python bench/first_layer_ratio.py
"""
import math
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from taichi_dem.thermal import correlations, first_layer  # noqa: E402
from taichi_dem.thermal.gas_gap import VORONOI_FACE  # noqa: E402
from taichi_dem.thermal.particle_transient import conductance_ratio, half_pair_conductance  # noqa: E402

R, K_GAS = 1e-3, 0.0262
SOLIDS = {  # k W/(m K), rho kg/m^3, c J/(kg K)
    "glass": (1.0, 2500.0, 840.0), "steel": (45.0, 7800.0, 480.0),
    "alumina": (30.0, 3900.0, 880.0), "ash (k 0.3)": (0.3, 2300.0, 800.0)}


def main():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    free_path = correlations.modified_mean_free_path(300.0)
    face = VORONOI_FACE * 0.6 ** (-1.0 / 3.0)
    reach_sin = face / math.sqrt(face * face + 1.0)
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    print(f"l = {free_path:.3g} m; G(0) = {K_GAS * first_layer.widened_gap_integral_reference(R, R, first_layer.REACH, free_path):.4g} W/K")
    print("| solid | G/G0 at 0.01 s | 0.1 s | 1 s | 10 s | pair share (touching) |")
    print("|---|---|---|---|---|---|")
    for name, (k, rho, c) in SOLIDS.items():
        times, ratio, _ = conductance_ratio(R, k, rho, c, K_GAS, free_path, first_layer.REACH)
        at = [float(np.interp(math.log(t), np.log(times), ratio)) for t in (0.01, 0.1, 1.0, 10.0)]
        half, gas = half_pair_conductance(R, k, K_GAS, 0.5 * free_path, reach_sin)
        print(f"| {name} | " + " | ".join(f"{x:.3f}" for x in at) + f" | {half / gas:.3f} |")
        ax.semilogx(times, ratio, label=name)
    ax.set_xlabel("time against the wall, s (thermal)")
    ax.set_ylabel("G(t) / G(0)")
    ax.set_title("First layer: the particle's own resistance (2 mm, air, 1 bar)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    out = pathlib.Path(__file__).resolve().parents[1] / "docs" / "verification" / "first_layer_ratio.png"
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
