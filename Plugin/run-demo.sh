#!/usr/bin/env bash
# The demo: installs what is missing, builds, then runs pvbatch on 4 MPI ranks with the APC
# plugin loaded on every rank. Output goes to ./out/ (override with APC_DEMO_OUT).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/.ci/build"
out=${APC_DEMO_OUT:-$top/out}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN="$top/build/lib/paraview-5.11/plugins/APC/APC.so"
export PYTHONPATH="$top/Plugin/Python${PYTHONPATH:+:$PYTHONPATH}"
bash "$top/.ci/with-xvfb" \
  mpirun --oversubscribe -np "${APC_DEMO_RANKS:-4}" -x APC_PLUGIN -x PYTHONPATH \
  pvbatch --disable-xdisplay-test "$top/Plugin/Python/apc_demo.py" --output "$out"
