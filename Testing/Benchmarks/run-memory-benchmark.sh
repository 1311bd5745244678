#!/usr/bin/env bash
# Peak memory per rank of an APC frame: for each scene, view size and rank count,
# one pvbatch run showing APC Volume and one showing an outline of the same data at the same
# size (the floor: ParaView, the data, the window). Each rank's peak resident set comes from
# /usr/bin/time. Writes $APC_MEMORY_OUT/memory.csv (default out/memory) and prints a summary:
# the busiest rank's peak, APC's share above the floor, and that share per covered pixel
# ("process" numbers the ranks in the order they exit, as /usr/bin/time reports them).
#   APC_MEMORY_SIZES="1024 4096 8192" APC_MEMORY_RANKS="1 2 4" APC_MEMORY_SCENES="wind puzzle"
# Arguments go to memory_footprint.py (e.g. --sample-distance 8).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
out=${APC_MEMORY_OUT:-$top/out/memory}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN=${APC_PLUGIN:-$top/build/lib/paraview-5.11/plugins/APC/APC.so}
export PYTHONPATH="$top/Plugin/Python" LD_LIBRARY_PATH=${LD_LIBRARY_PATH:-}
script="$top/Testing/Benchmarks/memory_footprint.py"
csv="$out/memory.csv"
echo "scene,size,ranks,case,process,peak_mb,covered_pixels,seconds" >"$csv"
for scene in ${APC_MEMORY_SCENES:-wind puzzle}; do
  for size in ${APC_MEMORY_SIZES:-1024 4096 8192}; do
    for n in ${APC_MEMORY_RANKS:-1 2 4}; do
      for case in outline apc; do
        log="$out/${scene}_${size}_np${n}_${case}.log"
        # Each rank's line is appended to its own file (ranks writing one log interleave).
        peaks="$out/${scene}_${size}_np${n}_${case}.peaks"
        rm -f "$peaks"
        start=$(date +%s.%N)
        status=0
        timeout 3600 bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" -x APC_PLUGIN -x LD_LIBRARY_PATH \
          -x PYTHONPATH /usr/bin/time -a -o "$peaks" -f "APC-PEAK-KB %M" pvbatch --disable-xdisplay-test \
          "$script" --scene "$scene" --size "$size" "$size" --case "$case" "$@" \
          >"$log" 2>&1 || status=$?
        seconds=$(echo "$(date +%s.%N) - $start" | bc)
        covered=$(sed -n 's/.*APC-FOOTPRINT covered \([0-9]*\).*/\1/p' "$log" | head -1)
        if [ "$status" != 0 ] || [ -z "$covered" ]; then
          echo "$scene $size np$n $case: failed (status $status), see $log" >&2
          covered=-1
        fi
        rank=0
        for kb in $(sed -n 's/^APC-PEAK-KB \([0-9]*\)$/\1/p' "$peaks" 2>/dev/null); do
          echo "$scene,$size,$n,$case,$rank,$(echo "scale=1; $kb / 1024" | bc),$covered,$seconds" >>"$csv"
          rank=$((rank + 1))
        done
      done
    done
  done
done
/usr/bin/python3 - "$csv" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
peak, covered = {}, {}
for r in rows:
    key = (r["scene"], int(r["size"]), int(r["ranks"]), r["case"])
    peak[key] = max(peak.get(key, 0.0), float(r["peak_mb"]))
    covered[key] = int(r["covered_pixels"])
print("| scene | view | ranks | outline MB | APC MB | APC - outline MB | B per covered px |")
print("|---|---|---|---|---|---|---|")
for key in sorted(k for k in peak if k[3] == "apc"):
    floor = peak.get(key[:3] + ("outline",), float("nan"))
    extra = peak[key] - floor
    px = covered[key]
    per = "%.0f" % (extra * 2**20 / px) if px > 0 else "-"
    print("| %s | %d² | %d | %.0f | %.0f | %.0f | %s |" % (key[0], key[1], key[2], floor,
                                                           peak[key], extra, per))
EOF
