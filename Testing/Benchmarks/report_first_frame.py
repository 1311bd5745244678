"""The first frame's breakdown as a Markdown table, from first_frame.py --csv files.

    python3 report_first_frame.py [LABEL=]A.csv [[LABEL=]B.csv ...] > table.md

One column group per build and run setting: CSVs with the same LABEL (e.g. main=, this=), size,
ranks and properties are one group, each value the median over its CSVs (the number of runs
in the heading). A group holds the first frame's seconds, the same view's again (no camera move:
the same samples), the median later frame's and the first's extra over it, per part.
frame_cpu is the process CPU time of the whole Render() (the robust number on a loaded
machine), frame_sys_cpu its system part (mostly page faults), page_faults its minor page
faults; the other parts are wall seconds of rank 0: outside_apc is Render() minus APC's stages
(ParaView's own first-render work), agree holds the conversion of the VTK grid, pass1 the view's
set-up (ray ends, binning) and the first touch of pass 1's memory. The last two rows are the
median over runs of each run's first frame divided by its same view and by its later frame.
"""

import csv
import statistics
import sys

ORDER = ["frame_cpu", "frame_sys_cpu", "page_faults", "frame_wall", "outside_apc", "agree",
         "depth", "pass1", "tiles", "profile", "cut", "allreduce", "pass2", "reduce", "resolve",
         "ranks", "blend", "total"]
COLUMNS = ["first_s", "same_s", "later_s", "extra_s"]


def read(argument):
    label, _, path = argument.rpartition("=")
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    first = rows[0]
    key = (label, first["width"], first["height"], int(first["ranks"]), first["properties"])
    return key, first.get("load_average", ""), {r["part"]: r for r in rows}


def main(arguments):
    groups = {}
    for argument in arguments:
        key, load, rows = read(argument)
        groups.setdefault(key, []).append((load, rows))
    heads = ["part"]
    for (label, width, height, ranks, properties), runs in groups.items():
        columns = [c for c in COLUMNS if c in runs[0][1][ORDER[0]]]
        loads = sorted(float(load) for load, _ in runs if load)
        what = "%s%sx%s, %d rank%s%s, %d run%s%s" % (
            label + ": " if label else "", width, height, ranks, "" if ranks == 1 else "s",
            ", " + properties if properties else "", len(runs), "" if len(runs) == 1 else "s",
            ", load %.1f-%.1f" % (loads[0], loads[-1]) if loads else "")
        heads += ["first (%s)" % what] + (["same view"] if "same_s" in columns else []) + [
            "later", "extra"]
    print("| " + " | ".join(heads) + " |")
    print("|" + "---|" * len(heads))
    for part in ORDER:
        cells = [part]
        present = False
        for runs in groups.values():
            columns = [c for c in COLUMNS if c in runs[0][1][ORDER[0]]]
            values = [rows[part] for _, rows in runs if part in rows]
            present = present or bool(values)
            for c in columns:
                if not values:
                    cells.append("")
                    continue
                median = statistics.median(float(v[c]) for v in values)
                cells.append("%.0f" % median if part == "page_faults" else "%.3f" % median)
        if present:
            print("| " + " | ".join(cells) + " |")
    # Ratios within each run (the robust numbers on a loaded machine), then their median: the
    # first frame over the same view again and over a later frame, wall and CPU.
    for part, name in (("frame_wall", "wall"), ("frame_cpu", "cpu")):
        cells = ["first / (same, later), %s" % name]
        for runs in groups.values():
            columns = [c for c in COLUMNS if c in runs[0][1][ORDER[0]]]
            rows = [r[part] for _, r in runs]
            ratio = {c: statistics.median(float(r["first_s"]) / float(r[c]) for r in rows)
                     for c in ("same_s", "later_s") if c in columns}
            cells += ["", "%.2f" % ratio["same_s"] if "same_s" in ratio else ""][
                :len(columns) - 2] + ["%.2f" % ratio["later_s"], ""]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
