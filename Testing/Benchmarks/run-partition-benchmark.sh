#!/usr/bin/env bash
# Speed of vtkAPCGraphPartition (Filters ▸ APC ▸ APC Graph Partition): builds, then runs
# apcPartitionBenchmark on 1 rank (label only: graph + partition) and, with RANKS="2 4", on more
# ranks (the pieces moved too), for K = 2 4 8 16 64 256 on the wind data and a 625k-cell
# tetrahedral mesh, METIS and PT-Scotch side by side (--partitioners). Writes
# out/benchmark/partition.csv and prints it.
#
# Arguments go to the program (e.g. --grid 58 --repeats 5 --k 2,16). Not a test: the times
# need a quiet machine (the load average is printed before and after).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
program="$top/build/bin/apcPartitionBenchmark"
out="$top/out/benchmark"
mkdir -p "$out"
csv="$out/partition.csv"
rm -f "$csv"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
mpirun -np 1 "$program" --label-only --out "$csv" "$@"
for n in ${RANKS:-}; do
  mpirun --oversubscribe -np "$n" "$program" --out "$csv" "$@"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
column -s, -t < "$csv"
