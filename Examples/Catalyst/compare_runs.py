"""Side by side: the per-step times of apcCatalystMiniApp runs (their --csv lines), one column
per representation, and the ratio APC Volume / ParaView's Volume of the same steps.

  compare_runs.py RUNS.csv [--summary SUMMARY.csv]

RUNS.csv holds the mini-app's lines: "step,REPRESENTATION,RANKS,STEP,CATALYST_S,SOLVER_S" and
"memory,REPRESENTATION,RANKS,RANK,PEAK_MB,". Prints a table per rank count; --summary writes
one line per rank count: mean time of the steps after the first (the first also sets up the
pipeline), the first step's time, peak memory over ranks, for each representation, and ratios.
"""
import argparse
import collections
import csv

APC, PARAVIEW = "APC Volume", "Volume"


def load(path):
    steps = collections.defaultdict(dict)    # (ranks) -> {(rep, step): seconds}
    memory = collections.defaultdict(dict)   # (ranks) -> {(rep, rank): MB}
    with open(path) as f:
        for row in csv.reader(f):
            if not row:
                continue
            kind, rep, ranks = row[0], row[1], int(row[2])
            if kind == "step":
                steps[ranks][(rep, int(row[3]))] = float(row[4])
            elif kind == "memory":
                memory[ranks][(rep, int(row[3]))] = float(row[4])
    return steps, memory


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("runs")
    parser.add_argument("--summary")
    args = parser.parse_args()
    steps, memory = load(args.runs)
    rows = []
    for ranks in sorted(steps):
        times = steps[ranks]
        numbers = sorted({s for (_, s) in times})
        print("%d rank%s: seconds per Catalyst step (render + write the PNG)" %
              (ranks, "" if ranks == 1 else "s"))
        print("  %6s  %10s  %16s  %6s" % ("step", APC, "ParaView Volume", "ratio"))
        for s in numbers:
            a, p = times.get((APC, s)), times.get((PARAVIEW, s))
            print("  %6d  %10s  %16s  %6s" % (
                s, "%.3f" % a if a is not None else "-", "%.3f" % p if p is not None else "-",
                "%.3f" % (a / p) if a and p else "-"))
        later = numbers[1:] or numbers
        mean = {rep: sum(times[(rep, s)] for s in later if (rep, s) in times) /
                max(1, sum((rep, s) in times for s in later)) for rep in (APC, PARAVIEW)}
        peak = {rep: max([v for (r, _), v in memory[ranks].items() if r == rep] or [0])
                for rep in (APC, PARAVIEW)}
        first = {rep: times.get((rep, numbers[0]), 0.0) for rep in (APC, PARAVIEW)}
        ratio = mean[APC] / mean[PARAVIEW] if mean[PARAVIEW] else float("nan")
        print("  steps after the first: APC %.3f s, ParaView's Volume %.3f s per step "
              "(ratio %.3f); peak memory per rank %.0f MB vs %.0f MB" %
              (mean[APC], mean[PARAVIEW], ratio, peak[APC], peak[PARAVIEW]))
        rows.append([ranks, len(later), "%.4f" % mean[APC], "%.4f" % mean[PARAVIEW],
                     "%.4f" % ratio, "%.3f" % first[APC], "%.3f" % first[PARAVIEW],
                     "%.1f" % peak[APC], "%.1f" % peak[PARAVIEW],
                     "%.3f" % (peak[APC] / peak[PARAVIEW]) if peak[PARAVIEW] else "nan"])
    if args.summary:
        with open(args.summary, "w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["ranks", "steps_timed", "apc_s_per_step", "paraview_s_per_step",
                          "ratio_apc_over_paraview", "apc_first_step_s",
                          "paraview_first_step_s", "apc_peak_mb_per_rank",
                          "paraview_peak_mb_per_rank", "memory_ratio"])
            out.writerows(rows)


main()
