"""One pvbatch frame for the memory benchmark (run-memory-benchmark.sh): a scene at a view size,
shown as APC Volume or as an outline (the floor: ParaView, the data and a window of that size).

    mpirun -np N /usr/bin/time -f "APC-PEAK-KB %M" pvbatch memory_footprint.py --size 4096 4096

The runner reads each rank's peak resident set from /usr/bin/time; this script prints, on the
first rank, the pixels the volume covers and the view's pixels (APC-FOOTPRINT ...).
"""

import argparse
import os

from paraview.simple import *  # noqa: F401,F403
import apcparaview

parser = argparse.ArgumentParser()
parser.add_argument("--scene", choices=["wind", "puzzle"], default="wind")
parser.add_argument("--size", type=int, nargs=2, default=[1024, 1024])
parser.add_argument("--case", choices=["apc", "outline"], default="apc")
parser.add_argument("--sample-distance", type=float, default=0.0,
                    help="APC sample distance (0: the scene's default for this benchmark)")
parser.add_argument("--frames", type=int, default=1)
parser.add_argument("--sample-cache", type=int, default=1024,
                    help="APC Sample Cache (MB) per rank")
parser.add_argument("--band-megapixels", type=float, default=0.0,
                    help="APC Band Size (megapixels); 0: the default")
args = parser.parse_args()


def main():
    apcparaview.load_plugin(ns=globals())
    data = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Data")
    if args.scene == "wind":
        source = XMLPartitionedUnstructuredGridReader(
            FileName=[os.path.join(data, "windAroundBuildings", "wind.pvtu")])
        array, lo, hi, unit, spacing = "U_mag", 0.0, 20.0, 20.0, 4.0
        camera = dict(CameraPosition=[-120, -260, 420], CameraFocalPoint=[155, 90, 40],
                      CameraViewUp=[0, 0, 1])
    else:
        # Small: 4 puzzle pieces of 16^3 hexahedra split into slabs, seen whole.
        source = APCPuzzleSource(NumberOfPuzzlePieces=4, SlabsPerPiece=4, Resolution=16,
                                 Field="Spheres")
        array, lo, hi, unit, spacing = "Spheres", 0.0, 1.0, 0.2, 0.02
        camera = dict(CameraPosition=[2.5, 1.7, 3.1], CameraFocalPoint=[0, 0, 0],
                      CameraViewUp=[0, 1, 0])
    if args.sample_distance > 0:
        spacing = args.sample_distance
    view = CreateView("RenderView")
    view.ViewSize = args.size
    view.OrientationAxesVisibility = 0
    display = Show(source, view)
    if args.case == "apc":
        display.Representation = "APC Volume"
        ColorBy(display, ("POINTS", array))
        GetColorTransferFunction(array).RGBPoints = [lo, 0.2, 0.3, 1.0, hi, 1.0, 0.2, 0.1]
        GetOpacityTransferFunction(array).Points = [lo, 0.05, 0.5, 0.0, hi, 0.6, 0.5, 0.0]
        display.ScalarOpacityUnitDistance = unit
        display.APCSampleDistance = spacing
        if args.sample_cache != 1024:  # older builds lack the property
            display.APCSampleCacheSize = args.sample_cache
        if args.band_megapixels > 0:  # the property exists since the bands
            display.APCBandMegapixels = args.band_megapixels
    else:
        display.Representation = "Outline"
    # paraview.simple resets the camera on a view's first render: that render shows nothing,
    # so every timed frame is one of the case at the benchmark's camera.
    Hide(source, view)
    Render(view)
    for key, value in camera.items():
        setattr(view, key, value)
    view.CameraViewAngle = 30
    Show(source, view)
    for _ in range(args.frames):
        Render(view)
    covered = 0
    seconds = 0.0
    if args.case == "apc":
        timings = apcparaview.last_timings(display)
        covered = int(timings["covered_pixels"])
        seconds = timings["total"]
    print("APC-FOOTPRINT covered %d view %d" % (covered, args.size[0] * args.size[1]),
          flush=True)
    # The last frame's total on the display rank (the mesh was converted in the first).
    print("APC-FRAME seconds %.6f" % seconds, flush=True)


main()
