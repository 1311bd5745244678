"""Export the last time step of an OpenFOAM case to .vtu pieces (run with pvpython).

usage: pvpython export_vtu.py CASE OUTDIR NAME FIELD... [--whole] [--pieces]
  --whole   write OUTDIR/NAME.vtu (the whole internal mesh)
  --pieces  write OUTDIR/NAME_<i>.vtu + NAME.pvtu, piece i = cells with cellDist == i
Vector fields are written as their magnitude FIELD_mag; every field as point AND cell data,
float32.

Why the pieces come from the whole case and not from processorN: the reader interpolates
cell data to points per dataset it reads, so reading processorN alone gives interface points
other values than its neighbour gives them (on wind: up to 50 of a 320 m2/s2 p range at ~2-3k
points per piece), i.e. seams that no renderer can fix. So we read the reconstructed case
once (one global interpolation) and cut it by `cellDist`, the processor id of each cell that
`decomposePar -cellDist` writes for the scotch `manual` decomposition. The reader copies
cellDist onto the tets/pyramids it splits polyhedra into, so the cut follows OpenFOAM cells.
"""
import os
import sys

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkFiltersCore import vtkExtractCells
from vtkmodules.vtkIOGeometry import vtkOpenFOAMReader
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter

args = [a for a in sys.argv[1:] if not a.startswith("--")]
case, outdir, name, fields = args[0], args[1], args[2], args[3:]
os.makedirs(outdir, exist_ok=True)

foam = os.path.join(case, "p.foam")  # the reader wants a file name; an empty one will do
open(foam, "a").close()
reader = vtkOpenFOAMReader()
reader.SetFileName(foam)
reader.SetDecomposePolyhedra(1)  # polyhedra -> tets + pyramids: linear VTK cell types only
reader.SetCreateCellToPoint(1)
reader.SetUse64BitFloats(0)
reader.UpdateInformation()
reader.DisableAllPatchArrays()
reader.SetPatchArrayStatus("internalMesh", 1)  # no boundary patches
reader.DisableAllCellArrays()
want = fields + (["cellDist"] if "--pieces" in sys.argv else [])
for f in want:
    reader.SetCellArrayStatus(f, 1)
times = [reader.GetTimeValues().GetValue(i) for i in range(reader.GetTimeValues().GetNumberOfTuples())]
reader.UpdateTimeStep(times[-1])
mesh = reader.GetOutput().GetBlock(0)
assert mesh.IsA("vtkUnstructuredGrid") and mesh.GetNumberOfCells() > 0, "nothing read"
print(f"{case}: time {times[-1]:g}, {mesh.GetNumberOfCells()} cells, {mesh.GetNumberOfPoints()} points")


def float32_fields(src):
    """The wanted fields of src (point and cell data) as float32 scalars; vectors -> |v|."""
    out = []
    for data in (src.GetPointData(), src.GetCellData()):
        arrays = []
        for f in fields:
            a = vtk_to_numpy(data.GetArray(f))
            if a.ndim == 2:
                a, f = np.linalg.norm(a, axis=1), f + "_mag"
            v = numpy_to_vtk(np.ascontiguousarray(a, dtype=np.float32), deep=1)
            v.SetName(f)
            arrays.append(v)
        out.append(arrays)
    return out


def write(grid, path):
    """Only points, cells and our fields; binary (inline base64) + zlib: Debian's ParaView
    cannot read the appended mode."""
    ug = vtkUnstructuredGrid()
    ug.SetPoints(grid.GetPoints())
    ug.SetCells(grid.GetCellTypesArray(), grid.GetCells())
    point_arrays, cell_arrays = float32_fields(grid)
    for a in point_arrays:
        ug.GetPointData().AddArray(a)
    for a in cell_arrays:
        ug.GetCellData().AddArray(a)
    ug.GetPointData().SetActiveScalars(point_arrays[0].GetName())
    ug.GetCellData().SetActiveScalars(cell_arrays[0].GetName())
    w = vtkXMLUnstructuredGridWriter()
    w.SetInputData(ug)
    w.SetFileName(path)
    w.SetDataModeToBinary()
    w.SetCompressorTypeToZLib()
    w.SetCompressionLevel(9)
    w.SetIdTypeToInt32()  # halves connectivity/offsets; our meshes are far below 2^31
    w.SetHeaderTypeToUInt64()
    assert w.Write() == 1, path
    print(f"  {path}: {ug.GetNumberOfCells()} cells, {os.path.getsize(path)} bytes")
    return point_arrays, cell_arrays


if "--whole" in sys.argv:
    write(mesh, os.path.join(outdir, f"{name}.vtu"))

if "--pieces" in sys.argv:
    dist = vtk_to_numpy(mesh.GetCellData().GetArray("cellDist")).astype(np.int64)
    nparts = int(dist.max()) + 1
    for i in range(nparts):
        ids = vtkIdList()
        for c in np.flatnonzero(dist == i):
            ids.InsertNextId(int(c))
        ex = vtkExtractCells()  # keeps cell order and only the points these cells use
        ex.SetInputData(mesh)
        ex.SetCellList(ids)
        ex.Update()
        point_arrays, cell_arrays = write(ex.GetOutput(), os.path.join(outdir, f"{name}_{i}.vtu"))

    def pdata(tag, arrays):
        lines = [f'    <{tag} Scalars="{arrays[0].GetName()}">']
        lines += [f'      <PDataArray type="Float32" Name="{a.GetName()}"/>' for a in arrays]
        return lines + [f"    </{tag}>"]

    pvtu = ['<?xml version="1.0"?>',
            '<VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
            '  <PUnstructuredGrid GhostLevel="0">']
    pvtu += pdata("PPointData", point_arrays) + pdata("PCellData", cell_arrays)
    pvtu += ['    <PPoints>', '      <PDataArray type="Float32" Name="Points" NumberOfComponents="3"/>',
             '    </PPoints>']
    pvtu += [f'    <Piece Source="{name}_{i}.vtu"/>' for i in range(nparts)]
    pvtu += ['  </PUnstructuredGrid>', '</VTKFile>']
    with open(os.path.join(outdir, f"{name}.pvtu"), "w") as f:
        f.write("\n".join(pvtu) + "\n")
    print(f"  {os.path.join(outdir, name)}.pvtu: {nparts} pieces")
