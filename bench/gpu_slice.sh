#!/usr/bin/env bash
# The seed's cooler slice on a GPU (issue 31 item 8: what a GPU changes in the time to the
# seed's answers). On the lent device (`run` tool), from the repository root:
#     bash bench/gpu_slice.sh
# The device has no network: with no taichi importable, the wheels carried in .device/
# (taichi 1.7.4 for its python3, dill, colorama, trimesh, tomli-w; `pip download ... -d .device`
# here) are installed first. Prints: the CPU-vs-CUDA check of small scenes
# (bench/cuda_verify.py), the slice's step rate on CUDA at 30/60/90 kg/m and on the device's
# CPU cores at 60 kg/m, then the original design's map at 5 deg on CUDA (6 s per hold-up, as
# bench/seed_cooler.py maps it) with its wall time. Writes logs and the map under ${OUT:-out}.
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-out/gpu_slice}
mkdir -p "$OUT"
PY=${PY:-python3}
export PYTHONUNBUFFERED=1 PYTHONPATH=$PWD
if ! $PY -c "import taichi" 2>/dev/null; then
    $PY -m pip install --no-index --no-deps .device/*.whl > "$OUT/pip.log" 2>&1 || { tail "$OUT/pip.log"; exit 1; }
fi
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader || true
$PY -c "import taichi as ti; ti.init(arch=ti.cuda); print('cuda arch:', ti.lang.impl.current_cfg().arch)" 2>&1 | tail -2
echo "== the same physics on CUDA? (bench/cuda_verify.py)"
timeout 170 $PY bench/cuda_verify.py 2>&1 | grep -v "^\[Taichi\]" | tee "$OUT/verify.log"
echo "== the seed slice's step rate, CUDA"
timeout 120 $PY bench/cooler_slice_step.py --arch cuda --holdup 30 60 90 --settle 0.2 --seconds 0.5 2>&1 | grep "^run" | tee "$OUT/step_cuda.log"
echo "== the seed slice's step rate, the device's CPU ($(nproc) cores)"
timeout 60 $PY bench/cooler_slice_step.py --arch cpu --holdup 60 --settle 0.1 --seconds 0.1 2>&1 | grep "^run" | tee "$OUT/step_cpu.log"
echo "== the original design's map at 5 deg on CUDA (30/60/90 kg/m, 6 s each)"
t0=$(date +%s)
timeout 200 $PY -m taichi_dem map demos/cooler_slice.toml --holdup 30 60 90 --incline 5 --time 6 --arch cuda --out "$OUT/map5" 2>&1 | grep -v "unroll\|iterations\|non-static\|unrolling_limit\|ti.static" | tee "$OUT/map.log"
echo "map wall: $(( $(date +%s) - t0 )) s"
rm -f "$OUT/pip.log" "$OUT/map5/map.png" "$OUT/map5/map.csv"
