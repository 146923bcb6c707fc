#!/usr/bin/env bash
# Installs the Debian 12 packages probecomp builds against, only those that are missing; with --tests also what the
# tests need beyond the build (a browser for the HTML report, Python for its checker); with --fuzz the libFuzzer
# runtime of the sanitizer build's fuzz targets.
# Safe to run repeatedly: when everything is present it does nothing and needs no network.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  clang                         # the compiler the scripts build with (scripts/release_build.sh)
  libeigen3-dev                 # linear algebra
  libocct-foundation-dev        # OpenCASCADE: TKernel, TKMath
  libocct-modeling-data-dev     # OpenCASCADE: Geom_BSplineSurface, BRep
  libocct-modeling-algorithms-dev # OpenCASCADE: GeomAPI_ProjectPointOnSurf (reference)
  libocct-data-exchange-dev     # OpenCASCADE: STEP and IGES readers and writers, XDE (STEP PMI; pulls in OCAF)
  libnanoflann-dev              # k-d tree for nearest seeds
  libcli11-dev                  # command line
  libpugixml-dev                # XML: QIF 3.0 point files in and out
  nlohmann-json3-dev            # JSON: the statistics, the studies' summaries, the report's data
  libxml2-utils                 # xmllint: the tests validate every QIF file written against the QIF 3.0 schemas
  libtbb-dev                    # oneTBB threads
  libgtest-dev                  # GoogleTest
  libbenchmark-dev              # Google Benchmark
  pybind11-dev python3-dev      # the Python package's compiled core
  python3-numpy                 # its arrays
)
if [ "${1:-}" = "--tests" ]; then
  packages+=(
    python3                     # tests/results/check_report.py: the report's numbers against the JSON, its screenshot
    python3-pytest              # the Python package's tests (tests/python)
    python3-matplotlib          # the example examples/compensate_and_plot.py draws with it
    chromium                    # renders the HTML report headless: no console error, the 3-D view not blank
    fonts-dejavu-core           # a font for it to draw text with
  )
fi
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(libclang-rt-dev)   # -fsanitize=fuzzer: its runtime is only recommended by clang, so named
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "setup: installing ${missing[*]}" >&2
if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo
else
  SUDO=
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
