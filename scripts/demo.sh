#!/usr/bin/env bash
# Sets up (installs missing Debian packages), builds probecomp and runs the main job.
# Until `probecomp demo` exists, the main job is the kernel's benchmark against OpenCASCADE: closest points
# and surface evaluation on a rational bicubic surface with a 20 × 20 control net.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
./build/probecomp --version
./build/bench/probecomp_bench --benchmark_filter='BM_ClosestPoint/|BM_ClosestPoint_OCCT|BM_SurfaceD1' \
  --benchmark_min_time=0.5 "$@"
