"""Partition an OpenFOAM mesh with APC's own filter and write the cell->part list for
decomposePar's `method manual` (run with pvpython; the alternative to scotch_partition.py).

The mesh is read with ParaView's OpenFOAM reader with *Decompose polyhedra* off, so VTK cell
i is OpenFOAM cell i (polyhedra stay whole), and vtkAPCGraphPartition (Filters > APC > APC
Graph Partition, METIS on the cell dual graph, Label Only) labels every cell with its part.
Needs the APC plugin built (APC_PLUGIN, or the build tree) and Plugin/Python on PYTHONPATH.

usage: pvpython apc_partition.py CASE NPARTS NAME [SEED]   (writes CASE/constant/NAME)
"""
import os
import sys

import numpy as np
from paraview import servermanager
from paraview.simple import *  # noqa: F401,F403
from vtkmodules.util.numpy_support import vtk_to_numpy

import apcparaview
from foam_label_list import write_label_list

case, nparts, name = sys.argv[1], int(sys.argv[2]), sys.argv[3]
seed = int(sys.argv[4]) if len(sys.argv) > 4 else 0
apcparaview.load_plugin(ns=globals())

foam = os.path.join(case, "p.foam")  # the reader wants a file name; an empty one will do
open(foam, "a").close()
reader = OpenFOAMReader(FileName=foam)
reader.MeshRegions = ["internalMesh"]
reader.CellArrays = []
reader.Decomposepolyhedra = 0  # one VTK cell per OpenFOAM cell, in OpenFOAM's order
partition = APCGraphPartition(Input=reader, NumberOfPartitions=nparts, LabelOnly=1, Seed=seed)
data = servermanager.Fetch(partition)
mesh = data.GetBlock(0) if data.IsA("vtkMultiBlockDataSet") else data
part = vtk_to_numpy(mesh.GetCellData().GetArray("PartitionId")).astype(np.int64)
assert part.min() >= 0 and part.max() < nparts, "every cell labelled"
sizes = np.bincount(part, minlength=nparts)
print(f"vtkAPCGraphPartition (METIS): {len(part)} cells -> {nparts} parts, "
      f"sizes {sizes.min()}..{sizes.max()}")

write_label_list(f"{case}/constant/{name}", part)
