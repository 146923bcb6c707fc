#!/usr/bin/env bash
# Sets up (installs missing Debian packages), builds probecomp and runs the main job.
# The main job is `probecomp demo`: the paper's free-form case simulated, compensated both ways and compared
# (Table 2); its files go to build/demo (extra arguments are passed to the demo).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
source scripts/release_build.sh
configure_release_build
cmake --build build -j"$(nproc)"
./build/probecomp --version
./build/probecomp demo --output-dir build/demo "$@"
