"""Read every Data/ file back with ParaView and check it (run with pvpython).

usage: pvpython verify_vtu.py FILE.vtu|FILE.pvtu ...
Per piece: cells, cell types, bounds, ranges. Asserts: no reader error (Debian's ParaView
reads an appended-mode file as 0 cells + an XML error), cells > 0, float32 fields, a .pvtu
reads as the sum of its pieces (through VTK and through a ParaView proxy), points shared by
pieces carry identical values (no seams), and a NAME.vtu next to NAME.pvtu has the same cells.
For the pieces of a .pvtu: how many pairs of piece bounding boxes overlap (graph partitions
are puzzle pieces: boxes overlap although the cells do not).
"""
import itertools
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np
from paraview import simple
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCellTypes
from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter
from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader, vtkXMLUnstructuredGridReader

def read(path, reader_class=vtkXMLUnstructuredGridReader):
    r = reader_class()
    errors = []
    r.AddObserver("ErrorEvent", lambda obj, event: errors.append(event))
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    assert not errors, f"{path}: reader error"
    assert g.GetNumberOfCells() > 0, f"{path}: no cells"
    return g


def describe(path, g):
    types = vtk_to_numpy(g.GetCellTypesArray())
    hist = ", ".join(f"{vtkCellTypes.GetClassNameFromTypeId(int(t)).replace('vtk', '')} {n}"
                     for t, n in zip(*np.unique(types, return_counts=True)))
    b = g.GetBounds()
    print(f"{os.path.basename(path)}: {g.GetNumberOfCells()} cells ({hist}), "
          f"{g.GetNumberOfPoints()} points, {os.path.getsize(path)} bytes")
    print(f"    bounds x [{b[0]:.4g}, {b[1]:.4g}] y [{b[2]:.4g}, {b[3]:.4g}] z [{b[4]:.4g}, {b[5]:.4g}]")
    for kind, data in (("point", g.GetPointData()), ("cell", g.GetCellData())):
        for i in range(data.GetNumberOfArrays()):
            a = data.GetArray(i)
            assert a.GetDataTypeAsString() == "float", f"{path}: {a.GetName()} not float32"
            lo, hi = a.GetRange()
            print(f"    {kind} {a.GetName()}: [{lo:.6g}, {hi:.6g}]")


def box_overlaps(boxes):
    """Pairs whose boxes intersect with positive volume; and those where the intersection
    holds more than half of the smaller box."""
    vol = lambda b: np.prod(np.maximum(b[1::2] - b[0::2], 0))
    pairs = list(itertools.combinations(range(len(boxes)), 2))
    inter = [vol(np.ravel(np.column_stack([np.maximum(boxes[i][0::2], boxes[j][0::2]),
                                           np.minimum(boxes[i][1::2], boxes[j][1::2])])))
             for i, j in pairs]
    half = [v > 0.5 * min(vol(boxes[i]), vol(boxes[j])) for v, (i, j) in zip(inter, pairs)]
    return len(pairs), sum(v > 0 for v in inter), sum(half)


def fill(g):
    """Volume of the cells / volume of their bounding box."""
    f = vtkCellSizeFilter()
    f.SetInputData(g)
    f.Update()
    b = np.array(g.GetBounds())
    return vtk_to_numpy(f.GetOutput().GetCellData().GetArray("Volume")).sum() / np.prod(b[1::2] - b[0::2])


for path in sys.argv[1:]:
    if path.endswith(".vtu"):
        describe(path, read(path))
        continue
    # A .pvtu: each piece, then the whole through VTK and through ParaView.
    sources = [p.get("Source") for p in ET.parse(path).getroot().iter("Piece")]
    pieces = [read(os.path.join(os.path.dirname(path), s)) for s in sources]
    for s, g in zip(sources, pieces):
        describe(os.path.join(os.path.dirname(path), s), g)
        print(f"    cell volume / bbox volume {fill(g):.2f}")
    total = sum(g.GetNumberOfCells() for g in pieces)
    whole = read(path, vtkXMLPUnstructuredGridReader)
    proxy = simple.OpenDataFile(path)
    proxy.UpdatePipeline()
    pv_cells = proxy.GetDataInformation().GetNumberOfCells()
    assert whole.GetNumberOfCells() == total == pv_cells, (whole.GetNumberOfCells(), total, pv_cells)
    print(f"{os.path.basename(path)}: {len(pieces)} pieces, {total} cells = sum of pieces "
          f"(VTK reader and ParaView proxy)")
    single = path[:-len(".pvtu")] + ".vtu"
    if os.path.exists(single):
        assert read(single).GetNumberOfCells() == total, f"{single} differs from {path}"
        print(f"    same cell count as {os.path.basename(single)}")
    # Points shared by pieces: same coordinates must carry the same point values.
    pts = np.concatenate([vtk_to_numpy(g.GetPoints().GetData()) for g in pieces])
    _, inverse, counts = np.unique(pts, axis=0, return_inverse=True, return_counts=True)
    for name in (pieces[0].GetPointData().GetArrayName(i)
                 for i in range(pieces[0].GetPointData().GetNumberOfArrays())):
        vals = np.concatenate([vtk_to_numpy(g.GetPointData().GetArray(name)) for g in pieces])
        lo = np.full(counts.size, np.inf)
        hi = np.full(counts.size, -np.inf)
        np.minimum.at(lo, inverse, vals)
        np.maximum.at(hi, inverse, vals)
        assert np.all(lo == hi), f"{path}: point {name} differs between pieces"
    print(f"    {np.count_nonzero(counts > 1)} points shared by several pieces, identical values there")
    n, overlap, half = box_overlaps([np.array(g.GetBounds()) for g in pieces])
    print(f"    bounding boxes: {overlap} of {n} piece pairs overlap, {half} by more than half "
          f"of the smaller box")
print("verify: all files OK")
