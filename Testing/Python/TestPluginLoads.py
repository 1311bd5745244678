"""pvbatch on N ranks: the APC plugin loads on every rank and its puzzle source generates, on
each rank, exactly that rank's piece (which only happens if every rank created the VTK object
from the plugin)."""

import sys

from paraview.simple import *  # noqa: F401,F403  (pvbatch scripts use the simple namespace)
import apcparaview

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("check failed:", what)


apcparaview.load_plugin(ns=globals())
ranks = apcparaview.number_of_ranks()
slabs, res = 4, 6
src = APCPuzzleSource(SlabsPerPiece=slabs, Resolution=res, Field="Smooth")
per_piece = slabs * res * res * 2

summaries = apcparaview.rank_summaries(src)
for s in summaries:
    print(s)
check(len(summaries) == ranks, "one summary per rank")
check(all(s["cells"] == per_piece for s in summaries), "every rank generated its own piece")
check(src.GetDataInformation().GetNumberOfCells() == ranks * per_piece, "total cells")
check(tuple(src.CellData["PuzzlePiece"].GetRange()) == (0.0, ranks - 1.0), "piece ids 0..N-1")
check("Smooth" in src.PointData.keys(), "the chosen field is the point scalar array")
lo, hi = src.PointData["Smooth"].GetRange()
check(0.0 <= lo < hi <= 1.0, "smooth field within [0,1]")

# The bounds of every pair of ranks overlap: the puzzle-piece property.
for a in summaries:
    for b in summaries:
        if a["rank"] < b["rank"]:
            overlap = all(a["bounds"][2 * d] < b["bounds"][2 * d + 1] and
                          b["bounds"][2 * d] < a["bounds"][2 * d + 1] for d in range(3))
            check(overlap, "bounds of ranks %d and %d overlap" % (a["rank"], b["rank"]))

print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED", "on", ranks, "ranks")
sys.exit(1 if failures else 0)
