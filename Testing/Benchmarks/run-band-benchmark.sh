#!/usr/bin/env bash
# What compositing in bands costs in time and saves in memory: the same pvbatch frames
# (memory_footprint.py, the last of APC_BAND_FRAMES timed on the display rank) with the default
# Band Size, with one band for the whole view, and with a previous build's plugin
# (APC_PREVIOUS_PLUGIN, optional), side by side in one run. Writes
# $APC_BAND_OUT/bands.csv (default out/bands) and prints each variant's frame time and peak
# against the one-band frame's.
#   APC_BAND_SIZES="4096" APC_BAND_RANKS="1 2 4" APC_BAND_SCENES="puzzle wind"
# Arguments go to memory_footprint.py (e.g. --sample-distance 8).
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
out=${APC_BAND_OUT:-$top/out/bands}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
plugin=$top/build/lib/paraview-5.11/plugins/APC/APC.so
script="$top/Testing/Benchmarks/memory_footprint.py"
csv="$out/bands.csv"
echo "scene,size,ranks,variant,frame_seconds,peak_mb_max,covered_pixels" >"$csv"
variants="bands one-band"
[ -z "${APC_PREVIOUS_PLUGIN:-}" ] || variants="$variants previous"
for scene in ${APC_BAND_SCENES:-puzzle wind}; do
  for size in ${APC_BAND_SIZES:-4096}; do
    for n in ${APC_BAND_RANKS:-1 2 4}; do
      for variant in $variants; do
        log="$out/${scene}_${size}_np${n}_${variant}.log"
        peaks="$out/${scene}_${size}_np${n}_${variant}.peaks" # one line per rank, appended
        rm -f "$peaks"
        extra=()
        APC_PLUGIN=$plugin
        LD_LIBRARY_PATH=${LD_LIBRARY_PATH:-}
        case $variant in
          one-band) extra=(--band-megapixels 1024) ;;
          previous)
            APC_PLUGIN=$APC_PREVIOUS_PLUGIN
            LD_LIBRARY_PATH=$(dirname "$APC_PREVIOUS_PLUGIN")${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
            ;;
        esac
        export APC_PLUGIN LD_LIBRARY_PATH PYTHONPATH="$top/Plugin/Python"
        status=0
        timeout 3600 bash "$top/.ci/with-xvfb" mpirun --oversubscribe -np "$n" -x APC_PLUGIN \
          -x LD_LIBRARY_PATH -x PYTHONPATH /usr/bin/time -a -o "$peaks" -f "APC-PEAK-KB %M" pvbatch \
          --disable-xdisplay-test "$script" --scene "$scene" --size "$size" "$size" --case apc \
          --frames "${APC_BAND_FRAMES:-2}" "${extra[@]}" "$@" >"$log" 2>&1 || status=$?
        seconds=$(sed -n 's/.*APC-FRAME seconds \([0-9.]*\).*/\1/p' "$log" | head -1)
        covered=$(sed -n 's/.*APC-FOOTPRINT covered \([0-9]*\).*/\1/p' "$log" | head -1)
        peak=$(sed -n 's/^APC-PEAK-KB \([0-9]*\)$/\1/p' "$peaks" 2>/dev/null | sort -n | tail -1)
        if [ "$status" != 0 ] || [ -z "$seconds" ] || [ -z "$peak" ]; then
          echo "$scene $size np$n $variant: failed (status $status), see $log" >&2
          seconds=nan covered=-1 peak=0
        fi
        echo "$scene,$size,$n,$variant,$seconds,$(echo "scale=1; $peak / 1024" | bc),$covered" >>"$csv"
      done
    done
  done
done
/usr/bin/python3 - "$csv" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
base = {(r["scene"], r["size"], r["ranks"]): r for r in rows if r["variant"] == "one-band"}
print("| scene | view | ranks | variant | frame s | / one band | busiest rank MB | / one band |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    b = base.get((r["scene"], r["size"], r["ranks"]))
    t, bt = float(r["frame_seconds"]), float(b["frame_seconds"]) if b else float("nan")
    m, bm = float(r["peak_mb_max"]), float(b["peak_mb_max"]) if b else float("nan")
    print("| %s | %s² | %s | %s | %.2f | %.2f | %.0f | %.2f |" % (
        r["scene"], r["size"], r["ranks"], r["variant"], t, t / bt if bt else float("nan"), m,
        m / bm if bm else float("nan")))
PY
