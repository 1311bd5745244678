"""Scenes whose messages TestMessages.py counts (run by pvbatch on any number of ranks):
prints its own checks' verdict (APC-TEST-PASSED / APC-TEST-FAILED) and, one per line,
"APC-EXPECT <min> <max> <regex>": how many lines of the whole run's output must match.

--case view-settings: two APC volumes in one view asking for different view settings (the
  first shown: verbosity 1 and a float image file; the second: the defaults). The view follows
  the first one shown, whatever the order they are rendered in, and says once that the second
  asks for something else.
--case ranges: settings outside their range (negative sample distance, band size 0, beta 5,
  sample cache -5, interactive reduction 0, ...): one warning each, once for all ranks, and
  the frame renders with the clamped values.
--case sample-cap: a sample distance that would take ~35,000 samples per ray: capped at the
  stated limit (4096) with one warning saying what to change; the render stays quick.
--case solid-color: APC Volume coloured by Solid Color draws nothing and says so once (no error
  per frame); choosing an array draws again.
--case nan-once: NaN scalars and a collapsed cell are said once per data change: not again
  after display-property changes, again after the data changes.
--case overlap: two overlapping APC volumes asking for Exact (segments): the exact modes cannot
  interleave two volumes, so the view renders them with APC (the same float image as APC mode)
  and says so once; Auto never picks the segments while both are shown, and does again for
  one; the float image file is written.
--case refresh-timings: pushing "Refresh Timings" (what the panel's button does) fills "Last
  Timings" with the last frame's timings, without any other call.
"""

import argparse
import os
import sys

from paraview.simple import *  # noqa: F401,F403
import apcparaview

parser = argparse.ArgumentParser()
parser.add_argument("--case", required=True,
                    choices=["view-settings", "ranges", "sample-cap", "solid-color", "nan-once",
                             "refresh-timings", "overlap"])
parser.add_argument("--out", default=".", help="folder for files the scene writes")
args = parser.parse_args()

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("check failed:", what)


def expect(low, high, pattern):
    # One write of the whole line: pvbatch's Python writes unbuffered, so print() would send
    # the text and its newline apart, and a message another rank or thread prints between the
    # two would end up on the expectation's line.
    sys.stdout.write("APC-EXPECT %d %d %s\n" % (low, high, pattern))
    sys.stdout.flush()


def step(what):
    """Marks the output (stderr, as the messages), so that a wrong count shows where."""
    sys.stderr.write("APC-STEP %s\n" % what)
    sys.stderr.flush()


def make_view():
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [96, 72]
    view.OrientationAxesVisibility = 0
    return view


def apc_display(source, view, array="Spheres"):
    display = Show(source, view)
    display.Representation = "APC Volume"
    ColorBy(display, ("POINTS", array))
    GetOpacityTransferFunction(array).Points = [0.0, 0.05, 0.5, 0.0, 1.0, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = 0.2
    display.APCSampleDistance = 0.05
    return display


def view_settings():
    view = make_view()
    first = APCPuzzleSource(NumberOfPuzzlePieces=2, SlabsPerPiece=2, Resolution=8,
                            Field="Spheres")
    second = Transform(Input=APCPuzzleSource(NumberOfPuzzlePieces=2, SlabsPerPiece=2,
                                             Resolution=8, Field="Spheres"))
    second.Transform.Translate = [2.5, 0, 0]
    image = os.path.join(os.path.abspath(args.out), "view_settings.vti")
    if os.path.exists(image):
        os.remove(image)
    a = apc_display(first, view)
    a.APCVerbosity = 1
    a.APCImageFile = image
    Render(view)
    b = apc_display(second, view)  # shown second: asks for no file and no verbosity
    os.remove(image)  # written by the first render: it must be written again
    renders = 3
    for _ in range(renders):
        Render(view)
    check(os.path.exists(image), "the first volume's float image file is written")
    expect(1, 1, r"ask for different view settings \(Compositing Verbosity, Float Image File\)")
    # Asking alike ends the conflict: nothing more is said.
    b.APCVerbosity = 1
    b.APCImageFile = image
    Render(view)
    # Verbose frames: every render's, the first one's (one volume) and the others' (both;
    # paraview.simple's first render of a view may render twice).
    expect(renders + 2, renders + 3, r"APC frame \(")
    expect(0, 0, r"APC frame skipped|ERROR")


def puzzle():
    return APCPuzzleSource(NumberOfPuzzlePieces=2, SlabsPerPiece=2, Resolution=8,
                           Field="Spheres")


def ranges():
    view = make_view()
    display = apc_display(puzzle(), view)
    Render(view)
    bad = [("APCSampleDistance", -1.0, r"SampleDistance must be in \[0,"),
           ("APCBandMegapixels", 0.0, r"Band Size \(megapixels\) must be in \[0.01, 1024\]"),
           ("APCOverestimation", 5.0, r"Overestimation must be in \[0, 1\]"),
           ("APCSampleCacheSize", -5, r"SampleCacheSize must be in \[-1,"),
           ("APCInteractiveImageReduction", 0, r"Interactive Image Reduction must be in \[1, 16\]"),
           ("APCInteractiveSampleDistanceFactor", 0.5,
            r"Interactive Sample Distance Factor must be in \[1, 16\]"),
           ("APCVerbosity", 3, r"Compositing Verbosity must be in \[0, 1\]")]
    for name, value, pattern in bad:
        setattr(display, name, value)
        expect(1, 1, pattern)
    for _ in range(2):
        Render(view)
    t = apcparaview.last_timings(display)
    check(t["total"] > 0 and t["mode"] == 0, "the frame renders with the clamped values")
    expect(0, 0, r"ERROR|APC frame skipped")


def sample_cap():
    import time

    view = make_view()
    display = apc_display(puzzle(), view)
    # The puzzle's diagonal is 2*sqrt(3): 1e-4 would take ~34,600 samples per ray.
    display.APCSampleDistance = 1e-4
    start = time.perf_counter()
    for _ in range(2):
        Render(view)
    display.ScalarOpacityUnitDistance = 0.3  # a display change: nothing more to say
    Render(view)
    seconds = time.perf_counter() - start
    print("three renders at the capped distance: %.1f s" % seconds)
    check(seconds < 60, "capped renders take seconds, not minutes (%.1f s)" % seconds)
    expect(1, 1, r"Sample Distance 0.0001 would take up to 3\d{4} samples .* the limit is "
                 r"4096, so 0.000845\d* is used. Raise Sample Distance to at least")
    expect(0, 0, r"ERROR")


def solid_color():
    view = make_view()
    display = apc_display(puzzle(), view)
    Render(view)
    ColorBy(display, None)
    for _ in range(3):
        Render(view)
    display.ScalarOpacityUnitDistance = 0.3
    Render(view)
    t = apcparaview.last_timings(display)
    check(t["total"] == 0, "nothing is composited with Solid Color")
    expect(1, 1, r"APC Volume renders the values of an array: choose one in Coloring")
    expect(0, 0, r"ERROR|no scalars to render")
    ColorBy(display, ("POINTS", "Spheres"))
    Render(view)
    t = apcparaview.last_timings(display)
    check(t["total"] > 0 and t["covered_pixels"] > 0, "an array chosen again draws again")


# NaN scalars in the first cells of every rank's piece and one collapsed hexahedron (its eight
# corners in one plane); "shift" changes the data.
BROKEN = """
import numpy
from vtkmodules.util.numpy_support import vtk_to_numpy
out = self.GetOutput()
out.DeepCopy(self.GetInput())
pd = out.GetPointData()
for name in [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]:
    if name != "Spheres":
        pd.RemoveArray(name)
values = vtk_to_numpy(pd.GetArray("Spheres"))
values[:%(nans)d] = numpy.nan
ids = [out.GetPoints().InsertNextPoint(x, y, 0.0)
       for x, y in [(0, 0), (0.1, 0), (0.1, 0.1), (0, 0.1)] * 2]
for _ in ids:
    pd.GetArray("Spheres").InsertNextValue(0.5)
out.InsertNextCell(12, 8, ids)
"""


def nan_once():
    view = make_view()
    broken = ProgrammableFilter(Input=puzzle())
    broken.OutputDataSetType = "vtkUnstructuredGrid"
    broken.Script = BROKEN % dict(nans=20)
    display = apc_display(broken, view)
    step("first render")
    Render(view)
    # Display changes: the data is the same, nothing more to say.
    step("unit distance")
    display.ScalarOpacityUnitDistance = 0.3
    Render(view)
    step("sample distance")
    display.APCSampleDistance = 0.04
    Render(view)
    step("opacity")
    GetOpacityTransferFunction("Spheres").Points = [0.0, 0.1, 0.5, 0.0, 1.0, 0.7, 0.5, 0.0]
    Render(view)
    # The data changes: said again, once.
    step("data change")
    broken.Script = BROKEN % dict(nans=30)
    Render(view)
    Render(view)
    expect(2, 2, r"cells with a NaN or infinite scalar are transparent")
    expect(2, 2, r"cells with no volume \(collapsed, or all corners in one plane\) were skipped")


def refresh_timings():
    view = make_view()
    display = apc_display(puzzle(), view)
    Render(view)
    Render(view)
    # What the panel's button does: push the command property, then read the field it shows.
    display.SMProxy.InvokeCommand("APCRefreshTimings")
    names_property = display.GetProperty("APCLastTimingNames")
    names = names_property.GetData() if names_property else ""
    values = display.GetProperty("APCLastTimings").GetData()
    print("Last Timings after Refresh Timings, as the panel shows them:", list(values))
    names = (" ".join(names) if isinstance(names, (list, tuple)) else names or "").split()
    shown = dict(zip(names, values))
    check(shown.get("total", 0) > 0 and shown.get("pass1", 0) > 0,
          "Refresh Timings fills Last Timings (total %s)" % shown.get("total"))
    # The split of the stages with collectives and the ranks' render times travel too.
    parts = shown.get("tiles_wait", -1) + shown.get("tiles_transfer", -1)
    check(0 <= parts <= shown.get("tiles", 0) + 1e-9,
          "the tiles' wait and transfer are published and within the stage")
    renders = apcparaview.rank_render_seconds(display)
    check(len(renders) == 2 and max(renders) == shown.get("render_max"),
          "every rank's render seconds are published (%s)" % renders)
    expect(0, 0, r"ERROR")


def float_rgba(path):
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader
    from vtkmodules.util.numpy_support import vtk_to_numpy

    reader = vtkXMLImageDataReader()
    reader.SetFileName(path)
    reader.Update()
    return vtk_to_numpy(reader.GetOutput().GetPointData().GetArray("RGBA")).astype(float)


def overlap():
    view = make_view()
    first = puzzle()
    second = Transform(Input=puzzle())
    second.Transform.Translate = [0.5, 0.3, 0.2]  # overlaps the first
    displays = [apc_display(first, view), apc_display(second, view)]
    view.ResetCamera()
    images = {}
    for mode in ("APC", "Exact (segments)"):
        step(mode)
        images[mode] = os.path.join(os.path.abspath(args.out), "overlap_%s.vti" % mode[:3])
        if os.path.exists(images[mode]):
            os.remove(images[mode])
        for d in displays:
            d.APCMode = mode
            d.APCImageFile = images[mode]
        for _ in range(3):
            Render(view)
            ran = int(apcparaview.last_timings(displays[0])["mode"])
            check(ran == 0, "%s with two volumes runs APC (ran mode %d)" % (mode, ran))
        check(os.path.exists(images[mode]), "two volumes write the float image (%s)" % mode)
    if all(os.path.exists(p) for p in images.values()):
        a, b = (float_rgba(images[m]) for m in ("APC", "Exact (segments)"))
        diff = float(abs(a - b).max()) if a.shape == b.shape else float("inf")
        print("two volumes, Exact (segments) against APC: max |diff| = %g, max alpha %.3f"
              % (diff, float(a[:, 3].max())))
        check(diff <= 1e-6 and float(a[:, 3].max()) > 0.2,
              "Exact (segments) renders two volumes as APC does")
    expect(1, 1, r"cannot interleave 2 APC volumes where they overlap")
    step("Auto")
    for d in displays:
        d.APCMode = "Auto"
    for _ in range(3):
        Render(view)
        ran = int(apcparaview.last_timings(displays[0])["mode"])
        check(ran == 0, "Auto never composites segments with two volumes (ran mode %d)" % ran)
    Hide(second, view)
    Render(view)
    ran = int(apcparaview.last_timings(displays[0])["mode"])
    check(ran == 1, "with one volume left, Auto's first frame composites segments (ran %d)" % ran)
    expect(0, 0, r"ERROR|APC frame skipped")


apcparaview.load_plugin(ns=globals())
{"view-settings": view_settings, "ranges": ranges, "sample-cap": sample_cap,
 "solid-color": solid_color, "nan-once": nan_once,
 "refresh-timings": refresh_timings, "overlap": overlap}[args.case]()
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
if failures:
    sys.exit(1)
