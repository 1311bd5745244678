#!/usr/bin/env bash
# Speed of vtkAPCVolumeMapper against VTK's unstructured-grid volume mappers: builds, runs
# apcBenchmarkMappers under a virtual X server, writes out/benchmark/mappers.csv (and one PNG
# per data set and mapper), prints the CSV and a summary of the ratios against the targets.
# Arguments go to the program: --quick (256^2, 1 timed frame), --size N, --repeats N,
# --datasets gear,wind,flange, --threads 1,2, --zsweep-max-cells N, --time-cap S, ...
# Timings are wall clock on a shared machine: run it when nothing else is busy (the load
# average is printed before and after).
# Before/after in one run: APC_BASELINE_BUILD=<another build dir> (e.g. a `git worktree` of
# main built with .ci/build's settings) runs that build's apcBenchmarkMappers with the same
# arguments first, writes out/benchmark/mappers_baseline.csv and prints baseline/this ratios
# of the frame and of each pass.
set -euo pipefail
top=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bash "$top/.ci/build"
program="$top/build/bin/apcBenchmarkMappers"
if [ ! -x "$program" ]; then
  echo "error: $program was not built (is Testing/Benchmarks added to the build?)" >&2
  exit 1
fi
out="$top/out/benchmark"
mkdir -p "$out"

baseline=""
if [ -n "${APC_BASELINE_BUILD:-}" ]; then
  baseline="$out/mappers_baseline.csv"
  echo "baseline: $APC_BASELINE_BUILD/bin/apcBenchmarkMappers; load average $(cut -d' ' -f1-3 /proc/loadavg)"
  mkdir -p "$out/baseline"
  bash "$top/.ci/with-xvfb" "$APC_BASELINE_BUILD/bin/apcBenchmarkMappers" --out "$out/baseline" \
    --csv "$baseline" "$@"
fi
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
start=$(date +%s)
# The project's private Xvfb (2048x2048x24), not xvfb-run -a: with other X jobs running,
# xvfb-run's display race and auth cookie killed the benchmark's windows mid-run.
bash "$top/.ci/with-xvfb" "$program" --out "$out" --csv "$out/mappers.csv" "$@"
end=$(date +%s)
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg); benchmark $((end - start)) s"
echo
cat "$out/mappers.csv"
echo

python3 - "$out/mappers.csv" <<'EOF'
import csv
import sys

rows = list(csv.DictReader(open(sys.argv[1])))


def num(text):
    try:
        return float(text)
    except ValueError:
        return None


def frame(dataset, mapper, mode, threads, column="frame_s"):
    for r in rows:
        if (r["dataset"], r["mapper"], r["mode"], r["threads"]) == (dataset, mapper, mode, threads):
            return num(r[column])
    return None


def ratio(a, b):
    return f"{a / b:.2f}" if a and b else "-"


def check(value, target, above):
    if value is None:
        return "-"
    ok = value >= target if above else value <= target
    return f"{value:.2f} {'ok' if ok else 'MISSED'}"


threads = sorted({r["threads"] for r in rows if r["mapper"] == "apc"}, key=int)
most = threads[-1]
print(f"Summary (ratios; targets: MBOIT >= 2x faster than Bunyk, pass2/pass1 <= 1.2, "
      f"{most} threads >= 1.8x one thread)")
header = ["dataset", "mboit/bunyk", "matched/bunyk", "exact/bunyk", "pt/bunyk",
          "pass2/pass1", "setup/frame", "mboit x" + most, "exact x" + most, "bunyk x" + most]
table = [header]
for dataset in dict.fromkeys(r["dataset"] for r in rows):
    bunyk = frame(dataset, "bunyk", "", most)
    mboit = frame(dataset, "apc", "mboit", most)
    exact = frame(dataset, "apc", "exact", most)
    matched = frame(dataset, "apc", "mboit-matched", most)
    pt = frame(dataset, "pt", "", "gl")
    p1 = frame(dataset, "apc", "mboit", "1", "pass1_s")
    p2 = frame(dataset, "apc", "mboit", "1", "pass2_s")
    setup = frame(dataset, "apc", "mboit", most, "setup_s")
    speedups = []
    for mapper, mode in (("apc", "mboit"), ("apc", "exact"), ("bunyk", "")):
        one = frame(dataset, mapper, mode, "1")
        many = frame(dataset, mapper, mode, most)
        speedups.append(check(one / many, 1.8, True) if one and many else "-")
    table.append([
        dataset,
        check(bunyk / mboit, 2.0, True) if bunyk and mboit else "-",
        ratio(bunyk, matched),
        ratio(bunyk, exact),
        ratio(bunyk, pt),
        check(p2 / p1, 1.2, False) if p1 and p2 else "-",
        ratio(setup, mboit),
        *speedups,
    ])
widths = [max(len(row[c]) for row in table) for c in range(len(header))]
for row in table:
    print("  ".join(cell.ljust(w) for cell, w in zip(row, widths)))
print("(x/bunyk = Bunyk's frame time / x's at the same thread count, > 1 is faster than Bunyk;"
      " pass2/pass1 at 1 thread; matched = MBOIT with as many samples as Bunyk integrates"
      " segments)")

# A frame of t CPU-bound threads that had its cores to itself uses about t times its wall
# time in CPU time; much less means other processes took cores and the wall times (and the
# ratios and speedups) are inflated. Only 1-thread frames and APC's (whose serial part is
# tiny) are judged: Bunyk's per-frame set-up runs on one thread whatever its thread count.
noisy = []
for r in rows:
    wall, cpu = num(r["frame_s"]), num(r.get("cpu_s", ""))
    judged = r["threads"] == "1" or (r["mapper"] == "apc" and r["threads"].isdigit())
    if judged and wall and cpu and cpu < 0.85 * int(r["threads"]) * wall:
        noisy.append(f"{r['dataset']}/{r['mapper']}/{r['mode'] or '-'}/{r['threads']} threads: "
                     f"cpu {cpu:.3g} s in {wall:.3g} s wall")
if noisy:
    print("WARNING: other processes competed for the cores (frames got < 85 % of their threads' cores):")
    for line in noisy:
        print("  " + line)
    print("The numbers are noisy: rerun on a quiet machine.")
EOF

if [ -n "$baseline" ]; then
  python3 - "$baseline" "$out/mappers.csv" <<'EOF'
import csv
import sys


def load(path):
    return {(r["dataset"], r["mapper"], r["mode"], r["threads"]): r for r in csv.DictReader(open(path))}


def num(row, column):
    try:
        return float(row[column])
    except (KeyError, ValueError):
        return None


def per_sample(row, column):
    seconds, samples = num(row, column), num(row, "samples")
    return f"{seconds / samples * 1e9:.0f}" if seconds and samples else "-"


before, after = load(sys.argv[1]), load(sys.argv[2])
print("Against the baseline build, same arguments, same run (ratio = baseline time / this time,"
      " > 1 is faster; ns/sample = pass-1 time / lattice samples marched)")
header = ["dataset", "mode", "threads", "frame", "pass1", "pass2", "samples base/this",
          "pass1 ns/sample base/this"]
table = [header]
for key, row in after.items():
    old = before.get(key)
    if not old or key[1] != "apc":
        continue
    ratios = []
    for column in ("frame_s", "pass1_s", "pass2_s"):
        a, b = num(old, column), num(row, column)
        ratios.append(f"{a / b:.2f}x" if a and b else "-")
    table.append([key[0], key[2], key[3], *ratios,
                  f"{num(old, 'samples'):.3g}/{num(row, 'samples'):.3g}",
                  f"{per_sample(old, 'pass1_s')}/{per_sample(row, 'pass1_s')}"])
widths = [max(len(r[c]) for r in table) for c in range(len(header))]
for r in table:
    print("  ".join(cell.ljust(w) for cell, w in zip(r, widths)))
EOF
fi
