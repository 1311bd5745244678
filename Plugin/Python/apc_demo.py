"""The APC demo (pvbatch under mpirun): every rank generates its own piece of the puzzle-piece
("gear teeth") data set, the script prints each rank's cell count and bounds, writes the
distributed data set as a .pvtu (one binary .vtu per rank) and reads it back to check it.

    mpirun -np 4 pvbatch --disable-xdisplay-test apc_demo.py --output out
"""

import argparse
import os
import sys

from paraview.simple import *  # noqa: F401,F403
import apcparaview

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--output", default="out", help="folder for the data set")
parser.add_argument("--slabs", type=int, default=4, help="slabs per puzzle piece")
parser.add_argument("--resolution", type=int, default=64, help="cells per slab side")
parser.add_argument("--field", default="Spheres", choices=["Spheres", "Smooth", "Sandwich"])
args = parser.parse_args()

apcparaview.load_plugin(ns=globals())
ranks = apcparaview.number_of_ranks()
src = APCPuzzleSource(SlabsPerPiece=args.slabs, Resolution=args.resolution, Field=args.field)

print("APC puzzle-piece data set on %d ranks: %d slabs x %d^2 x 2 hexahedra per piece"
      % (ranks, args.slabs, args.resolution))
summaries = apcparaview.rank_summaries(src)
for s in summaries:
    b = s["bounds"] or (0,) * 6
    print("  rank %d: %8d cells  bounds x[%6.3f %6.3f] y[%6.3f %6.3f] z[%6.3f %6.3f]"
          % ((s["rank"], s["cells"]) + tuple(b)))
pairs = [(a, b) for a in summaries for b in summaries if a["rank"] < b["rank"]]
overlapping = sum(all(a["bounds"][2 * d] < b["bounds"][2 * d + 1] and
                      b["bounds"][2 * d] < a["bounds"][2 * d + 1] for d in range(3))
                  for a, b in pairs if a["bounds"] and b["bounds"])
print("  %d of %d rank pairs have overlapping bounds: no depth order of the pieces exists"
      % (overlapping, len(pairs)))

os.makedirs(args.output, exist_ok=True)
path = os.path.join(os.path.abspath(args.output), "puzzle.pvtu")
# Binary (inline) mode: Debian's ParaView cannot read back XML files in appended mode.
SaveData(path, proxy=src, DataMode="Binary", CompressorType="ZLib", GhostLevel=0)
back = OpenDataFile(path)
back.UpdatePipeline()
cells_back = back.GetDataInformation().GetNumberOfCells()
cells = sum(s["cells"] for s in summaries)
print("wrote %s (%d cells); read back %d cells" % (path, cells, cells_back))
if cells_back != cells:
    print("ERROR: the written data set does not read back whole")
    sys.exit(1)
