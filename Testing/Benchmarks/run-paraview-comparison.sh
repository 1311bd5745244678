#!/usr/bin/env bash
# APC Volume against ParaView's own Volume representation (Projected tetra, Bunyk ray cast) on
# the real data (Data/windAroundBuildings/wind.pvtu, 331,699 cells in 8 Scotch pieces) at
# 1024x1024: builds, then runs paraview_vs_apc.py in pvbatch under mpirun on each rank count
# ($APC_COMPARE_RANKS, default "1 2 4": 1 rank is the reference image for holes and seams,
# 2 and 4 are the distributed runs), one pvbatch at a time under the project's private Xvfb.
# Writes out/benchmark/paraview_vs_apc.csv, one PNG per case and rank count, one log per rank
# count; prints the CSV and the time ratios.
# Arguments go to paraview_vs_apc.py (--size W H, --frames N, --sample-distance S, --cases ...,
# --distances ..., --only-rendered-array, --opacity ramp); $APC_COMPARE_OUT (default out/benchmark) is the
# output folder. run-evaluation.sh uses this script for the real-data experiment. Timings are wall clock on a shared 2-core machine (4 ranks are
# oversubscribed): the load average is printed around each run; rerun when it is high.
#
# ParaView's default setup:
#   run-paraview-comparison.sh --default-setup [--ranks "1 2 4"] [--sizes "1024x1024 1920x1080"]
#   run-paraview-comparison.sh --default-setup --opacity lower60 [...]
# runs paraview_vs_apc.py --setup paraview (ParaView's colour map and linear opacity ramp,
# every APC property at its default) for cases apc-default, apc-nostop (Stop Where Opaque off), auto,
# pt, apc-again and apc-nostop-again (APC's first frame again, stop on and off, once the process
# holds memory: only these two first frames compare the stop's first frame fairly), cameras fill and
# overview, first frame and later frames after small camera moves, once per rank count and
# image size, into $APC_COMPARE_OUT (default out/benchmark/paraview-default), one CSV per part
# (np<N>_<W>x<H>.csv; np<N>_<W>x<H>_lower60.csv with --opacity lower60, ParaView's ramp with the
# lower 60 % of the range transparent; replaced when that part is rerun, so the set can be run in parts), then
# writes the table of every part present to docs/evaluation/paraview_default_setup.md and the
# merged CSV beside it (report_paraview_default.py). Further arguments go to the script.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
default_setup=""
sizes=""
opacity=""
if [ "${1:-}" = "--default-setup" ]; then
  default_setup=1
  shift
  APC_COMPARE_RANKS=${APC_COMPARE_RANKS:-1 2 4}
  sizes="1024x1024 1920x1080"
  # These three in any place; every other argument goes on to paraview_vs_apc.py.
  rest=()
  while [ $# -gt 0 ]; do
    case "$1" in
      --ranks) APC_COMPARE_RANKS=$2; shift 2 ;;
      --sizes) sizes=$2; shift 2 ;;
      --opacity) opacity=$2; shift 2 ;;
      *) rest+=("$1"); shift ;;
    esac
  done
  set -- ${rest[@]+"${rest[@]}"}
  APC_COMPARE_OUT=${APC_COMPARE_OUT:-$top/out/benchmark/paraview-default}
fi
[ -n "${APC_NO_BUILD:-}" ] || bash "$top/.ci/build"
# $APC_COMPARE_PLUGIN: another build's plugin (with APC_NO_BUILD=1), e.g. to run two builds in turn.
plugin="${APC_COMPARE_PLUGIN:-$top/build/lib/paraview-5.11/plugins/APC/APC.so}"
[ -f "$plugin" ] || { echo "error: $plugin was not built" >&2; exit 1; }
out=${APC_COMPARE_OUT:-$top/out/benchmark}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN="$plugin" PYTHONPATH="$top/Plugin/Python"
ranks=${APC_COMPARE_RANKS:-1 2 4}

parts=()
for n in $ranks; do
for size in ${sizes:-default}; do
  extra=()
  part="$out/paraview_vs_apc_np$n.csv"
  log="$out/paraview_vs_apc_np$n.log"
  if [ -n "$default_setup" ]; then
    part="$out/np${n}_$size${opacity:+_$opacity}.csv"
    log="$out/np${n}_$size${opacity:+_$opacity}.log"
    extra=(--setup paraview ${opacity:+--opacity "$opacity"} --size "${size%x*}" "${size#*x}" --cases apc-default,apc-nostop,auto,pt,apc-again,apc-nostop-again
      --frames 3 --no-float-images --only-rendered-array)
  fi
  rm -f "$part"
  echo "== $n rank(s) ${sizes:+$size }; load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
  start=$(date +%s)
  status=0
  timeout 2400 bash "$top/.ci/with-xvfb" \
    mpirun --oversubscribe -np "$n" -x APC_PLUGIN -x PYTHONPATH \
    pvbatch --disable-xdisplay-test "$top/Testing/Benchmarks/paraview_vs_apc.py" \
    --output "$out" --csv "$part" "${extra[@]}" "$@" >"$log" 2>&1 || status=$?
  end=$(date +%s)
  grep -E '^(paraview_vs_apc|  )' "$log" || true
  echo "   $((end - start)) s; load average after: $(cut -d' ' -f1-3 /proc/loadavg);" \
    "'not well-formed' XML errors in the log (ParaView's redistribution failing):" \
    "$(grep -c 'not well-formed' "$log" || true); log: $log"
  if [ "$status" -ne 0 ] || [ ! -f "$part" ]; then
    echo "error: pvbatch on $n ranks failed (exit $status); last lines of $log:" >&2
    tail -30 "$log" >&2
    exit 1
  fi
  parts+=("$part")
done
done

py=/usr/bin/python3
[ -x "$py" ] || py=python3
if [ -n "$default_setup" ]; then
  "$py" "$top/Testing/Benchmarks/report_paraview_default.py" "$out" "$top/docs/evaluation"
  exit 0
fi

# Debian's python3 (a pyenv python3 may come first on PATH): $py above.
"$py" - "$out" "${parts[@]}" <<'EOF'
import csv
import os
import sys

out, parts = sys.argv[1], sys.argv[2:]
rows = []
for part in parts:
    with open(part) as fh:
        rows += list(csv.DictReader(fh))
merged = os.path.join(out, "paraview_vs_apc.csv")
with open(merged, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
print("\n" + open(merged).read())

print("Ratios (APC case / ParaView case, < 1 means APC is faster; same ranks, camera, transfer "
      "function):")
by = {(r["ranks"], r["distance"], r["case"]): r for r in rows}
for (ranks, distance, name), a in by.items():
    if a["representation"] != "APC Volume":
        continue
    for other in ("pt", "bunyk"):
        p = by.get((ranks, distance, other))
        if p:
            print("  %s ranks, distance %s: %s vs %s: first frame %.2f / %.2f s = %.2f, later "
                  "frames %.2f / %.2f s = %.2f" % (
                      ranks, distance, name, other, float(a["first_frame_s"]),
                      float(p["first_frame_s"]), float(a["first_frame_s"]) /
                      float(p["first_frame_s"]), float(a["frame_s"]), float(p["frame_s"]),
                      float(a["frame_s"]) / float(p["frame_s"])))
            if a.get("pass1_s") and a.get("pass2_s"):
                render = float(a["pass1_s"]) + float(a["pass2_s"])
                print("    render stages (pass 1 + pass 2) %.2f s = %.2f of %s's later frame" % (
                      render, render / float(p["frame_s"]), other))
EOF
