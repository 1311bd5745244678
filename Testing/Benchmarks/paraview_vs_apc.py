"""APC Volume against ParaView's own "Volume" representation, in one pvbatch run on N ranks.

    mpirun -np N pvbatch --disable-xdisplay-test paraview_vs_apc.py --output out/benchmark

Renders the bundled OpenFOAM data (Data/windAroundBuildings/wind.pvtu: 331,699 cells in 8
Scotch pieces, field U_mag) at 1024x1024 with the same camera and transfer function:

  apc          the APC Volume representation, sample distance --sample-distance;
  apc-default  the same at its default sample distance (0: 1.25 mean cell sizes from the
               cells' volume, at least 96 samples along the bounding-box diagonal);
  apc-again    apc-default again, as a later case of the process: the first frame a new APC
               view of the data costs once the process holds memory (its cells are converted
               again, as after a data change); run it after apc-default to tell the process's
               first-touched memory from the per-data set-up;
  apc-nostop-again  apc-nostop (Stop Where Opaque off) in that place: with apc-again after
               it, the stop's first frame against the stop-off one with neither paying the
               process's first APC view (which falls on whichever case runs first);
  auto         the APC Volume representation in its "Auto" mode, default sample distance;
  segments     the APC Volume representation in its "Exact (segments)" mode (sort-last
               compositing of ray segments, the exact distributed baseline), default spacing;
  pt      ParaView's Volume representation with its default mapper 'Projected tetra';
  bunyk   ParaView's Volume representation with 'Bunyk ray cast'.

The camera looks at the buildings from the south-west; --distances moves it along its line of
sight (factors of the focal distance, 1 = the demo's view). Each case and distance gets a fresh
view (only one volume visible). Times are wall clock on rank 0 (the
script's process) around Render(view): the first frame of a new representation (for ParaView's
Volume that includes its tetrahedralisation and the redistribution of the data into a kd-tree
for ordered compositing) and --frames later frames (median). The reader is updated before any
case, so no first frame includes reading the files.

After each ParaView case a probe (a programmable filter, which runs on every rank) looks at the
data the volume mapper actually rendered on its rank (after the redistribution) and compares it
with the rank's own tetrahedralised input: tetrahedra, total volume, and how many of the rendered
tetrahedra the rank already had (matched by centroid). Every rank writes what it found to a small
JSON file next to the CSV; rank 0 reads them. From these, cells dropped by the redistribution
(ParaView 5.11 on Debian loses cells there) and an estimate of the bytes it moved.

Writes --csv (one row per case and distance), one screenshot PNG per case and distance, for the
APC cases the display rank's float image (<case>_d<distance>_np<N>.vti, written in one extra,
untimed frame) so that runs on different rank counts can be compared, and prints the CSV.
The script ends normally: pvbatch 5.11 aborts with a GLX error on sys.exit(0) after rendering.
"""

import argparse
import builtins as B  # the programmable filters' helpers rebind sum, max, abs, ...
import csv
import glob
import json
import math
import os
import resource
import statistics
import sys
import time

from paraview.simple import *  # noqa: F401,F403
from paraview import simple
import apcparaview

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--output", default="out/benchmark", help="folder for the PNGs and the CSV")
parser.add_argument("--csv", help="CSV to write (default <output>/paraview_vs_apc_np<N>.csv)")
parser.add_argument("--size", type=int, nargs=2, default=[1024, 1024])
parser.add_argument("--frames", type=int, default=3, help="later frames to time (median)")
parser.add_argument("--sample-distance", type=float, default=1.0,
                    help="APC sample distance in metres (the cells are ~1-10 m)")
parser.add_argument("--cases", default="apc,apc-default,pt,bunyk",
                    help="comma-separated: apc, apc-default, apc-again, apc-stop (defaults with Stop Where Opaque "
                    "on), apc-nostop (defaults with it off), apc-nostop-again, segments, auto, pt, "
                    "bunyk")
parser.add_argument("--distances", default="1",
                    help="comma-separated camera distance factors (1 = the default view)")
parser.add_argument("--no-float-images", action="store_true",
                    help="do not write the APC cases' float images")
parser.add_argument("--only-rendered-array", action="store_true",
                    help="read only U_mag (default: every array, as the reader does in the GUI)")
parser.add_argument("--opacity", choices=["comparison", "ramp", "lower60"], default=None,
                    help="comparison: most of the air transparent (what a user would set to "
                    "see the wakes); ramp: ParaView's default linear ramp, little to skip; "
                    "lower60: the ramp with the lower 60 %% of the range transparent (zero "
                    "up to 60 %% of the range, then linear to 1). Default: comparison, or with "
                    "--setup paraview the ramp ParaView sets")
parser.add_argument("--setup", choices=["evaluation", "paraview"], default="evaluation",
                    help="evaluation: the transfer function and unit distance above; paraview: "
                    "ParaView's default setup (its colour map and linear opacity ramp rescaled to "
                    "the data range, its opacity unit distance, APC properties at their "
                    "defaults), --cameras instead of --distances, and every later frame after a "
                    "small camera move")
parser.add_argument("--cameras", default="fill,overview",
                    help="with --setup paraview: fill (0.6 x the demo's focal distance: the data "
                    "fills the view), overview (the demo's direction, the whole data in view)")
parser.add_argument("--apc-property", action="append", default=[], metavar="NAME=VALUE",
                    help="set an APC Volume property on the APC cases (repeatable), e.g. "
                    "APCStopWhereOpaque=1")
parser.add_argument("--perf-control", metavar="FIFO",
                    help="rank 0 writes 'enable' / 'disable' to this perf control FIFO around "
                    "each case's first frame (perf record -D -1 --control fifo:FIFO ...): a "
                    "profile of the first frames alone")
parser.add_argument("--data", default=os.path.join(here, "..", "..", "Data",
                                                   "windAroundBuildings", "wind.pvtu"))

FIELD, LO, HI, UNIT = "U_mag", 0.0, 20.0, 5.0
# Still air in the buildings' wakes and the fast stream above them (as in apc_demo.py).
OPACITY = [0, 0.5, 0.5, 0, 2, 0.15, 0.5, 0, 5, 0, 0.5, 0, 12, 0, 0.5, 0,
           16, 0.03, 0.5, 0, 20, 0.2, 0.5, 0]
# ParaView's default opacity: a linear ramp over the colour range.
RAMP = [LO, 0, 0.5, 0, HI, 1, 0.5, 0]


def lower60(lo, hi):
    """The linear ramp over [lo, hi] with its lower 60 % transparent."""
    return [lo, 0, 0.5, 0, lo + 0.6 * (hi - lo), 0, 0.5, 0, hi, 1, 0.5, 0]


CAMERA = dict(CameraPosition=[-120, -260, 420], CameraFocalPoint=[155, 90, 40],
              CameraViewUp=[0, 0, 1], CameraViewAngle=30, CameraParallelProjection=0)
STAGES = ["agree", "depth", "pass1", "allreduce", "pass2", "reduce", "resolve", "blend"]
# APC's collectives: each stage's wait for the slowest rank and its transfer after it.
COLLECTIVES = ["tiles", "profile", "allreduce", "reduce"]
SEGMENT_STAGES = ["segments", "exchange", "blend_segments", "gather"]
FIRST_STAGES = ["boundary", "opaque_prepass", "pass1", "tiles", "profile", "cut", "allreduce", "pass2",
                "reduce"]
# Stop Where Opaque's counts in the first frame (several ranks: the probe's samples, the pixels
# its bound left unresolved and the tiles marched again for them).
FIRST_OPAQUE_COUNTS = ["pass1_samples", "opaque_unstopped_tiles", "opaque_prepass_samples",
                       "opaque_predicted_unresolved", "opaque_predicted_redone"]
FIRST_COUNTS = ["bytes_display_rank", "profile_bytes_per_covered_pixel"] + FIRST_OPAQUE_COUNTS
COLUMNS = (["case", "representation", "mapper", "ranks", "distance", "image", "float_image",
            "first_frame_s", "frame_s", "first_frame_cpu_s", "frame_cpu_s",
            "first_frame_sys_s", "frame_sys_s", "first_frame_faults", "first_frame_peak_mb", "setup",
            "opacity",
            "camera", "width", "height", "load_average"] +
           [s + "_s" for s in STAGES] + ["tiles_s", "profile_s", "cut_s"] + [s + "_s" for s in SEGMENT_STAGES] +
           [c + p + "_s" for c in COLLECTIVES for p in ("_wait", "_transfer")] +
           ["mode_ran", "bytes_display_rank", "messages_display_rank", "pixels_composited",
            "covered_pixels", "bytes_per_covered_pixel", "pass1_samples",
            "pass2_cached_share", "pass2_hidden_share", "pass2_samples", "opaque_stop_skipped", "opaque_unstopped_tiles",
            "opaque_stop_redone", "opaque_predicted_unresolved", "opaque_predicted_redone",
            "avg_segments_per_pixel", "max_segments_per_pixel", "render_imbalance",
            "render_max_s", "render_mean_s", "cells_per_rank_before", "cells_per_rank_after"] +
           # The first frame's own (APC mode): its stages, wire bytes and opaque-stop counts.
           ["first_" + s + "_s" for s in FIRST_STAGES] +
           ["first_" + c for c in FIRST_COUNTS] + ["note"])

# Runs on every rank inside a programmable filter (its input: the reader's piece on that rank).
# Writes <folder>/probe_<tag>_rank<r>.json. For tag "input" only the rank's own piece is
# measured; otherwise also the data rendered by the volume mapper of the display proxy GID.
PROBE = r'''
import builtins as B, json, os
import numpy as np
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid, vtkCompositeDataSet
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkFiltersVerdict import vtkCellSizeFilter
from vtkmodules.vtkParallelCore import vtkMultiProcessController
from vtkmodules.util.numpy_support import vtk_to_numpy
from paraview.modules.vtkRemotingCore import vtkProcessModule

FOLDER, TAG, GID = %(folder)r, %(tag)r, %(gid)d

def leaves(d):
    if d is None:
        return []
    if d.IsA("vtkCompositeDataSet"):
        it = d.NewIterator(); it.InitTraversal(); out = []
        while not it.IsDoneWithTraversal():
            out.append(it.GetCurrentDataObject()); it.GoToNextItem()
        return out
    return [d]

def tets(ug):
    """(centroids rounded to 0.1 mm, volumes) of a grid of tetrahedra; None if not all tets."""
    if ug.GetNumberOfCells() == 0:
        return np.zeros((0, 3)), np.zeros(0)
    types = vtk_to_numpy(ug.GetCellTypesArray())
    if not (types == 10).all():
        return None
    conn = vtk_to_numpy(ug.GetCells().GetConnectivityArray()).reshape(-1, 4)
    p = vtk_to_numpy(ug.GetPoints().GetData()).astype(np.float64)[conn]
    vol = np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                           np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))) / 6.0
    return np.round(p.mean(axis=1), 4), vol

def volume(ds):
    f = vtkCellSizeFilter(); f.SetInputData(ds)
    f.ComputeVertexCountOff(); f.ComputeLengthOff(); f.ComputeAreaOff(); f.ComputeVolumeOn()
    f.Update()
    return float(vtk_to_numpy(f.GetOutput().GetCellData().GetArray("Volume")).sum())

def keys(c):
    c = np.ascontiguousarray(c)
    return c.view(np.dtype((np.void, c.dtype.itemsize * 3))).ravel()

rank = vtkMultiProcessController.GetGlobalController().GetLocalProcessId()
piece = self.GetInput()
res = {"rank": rank, "cells": piece.GetNumberOfCells(), "volume": volume(piece)}
if TAG != "input":
    tri = vtkDataSetTriangleFilter(); tri.TetrahedraOnlyOn(); tri.SetInputData(piece); tri.Update()
    mine = tets(tri.GetOutput())
    res["tets_before"] = tri.GetOutput().GetNumberOfCells()
    # Import the modules that wrap the real classes of the session (vtkSMSession) and of the
    # representations: on the satellites nothing else has, and Python would see only the
    # nearest wrapped base classes (vtkPVSession, vtkPassInputTypeAlgorithm).
    import paraview.modules.vtkRemotingServerManager  # noqa: F401
    import paraview.modules.vtkRemotingViews  # noqa: F401  (the representations' classes)
    session = vtkProcessModule.GetProcessModule().GetActiveSession()
    res["session_class"] = session.GetClassName()
    rep = session.GetSIObject(GID).GetVTKObject()  # the display's vtkPVCompositeRepresentation
    while not hasattr(rep, "GetActiveVolumeMapper"):
        rep = rep.GetActiveRepresentation()
    res["representation_class"] = rep.GetClassName()
    mapper = rep.GetActiveVolumeMapper()
    res["mapper_class"] = mapper.GetClassName() if mapper else None
    rendered = leaves(mapper.GetInputDataObject(0, 0) if mapper else None)
    res["rendered_class"] = [d.GetClassName() for d in rendered]
    res["tets_after"] = B.sum(d.GetNumberOfCells() for d in rendered)
    res["points_after"] = B.sum(d.GetNumberOfPoints() for d in rendered)
    res["kib_after"] = B.sum(d.GetActualMemorySize() for d in rendered)
    res["volume_after"] = B.sum(volume(d) for d in rendered)
    theirs = [tets(d) for d in rendered]
    if mine is not None and B.all(t is not None for t in theirs):
        known = keys(mine[0])
        res["tets_kept"] = int(B.sum(np.isin(keys(t[0]), known).sum() for t in theirs))
    else:
        res["tets_kept"] = None
with open(os.path.join(FOLDER, "probe_%%s_rank%%d.json" %% (TAG, rank)), "w") as f:
    json.dump(res, f)
'''


def main(args):
    apcparaview.load_plugin(ns=globals())
    ranks = apcparaview.number_of_ranks()
    out = os.path.abspath(args.output)
    os.makedirs(out, exist_ok=True)
    csv_path = os.path.abspath(args.csv or os.path.join(out, "paraview_vs_apc_np%d.csv" % ranks))
    # The camera is set before each view's first render, so the timed first frame already
    # uses it: no reset by paraview.simple on the session's first Render().
    simple._DisableFirstRenderCameraReset()

    reader = XMLPartitionedUnstructuredGridReader(FileName=[os.path.abspath(args.data)])
    if args.only_rendered_array:
        # What ParaView's redistribution moves is then only the mesh and U_mag.
        reader.PointArrayStatus = [FIELD]
        reader.CellArrayStatus = []
    reader.UpdatePipeline()
    before = apcparaview.rank_summaries(reader)
    total_cells = B.sum(s["cells"] for s in before)
    print("paraview_vs_apc: %d cells on %d ranks: %s" % (
        total_cells, ranks, " ".join(str(s["cells"]) for s in before)), flush=True)
    b = reader.GetDataInformation().GetBounds()
    diagonal = ((b[1] - b[0]) ** 2 + (b[3] - b[2]) ** 2 + (b[5] - b[4]) ** 2) ** 0.5

    probe_count = [0]

    def probe(tag, gid=0):
        """Runs PROBE on every rank, returns the ranks' results (rank order)."""
        for old in glob.glob(os.path.join(out, "probe_%s_rank*.json" % tag)):
            os.remove(old)
        probe_count[0] += 1
        f = ProgrammableFilter(Input=reader)
        f.OutputDataSetType = "vtkUnstructuredGrid"
        f.Script = "# probe %d\n" % probe_count[0] + PROBE % dict(folder=out, tag=tag, gid=gid)
        f.UpdatePipeline()
        Delete(f)
        results = []
        for r in range(ranks):
            with open(os.path.join(out, "probe_%s_rank%d.json" % (tag, r))) as fh:
                results.append(json.load(fh))
            os.remove(os.path.join(out, "probe_%s_rank%d.json" % (tag, r)))
        return results

    own = probe("input")
    total_volume = B.sum(r["volume"] for r in own)
    mean_cell = (total_volume / total_cells) ** (1.0 / 3.0)
    # APC's default sample distance (Rendering/Core/apcDefaultSpacing.h), for the notes: with
    # Sample End Weights = Boundary (the default) 1.25 times the mean cell size rounded down to
    # 5 significant bits, at least diagonal / 96.
    m, e = math.frexp(mean_cell)
    default_spacing = B.min(1.25 * math.ldexp(math.floor(math.ldexp(m, 5)), e - 5), diagonal / 96)
    print("  domain volume %.4g m^3, mean cell size (volume/cells)^(1/3) = %.2f m, "
          "diagonal %.1f m (APC's default sample distance %.2f m)"
          % (total_volume, mean_cell, diagonal, default_spacing), flush=True)

    # Warm-up: the process's first view pays for the GL context and IceT set-up; render an
    # empty view once so that no case's first frame includes that.
    warm = CreateView("RenderView")
    warm.ViewSize = args.size
    Render(warm)
    Delete(warm)
    del warm

    cases = {
        "apc": ("APC Volume", "APC", args.sample_distance),
        "apc-default": ("APC Volume", "APC", 0.0),
        "apc-again": ("APC Volume", "APC", 0.0),
        # APC's defaults with Stop Where Opaque set on or off whatever its default.
        "apc-stop": ("APC Volume", "APC", 0.0),
        "apc-nostop": ("APC Volume", "APC", 0.0),
        "apc-nostop-again": ("APC Volume", "APC", 0.0),
        "segments": ("APC Volume", "Exact (segments)", 0.0),
        "auto": ("APC Volume", "Auto", 0.0),
        "pt": ("Volume", "Projected tetra", None),
        "bunyk": ("Volume", "Bunyk ray cast", None),
    }
    rows = []
    default_setup = args.setup == "paraview"
    views = args.cameras if default_setup else args.distances
    runs = [(d, key) for d in views.split(",") for key in args.cases.split(",")]
    for distance, key in runs:
        representation, mapper, spacing = cases[key]
        camera = dict(CAMERA)
        factor = {"fill": 0.6, "overview": 1.0}.get(distance) if default_setup else float(distance)
        camera["CameraPosition"] = [f + factor * (p - f) for p, f in
                                    zip(CAMERA["CameraPosition"], CAMERA["CameraFocalPoint"])]
        view = CreateView("RenderView")
        view.ViewSize = args.size
        view.OrientationAxesVisibility = 0
        for k, v in camera.items():
            setattr(view, k, v)
        display = Show(reader, view)
        display.Representation = representation
        ColorBy(display, ("POINTS", FIELD))
        apc = representation == "APC Volume"
        if default_setup:
            # As the GUI leaves it: the default map and ramp over the data range, the unit
            # distance of the representation's domain, APC's own defaults except the mode.
            display.RescaleTransferFunctionToDataRange(False, True)
            if args.opacity == "lower60":
                xs = GetColorTransferFunction(FIELD).RGBPoints[0::4]
                GetOpacityTransferFunction(FIELD).Points = lower60(xs[0], xs[-1])
            if apc:
                display.APCMode = mapper
        else:
            lut = GetColorTransferFunction(FIELD)
            lut.ApplyPreset("Cool to Warm", True)
            lut.RescaleTransferFunction(LO, HI)
            GetOpacityTransferFunction(FIELD).Points = (
                OPACITY if args.opacity in (None, "comparison") else
                lower60(LO, HI) if args.opacity == "lower60" else RAMP)
            display.ScalarOpacityUnitDistance = UNIT
            if apc:
                display.APCSampleDistance = spacing
                display.APCMode = mapper
        if apc:
            for setting in args.apc_property:
                name, value = setting.split("=", 1)
                current = getattr(display, name)
                # Numbers keep their type; strings and enumerations (e.g.
                # APCSampleEndWeights=Boundary) take the text as ParaView does.
                setattr(display, name, type(current)(value)
                        if isinstance(current, (int, float)) else value)
            if key in ("apc-stop", "apc-nostop", "apc-nostop-again"):
                display.APCStopWhereOpaque = 1 if key == "apc-stop" else 0
        if not apc:
            display.SelectMapper = mapper
        for k, v in camera.items():  # Show() may have touched the camera
            setattr(view, k, v)
        if default_setup and distance == "overview":
            view.ResetCamera(False)

        timings = []

        cpu = []
        # The kernel's share of cpu and the minor page faults: memory first touched shows here
        # (on a virtual machine whose host backs fresh memory lazily, at a high price).
        system = []
        faults = []
        # How far the process's peak resident memory rose in the frame (MB): in the process's
        # first view nearly all the memory the frame touched afresh, whatever its page size.
        peak = []

        def frame(move=False):
            if move:
                # A small camera move: nothing of the last frame's image can be reused.
                view.GetActiveCamera().Azimuth(0.5)
            # A perf control FIFO (--perf-control): the profile covers first frames only; written
            # outside the timed span. pvbatch runs this script on rank 0 alone.
            control = args.perf_control if not cpu else None
            if control:
                with open(control, "w") as fifo:
                    fifo.write("enable\n")
            start = time.perf_counter()
            start_cpu = time.process_time()
            start_sys = os.times().system
            start_faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            start_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            Render(view)
            seconds = time.perf_counter() - start
            cpu.append(time.process_time() - start_cpu)
            system.append(os.times().system - start_sys)
            faults.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - start_faults)
            peak.append((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - start_peak) / 1024.0)
            if control:
                with open(control, "w") as fifo:
                    fifo.write("disable\n")
            if apc:
                timings.append(apcparaview.last_timings(display))
            return seconds

        first = frame()
        later = [frame(move=default_setup) for _ in range(args.frames)]
        stem = "%s_d%s_np%d" % (key, distance, ranks)
        name = stem + ".png"
        SaveScreenshot(os.path.join(out, name), view, ImageResolution=args.size)
        row = dict(case=key, representation=representation, mapper=mapper, ranks=ranks,
                   distance=distance, image=name, first_frame_s="%.3f" % first,
                   frame_s="%.3f" % statistics.median(later), setup=args.setup,
                   opacity=args.opacity or ("ramp" if default_setup else "comparison"),
                   first_frame_cpu_s="%.3f" % cpu[0],
                   frame_cpu_s="%.3f" % statistics.median(cpu[1:]),
                   first_frame_sys_s="%.3f" % system[0],
                   frame_sys_s="%.3f" % statistics.median(system[1:]),
                   first_frame_faults="%d" % faults[0],
                   first_frame_peak_mb="%.0f" % peak[0],
                   camera=distance if default_setup else "", width=args.size[0],
                   height=args.size[1], load_average=open("/proc/loadavg").read().split()[0])
        if apc and not args.no_float_images:
            display.APCImageFile = os.path.join(out, stem + ".vti")
            Render(view)
            display.APCImageFile = ""
            row["float_image"] = stem + ".vti"
        notes = ["later frames %s s" % " ".join("%.2f" % t for t in later)]
        if apc:
            # Median of each stage over the later frames (the first frame's are in the note).
            # Auto may change mode between frames: the later frames' modes are listed and the
            # stage columns are those of the last frame's mode.
            modes = {0: "APC", 1: "segments", 2: "local exact"}
            ran = [modes.get(int(t["mode"]), "none") for t in timings[1:]]
            row["mode_ran"] = "/".join(sorted(set(ran)))
            segments = int(timings[-1]["mode"]) == 1
            same = [t for t in timings[1:] if int(t["mode"]) == int(timings[-1]["mode"])]
            for s in STAGES:
                if not segments or s in ("agree", "depth", "blend"):
                    row[s + "_s"] = "%.4f" % statistics.median(t[s] for t in same)
            if segments:
                for s in SEGMENT_STAGES:
                    row[s + "_s"] = "%.4f" % statistics.median(t[s] for t in same)
                row["avg_segments_per_pixel"] = "%.4f" % timings[-1]["average_segments_per_pixel"]
                row["max_segments_per_pixel"] = "%d" % timings[-1]["max_segments_per_pixel"]
            else:
                row["tiles_s"] = "%.4f" % statistics.median(t["tiles"] for t in same)
                # Stop Where Opaque: the profiles' allreduce and the cut (0 without it).
                for s in ("profile", "cut"):
                    row[s + "_s"] = "%.4f" % statistics.median(t.get(s, 0) for t in same)
                for c in COLLECTIVES:
                    for part in ("_wait", "_transfer"):
                        row[c + part + "_s"] = "%.4f" % statistics.median(
                            t.get(c + part, 0) for t in same)
                covered = statistics.median(t["covered_pixels"] for t in same)
                row["covered_pixels"] = "%d" % covered
                if covered > 0:
                    row["bytes_per_covered_pixel"] = "%.2f" % (
                        statistics.median(t["bytes_sent"] for t in same) / covered)
                # The display rank's samples: with pass1_s and pass2_s, ns per sample.
                if "pass1_samples" in same[0]:
                    row["pass1_samples"] = "%d" % statistics.median(
                        t["pass1_samples"] for t in same)
                    for share in ("pass2_cached_share", "pass2_hidden_share"):
                        row[share] = "%.4f" % statistics.median(t[share] for t in same)
                # Pass 2's samples: pass 1's with an opacity (less the opaque cut's).
                row["pass2_samples"] = "%d" % statistics.median(
                    t.get("pass2_samples", 0) for t in same)
                # The first frame's own (when it ran APC mode): its stages, its bytes on the
                # wire, the opaque summaries' and profiles' bytes per covered pixel, its counts.
                t0 = timings[0]
                if int(t0["mode"]) == 0:
                    for s in FIRST_STAGES:
                        row["first_" + s + "_s"] = "%.4f" % t0.get(s, 0)
                    row["first_bytes_display_rank"] = "%d" % t0["bytes_sent"]
                    if "profile_bytes" in t0 and t0["covered_pixels"] > 0:
                        row["first_profile_bytes_per_covered_pixel"] = "%.2f" % (
                            t0["profile_bytes"] / t0["covered_pixels"])
                    for c in FIRST_OPAQUE_COUNTS:
                        row["first_" + c] = "%d" % t0.get(c, 0)
                # Bands marched without Stop Where Opaque, and again with it, in the later frames.
                # One rank: tiles pass 1 kept without the stop. On several ranks: pixels the
                # predicted cut left unknown, tiles marched again.
                for s in ("opaque_stop_skipped", "opaque_stop_redone", "opaque_unstopped_tiles",
                          "opaque_predicted_unresolved",
                          "opaque_predicted_redone"):
                    row[s] = "/".join("%d" % t.get(s, 0) for t in same)
            row["messages_display_rank"] = "%d" % timings[-1]["messages_sent"]
            row["bytes_display_rank"] = "%d" % statistics.median(t["bytes_sent"] for t in same)
            row["pixels_composited"] = "%d" % statistics.median(
                t["composited_pixels"] for t in same)
            # How evenly the ranks share the frame's work: the slowest rank's render seconds
            # (pass 1 + pass 2) over the ranks' mean, median over the later frames (1 = even;
            # the display rank's frame waits for the slowest).
            if "render_imbalance" in same[0]:
                row["render_imbalance"] = "%.2f" % statistics.median(
                    t["render_imbalance"] for t in same)
                row["render_max_s"] = "%.4f" % statistics.median(t["render_max"] for t in same)
                row["render_mean_s"] = "%.4f" % statistics.median(t["render_mean"] for t in same)
            row["cells_per_rank_before"] = "/".join(str(s["cells"]) for s in before)
            after = apcparaview.rank_summaries(reader)
            row["cells_per_rank_after"] = "/".join(str(s["cells"]) for s in after)
            notes.insert(0, "sample distance %.3g m%s; stage times are medians of the later "
                            "frames (pass total %.3f s; first frame's total %.3f s)"
                         % (spacing or default_spacing, " (default 0: 1.25 mean cell sizes, at "
                            "least diagonal / 96)"
                            if not spacing else "", statistics.median(t["total"] for t in timings[1:]),
                            timings[0]["total"]))
            # Where the first frame's time went, beside the later frames' medians above.
            notes.append("first frame's stages (s): " + " ".join(
                "%s %.3f" % (s, timings[0].get(s, 0))
                for s in STAGES + ["boundary", "opaque_prepass", "tiles", "profile", "cut"]))
            notes.append("cells unchanged by rendering" if after == before
                         else "CELLS MOVED by rendering")
        else:
            gid = display.SMProxy.GetGlobalID()
            res = probe("volume", gid)
            tb = [r["tets_before"] for r in res]
            ta = [r["tets_after"] for r in res]
            row["cells_per_rank_before"] = "/".join(map(str, tb))
            row["cells_per_rank_after"] = "/".join(map(str, ta))
            lost = 1.0 - B.sum(r["volume_after"] for r in res) / total_volume
            notes.insert(0, "counts are tetrahedra (ParaView tetrahedralises the %d cells into "
                            "%d tets on the ranks, then redistributes them into a kd-tree); "
                            "after redistribution %d tets (%+d) covering %.2f %% less volume "
                            "than the data" % (total_cells, B.sum(tb), B.sum(ta),
                                               B.sum(ta) - B.sum(tb), 100 * lost))
            if B.all(r["tets_kept"] is not None for r in res):
                kept = [r["tets_kept"] for r in res]
                per_tet = [1024.0 * r["kib_after"] / B.max(r["tets_after"], 1) for r in res]
                received = B.sum((a - k) * p for a, k, p in zip(ta, kept, per_tet))
                sent0 = (tb[0] - kept[0]) * per_tet[0]
                notes.append("redistribution moved ~%d of %d tets (rank 0 sent ~%d); ESTIMATED "
                             "bytes moved ~%.1f MB in total, ~%.1f MB sent by rank 0 "
                             "(moved tets x rendered piece memory per tet; excludes IceT "
                             "compositing)" % (B.sum(ta) - B.sum(kept), B.sum(tb), tb[0] - kept[0],
                                               received / 1e6, sent0 / 1e6))
            notes.append("rendered by %s on %s" % (res[0]["mapper_class"],
                                                    "+".join(res[0]["rendered_class"])))
            if B.abs(lost) > 1e-3:
                notes.append("REDISTRIBUTION LOST %.2f %% OF THE VOLUME" % (100 * lost))
        row["note"] = "; ".join(notes)
        rows.append(row)
        print("  %-10s %-16s distance %-4s first %.2f s, later %s s" % (
            representation, mapper, distance, first, " ".join("%.2f" % t for t in later)),
            flush=True)
        Hide(reader, view)
        Delete(display)
        del display
        Delete(view)
        del view

    with open(csv_path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS)
        w.writeheader()
        for row in rows:
            w.writerow({c: row.get(c, "") for c in COLUMNS})
    print("wrote", csv_path, flush=True)
    with open(csv_path) as fh:
        print(fh.read(), flush=True)
    return True


if not main(parser.parse_args()):
    sys.exit(1)
