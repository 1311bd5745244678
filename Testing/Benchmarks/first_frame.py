"""APC Volume's first frame against its later ones, in ParaView's default setup, one pvbatch run.

    mpirun -np N pvbatch --disable-xdisplay-test first_frame.py [--size W H] [--frames N]

Reads the bundled wind data (every array, as the GUI does), shows it as APC Volume coloured by
U_mag with ParaView's default linear opacity ramp and every APC property at its default, and
times Render() on rank 0: the first frame (the data's conversion and every per-data set-up), the
same view rendered again without a camera move (what the first frame costs beyond its samples,
with the same samples) and --frames later frames, each after a small camera move (one degree of
azimuth). Prints one CSV row: ranks, first frame, median later frame, their ratio, and the
first frame's named timings.

--csv FILE writes the breakdown, one row per part: the first frame's, the same view's and the
median later frame's wall seconds of each of APC's stages on rank 0 ("agree" holds the
conversion of the VTK grid, which only the first frame does; "pass1" holds the view's set-up:
ray ends and binning, and the first touch of pass 1's buffers and sample cache), the Render()
time outside APC's stages (ParaView's own first-render work: the representation's data delivery,
the new view's framebuffers), the process CPU seconds of the whole Render() (user and system:
robust on a loaded machine, with `mpirun -np 1` the rank runs one thread) and its minor page
faults (memory paged in for the first time: on the virtual machines measured ~3-5 ms per MB,
in 4 KiB or in huge pages, when the memory is new to the machine). --apc-property NAME=VALUE
sets a property of the display (e.g. APCSampleCacheSize=0 to see the cache's share of pass 1).
"""

import argparse
import os
import resource
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


samples = []


def frame():
    before = resource.getrusage(resource.RUSAGE_SELF)
    start = time.perf_counter()
    Render(view)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_SELF)
    samples.append({"frame_wall": wall,
                    "frame_cpu": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
                    "frame_sys_cpu": after.ru_stime - before.ru_stime,
                    "page_faults": float(after.ru_minflt - before.ru_minflt)})
    return wall


first = frame()
first_timings = apcparaview.last_timings(display)
same = frame()  # the same view again: the same samples, no set-up
same_timings = apcparaview.last_timings(display)
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

    timed = [first_timings, same_timings] + later_timings
    for t, w in zip(timed, samples):
        w["outside_apc"] = w["frame_wall"] - t["total"]
        w.update((name, t.get(name, 0.0)) for name in apcparaview.STAGES + ["total"])
    names = ["frame_wall", "frame_cpu", "frame_sys_cpu", "page_faults", "outside_apc"]
    names += [n for n in apcparaview.STAGES + ["total"]
              if any(t.get(n, 0) > 0 for t in timed)]
    with open(args.csv, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["part", "first_s", "same_s", "later_s", "extra_s", "ranks", "width",
                    "height", "properties", "load_average"])
        load = open("/proc/loadavg").read().split()[0]
        for name in names:
            a, b = samples[0][name], samples[1][name]
            c = statistics.median(x[name] for x in samples[2:])
            fmt = "%.0f" if name == "page_faults" else "%.4f"
            w.writerow([name, fmt % a, fmt % b, fmt % c, fmt % (a - c), ranks, args.size[0],
                        args.size[1], " ".join(args.apc_property), load])


def stages(timings):
    return " ".join("%s=%.3f" % (k, v) for k, v in sorted(timings.items())
                    if isinstance(v, float) and 0.005 < v < 1e4)


print("first_frame,ranks=%d,first_s=%.3f,same_s=%.3f,later_s=%.3f,ratio=%.3f,later=%s"
      % (ranks, first, same, median, first / median, "/".join("%.2f" % t for t in later)))
print("  first frame's timings: " + stages(first_timings))
print("  last frame's timings:  " + stages(last_timings), flush=True)
