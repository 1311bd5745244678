"""Renders one APC scene with ParaView (pvbatch under mpirun, or pvpython connected to a
pvserver with --server) and checks what every test of the ParaView integration needs:
each rank's cells before and after rendering (no redistribution), the float image the display
rank writes (--out), an optional comparison with a reference float image (--compare), and the
screenshot (--png).

Prints APC-TEST-PASSED or APC-TEST-FAILED (the ctest verdict) and the stage timings.
"""

import argparse
import os
import sys

from paraview.simple import *  # noqa: F401,F403
from paraview import servermanager
import apcparaview

parser = argparse.ArgumentParser()
parser.add_argument("--scene", choices=["puzzle", "wind", "flange", "flange-blocks"],
                    default="puzzle")
parser.add_argument("--puzzle-pieces", type=int, default=4)
parser.add_argument("--size", type=int, nargs=2, default=[160, 120])
parser.add_argument("--out", help="float image (.vti or .exr) written by the display rank")
parser.add_argument("--png", help="screenshot")
parser.add_argument("--compare", help="reference .vti: the RGBA must match within --tolerance")
parser.add_argument("--compare-if-apc", help="with --mode Auto: the reference .vti instead of "
                    "--compare when the last frame ran APC (Auto follows the measured time)")
parser.add_argument("--compare-also", action="append", default=[],
                    help="another reference .vti held to the same tolerance (repeatable)")
# The moments travel in 32-bit fixed point and the colour sums in float: N ranks match one to
# ~1e-6 here.
parser.add_argument("--tolerance", type=float, default=1e-5)
parser.add_argument("--outliers", type=int, default=0,
                    help="pixels allowed beyond --tolerance, by at most 0.05: where a lattice "
                         "sample lies within one depth-buffer step of opaque geometry that "
                         "ParaView cut differently on N ranks (ordered compositing moves it)")
parser.add_argument("--plane", action="store_true", help="add an opaque slice through the data")
parser.add_argument("--band-megapixels", type=float, default=0.0,
                    help="APC Band Size (megapixels): composite in bands of rows (0: default)")
parser.add_argument("--sample-distance", type=float, default=0.0,
                    help="APC sample distance (0: the scene's own)")
parser.add_argument("--paraview-volume", action="store_true",
                    help="add ParaView's own Volume of a resampled corner of the data (IceT then "
                         "composites in visibility order, without depth)")
parser.add_argument("--compare-png", help="reference screenshot: --png must match it to "
                    "--png-tolerance 8-bit steps")
parser.add_argument("--png-tolerance", type=int, default=1)
parser.add_argument("--mode", default="APC",
                    choices=["APC", "Local exact", "Exact (segments)", "Auto"])
parser.add_argument("--resolve", default="Renormalised (MBOIT)",
                    choices=["Renormalised (MBOIT)", "Plain sum (paper)",
                             "Hybrid (own exact, others by moments)"])
parser.add_argument("--drop-array-on-rank", type=int, default=-1,
                    help="remove the rendered array on this rank (a broken piece)")
parser.add_argument("--server", help="host:port of a pvserver to connect to")
parser.add_argument("--partition", type=int,
                    help="cut the scene with APC Graph Partition into this many pieces first "
                         "(0 = one per rank) and render the moved pieces")
parser.add_argument("--expect-blank", action="store_true",
                    help="the frame must be skipped (no float image written)")
parser.add_argument("--interactive", help="folder: interactive renders (camera moving) run "
                    "reduced, the next still render is bit-identical to the one before, and "
                    "the interactive picture reads as the still one (SSIM)")
parser.add_argument("--stop-where-opaque", help="folder: render with APCStopWhereOpaque off, "
                    "then on, on a nearly opaque transfer function; the stop must drop samples "
                    "and leave no pixel farther from --compare (an exact reference of the same "
                    "opaque scene) than 1/255 beyond where marching every sample leaves it")
parser.add_argument("--stop", type=int, choices=(0, 1),
                    help="set APCStopWhereOpaque (default: the property's default)")
parser.add_argument("--end-weights", choices=("Off", "All", "Boundary"),
                    help="set APCSampleEndWeights (it must be Boundary by default)")
parser.add_argument("--paraview-setup", action="store_true",
                    help="ParaView's default colour map and linear opacity ramp over the data "
                    "range, the representation's unit distance, APC's default sample distance")
parser.add_argument("--opaque", action="store_true",
                    help="a nearly opaque transfer function (what the stop is for)")
parser.add_argument("--offset", type=float, default=0.0,
                    help="move the data (and the camera) by this much along x, y and z, in "
                    "double precision: precision must not depend on where the mesh sits")
parser.add_argument("--scale", type=float, default=1.0,
                    help="scale the data (and the camera, sample and opacity unit distances) "
                    "by this factor after --offset")
parser.add_argument("--client-timings", action="store_true",
                    help="the timings must reach this client (total > 0): client-server")
parser.add_argument("--tiled", help="folder: a screenshot at twice the view size (ParaView "
                    "renders it in tiles) must equal one render of a view of that size")
parser.add_argument("--evaluation-setup", action="store_true",
                    help="the evaluation's transfer function (Testing/Benchmarks/"
                    "paraview_vs_apc.py: Cool to Warm, opacity on still air and the fast stream, "
                    "unit distance 5 on the wind data) at APC's default sample distance; it "
                    "makes the wakes behind the buildings, where cells overlap, visible")
args = parser.parse_args()

def check_tiled(view, check):
    """A screenshot at twice the view size is rendered by ParaView in 2x2 tiles (the window's
    tile scale and viewport, the camera's window centre); it must equal a single render of a
    view that size, to one 8-bit step (the float images equal to rounding)."""
    import numpy
    from PIL import Image

    os.makedirs(args.tiled, exist_ok=True)
    size = [2 * args.size[0], 2 * args.size[1]]
    tiled = os.path.join(args.tiled, "tiled.png")
    single = os.path.join(args.tiled, "single.png")
    SaveScreenshot(tiled, view, ImageResolution=size)
    view.ViewSize = size
    Render(view)
    SaveScreenshot(single, view, ImageResolution=size)
    view.ViewSize = args.size
    Render(view)
    a = numpy.asarray(Image.open(tiled).convert("RGB"), dtype=int)
    b = numpy.asarray(Image.open(single).convert("RGB"), dtype=int)
    check(a.shape == b.shape, "tiled screenshot size %s vs %s" % (a.shape, b.shape))
    if a.shape == b.shape:
        diff = numpy.abs(a - b)
        print("tiled %dx%d screenshot vs one render at that size: max |diff| = %d/255, "
              "pixels differing %d" % (size[0], size[1], int(diff.max()),
                                       int((diff.max(axis=2) > 0).sum())))
        check(int(diff.max()) <= 1, "the tiled screenshot equals the single render")
        check(int((b < 250).any(axis=2).sum()) > 100, "the single render shows the volume")


def float_rgba(path):
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    return image.GetDimensions(), vtk_to_numpy(image.GetPointData().GetArray("RGBA")).copy()


def sample_count(path):
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader

    reader = vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput().GetFieldData().GetArray("SampleCount").GetValue(0)


def check_opaque_stop(view, display, check):
    """APCStopWhereOpaque set through ParaView reaches the ray marcher: fewer samples, and
    against the exact reference no pixel moves farther than 1/255 beyond the unstopped
    image's error."""
    import numpy

    os.makedirs(args.stop_where_opaque, exist_ok=True)
    check(display.APCStopWhereOpaque == 1, "APCStopWhereOpaque is on by default")
    images = {}
    for stop in (0, 1):
        display.APCStopWhereOpaque = stop
        images[stop] = os.path.join(args.stop_where_opaque, "stop%d.vti" % stop)
        display.APCImageFile = images[stop]
        Render(view)
    display.APCImageFile = ""
    display.APCStopWhereOpaque = 1  # back to its default
    if apcparaview.number_of_ranks() > 1 and not os.path.exists(images[0]):
        return  # only the display rank writes and checks the images
    every, stopped = sample_count(images[0]), sample_count(images[1])
    print("samples: %d marching every sample, %d with the stop (%.3f)"
          % (every, stopped, stopped / max(every, 1)))
    check(stopped < 0.9 * every, "the stop drops samples on the opaque scene")
    (_, a), (_, b), (_, ref) = (float_rgba(images[0]), float_rgba(images[1]),
                                float_rgba(args.compare))
    check(a.shape == ref.shape and b.shape == ref.shape, "image sizes agree")
    if a.shape == ref.shape and b.shape == ref.shape:
        err_all = numpy.abs(a - ref).max(axis=1)
        err_stop = numpy.abs(b - ref).max(axis=1)
        worse = float((err_stop - err_all).max())
        print("largest |image - exact|: %.4f every sample, %.4f stopped; largest growth %.5f"
              % (float(err_all.max()), float(err_stop.max()), worse))
        check(worse <= 1.0 / 255, "no pixel farther from the exact image than 1/255 beyond "
              "the unstopped image's error")
        check(float(ref[:, 3].max()) > 0.99, "the reference is opaque somewhere")


def ssim_of(a_png, b_png):
    """SSIM of two screenshots (RGB in [0, 1]) by APC's metrics tool (held to scikit-image)."""
    import json
    import subprocess
    import tempfile

    import numpy
    from PIL import Image

    tool = os.environ.get("APC_METRICS_TOOL")
    if not tool:
        return None
    a = numpy.asarray(Image.open(a_png).convert("RGB"), dtype=numpy.float32) / 255.0
    b = numpy.asarray(Image.open(b_png).convert("RGB"), dtype=numpy.float32) / 255.0
    with tempfile.TemporaryDirectory() as tmp:
        paths = [os.path.join(tmp, n) for n in ("a.raw", "b.raw")]
        for path, image in zip(paths, (a, b)):
            image.astype("<f4").tofile(path)
        out = subprocess.run([tool] + paths + [str(a.shape[1]), str(a.shape[0]), "3", "1"],
                             stdout=subprocess.PIPE, text=True, check=True).stdout
    return json.loads(out)["ssim"]


def check_interactive(view, display, check):
    """Interactive renders (what ParaView does while the camera moves) render a reduced
    image; the still render after them is bit-identical to the still render before; the
    interactive picture reads as the still one."""
    import numpy

    os.makedirs(args.interactive, exist_ok=True)
    still, still_after, fast = (os.path.join(args.interactive, n + ".vti")
                                for n in ("still", "still_after", "interactive"))
    display.APCImageFile = still
    Render(view)
    SaveScreenshot(os.path.join(args.interactive, "still.png"), view, ImageResolution=args.size)
    display.APCImageFile = ""
    camera = GetActiveCamera()
    for step in range(4):
        camera.Azimuth(10)
        view.SMProxy.InteractiveRender()
    for step in range(4):
        camera.Azimuth(-10)
        if step == 3:
            display.APCImageFile = fast
        view.SMProxy.InteractiveRender()
    t = apcparaview.last_timings(display)
    reduction = display.APCInteractiveImageReduction
    check(t["image_reduction"] == reduction,
          "the interactive frame ran with image reduction %d (got %g)"
          % (reduction, t["image_reduction"]))
    dims, _ = float_rgba(fast)
    expected = [(n + reduction - 1) // reduction for n in args.size]
    check(list(dims[:2]) == expected, "interactive float image %s, expected %s" % (dims[:2], expected))
    # The interactive picture, as ParaView would show it while rotating.
    view.UseInteractiveRenderingForScreenshots = 1
    SaveScreenshot(os.path.join(args.interactive, "interactive.png"), view,
                   ImageResolution=args.size)
    view.UseInteractiveRenderingForScreenshots = 0
    display.APCImageFile = still_after
    Render(view)
    display.APCImageFile = ""
    check(apcparaview.last_timings(display)["image_reduction"] == 1,
          "the still frame is full size")
    (_, a), (_, b) = float_rgba(still), float_rgba(still_after)
    check(a.shape == b.shape and bool(numpy.array_equal(a, b)),
          "the still frame after interaction is bit-identical to the one before")
    ssim = ssim_of(os.path.join(args.interactive, "interactive.png"),
                   os.path.join(args.interactive, "still.png"))
    if ssim is not None:
        print("interactive vs still picture: SSIM %.4f" % ssim)
        check(ssim > 0.9, "the interactive picture reads as the still one (SSIM > 0.9)")


# Everything lives in main(): pvbatch runs programmable filters in this interpreter, and their
# helpers rebind module globals (e.g. "source").
def main():
    failures = []


    def check(ok, what):
        if not ok:
            failures.append(what)
            print("check failed:", what)


    if args.server:
        host, port = args.server.split(":")
        Connect(host, int(port))
    apcparaview.load_plugin(ns=globals())
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Data")

    if args.scene == "puzzle":
        scene_source = APCPuzzleSource(NumberOfPuzzlePieces=args.puzzle_pieces, SlabsPerPiece=4,
                                 Resolution=16, Field="Spheres")
        scene_array, lo, hi, unit, spacing = "Spheres", 0.0, 1.0, 0.2, 0.02
        camera = dict(CameraPosition=[2.5, 1.7, 3.1], CameraFocalPoint=[0, 0, 0],
                      CameraViewUp=[0, 1, 0])
    elif args.scene == "wind":
        scene_source = XMLPartitionedUnstructuredGridReader(
            FileName=[os.path.join(data, "windAroundBuildings", "wind.pvtu")])
        scene_array, lo, hi, unit, spacing = "U_mag", 0.0, 20.0, 20.0, 2.0
        camera = dict(CameraPosition=[-120, -260, 420], CameraFocalPoint=[155, 90, 40],
                      CameraViewUp=[0, 0, 1])
    elif args.scene == "flange-blocks":
        # A multiblock dataset (as the OpenFOAM and Exodus readers produce): the four Scotch
        # pieces of the flange as four blocks.
        blocks = [XMLUnstructuredGridReader(
            FileName=[os.path.join(data, "flange", "flange_%d.vtu" % i)]) for i in range(4)]
        scene_source = GroupDatasets(Input=blocks)
        scene_array, lo, hi, unit, spacing = "T", 273.0, 573.0, 0.005, 0.0005
        camera = dict(CameraPosition=[0.07, -0.06, 0.05], CameraFocalPoint=[0, -0.0025, -0.01],
                      CameraViewUp=[0, 0, 1])
    else:
        scene_source = XMLPartitionedUnstructuredGridReader(
            FileName=[os.path.join(data, "flange", "flange.pvtu")])
        scene_array, lo, hi, unit, spacing = "T", 273.0, 573.0, 0.005, 0.0005
        camera = dict(CameraPosition=[0.07, -0.06, 0.05], CameraFocalPoint=[0, -0.0025, -0.01],
                      CameraViewUp=[0, 0, 1])

    if args.partition is not None:
        scene_source.UpdatePipeline()
        cells_in = scene_source.GetDataInformation().GetNumberOfCells()
        scene_source = APCGraphPartition(Input=scene_source, NumberOfPartitions=args.partition)
        scene_source.UpdatePipeline()
        pieces = args.partition or apcparaview.number_of_ranks()
        info = scene_source.GetDataInformation()
        check(info.GetNumberOfCells() == cells_in, "partition kept all %d cells" % cells_in)
        ids = scene_source.CellData["PartitionId"]
        check(ids is not None and tuple(ids.GetRange()) == (0.0, pieces - 1.0),
              "PartitionId covers 0..%d" % (pieces - 1))

    if args.offset != 0 or args.scale != 1:
        # x -> scale * (x + offset), points in double (float points 1e7 away are 1 m apart).
        moved = ProgrammableFilter(registrationName="Moved", Input=scene_source)
        moved.OutputDataSetType = "vtkUnstructuredGrid"
        moved.Script = (
            "from vtkmodules.vtkCommonCore import vtkPoints\n"
            "from vtkmodules.util.numpy_support import vtk_to_numpy, numpy_to_vtk\n"
            "import numpy\n"
            "out = self.GetOutput(); out.ShallowCopy(self.GetInput())\n"
            "if out.GetPoints() is not None:\n"
            "    x = vtk_to_numpy(out.GetPoints().GetData()).astype(numpy.float64)\n"
            "    points = vtkPoints(); points.SetDataTypeToDouble()\n"
            "    points.SetData(numpy_to_vtk((x + %r) * %r, deep=1))\n"
            "    out.SetPoints(points)\n" % (args.offset, args.scale))
        scene_source = moved
        camera = {key: ([args.scale * (v + args.offset) for v in value]
                        if key != "CameraViewUp" else value) for key, value in camera.items()}
        unit *= args.scale
        spacing *= args.scale

    if args.drop_array_on_rank >= 0:
        broken = ProgrammableFilter(registrationName="BrokenPiece", Input=scene_source)
        broken.OutputDataSetType = "vtkUnstructuredGrid"
        broken.Script = (
            "from vtkmodules.vtkParallelCore import vtkMultiProcessController as C\n"
            "out = self.GetOutput(); out.ShallowCopy(self.GetInput())\n"
            "c = C.GetGlobalController()\n"
            "if c and c.GetLocalProcessId() == %d:\n"
            "    out.GetPointData().RemoveArray('%s')\n" % (args.drop_array_on_rank, scene_array))
        scene_source = broken

    before = apcparaview.rank_summaries(scene_source)
    for s in before:
        print("before:", s)

    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = args.size
    view.OrientationAxesVisibility = 0
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    display = Show(scene_source, view)
    display.Representation = "APC Volume"
    ColorBy(display, ("POINTS", scene_array))
    paraview_unit = display.ScalarOpacityUnitDistance  # the representation's, from the data
    lut = GetColorTransferFunction(scene_array)
    lut.RGBPoints = [lo, 0.2, 0.3, 1.0, 0.5 * (lo + hi), 0.9, 0.9, 0.9, hi, 1.0, 0.2, 0.1]
    pwf = GetOpacityTransferFunction(scene_array)
    pwf.Points = [lo, 0.05, 0.5, 0.0, hi, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = unit
    if args.opaque:
        pwf.Points = [lo, 0.5, 0.5, 0.0, hi, 0.9, 0.5, 0.0]
        display.ScalarOpacityUnitDistance = 0.1 * unit
    display.APCSampleDistance = (args.sample_distance * args.scale if args.sample_distance > 0
                                 else spacing)
    if args.evaluation_setup:
        lut.ApplyPreset("Cool to Warm", True)
        lut.RescaleTransferFunction(lo, hi)
        pwf.Points = [0, 0.5, 0.5, 0, 2, 0.15, 0.5, 0, 5, 0, 0.5, 0, 12, 0, 0.5, 0,
                      16, 0.03, 0.5, 0, 20, 0.2, 0.5, 0]
        display.ScalarOpacityUnitDistance = 5.0 * args.scale
        display.APCSampleDistance = 0.0
    if args.paraview_setup:
        # As the GUI leaves it: the default map and linear ramp over the data range, the
        # representation's unit distance, APC's default sample distance.
        display.RescaleTransferFunctionToDataRange(False, True)
        data_lo, data_hi = lut.RGBPoints[0], lut.RGBPoints[-4]
        pwf.Points = [data_lo, 0.0, 0.5, 0.0, data_hi, 1.0, 0.5, 0.0]
        display.ScalarOpacityUnitDistance = paraview_unit
        display.APCSampleDistance = 0.0
    display.APCMode = args.mode
    if args.stop is not None:
        display.APCStopWhereOpaque = args.stop
    if args.end_weights:
        # An enumeration (Off / All / Boundary): Python sees its text.
        check(display.APCSampleEndWeights in (2, "Boundary"),
              "APCSampleEndWeights is Boundary by default")
        display.APCSampleEndWeights = args.end_weights
    if args.band_megapixels > 0:
        display.APCBandMegapixels = args.band_megapixels
    display.APCResolveMode = args.resolve
    display.APCVerbosity = 1
    if args.out:
        display.APCImageFile = os.path.abspath(args.out)
        if os.path.exists(args.out):
            os.remove(args.out)
    if args.plane:
        slice_ = Slice(Input=scene_source)
        slice_.SliceType.Normal = [0, 0, 1]
        sd = Show(slice_, view)
        sd.Representation = "Surface"
        ColorBy(sd, None)
        sd.AmbientColor = sd.DiffuseColor = [0.1, 0.8, 0.2]
    if args.paraview_volume:
        # Image data: ParaView's Volume needs ordered compositing on several ranks.
        corner = ResampleToImage(Input=scene_source, UseInputBounds=0,
                                 SamplingBounds=[0.1, 1.0, 0.1, 1.0, 0.1, 1.0],
                                 SamplingDimensions=[24, 24, 24])
        pvd = Show(corner, view)
        pvd.Representation = "Volume"
        ColorBy(pvd, ("POINTS", scene_array))
        pvlut = GetColorTransferFunction(scene_array + "_pv")
        pvd.LookupTable = pvlut
        pvlut.RGBPoints = [lo, 1.0, 0.8, 0.0, hi, 0.0, 0.6, 0.2]
        pvpwf = GetOpacityTransferFunction(scene_array + "_pv")
        pvpwf.Points = [lo, 0.0, 0.5, 0.0, hi, 1.0, 0.5, 0.0]
        pvd.ScalarOpacityFunction = pvpwf
        pvd.ScalarOpacityUnitDistance = 0.05
    Render(view)  # paraview.simple resets the camera on a view's first render: set ours after
    for key, value in camera.items():
        setattr(view, key, value)
    view.CameraParallelProjection = 0
    view.CameraViewAngle = 30
    Render(view)
    if args.png:
        SaveScreenshot(args.png, view, ImageResolution=args.size)

    if args.tiled:
        check_tiled(view, check)
    if args.interactive:
        check_interactive(view, display, check)
    if args.stop_where_opaque:
        check_opaque_stop(view, display, check)

    t = apcparaview.last_timings(display)
    print("APC timings on the display rank: " + ", ".join(
        "%s %.4f s" % stage for stage in apcparaview.stage_seconds(t)) +
        ", total %.4f s, bytes sent %.0f, pixels composited %.0f, mode ran %d (0 APC, "
        "1 segments)" % (t["total"], t["bytes_sent"], t["composited_pixels"], t["mode"]))
    if args.client_timings:
        # The pass runs on the render server; these values were pulled from its display rank.
        check(t["total"] > 0 and t["pass1"] > 0 and t["image_reduction"] == 1,
              "the client sees the display rank's timings (total %.4f s, image reduction %g)"
              % (t["total"], t["image_reduction"]))

    after = apcparaview.rank_summaries(scene_source)
    check([s["cells"] for s in after] == [s["cells"] for s in before],
          "rendering moved no cells (per-rank counts unchanged)")

    if args.out:
        written = os.path.exists(args.out)
        check(written != args.expect_blank,
              "float image %s" % ("skipped" if args.expect_blank else "written"))
    if args.compare_png and args.png:
        import numpy
        from PIL import Image

        a = numpy.asarray(Image.open(args.png).convert("RGB"), dtype=int)
        b = numpy.asarray(Image.open(args.compare_png).convert("RGB"), dtype=int)
        check(a.shape == b.shape, "screenshot sizes %s vs %s" % (a.shape, b.shape))
        if a.shape == b.shape:
            diff = numpy.abs(a - b).max(axis=2)
            print("screenshot vs reference screenshot: max |diff| = %d/255, pixels differing %d"
                  % (int(diff.max()), int((diff > 0).sum())))
            check(int(diff.max()) <= args.png_tolerance,
                  "the screenshot matches the reference to %d/255" % args.png_tolerance)
    compare = args.compare_if_apc if args.compare_if_apc and t["mode"] == 0 else args.compare
    references = ([compare] if compare else []) + args.compare_also
    if references and args.out and os.path.exists(args.out):
        from vtkmodules.vtkIOXML import vtkXMLImageDataReader
        from vtkmodules.util.numpy_support import vtk_to_numpy
        import numpy

        def rgba(path):
            reader = vtkXMLImageDataReader()
            reader.SetFileName(path)
            reader.Update()
            return vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("RGBA")).astype(numpy.float64)

        a = rgba(args.out)
        for reference in references:
            b = rgba(reference)
            check(a.shape == b.shape, "image sizes %s vs %s" % (a.shape, b.shape))
            if a.shape != b.shape:
                continue
            per_pixel = numpy.abs(a - b).max(axis=1)
            diff = float(per_pixel.max())
            beyond = int((per_pixel > args.tolerance).sum())
            print("max |distributed - reference| = %.3g over %d pixels (max alpha %.3f), "
                  "%d pixels beyond %g (%s)" % (diff, a.shape[0], float(b[:, 3].max()), beyond,
                                                args.tolerance, os.path.basename(reference)))
            if args.outliers:
                check(beyond <= args.outliers and diff <= 0.05,
                      "within %g of %s but for %d pixels within 0.05"
                      % (args.tolerance, reference, args.outliers))
            else:
                check(diff <= args.tolerance, "within %g of %s" % (args.tolerance, reference))
            check(float(b[:, 3].max()) > 0.2, "the reference shows something")
    return failures


failures = main()
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
if failures:
    sys.exit(1)
