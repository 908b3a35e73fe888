#!/usr/bin/env bash
# On a machine with an NVIDIA GPU (the lent device: `run` tool), from the repository root:
#     bash bench/gpu_check.sh
# Sets up .venv if needed, then prints: the chute cost on CUDA at 32k, 128k and 512k particles
# (f32, particle-steps per second, no LAMMPS there), the same on the CPU for the ratio, and
# the CPU-vs-CUDA comparison of small verification scenes (bench/cuda_verify.py).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || python3 tasks.py setup
PY=.venv/bin/python
nvidia-smi --query-gpu=name,memory.total --format=csv,noheader || true
echo "== chute on CUDA (f32)"
$PY bench/chute.py --arch cuda --no-lammps --sizes 32k 128k 512k --steps 1000 --repeats 3
echo "== chute on the CPU (f32, all cores)"
$PY bench/chute.py --no-lammps --sizes 32k 128k --steps 500 --repeats 1
echo "== the same physics on CUDA?"
$PY bench/cuda_verify.py
echo "== the seed's 6 m cooler (original design, 24 rows, 15 mm, 150 kg/m: ~585,000 spheres) on CUDA"
$PY bench/gpu_cooler.py --arch cuda --rows 24 --holdup 150 --time 2 --json /tmp/gpu_cooler.json || true
