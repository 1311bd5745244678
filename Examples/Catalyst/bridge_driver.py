"""The Python route: a Python simulation hands its steps to Catalyst through ParaView's bridge
(paraview.catalyst.bridge), with the same analysis script as the C++ mini-app.

    mpirun -np 2 pvbatch --sym bridge_driver.py --script apc_catalyst_tracer.py --steps 4

Each rank reads its pieces of the wind mesh (piece p on rank p % ranks); the "simulation" is
a tracer front moving along x at the local wind speed, c = 1 where x < x_inlet + U_mag t (no
solver: the point is the hand-over). bridge.coprocess hands over one channel, "mesh"; the
script's other channel, "walls", stays empty here.
"""
import argparse
import os

from paraview.catalyst import bridge
from paraview import servermanager
from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet, vtkUnstructuredGrid
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader
from vtkmodules.util import numpy_support
import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser()
parser.add_argument("--script", default=os.path.join(here, "apc_catalyst_tracer.py"))
parser.add_argument("--data", default=os.path.join(here, "..", "..", "Data",
                                                   "windAroundBuildings", "wind.pvtu"))
parser.add_argument("--steps", type=int, default=4)
parser.add_argument("--dt", type=float, default=2.0)
args = parser.parse_args()

bridge.initialize()
bridge.add_pipeline(args.script)

pm = servermanager.vtkProcessModule.GetProcessModule()
rank, ranks = pm.GetPartitionId(), pm.GetNumberOfLocalPartitions()
reader = vtkXMLPUnstructuredGridReader()
reader.SetFileName(args.data)
reader.UpdateInformation()
pieces = reader.GetNumberOfPieces()
mesh = vtkMultiBlockDataSet()
mesh.SetNumberOfBlocks(pieces)
fields = []
for p in range(rank, pieces, ranks):
    reader.UpdatePiece(p, pieces, 0)
    block = vtkUnstructuredGrid()
    block.ShallowCopy(reader.GetOutput())
    centre = vtkCellCenters()
    centre.SetInputData(block)
    centre.Update()
    centres = numpy_support.vtk_to_numpy(centre.GetOutput().GetPoints().GetData())[:, 0]
    speed = numpy_support.vtk_to_numpy(block.GetCellData().GetArray("U_mag"))
    tracer = numpy_support.numpy_to_vtk(np.zeros(block.GetNumberOfCells(), np.float32), deep=1)
    tracer.SetName("tracer")
    block.GetCellData().AddArray(tracer)
    mesh.SetBlock(p, block)
    fields.append((centres, speed, tracer))

for step in range(args.steps + 1):
    time = step * args.dt
    for centres, speed, tracer in fields:  # the simulation's step
        values = numpy_support.vtk_to_numpy(tracer)
        values[:] = (centres < -20.0 + speed * time).astype(np.float32)
        tracer.Modified()
    bridge.coprocess(time, step, mesh, name="mesh")
bridge.finalize()
if rank == 0:
    import glob
    out = os.environ.get("APC_CATALYST_OUTPUT", "catalyst-out")
    print("bridge_driver: wrote %d images in %s" % (len(glob.glob(os.path.join(out, "*.png"))), out))
