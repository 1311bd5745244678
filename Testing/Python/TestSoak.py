"""Soak test (pvbatch, any number of ranks): an APC volume rendered for --frames frames while
the camera turns, its data changing every --change-every frames (new scalars on the same cells,
then new cells, in turn), must keep every rank's resident memory flat once the first frames
have filled the sample cache and the buffers: the least-squares slope of the RSS over the last
--window frames must stay below --max-slope MB per frame on every rank. A leak of one frame's
samples or tiles (hundreds of kB here) would exceed it many times over. Prints each rank's RSS
series and slope, then APC-TEST-PASSED or APC-TEST-FAILED. Only rank 0 runs a pvbatch script:
it reads the other ranks' RSS from /proc (the ranks run on this machine, children of one
launcher).
"""

import argparse
import os

from paraview.simple import *  # noqa: F401,F403
import apcparaview

parser = argparse.ArgumentParser()
parser.add_argument("--frames", type=int, default=200)
parser.add_argument("--change-every", type=int, default=10)
parser.add_argument("--window", type=int, default=100, help="frames the slope is taken over")
parser.add_argument("--max-slope", type=float, default=0.05, help="MB per frame")
parser.add_argument("--size", type=int, nargs=2, default=[96, 72])
args = parser.parse_args()


def rss_mb(pid):
    try:
        with open("/proc/%d/status" % pid) as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def ranks_pids():
    """This process and its sibling pvbatch ranks (only rank 0 runs the script; the launcher,
    mpirun or orted, is the parent of every rank on this machine)."""
    parent = os.getppid()
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % entry) as stat:
                fields = stat.read().rsplit(")", 1)[1].split()
            with open("/proc/%s/comm" % entry) as comm:
                name = comm.read().strip()
        except OSError:
            continue
        if int(fields[1]) == parent and name.startswith("pvbatch"):
            pids.append(int(entry))
    return sorted(pids, key=lambda pid: (pid != os.getpid(), pid))


def slope(values):
    """Least-squares slope of values against their index."""
    n = len(values)
    mean_x = (n - 1) / 2.0
    mean_y = sum(values) / n
    num = sum((x - mean_x) * (y - mean_y) for x, y in enumerate(values))
    den = sum((x - mean_x) ** 2 for x in range(n))
    return num / den


apcparaview.load_plugin(ns=globals())
source = APCPuzzleSource(NumberOfPuzzlePieces=3, SlabsPerPiece=2, Resolution=6, Field="Spheres")
calc = Calculator(Input=source, ResultArrayName="Soak", Function="Spheres")
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = args.size
view.OrientationAxesVisibility = 0
display = Show(calc, view)
display.Representation = "APC Volume"
ColorBy(display, ("POINTS", "Soak"))
GetColorTransferFunction("Soak").RescaleTransferFunction(0.0, 1.0)
GetOpacityTransferFunction("Soak").Points = [0.0, 0.05, 0.5, 0.0, 1.0, 0.6, 0.5, 0.0]
GetOpacityTransferFunction("Soak").RescaleTransferFunction(0.0, 1.0)
display.ScalarOpacityUnitDistance = 0.2
display.APCSampleDistance = 0.04
view.ResetCamera()
camera = GetActiveCamera()

pids = ranks_pids()
rss = [[] for _ in pids]
changes = 0
modes = set()
for frame in range(args.frames):
    if frame > 0 and frame % args.change_every == 0:
        changes += 1
        if changes % 2:
            # New scalars, the same cells.
            calc.Function = "Spheres*%g" % (1.0 - 0.02 * (changes % 10))
        else:
            # New cells.
            source.Resolution = 6 + changes % 3
    camera.Azimuth(360.0 / args.frames)
    Render(view)
    modes.add(int(apcparaview.last_timings(display)["mode"]))
    for r, pid in enumerate(pids):
        rss[r].append(rss_mb(pid))

failures = []
if len(pids) != apcparaview.number_of_ranks():
    failures.append("found %d pvbatch ranks, expected %d" % (len(pids),
                                                              apcparaview.number_of_ranks()))
for r, series in enumerate(rss):
    tail = series[-args.window:]
    growth = slope(tail)
    print("rank %d: RSS %.1f MB after frame 1, %.1f MB after frame %d, %.1f MB at the end; "
          "slope over the last %d frames %.4f MB/frame (bound %.3f)" % (
              r, series[0], series[-len(tail) - 1], args.frames - len(tail), series[-1],
              len(tail), growth, args.max_slope))
    print("rank %d RSS per frame (MB):" % r, " ".join("%.1f" % v for v in series))
    if not growth < args.max_slope:
        failures.append("rank %d's RSS grows %.4f MB per frame" % (r, growth))
print("%d data changes; modes ran: %s" % (changes, sorted(modes)))
if changes < args.frames // args.change_every - 1 or modes != {0}:
    failures.append("the soak did not run as planned")
for f in failures:
    print("check failed:", f)
# No non-zero exit: only this rank runs the script, the others would be left waiting.
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED", flush=True)
