"""The real ParaView GUI against a pvserver on N ranks: runs gui_apc.py in `paraview
--script=gui_apc.py` (user steps: plugin, APC Puzzle Source, APC Volume, colour by an
array, rotate with the mouse, release, screenshots) and checks its results:

- "Refresh Timings" fills "Last Timings" with the last frame's timings;
- while the mouse drags, the client sees an interactive frame (the "image_reduction" timing
  = the image reduction) and after release a still one (1), with non-zero stage times;
- the GUI's still screenshot equals pvbatch's screenshot of the same scene;
- its screenshot at twice the view size (tiles) equals pvbatch's single render at that size
  and the GUI's own single render at that size.

    TestGUI.py <ranks> <pvbatch view png> <pvbatch 2x single png> <workdir>

Run under an X server; the environment carries APC_PLUGIN, PYTHONPATH and the OMPI_* settings.
"""

import json
import os
import subprocess
import sys

import numpy
from PIL import Image

from apc_pvserver import PvServer

ranks, reference_png, reference_2x_png, workdir = sys.argv[1:5]
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(workdir, exist_ok=True)
for name in ("gui_result.json", "gui_still.png", "gui_tiled.png", "gui_single.png"):
    if os.path.exists(os.path.join(workdir, name)):
        os.remove(os.path.join(workdir, name))


failures = []


def check(ok, what):
    print(("ok: " if ok else "check failed: ") + what)
    if not ok:
        failures.append(what)


def compare(a_path, b_path, what, tolerance=1):
    a = numpy.asarray(Image.open(a_path).convert("RGB"), dtype=int)
    b = numpy.asarray(Image.open(b_path).convert("RGB"), dtype=int)
    if a.shape != b.shape:
        check(False, "%s: sizes %s vs %s" % (what, a.shape, b.shape))
        return
    diff = numpy.abs(a - b)
    check(int(diff.max()) <= tolerance, "%s: max |diff| %d/255, %d pixels differ"
          % (what, int(diff.max()), int((diff.max(axis=2) > 0).sum())))


server = PvServer(ranks, workdir)
try:
    server.start()
    env = dict(os.environ, APC_GUI_OUT=workdir)
    gui = subprocess.run(
        ["paraview", "--dr", "--server-url=" + server.url,
         "--script=%s" % os.path.join(here, "gui_apc.py")],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=150, env=env)
    with open(os.path.join(workdir, "paraview.log"), "w") as f:
        f.write(gui.stdout)
    print("paraview exited with", gui.returncode)
    result = json.load(open(os.path.join(workdir, "gui_result.json")))
    print(json.dumps(result, indent=1))
    check(not result["errors"], "the GUI script ran without errors")
    if not result["errors"]:
        # (The ViewSize property lags behind the preview layout until Qt's event loop runs;
        # the screenshots below are the judges of size.)
        print("ViewSize property during the script:", result["view_size"])
        fast, still = result["timings_interactive"], result["timings_still"]
        check(fast["image_reduction"] == result["interactive_image_reduction"] > 1
              and fast["total"] > 0,
              "while dragging, the client sees an interactive frame (reduction %g, total %.3f s)"
              % (fast["image_reduction"], fast["total"]))
        check(still["image_reduction"] == 1 and still["total"] > 0 and still["pass1"] > 0,
              "after release, a still frame (reduction %g, total %.3f s)"
              % (still["image_reduction"], still["total"]))
        before, after = result["timings_before_refresh"], result["timings_after_refresh"]
        check(after == result["timings_pulled"] and after != before,
              "Refresh Timings fills Last Timings with the last frame's timings")
        compare(os.path.join(workdir, "gui_still.png"), reference_png,
                "GUI screenshot vs pvbatch screenshot")
        compare(os.path.join(workdir, "gui_tiled.png"), reference_2x_png,
                "GUI screenshot at 2x the view size (tiles) vs pvbatch single render at 2x")
        compare(os.path.join(workdir, "gui_tiled.png"), os.path.join(workdir, "gui_single.png"),
                "GUI screenshot at 2x (tiles) vs the GUI's single render at 2x")
except Exception as e:  # a broken launch is a failure, with the reason
    check(False, "GUI run: %r" % e)
finally:
    server.stop()
print("APC-TEST-FAILED" if failures else "APC-TEST-PASSED")
sys.exit(1 if failures else 0)
