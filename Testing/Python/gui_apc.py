"""Runs inside the real ParaView GUI (paraview --script=gui_apc.py), connected to a pvserver: what a user does with APC Volume, then the pictures the launcher (TestGUI.py) checks.

Loads the plugin on the client and the server, opens the APC Puzzle Source, picks APC Volume,
colours by Spheres, rotates the camera with the mouse (interactor events on the view's render
window interactor: ParaView renders those frames as interactive renders), releases it (a still
render), saves a screenshot at twice the view size (rendered in tiles) and one of a view of
that size, and writes the client-side timings (apcparaview.last_timings) after an interactive and a still frame.
Everything goes to $APC_GUI_OUT; the launcher judges. The same scene as apc_scene.py --scene
puzzle (its pvbatch screenshots are the references).
"""

import json
import os
import traceback

from paraview.simple import *  # noqa: F401,F403
import apcparaview

out = os.environ["APC_GUI_OUT"]
result = {"errors": []}
try:
    apcparaview.load_plugin(ns=globals())
    layout = GetLayout()
    view = GetActiveViewOrCreate("RenderView")
    layout.PreviewMode = [160, 120]  # the view's size, fixed as in ParaView's own GUI tests
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1, 1, 1]
    source = APCPuzzleSource(NumberOfPuzzlePieces=4, SlabsPerPiece=4, Resolution=16,
                             Field="Spheres")
    display = Show(source, view)
    display.Representation = "APC Volume"
    ColorBy(display, ("POINTS", "Spheres"))
    lut = GetColorTransferFunction("Spheres")
    lut.RGBPoints = [0.0, 0.2, 0.3, 1.0, 0.5, 0.9, 0.9, 0.9, 1.0, 1.0, 0.2, 0.1]
    GetOpacityTransferFunction("Spheres").Points = [0.0, 0.05, 0.5, 0.0, 1.0, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = 0.2
    display.APCSampleDistance = 0.02
    display.APCVerbosity = 1
    Render(view)
    view.CameraPosition = [2.5, 1.7, 3.1]
    view.CameraFocalPoint = [0, 0, 0]
    view.CameraViewUp = [0, 1, 0]
    view.CameraParallelProjection = 0
    view.CameraViewAngle = 30
    Render(view)

    # Rotate with the mouse: a left-button drag on the view's interactor, there and back, so
    # the camera ends where it started (up to rounding of the rotation).
    interactor = view.GetRenderWindow().GetInteractor()
    cx, cy = 80, 60

    position = list(view.CameraPosition)
    interactor.SetEventInformation(cx, cy, 0, 0)
    interactor.LeftButtonPressEvent()
    for k in range(1, 5):
        interactor.SetEventInformation(cx + 5 * k, cy, 0, 0)
        interactor.MouseMoveEvent()
    # Still dragging: the last frame was an interactive one.
    result["timings_interactive"] = apcparaview.last_timings(display)
    result["interactive_image_reduction"] = display.APCInteractiveImageReduction
    for k in range(3, -1, -1):
        interactor.SetEventInformation(cx + 5 * k, cy, 0, 0)
        interactor.MouseMoveEvent()
    interactor.LeftButtonReleaseEvent()
    result["camera_moved_back"] = max(abs(a - b) for a, b in zip(position, view.CameraPosition))
    # Back at the start exactly, then the still frame the GUI renders on release.
    view.CameraPosition = position
    view.CameraViewUp = [0, 1, 0]
    view.CameraFocalPoint = [0, 0, 0]
    Render(view)
    result["timings_still"] = apcparaview.last_timings(display)

    result["view_size"] = list(view.ViewSize)  # the preview size, once the GUI applied it
    SaveScreenshot(os.path.join(out, "gui_still.png"), view, ImageResolution=[160, 120])
    SaveScreenshot(os.path.join(out, "gui_tiled.png"), view, ImageResolution=[320, 240])
    layout.PreviewMode = [320, 240]
    Render(view)
    SaveScreenshot(os.path.join(out, "gui_single.png"), view, ImageResolution=[320, 240])
    layout.PreviewMode = [160, 120]

    # The panel's "Refresh Timings" button pushes APCRefreshTimings; "Last Timings" (the
    # property the panel shows) must then hold the last frame's timings, with no other call.
    Render(view)
    result["timings_before_refresh"] = list(display.GetProperty("APCLastTimings").GetData())
    display.SMProxy.InvokeCommand("APCRefreshTimings")
    result["timings_after_refresh"] = list(display.GetProperty("APCLastTimings").GetData())
    result["timings_pulled"] = list(apcparaview.last_timings(display).values())
except Exception:
    result["errors"].append(traceback.format_exc())
with open(os.path.join(out, "gui_result.json"), "w") as f:
    json.dump(result, f, indent=1)
# Debian's paraview 5.11 does not run Python files given to --test-script (it prints "Playing"
# and nothing runs), and --exit only ends test playback; --script runs this file in the GUI's
# interpreter, which has no handle on the Qt application: end the client here. The server sees
# the client disconnect and the launcher stops it.
os._exit(0)
