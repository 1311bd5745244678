"""pvbatch on N ranks: APC Graph Partition as ParaView users get it.

- the proxy is in the APC menu (filters group, ShowInMenu category "APC");
- label only: every rank keeps exactly its cells, PartitionId covers 0..K-1;
- moving (default): per-rank counts follow the pieces (rank r owns pieces [r*K/R, (r+1)*K/R))
  and nothing is lost;
- bad inputs (image data, K < 0, no cells) produce an empty output on every rank and the
  script goes on: no rank hangs.
"""

import sys

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager
import apcparaview

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("check failed:", what)


def main():
    apcparaview.load_plugin(ns=globals())
    ranks = apcparaview.number_of_ranks()

    prototype = servermanager.ProxyManager().GetPrototypeProxy("filters", "APCGraphPartition")
    check(prototype is not None, "APCGraphPartition is a filter proxy")
    if prototype is not None:
        hints = prototype.GetHints()
        menu = hints.FindNestedElementByName("ShowInMenu") if hints else None
        check(menu is not None and menu.GetAttribute("category") == "APC",
              "listed under Filters > APC")
        check(prototype.GetXMLLabel() == "APC Graph Partition", "labelled APC Graph Partition")

    # Interleaved slabs on every rank: a mesh whose pieces per rank are not graph pieces.
    source = APCPuzzleSource(SlabsPerPiece=3, Resolution=8, Field="Smooth")
    before = apcparaview.rank_summaries(source)
    total = sum(s["cells"] for s in before)

    k = 2 * ranks + 1
    label = APCGraphPartition(Input=source, NumberOfPartitions=k, LabelOnly=1, Seed=3)
    after = apcparaview.rank_summaries(label)
    check([s["cells"] for s in after] == [s["cells"] for s in before],
          "label only: every rank keeps its cells")
    check(tuple(label.CellData["PartitionId"].GetRange()) == (0.0, k - 1.0),
          "label only: PartitionId covers 0..K-1")

    moved = APCGraphPartition(Input=source, NumberOfPartitions=k, Seed=3)
    summaries = apcparaview.rank_summaries(moved)
    print("moved:", [s["cells"] for s in summaries])
    check(sum(s["cells"] for s in summaries) == total, "moving: every cell arrives")
    per_piece = total / k
    for s in summaries:
        owned = (s["rank"] + 1) * k // ranks - s["rank"] * k // ranks
        check(abs(s["cells"] - owned * per_piece) <= 0.03 * owned * per_piece + owned,
              "rank %d holds its %d piece(s)" % (s["rank"], owned))
    check(moved.CellData["PartitionId"] is not None, "moving: PartitionId present")
    check("Smooth" in moved.PointData.keys(), "moving: the point field is carried")

    # Bad inputs: an error on every rank (printed), an empty output, and everyone goes on.
    for name, bad in [("image data", APCGraphPartition(Input=Wavelet())),
                      ("K < 0", APCGraphPartition(Input=source, NumberOfPartitions=-1)),
                      ("no cells", APCGraphPartition(
                          Input=Threshold(Input=source, Scalars=["POINTS", "Smooth"],
                                          LowerThreshold=5, UpperThreshold=6)))]:
        print("expecting an error for", name)
        bad.UpdatePipeline()
        check(bad.GetDataInformation().GetNumberOfCells() == 0, name + ": empty output")
    # Still in lockstep: a collective after the failures completes.
    check(sum(s["cells"] for s in apcparaview.rank_summaries(moved)) == total,
          "all ranks still answer after the errors")


main()
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
sys.exit(1 if failures else 0)
