#!/usr/bin/env bash
# The paper's evaluation at this machine's scale, in one command:
#
#   bash Testing/Benchmarks/run-evaluation.sh [--quick]
#
# 1. image quality: apcQualitySweep (MBOIT vs EXACT for beta x moments x resolve on the spheres,
#    sandwich, gear-teeth and wind scenes);
# 2. weak scaling: apcScalingBenchmark on 1, 2, 4, 8 ranks (gear teeth, one piece per rank,
#    4 orbit cameras, APC vs the exact segment baseline; also N ranks vs one process);
# 3. segment transfers: apcSegmentAnalysis (direct send and computed binary swap vs APC's
#    payload, per-pixel segment-count heatmaps) for the same gear-teeth frames and the wind data;
# 4. real data: paraview_vs_apc.py in pvbatch (APC, Exact (segments), ParaView's Volume with
#    projected tetrahedra) at 2 and 4 ranks, 3 camera distances, first and later frames; APC
#    and segments also on 1 rank, the reference for the N-rank images;
# 5. make_evaluation_report.py: docs/evaluation.md and its plots, from the CSVs of 1-4.
#
# Results go to $APC_EVAL_OUT (default out/evaluation), the report to $APC_EVAL_DOCS (default
# docs). --quick runs every step at toy sizes (a minute or two; what ctest's EvaluationQuick
# runs, into a temporary folder); the full run took 25 minutes here.
#
# This machine has 2 cores: runs on more than 2 ranks are oversubscribed (mpirun
# --oversubscribe). Bytes and message counts do not depend on the cores; times above 2 ranks
# are not weak-scaling times. The report says so.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${APC_EVAL_OUT:-$top/out/evaluation}
docs=${APC_EVAL_DOCS:-$top/docs}
quick=0
for arg in "$@"; do
  case "$arg" in
    --quick) quick=1 ;;
    *) echo "usage: $0 [--quick]" >&2; exit 2 ;;
  esac
done

if [ "$quick" = 1 ]; then
  quality=(--size 48 --scenes spheres,sandwich)
  scaling=(--size 64 --frames 1)
  scaling_ranks="1 2"
  analysis=(--size 64 --wind-size 96 96 --gear-ranks 1,2 --wind-ranks 2 --wind-distances 1)
  realdata=(--size 96 96 --frames 1 --distances 1)
  realdata_ranks="2"
else
  quality=(--size 256)
  scaling=(--size 512 --frames 3)
  scaling_ranks="1 2 4 8"
  analysis=(--size 512 --wind-size 1024 1024 --gear-ranks 1,2,4,8 --wind-ranks 2,4,8
    --wind-distances 0.6,1,1.6)
  realdata=(--size 1024 1024 --frames 2 --distances 0.6,1,1.6)
  realdata_ranks="2 4"
fi

[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
export APC_NO_BUILD=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
bin="$top/build/bin"
rm -rf "$out"
mkdir -p "$out/quality"
log="$out/evaluation.log"
start=$(date +%s)
step() { echo "== $* ($(($(date +%s) - start)) s; load average $(cut -d' ' -f1-3 /proc/loadavg))" | tee -a "$log"; }

step "1/5 image quality"
bash "$top/.ci/with-xvfb" "$bin/apcQualitySweep" --out "$out/quality" "${quality[@]}" >>"$log" 2>&1

step "2/5 weak scaling on ranks: $scaling_ranks"
for n in $scaling_ranks; do
  bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" "$bin/apcScalingBenchmark" \
    "${scaling[@]}" --out "$out/scaling.csv" >>"$log" 2>&1
done

step "3/5 segment transfers"
bash "$top/.ci/with-xvfb" "$bin/apcSegmentAnalysis" --out "$out" "${analysis[@]}" >>"$log" 2>&1

step "4/5 real data in pvbatch"
mkdir -p "$out/realdata"
APC_COMPARE_OUT="$out/realdata" APC_COMPARE_RANKS=1 \
  bash "$top/Testing/Benchmarks/run-paraview-comparison.sh" --cases apc-default,segments \
  "${realdata[@]}" >>"$log" 2>&1
APC_COMPARE_OUT="$out/realdata" APC_COMPARE_RANKS="$realdata_ranks" \
  bash "$top/Testing/Benchmarks/run-paraview-comparison.sh" --cases apc-default,segments,pt \
  "${realdata[@]}" >>"$log" 2>&1

step "5/5 report"
machine="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'),"
machine+=" $(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo) RAM"
/usr/bin/python3 "$top/Testing/Benchmarks/make_evaluation_report.py" --results "$out" \
  --docs "$docs" --machine "$machine" --seconds "$(($(date +%s) - start))" \
  $([ "$quick" = 1 ] && echo --quick) | tee -a "$log"
step "done: $docs/evaluation.md; log $log"
