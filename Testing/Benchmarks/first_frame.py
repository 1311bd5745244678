"""APC Volume's first frame against its later ones, in ParaView's default setup, one pvbatch run.

    mpirun -np N pvbatch --disable-xdisplay-test first_frame.py [--size W H] [--frames N]

Reads the bundled wind data (every array, as the GUI does), shows it as APC Volume coloured by
U_mag with ParaView's default linear opacity ramp and every APC property at its default, and
times Render() on rank 0: the first frame (the data's conversion and every per-data set-up) and
--frames later frames, each after a small camera move (one degree of azimuth). Prints one CSV
row: ranks, first frame, median later frame, their ratio, and the first frame's named timings.

--csv FILE writes the breakdown, one row per part: the first frame's and the median later
frame's wall seconds of each of APC's stages on rank 0 ("agree" holds the conversion of the VTK
grid, which only the first frame does; "pass1" holds the view's set-up: ray ends and binning),
the Render() time outside APC's stages (ParaView's own first-render work: the representation's
data delivery and the like), and the process CPU seconds of the whole Render() (robust on a
loaded machine: with `mpirun -np 1` the rank runs one thread). --apc-property NAME=VALUE sets a
property of the display (e.g. APCSampleCacheSize=0 to see the cache's share of pass 1).
"""

import argparse
import os
import statistics
import time

from paraview.simple import *  # noqa: F401,F403
from paraview import simple
import apcparaview

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--size", type=int, nargs=2, default=[1024, 1024])
parser.add_argument("--frames", type=int, default=3)
parser.add_argument("--csv", help="write the breakdown here (rank 0)")
parser.add_argument("--apc-property", action="append", default=[], metavar="NAME=VALUE")
parser.add_argument("--data", default=os.path.join(here, "..", "..", "Data",
                                                   "windAroundBuildings", "wind.pvtu"))
args = parser.parse_args()

apcparaview.load_plugin()
ranks = apcparaview.number_of_ranks()
simple._DisableFirstRenderCameraReset()
reader = XMLPartitionedUnstructuredGridReader(FileName=[os.path.abspath(args.data)])
reader.UpdatePipeline()

# The process's first view pays for the GL context: not part of any frame timed here.
warm = CreateView("RenderView")
warm.ViewSize = args.size
Render(warm)
Delete(warm)
del warm

view = CreateView("RenderView")
view.ViewSize = args.size
view.OrientationAxesVisibility = 0
camera = dict(CameraPosition=[-120, -260, 420], CameraFocalPoint=[155, 90, 40],
              CameraViewUp=[0, 0, 1], CameraViewAngle=30)
for k, v in camera.items():
    setattr(view, k, v)
display = Show(reader, view)
display.Representation = "APC Volume"
ColorBy(display, ("POINTS", "U_mag"))
for setting in args.apc_property:
    name, value = setting.split("=", 1)
    setattr(display, name, type(getattr(display, name))(value))
for k, v in camera.items():  # Show() may have touched the camera
    setattr(view, k, v)


cpu = []


def frame():
    start = time.perf_counter()
    start_cpu = time.process_time()
    Render(view)
    cpu.append(time.process_time() - start_cpu)
    return time.perf_counter() - start


first = frame()
first_timings = apcparaview.last_timings(display)
later = []
later_timings = []
for _ in range(args.frames):
    view.GetActiveCamera().Azimuth(1.0)
    later.append(frame())
    later_timings.append(apcparaview.last_timings(display))
last_timings = later_timings[-1]
median = statistics.median(later)

if args.csv:
    import csv

    parts = [("frame_wall", first, median), ("frame_cpu", cpu[0], statistics.median(cpu[1:])),
             ("outside_apc", first - first_timings["total"],
              statistics.median(w - t["total"] for w, t in zip(later, later_timings)))]
    parts += [(name, first_timings[name], statistics.median(t[name] for t in later_timings))
              for name in apcparaview.STAGES + ["total"]
              if first_timings.get(name, 0) > 0 or later_timings[-1].get(name, 0) > 0]
    with open(args.csv, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["part", "first_s", "later_s", "extra_s", "ranks", "width", "height",
                    "properties", "load_average"])
        load = open("/proc/loadavg").read().split()[0]
        for name, a, b in parts:
            w.writerow([name, "%.4f" % a, "%.4f" % b, "%.4f" % (a - b), ranks, args.size[0],
                        args.size[1], " ".join(args.apc_property), load])


def stages(timings):
    return " ".join("%s=%.3f" % (k, v) for k, v in sorted(timings.items())
                    if isinstance(v, float) and 0.005 < v < 1e4)


print("first_frame,ranks=%d,first_s=%.3f,later_s=%.3f,ratio=%.3f,later=%s"
      % (ranks, first, median, first / median, "/".join("%.2f" % t for t in later)))
print("  first frame's timings: " + stages(first_timings))
print("  last frame's timings:  " + stages(last_timings), flush=True)
