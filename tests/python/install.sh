#!/bin/sh
# cmake --install to a fresh prefix, then `import probecomp` in a fresh shell (no variables from this one but
# PATH and the package's directory), and a compensation through the installed package.
# Usage: install.sh BUILD_DIR WORK_DIR PYTHON_INSTALL_DIR PYTHON
set -u
B=$1; W=$2; SUB=$3; PY=$4
rm -rf "$W"; mkdir -p "$W"
cmake --install "$B" --prefix "$W/prefix" >"$W/install.log" 2>&1 || { echo "FAIL: cmake --install"; cat "$W/install.log"; exit 1; }
[ -f "$W/prefix/$SUB/probecomp/__init__.py" ] || { echo "FAIL: no package in $W/prefix/$SUB"; exit 1; }
env -i PATH=/usr/bin:/bin PYTHONPATH="$W/prefix/$SUB" "$PY" -c '
import probecomp, numpy as np, sys
print("probecomp", probecomp.__version__, "from", probecomp.__file__)
assert probecomp.__file__.startswith(sys.argv[1]), probecomp.__file__
' "$W/prefix" || { echo "FAIL: import probecomp from the installed prefix"; exit 1; }
echo "installed to $W/prefix/$SUB and imported from a fresh shell"
