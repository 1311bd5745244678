"""The first frame's breakdown as a Markdown table, from first_frame.py --csv files.

    python3 report_first_frame.py A.csv [B.csv ...] > table.md

One column group per CSV (its properties and size in the heading): the first frame's seconds,
the same view's again (no camera move: the same samples), the median later frame's and the
first's extra over it, per part. frame_cpu is the process CPU time of the whole Render() (the
robust number on a loaded machine), frame_sys_cpu its system part (mostly page faults),
page_faults its minor page faults; the other parts are wall seconds of rank 0: outside_apc is
Render() minus APC's stages (ParaView's own first-render work), agree holds the conversion of
the VTK grid, pass1 the view's set-up (ray ends, binning) and the first touch of pass 1's memory.
"""

import csv
import sys

ORDER = ["frame_cpu", "frame_sys_cpu", "page_faults", "frame_wall", "outside_apc", "agree",
         "depth", "pass1", "tiles", "profile", "cut", "allreduce", "pass2", "reduce", "resolve",
         "ranks", "blend", "total"]
COLUMNS = ["first_s", "same_s", "later_s", "extra_s"]


def main(paths):
    runs = []
    for path in paths:
        with open(path) as fh:
            rows = list(csv.DictReader(fh))
        runs.append((rows[0], {r["part"]: r for r in rows}))
    heads = ["part"]
    for first, _ in runs:
        what = "%sx%s, %d rank%s%s, load %s" % (
            first["width"], first["height"], int(first["ranks"]),
            "" if first["ranks"] == "1" else "s",
            ", " + first["properties"] if first["properties"] else "", first["load_average"])
        heads += ["first (%s)" % what] + (["same view"] if "same_s" in first else []) + [
            "later", "extra"]
    print("| " + " | ".join(heads) + " |")
    print("|" + "---|" * len(heads))
    for part in ORDER:
        cells = [part]
        present = False
        for _, rows in runs:
            row = rows.get(part)
            present = present or row is not None
            width = sum(1 for c in COLUMNS if c in rows[ORDER[0]])
            cells += [row[c] for c in COLUMNS if c in row] if row else [""] * width
        if present:
            print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
