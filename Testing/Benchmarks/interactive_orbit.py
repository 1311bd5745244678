"""Interactive orbit: what a GUI user feels while rotating, APC Volume against ParaView's own
Volume, in pvbatch or from a pvpython client connected to a pvserver (--server host:port).

    mpirun -np N pvbatch --disable-xdisplay-test interactive_orbit.py [options]
    pvpython interactive_orbit.py --server localhost:11111 [options]

On the bundled OpenFOAM data (Data/windAroundBuildings/wind.pvtu, 331,699 cells, U_mag) at
--size (default 1024x768), for each case: one untimed still render (a new representation's
first frame: ParaView's Volume redistributes the data then), --frames interactive renders
(vtkSMViewProxy::InteractiveRender, what the GUI does while the mouse drags the camera) each
after a camera azimuth step of 360/frames degrees, then one timed still render (the frame the
GUI renders when the mouse is released), back at the starting camera. Then the interactive and
the still picture at that camera (the interactive one captured with the view's
UseInteractiveRenderingForScreenshots) and their SSIM (APC's metrics, held to scikit-image).

Cases: "volume" (ParaView's Volume, Projected tetra), and "apc:<factor>x<reduction>" (APC
Volume with that interactive sample distance factor and image reduction; apc:1x1 renders
interactive frames at full quality, as before interactive frames existed).

Prints one CSV row per frame (--csv: per_frame rows) and one summary row per case (--summary):
median interactive seconds, still seconds, their ratio, SSIM. Times are wall clock on the
script's process (the client in client-server mode: they include the image delivery). The load
average is printed: this machine is shared, rerun when it is high.
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from paraview.simple import *  # noqa: F401,F403
import apcparaview

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--server", help="host:port of a pvserver")
parser.add_argument("--size", type=int, nargs=2, default=[1024, 768])
parser.add_argument("--frames", type=int, default=36)
parser.add_argument("--cases", default="apc:1x1,apc:2x2,volume")
parser.add_argument("--sample-distance", type=float, default=1.0, help="APC, metres")
parser.add_argument("--output", default="out/interactive")
parser.add_argument("--label", default="", help="a tag for the CSV rows (setting, ranks)")
parser.add_argument("--data", default=os.path.join(here, "..", "..", "Data",
                                                   "windAroundBuildings", "wind.pvtu"))
args = parser.parse_args()

FIELD, LO, HI, UNIT = "U_mag", 0.0, 20.0, 5.0
OPACITY = [0, 0.5, 0.5, 0, 2, 0.15, 0.5, 0, 5, 0, 0.5, 0, 12, 0, 0.5, 0,
           16, 0.03, 0.5, 0, 20, 0.2, 0.5, 0]
CAMERA = dict(CameraPosition=[-120, -260, 420], CameraFocalPoint=[155, 90, 40],
              CameraViewUp=[0, 0, 1], CameraViewAngle=30, CameraParallelProjection=0)


def ssim(a_png, b_png):
    import numpy
    from PIL import Image

    a = numpy.asarray(Image.open(a_png).convert("RGB"), dtype=numpy.float32) / 255.0
    b = numpy.asarray(Image.open(b_png).convert("RGB"), dtype=numpy.float32) / 255.0
    tool = os.environ.get("APC_METRICS_TOOL")
    if not tool:
        return float("nan")
    with tempfile.TemporaryDirectory() as tmp:
        paths = [os.path.join(tmp, n) for n in ("a.raw", "b.raw")]
        for path, image in zip(paths, (a, b)):
            image.astype("<f4").tofile(path)
        out = subprocess.run([tool] + paths + [str(a.shape[1]), str(a.shape[0]), "3", "1"],
                             stdout=subprocess.PIPE, text=True, check=True).stdout
    return json.loads(out)["ssim"]


def main():
    if args.server:
        host, port = args.server.split(":")
        Connect(host, int(port))
    apcparaview.load_plugin(ns=globals())
    os.makedirs(args.output, exist_ok=True)
    mode = "client-server" if args.server else "pvbatch"
    ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()
    reader = XMLPartitionedUnstructuredGridReader(FileName=[args.data])
    reader.UpdatePipeline()
    rows, summaries = [], []
    print("load average before: %s" % open("/proc/loadavg").read().split()[:3], flush=True)
    for case in args.cases.split(","):
        view = CreateView("RenderView")
        view.ViewSize = args.size
        view.OrientationAxesVisibility = 0
        display = Show(reader, view)
        if case == "volume":
            display.Representation = "Volume"
        else:
            factor, reduction = case.split(":")[1].split("x")
            display.Representation = "APC Volume"
            display.APCSampleDistance = args.sample_distance
            display.APCInteractiveSampleDistanceFactor = float(factor)
            display.APCInteractiveImageReduction = int(reduction)
        ColorBy(display, ("POINTS", FIELD))
        lut = GetColorTransferFunction(FIELD)
        lut.RescaleTransferFunction(LO, HI)
        GetOpacityTransferFunction(FIELD).Points = OPACITY
        display.ScalarOpacityUnitDistance = UNIT
        Render(view)
        for key, value in CAMERA.items():
            setattr(view, key, value)
        Render(view)  # untimed first frame
        camera = view.GetActiveCamera()
        step = 360.0 / args.frames
        interactive = []
        for i in range(args.frames):
            camera.Azimuth(step)
            start = time.perf_counter()
            view.SMProxy.InteractiveRender()
            interactive.append(time.perf_counter() - start)
            rows.append(dict(mode=mode, ranks=ranks, case=case, label=args.label, kind="interactive",
                             frame=i, seconds="%.4f" % interactive[-1]))
        start = time.perf_counter()
        Render(view)
        still = time.perf_counter() - start
        rows.append(dict(mode=mode, ranks=ranks, case=case, label=args.label, kind="still",
                         frame=args.frames, seconds="%.4f" % still))
        stem = os.path.join(args.output, "%s_np%d_%s" % (mode, ranks, case.replace(":", "_")))
        view.UseInteractiveRenderingForScreenshots = 1
        SaveScreenshot(stem + "_interactive.png", view, ImageResolution=args.size)
        view.UseInteractiveRenderingForScreenshots = 0
        SaveScreenshot(stem + "_still.png", view, ImageResolution=args.size)
        median = statistics.median(interactive)
        summaries.append(dict(mode=mode, ranks=ranks, case=case, label=args.label,
                              interactive_s="%.3f" % median, still_s="%.3f" % still,
                              still_over_interactive="%.1f" % (still / median),
                              ssim="%.4f" % ssim(stem + "_interactive.png", stem + "_still.png")))
        print("case done:", summaries[-1], flush=True)
        Delete(display)
        Delete(view)
    print("load average after: %s" % open("/proc/loadavg").read().split()[:3])
    for name, table in (("per_frame", rows), ("summary", summaries)):
        path = os.path.join(args.output, "%s_%s_np%d%s.csv" % (name, mode, ranks,
                                                             "_" + args.label if args.label else ""))
        with open(path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(table[0].keys()))
            writer.writeheader()
            writer.writerows(table)
        print("%s (%s):" % (name, path))
        if name == "summary":
            print(open(path).read())


main()
