#!/usr/bin/env bash
# Interactive orbit on the wind data (interactive_orbit.py): 36 interactive renders with camera
# azimuth steps, then one still render, for APC Volume with interactive frames off (apc:1x1,
# every frame full quality: the behaviour before interactive frames) and with the defaults (apc:2x2), and
# for ParaView's own Volume, at 1024x768, in pvbatch and in client-server (pvserver + pvpython
# client), on 2 and 4 ranks ($APC_ORBIT_RANKS). Writes per-frame and summary CSVs into
# $APC_ORBIT_OUT (default out/interactive) and prints the summaries. Arguments go to
# interactive_orbit.py (--frames, --cases, --size). Times are wall clock on a shared machine:
# the load average is printed; rerun when it is high.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
plugin="$top/build/lib/paraview-5.11/plugins/APC/APC.so"
out=${APC_ORBIT_OUT:-$top/out/interactive}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN="$plugin" PYTHONPATH="$top/Plugin/Python"
export APC_METRICS_TOOL="$top/build/bin/apcImageMetricsTool"
script="$top/Testing/Benchmarks/interactive_orbit.py"
for n in ${APC_ORBIT_RANKS:-2 4}; do
  echo "== pvbatch, $n ranks; load average $(cut -d' ' -f1-3 /proc/loadavg)"
  timeout 3600 bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" -x APC_PLUGIN \
    -x PYTHONPATH -x APC_METRICS_TOOL pvbatch --disable-xdisplay-test "$script" \
    --output "$out" "$@" 2>&1 | grep -v INFO | tee "$out/pvbatch_np$n.log" | grep -v '^\s*$' | tail -8
  echo "== client-server, $n ranks; load average $(cut -d' ' -f1-3 /proc/loadavg)"
  port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
  bash "$top/.ci/with-xvfb" bash -c "
    mpirun --oversubscribe -np $n -x APC_PLUGIN -x PYTHONPATH -x DISPLAY pvserver \
      --disable-xdisplay-test --server-port=$port >'$out/pvserver_np$n.log' 2>&1 &
    server=\$!
    sleep 8
    timeout 3600 pvpython --force-offscreen-rendering '$script' --server localhost:$port \
      --output '$out' $* 2>&1 | grep -v INFO | tee '$out/client_np$n.log' | tail -8
    kill \$server 2>/dev/null; wait \$server 2>/dev/null || true"
done
