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
