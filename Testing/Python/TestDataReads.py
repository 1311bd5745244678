"""pvbatch on N ranks: the committed real data sets (Data/) read back whole, with their fields,
through ParaView's parallel XML reader (binary-mode files: Debian's ParaView rejects appended
mode in some paths)."""

import os
import sys

from paraview.simple import *  # noqa: F401,F403

data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Data")
failures = []

cases = [
    ("windAroundBuildings/wind.pvtu", 331699, ["p", "U_mag"]),
    ("flange/flange.pvtu", 5712, ["T"]),
    ("flange/flange.vtu", 5712, ["T"]),
]
for name, cells, fields in cases:
    reader = OpenDataFile(os.path.join(data, name))
    reader.UpdatePipeline()
    info = reader.GetDataInformation()
    got = info.GetNumberOfCells()
    print("%s: %d cells, point arrays %s, cell arrays %s"
          % (name, got, reader.PointData.keys(), reader.CellData.keys()))
    if got != cells:
        failures.append("%s has %d cells, expected %d" % (name, got, cells))
    for f in fields:
        if f not in reader.PointData.keys() or f not in reader.CellData.keys():
            failures.append("%s lacks point or cell array %s" % (name, f))

for f in failures:
    print("check failed:", f)
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
sys.exit(1 if failures else 0)
