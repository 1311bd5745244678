"""ColorBy(display, ('POINTS', 'v', 'X')) on an APC Volume renders v_x:
the same picture as colouring by a scalar array equal to v_x, and not the picture of |v|.
Point and cell arrays, on however many ranks pvbatch runs. Prints APC-TEST-PASSED or
APC-TEST-FAILED."""

import os
import sys

from paraview.simple import *  # noqa: F401,F403
import apcparaview


def main(out):
    failures = []

    def check(ok, what):
        if not ok:
            failures.append(what)
            print("check failed:", what)

    apcparaview.load_plugin(ns=globals())
    source = APCPuzzleSource(NumberOfPuzzlePieces=4, SlabsPerPiece=4, Resolution=12,
                             Field="Spheres")
    calc = Calculator(Input=source)
    calc.ResultArrayName = "v"
    calc.ResultArrayType = "Float"
    calc.Function = "Spheres*iHat + (0.3+0.2*coordsZ)*jHat + 0.5*kHat"
    cells = PointDatatoCellData(Input=calc)
    cells.PassPointData = 0

    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [96, 72]
    view.OrientationAxesVisibility = 0
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass

    # paraview.simple resets the camera on a view's first render: that one is thrown away.
    Show(source, view)
    Render(view)
    Hide(source, view)

    def render(data, colour_by, name):
        display = Show(data, view)
        display.Representation = "APC Volume"
        ColorBy(display, colour_by)
        array = colour_by[1]
        lut = GetColorTransferFunction(array)
        lut.AutomaticRescaleRangeMode = "Never"
        lut.RGBPoints = [0.0, 0.2, 0.3, 1.0, 0.5, 0.9, 0.9, 0.9, 1.0, 1.0, 0.2, 0.1]
        pwf = GetOpacityTransferFunction(array)
        pwf.Points = [0.0, 0.05, 0.5, 0.0, 1.0, 0.6, 0.5, 0.0]
        display.ScalarOpacityUnitDistance = 0.2
        display.APCSampleDistance = 0.03
        path = os.path.join(out, name + ".vti")
        if os.path.exists(path):
            os.remove(path)
        display.APCImageFile = path
        view.CameraPosition = [2.5, 1.7, 3.1]
        view.CameraFocalPoint = [0, 0, 0]
        view.CameraViewUp = [0, 1, 0]
        view.CameraViewAngle = 30
        Render(view)
        Hide(data, view)
        print("%s: vector mode %s, component %d" % (name, lut.VectorMode, lut.VectorComponent))
        return path

    from vtkmodules.vtkIOXML import vtkXMLImageDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy
    import numpy

    def rgba(path):
        reader = vtkXMLImageDataReader()
        reader.SetFileName(path)
        reader.Update()
        return vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("RGBA")).astype(numpy.float64)

    for kind, data in (("POINTS", calc), ("CELLS", cells)):
        x = rgba(render(data, (kind, "v", "X"), kind + "_vx"))
        s = rgba(render(data, (kind, "Spheres"), kind + "_spheres"))
        m = rgba(render(data, (kind, "v", "Magnitude"), kind + "_vmag"))
        same = float(numpy.abs(x - s).max())
        apart = float(numpy.abs(x - m).max())
        print("%s: max |v X - Spheres| = %.3g, max |v X - |v|| = %.3g, max alpha %.3f"
              % (kind, same, apart, float(s[:, 3].max())))
        check(same <= 1e-5, "%s: v X renders like the scalar equal to it" % kind)
        check(apart > 0.05, "%s: v X does not render like |v|" % kind)
        check(float(s[:, 3].max()) > 0.2, "%s: the picture shows something" % kind)
    return failures


failures = main(os.path.abspath(sys.argv[1]))
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
if failures:
    sys.exit(1)
