#!/usr/bin/env bash
# The demo: installs what is missing, builds, then runs the in-situ example on 4 MPI ranks: a
# simulation (Examples/Catalyst: a tracer carried by the wind through the buildings of the
# bundled OpenFOAM case, each rank advancing its own pieces of the graph-partitioned mesh)
# hands every time step to ParaView Catalyst, whose script renders every 200th step with APC
# Volume; then the same steps with ParaView's own Volume, and both steps' times side by side.
# Pictures: out/apc_insitu.png (the last step), out/apc/ and out/paraview/ (every step).
# APC_DEMO_RANKS (4), APC_DEMO_STEPS (400), APC_DEMO_EVERY (200), APC_DEMO_OUT (./out),
# APC_DEMO_PARAVIEW=0 skips ParaView's Volume (about 20 s per step here);
# APC_DEMO=pvbatch runs the earlier pvbatch demo instead (Plugin/Python/apc_demo.py).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$top/.ci/build"
out=${APC_DEMO_OUT:-$top/out}
ranks=${APC_DEMO_RANKS:-4}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN="$top/build/lib/paraview-5.11/plugins/APC/APC.so"
if [ "${APC_DEMO:-insitu}" = pvbatch ]; then
  export PYTHONPATH="$top/Plugin/Python${PYTHONPATH:+:$PYTHONPATH}"
  exec bash "$top/.ci/with-xvfb" \
    mpirun --oversubscribe -np "$ranks" -x APC_PLUGIN -x PYTHONPATH \
    pvbatch --disable-xdisplay-test "$top/Plugin/Python/apc_demo.py" --output "$out"
fi

csv="$out/insitu_steps.csv"
rm -f "$csv"
run() { # representation, output folder
  bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$ranks" \
    "$top/build/bin/apcCatalystMiniApp" --script "$top/Examples/Catalyst/apc_catalyst_tracer.py" \
    --steps "${APC_DEMO_STEPS:-400}" --every "${APC_DEMO_EVERY:-200}" --size 960 600 \
    --representation "$1" --output "$2" --csv "$csv" 2>&1 | grep --line-buffered -v "WARN|" || true
}
echo "== APC Volume, in situ on $ranks ranks"
run "APC Volume" "$out/apc"
last=$(ls "$out/apc"/tracer_*.png | tail -n 1)
cp "$last" "$out/apc_insitu.png"
if [ "${APC_DEMO_PARAVIEW:-1}" != 0 ]; then
  echo "== ParaView's Volume, the same steps"
  run "Volume" "$out/paraview"
fi
echo "== per-step times"
python3 "$top/Examples/Catalyst/compare_runs.py" "$csv"
echo "picture: $out/apc_insitu.png (the tracer in inferno colours, buildings grey)"
