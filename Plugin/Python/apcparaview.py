"""Helpers for using the APC plugin from pvbatch / pvpython scripts.

    import sys; sys.path.insert(0, "<repo>/Plugin/Python")
    import apcparaview
    apcparaview.load_plugin()            # on every rank (pvbatch) or on the server (pvpython)
    src = APCPuzzleSource()
    for r in apcparaview.rank_summaries(src): print(r)
"""

import os

from paraview import servermanager
from paraview import simple


def plugin_path():
    """The APC plugin library: $APC_PLUGIN if set, else the default build tree location."""
    path = os.environ.get("APC_PLUGIN")
    if path:
        return path
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.join(here, "..", "..", "build", "lib", "paraview-5.11", "plugins", "APC", "APC.so")


def load_plugin(path=None, ns=None):
    """Loads the plugin where the data lives: on every pvbatch rank, or on the pvserver ranks
    and the client when connected. Raises if the library is missing."""
    path = os.path.abspath(path or plugin_path())
    if not os.path.isfile(path):
        raise RuntimeError("APC plugin not found at %s: build it first, or set APC_PLUGIN" % path)
    simple.LoadPlugin(path, remote=False, ns=ns)
    if servermanager.ActiveConnection and servermanager.ActiveConnection.IsRemote():
        simple.LoadPlugin(path, remote=True, ns=ns)
    return path


def number_of_ranks():
    """Ranks holding data: pvbatch's MPI size, or pvserver's when connected."""
    return servermanager.ActiveConnection.GetNumberOfDataPartitions()


def rank_summaries(proxy, port=0):
    """Per-rank number of cells and bounds of a pipeline proxy's output, gathered from each
    data-server rank in turn (ParaView's vtkPVDataInformation restricted to one rank)."""
    proxy.UpdatePipeline()
    summaries = []
    for rank in range(number_of_ranks()):
        info = servermanager.vtkPVDataInformation()
        info.SetPortNumber(port)
        info.SetRank(rank)
        proxy.SMProxy.GatherInformation(info)
        cells = info.GetNumberOfCells()
        bounds = tuple(info.GetBounds()) if cells > 0 else None
        summaries.append({"rank": rank, "cells": cells, "points": info.GetNumberOfPoints(),
                          "bounds": bounds})
    return summaries


def last_timings(display):
    """The last frame of an "APC Volume" display on the display rank, as a dict by name:
    seconds of each stage ("agree", "depth", "boundary" (Sample End Weights = Boundary's
    matching and exchange of the boundary faces after a data change), "pass1", "tiles",
    "profile" and "cut" (Stop Where Opaque's profile allreduce and cut), "allreduce", "pass2",
    "reduce",
    "resolve", "segments", "exchange", "blend_segments", "gather", "exact", "blend", ...) and
    "total", and "bytes_sent", "messages_sent", "composited_pixels", "covered_pixels", "mode"
    (0 APC, 1 Exact (segments), 2 Local exact: what Auto chose; -1 skipped), "image_reduction"
    (1 still, more while interacting, 0 skipped), "average_segments_per_pixel" and
    "max_segments_per_pixel", "pass1_samples", "pass2_cached_share" and "pass2_hidden_share"
    (this rank's pass-1 samples and the shares of its pass-2 samples replayed from the sample
    cache and skipped as hidden), "pass2_samples", "opaque_stop_skipped" and
    "opaque_stop_redone" (bands rendered without Stop Where Opaque, as it would cut nothing,
    and bands marched again with it), "opaque_unstopped_tiles" (one rank, one volume: tiles
    pass 1 kept as marched without the stop, no ray of theirs near its threshold),
    "profile_bytes" (the opaque summaries' and profiles' share of "bytes_sent"),
    "opaque_predicted_unresolved" and
    "opaque_predicted_redone" (on several ranks: pixels whose cut the previous frame's
    predicted bound left unknown, and the 16x16 tiles marched again for them),
    "opaque_prepass" and "opaque_prepass_samples" (on several ranks, a first frame's probe
    of every 8th ray for that bound: its seconds and this rank's samples), "bands" (APC
    mode: the bands of rows the frame was rendered in); per stage with collectives its wait for the slowest rank and its
    transfer after the last arrival ("tiles_wait", "tiles_transfer", ...), "wait" and
    "transfer" (their sums), "render" (the display rank's), "render_mean", "render_max",
    "render_imbalance" (max / mean), "slowest_rank" and "wait_max" (every rank's render seconds:
    rank_render_seconds). Pulled from where the frame was rendered (the render server's root
    when connected)."""
    display.UpdatePropertyInformation()
    names = display.GetProperty("APCLastTimingNames").GetData()
    if isinstance(names, (list, tuple)):
        names = " ".join(names)
    values = display.GetProperty("APCLastTimings").GetData()
    names = names.split()
    if len(names) != len(values):
        raise RuntimeError("APCLastTimings holds %d values for %d names: plugin and script "
                           "disagree" % (len(values), len(names)))
    return dict(zip(names, values))


def rank_render_seconds(display):
    """The last frame's render seconds of every rank, in rank order (pass 1 + pass 2, or the
    segments and their sort and blend), as the display rank gathered them: a list (pull
    last_timings first, or call display.UpdatePropertyInformation())."""
    ranks = display.GetProperty("APCLastRankRenderSeconds").GetData()
    if isinstance(ranks, (list, tuple)):
        ranks = " ".join(ranks)
    return [float(v) for v in ranks.split()]


# The pass's stages in their order (they add up to last_timings()["total"]).
STAGES = ["agree", "depth", "boundary", "pass1", "tiles", "profile", "cut", "allreduce", "pass2", "reduce", "resolve",
          "segments", "exchange", "blend_segments", "gather", "statistics", "exact", "auto",
          "ranks", "blend"]


def stage_seconds(timings):
    """The stages of last_timings() that ran (nonzero), in the pass's order, without the
    total: they add up to timings["total"]."""
    return [(s, timings[s]) for s in STAGES if timings.get(s, 0) > 0]
