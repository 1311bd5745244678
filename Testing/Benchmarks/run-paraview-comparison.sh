#!/usr/bin/env bash
# APC Volume against ParaView's own Volume representation (Projected tetra, Bunyk ray cast) on
# the real data (Data/windAroundBuildings/wind.pvtu, 331,699 cells in 8 Scotch pieces) at
# 1024x1024: builds, then runs paraview_vs_apc.py in pvbatch under mpirun on each rank count
# ($APC_COMPARE_RANKS, default "1 2 4": 1 rank is the reference image for holes and seams,
# 2 and 4 are the distributed runs), one pvbatch at a time under the project's private Xvfb.
# Writes out/benchmark/paraview_vs_apc.csv, one PNG per case and rank count, one log per rank
# count; prints the CSV, the time ratios and how far each image is from its 1-rank image.
# Arguments go to paraview_vs_apc.py (--size W H, --frames N, --sample-distance S, --cases ...,
# --only-rendered-array). Timings are wall clock on a shared 2-core machine (4 ranks are
# oversubscribed): the load average is printed around each run; rerun when it is high.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bash "$top/.ci/build"
plugin="$top/build/lib/paraview-5.11/plugins/APC/APC.so"
[ -f "$plugin" ] || { echo "error: $plugin was not built" >&2; exit 1; }
out="$top/out/benchmark"
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export APC_PLUGIN="$plugin" PYTHONPATH="$top/Plugin/Python"
ranks=${APC_COMPARE_RANKS:-1 2 4}

parts=()
for n in $ranks; do
  part="$out/paraview_vs_apc_np$n.csv"
  log="$out/paraview_vs_apc_np$n.log"
  rm -f "$part"
  echo "== $n rank(s); load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
  start=$(date +%s)
  status=0
  timeout 900 bash "$top/.ci/with-xvfb" \
    mpirun --oversubscribe -np "$n" -x APC_PLUGIN -x PYTHONPATH \
    pvbatch --disable-xdisplay-test "$top/Testing/Benchmarks/paraview_vs_apc.py" \
    --output "$out" --csv "$part" "$@" >"$log" 2>&1 || status=$?
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

# Debian's python3 has numpy and PIL (a pyenv python3 may come first on PATH and lack them).
py=/usr/bin/python3
[ -x "$py" ] || py=python3
"$py" - "$out" "${parts[@]}" <<'EOF'
import csv
import os
import sys

out, parts = sys.argv[1], sys.argv[2:]
rows = []
for part in parts:
    with open(part) as fh:
        rows += list(csv.DictReader(fh))
columns = list(rows[0].keys())
merged = os.path.join(out, "paraview_vs_apc.csv")
with open(merged, "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=columns)
    w.writeheader()
    w.writerows(rows)
print("\n" + open(merged).read())


def case(r):
    return r["image"].rsplit("_np", 1)[0]


def find(ranks, name):
    return next((r for r in rows if r["ranks"] == ranks and case(r) == name), None)


print("Ratios (APC / ParaView, < 1 means APC is faster; same ranks, same camera and transfer "
      "function):")
for ranks in dict.fromkeys(r["ranks"] for r in rows):
    for name in ("apc", "apc-default"):
        a = find(ranks, name)
        if not a:
            continue
        sample = a["note"].split(";")[0].replace("sample distance ", "")
        for other in ("pt", "bunyk"):
            p = find(ranks, other)
            if not p:
                continue
            f = float(a["first_frame_s"]) / float(p["first_frame_s"])
            later = float(a["frame_s"]) / float(p["frame_s"])
            print("  %s ranks: APC (%s) vs %s: first frame %.2f / %.2f s = %.2f (%.1fx faster), "
                  "later frames %.2f / %.2f s = %.2f (%.1fx faster)" % (
                      ranks, sample, p["mapper"], float(a["first_frame_s"]),
                      float(p["first_frame_s"]), f, 1 / f, float(a["frame_s"]),
                      float(p["frame_s"]), later, 1 / later))

try:
    import numpy
    from PIL import Image
except ImportError:
    print("(numpy/PIL missing: no image comparison)")
    sys.exit(0)


def load(name):
    path = os.path.join(out, name)
    return numpy.asarray(Image.open(path).convert("RGB"), dtype=numpy.int16) if \
        os.path.exists(path) else None


def compare(a, b):
    d = numpy.abs(load(a) - load(b)).max(axis=2)
    return "%5.2f %% of pixels off by > 16/255, mean |diff| %.2f/255, max %d" % (
        100.0 * (d > 16).mean(), d.mean(), d.max())


print("\nImages against the same case's image at the lowest rank count (the reference):")
by_case = {}
for r in rows:
    by_case.setdefault(case(r), []).append(r)
for name, rs in by_case.items():
    rs = sorted(rs, key=lambda r: int(r["ranks"]))
    for r in rs[1:]:
        print("  %-12s %s ranks vs %s: %s" % (name, r["ranks"], rs[0]["ranks"],
                                              compare(r["image"], rs[0]["image"])))
    if len(rs) > 2:
        print("  %-12s %s ranks vs %s: %s" % (name, rs[-1]["ranks"], rs[-2]["ranks"],
                                              compare(rs[-1]["image"], rs[-2]["image"])))
print("\nAPC (--sample-distance) against ParaView's projected tetra at the same rank count (different "
      "algorithms, for scale):")
for ranks in dict.fromkeys(r["ranks"] for r in rows):
    if find(ranks, "apc") and find(ranks, "pt"):
        print("  %s ranks: %s" % (ranks, compare("apc_np%s.png" % ranks, "pt_np%s.png" % ranks)))
EOF
