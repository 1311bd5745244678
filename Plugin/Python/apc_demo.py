"""The APC demo (pvbatch under mpirun): volume-renders the bundled OpenFOAM data
(windAroundBuildings, 8 pieces cut by the Scotch graph partitioner) with the "APC Volume"
representation. Every rank keeps exactly the pieces the reader gave it: the script prints each
rank's cells and bounds (they overlap: no depth order of the pieces exists), renders, writes the
screenshot (PNG) and the float image (EXR), and prints the compositing stages' timings.

    mpirun -np 4 pvbatch --disable-xdisplay-test apc_demo.py --output out
"""

import argparse
import os

from paraview.simple import *  # noqa: F401,F403
import apcparaview

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--output", default="out", help="folder for the images")
parser.add_argument("--size", type=int, nargs=2, default=[1024, 768])
parser.add_argument("--scene", choices=["wind", "puzzle"], default="wind",
                    help="the real OpenFOAM data, or the synthetic gear-teeth puzzle")
parser.add_argument("--frames", type=int, default=3, help="frames to render (and time)")


def main(args):
    apcparaview.load_plugin(ns=globals())
    ranks = apcparaview.number_of_ranks()
    if args.scene == "wind":
        data = XMLPartitionedUnstructuredGridReader(FileName=[os.path.join(
            here, "..", "..", "Data", "windAroundBuildings", "wind.pvtu")])
        field, lo, hi, unit = "U_mag", 0.0, 20.0, 5.0
        camera = ([-120, -260, 420], [155, 90, 40], [0, 0, 1])
    else:
        data = APCPuzzleSource(SlabsPerPiece=4, Resolution=64, Field="Spheres")
        field, lo, hi, unit = "Spheres", 0.0, 1.0, 0.1
        camera = ([3.6, 2.5, 4.5], [0, 0, 0], [0, 1, 0])

    print("APC demo: %s on %d ranks" % (args.scene, ranks))
    summaries = apcparaview.rank_summaries(data)
    for s in summaries:
        b = s["bounds"] or (0,) * 6
        print("  rank %d: %7d cells  bounds x[%7.1f %7.1f] y[%7.1f %7.1f] z[%7.1f %7.1f]"
              % ((s["rank"], s["cells"]) + tuple(b)))
    pairs = [(a, b) for a in summaries for b in summaries if a["rank"] < b["rank"]]
    overlapping = sum(all(a["bounds"][2 * d] < b["bounds"][2 * d + 1] and
                          b["bounds"][2 * d] < a["bounds"][2 * d + 1] for d in range(3))
                      for a, b in pairs if a["bounds"] and b["bounds"])
    print("  %d of %d rank pairs have overlapping bounds" % (overlapping, len(pairs)))

    os.makedirs(args.output, exist_ok=True)
    png = os.path.join(os.path.abspath(args.output), "apc_%s.png" % args.scene)
    exr = os.path.join(os.path.abspath(args.output), "apc_%s.exr" % args.scene)
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = args.size
    view.OrientationAxesVisibility = 0
    display = Show(data, view)
    display.Representation = "APC Volume"
    ColorBy(display, ("POINTS", field))
    lut = GetColorTransferFunction(field)
    lut.ApplyPreset("Cool to Warm", True)
    lut.RescaleTransferFunction(lo, hi)
    opacity = GetOpacityTransferFunction(field)
    if args.scene == "wind":
        # Still air in the buildings' wakes and the fast stream above them.
        opacity.Points = [0, 0.5, 0.5, 0, 2, 0.15, 0.5, 0, 5, 0, 0.5, 0, 12, 0, 0.5, 0,
                          16, 0.03, 0.5, 0, 20, 0.2, 0.5, 0]
    else:
        opacity.Points = [0, 0, 0.5, 0, 0.2, 0, 0.5, 0, 0.5, 0.12, 0.5, 0, 0.75, 0.05, 0.5, 0,
                          1, 0.95, 0.5, 0]
    display.ScalarOpacityUnitDistance = unit
    display.APCImageFile = exr
    Render(view)  # paraview.simple resets the camera on a view's first render: set ours after
    view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp = camera
    view.CameraViewAngle = 30

    for frame in range(args.frames):
        Render(view)
        t = apcparaview.last_timings(display)
        # Every stage that ran: they add up to the total.
        print("frame %d on the display rank: " % frame + ", ".join(
            "%s %.3f s" % stage for stage in apcparaview.stage_seconds(t)) +
            ", total %.3f s; %.1f MB sent by the display rank, %d pixels composited"
            % (t["total"], t["bytes_sent"] / 1e6, t["composited_pixels"]))
    SaveScreenshot(png, view, ImageResolution=args.size)
    after = apcparaview.rank_summaries(data)
    moved = [a["cells"] != b["cells"] for a, b in zip(summaries, after)]
    print("wrote %s and %s; cells per rank %s by rendering"
          % (png, exr, "CHANGED" if any(moved) else "unchanged"))


main(parser.parse_args())
