"""APC Volume's first frame against its later ones, in ParaView's default setup, one pvbatch run.

    mpirun -np N pvbatch --disable-xdisplay-test first_frame.py [--size W H] [--frames N]

Reads the bundled wind data (every array, as the GUI does), shows it as APC Volume coloured by
U_mag with ParaView's default linear opacity ramp and every APC property at its default, and
times Render() on rank 0: the first frame (the data's conversion and every per-data set-up) and
--frames later frames, each after a small camera move (one degree of azimuth). Prints one CSV
row: ranks, first frame, median later frame, their ratio, and the first frame's named timings.
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
for k, v in camera.items():  # Show() may have touched the camera
    setattr(view, k, v)


def frame():
    start = time.perf_counter()
    Render(view)
    return time.perf_counter() - start


first = frame()
first_timings = apcparaview.last_timings(display)
later = []
for _ in range(args.frames):
    view.GetActiveCamera().Azimuth(1.0)
    later.append(frame())
last_timings = apcparaview.last_timings(display)
median = statistics.median(later)


def stages(timings):
    return " ".join("%s=%.3f" % (k, v) for k, v in sorted(timings.items())
                    if isinstance(v, float) and 0.005 < v < 1e4)


print("first_frame,ranks=%d,first_s=%.3f,later_s=%.3f,ratio=%.3f,later=%s"
      % (ranks, first, median, first / median, "/".join("%.2f" % t for t in later)))
print("  first frame's timings: " + stages(first_timings))
print("  last frame's timings:  " + stages(last_timings), flush=True)
