#!/usr/bin/env bash
# Weak scaling of vtkAPCCompositePass: builds, then runs apcScalingBenchmark under a virtual X
# server on N = 1 2 4 8 ranks (one gear-teeth puzzle piece per rank, so the work per rank is
# constant), collects out/benchmark/scaling.csv, prints it and, per N, the ratios APC/SEGMENTS
# of the compositing time (allreduce + reduce against exchange + gather, medians over the 4
# cameras) and of the bytes sent, then how much of each mode's compositing is the wait for the
# slowest rank and how much the transfer after the last arrival.
#
# Arguments go to the program (default: --size 512 --frames 5); RANKS="1 2 4" overrides the
# rank counts.
#
# NOTE: this machine has 2 cores, so runs with more than 2 ranks are oversubscribed
# (mpirun --oversubscribe): bytes and message counts do not depend on the cores and are
# meaningful at every N; the times of N > 2 are not weak-scaling times (ranks share cores,
# and a rank waits for every other's time slices).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
program="$top/build/bin/apcScalingBenchmark"
if [ ! -x "$program" ]; then
  echo "error: $program was not built (is Testing/Benchmarks added to the build?)" >&2
  exit 1
fi
out="$top/out/benchmark"
mkdir -p "$out"
csv="$out/scaling.csv"
rm -f "$csv"
if [ $# -eq 0 ]; then
  set -- --size 512 --frames 5
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
start=$(date +%s)
for n in ${RANKS:-1 2 4 8}; do
  bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" "$program" "$@" --out "$csv"
done
end=$(date +%s)
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg); benchmark $((end - start)) s"
echo
cat "$csv"
echo

python3 - "$csv" <<'PY'
import csv
import statistics
import sys

rows = list(csv.DictReader(open(sys.argv[1])))


def median(mode, n, key):
    values = [key(r) for r in rows if r["mode"] == mode and int(r["ranks"]) == n]
    return statistics.median(values) if values else float("nan")


def ratio(a, b):
    return a / b if b > 0 else float("nan")


print("ranks  APC comp s  SEG comp s  time APC/SEG  APC bytes  SEG bytes  bytes APC/SEG")
for n in sorted({int(r["ranks"]) for r in rows}):
    apc = median("APC", n, lambda r: float(r["allreduce_s"]) + float(r["reduce_s"]))
    seg = median("SEGMENTS", n, lambda r: float(r["exchange_s"]) + float(r["gather_s"]))
    apc_bytes = median("APC", n, lambda r: float(r["bytes_sent"]))
    seg_bytes = median("SEGMENTS", n, lambda r: float(r["bytes_sent"]))
    print(f"{n:5d}  {apc:10.5f}  {seg:10.5f}  {ratio(apc, seg):12.3f}  {apc_bytes:9.0f}"
          f"  {seg_bytes:9.0f}  {ratio(apc_bytes, seg_bytes):13.3f}")
print("(compositing time: APC allreduce + reduce, SEGMENTS exchange + gather; medians over"
      " the cameras of the max over ranks)")
print()
print("ranks  mode      compositing s  wait s  transfer s  wait share  render imbalance")
for n in sorted({int(r["ranks"]) for r in rows}):
    for mode, stages in (("APC", ("tiles", "allreduce", "reduce")),
                         ("SEGMENTS", ("exchange", "gather"))):
        comp = median(mode, n, lambda r: float(r["compositing_mean_s"]))
        wait = median(mode, n, lambda r: float(r["compositing_wait_mean_s"]))
        transfer = median(mode, n, lambda r: sum(float(r[s + "_transfer_s"]) for s in stages))
        imbalance = median(mode, n, lambda r: float(r["render_imbalance"]))
        print(f"{n:5d}  {mode:8s}  {comp:13.4f}  {wait:6.4f}  {transfer:10.4f}"
              f"  {ratio(wait, comp):10.3f}  {imbalance:16.3f}")
print("(compositing and its wait for the slowest rank: mean over ranks; transfer after the last"
      " arrival: max over ranks; medians over the cameras)")
PY
