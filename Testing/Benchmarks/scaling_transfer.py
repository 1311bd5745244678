"""The scaling model against the transfer alone, and the share of compositing that is waiting:
the parts of scaling_model.py that read the pass's wait and transfer per stage (the columns
"<stage>_wait_s" and "<stage>_transfer_s" of apcScalingBenchmark's CSV; older runs have none,
and add no rows here). vtkAPCCompositePass starts every collective with a barrier: the time
in it is the rank's wait for the slowest one, the collective's time after it the transfer.
"""

from scaling_model import (apc_compact, direct_send_pass, measured_at, median, mpi_alone,
                           num)


def has_transfer(r):
    """Whether a scaling.csv row has the pass's wait and transfer per stage (later builds)."""
    return num(r.get("allreduce_transfer_s", "")) == num(r.get("allreduce_transfer_s", ""))


def add_transfer_rows(groups, scaling, analysis, constants, comm):
    """The model against the transfer alone: the collectives' time after every rank arrived
    (the pass times the wait for the slowest rank apart, in a barrier before each collective),
    so neither the wait nor the packing around the collectives is in it; the model is taken
    without its packing copies. APC (compact wire): tiles + allreduce + reduce transfer;
    segments: exchange + gather transfer."""
    for r in scaling:
        p = int(r["ranks"])
        if p < 2 or p not in constants or not has_transfer(r):
            continue
        match = [a for a in analysis if a["case"] == "gearteeth" and a["ranks"] == p and
                 a["camera"] == r["camera"] and a["width"] == r["size"]]
        if not match:
            continue
        a, c = match[0], dict(constants[p], copy=0.0)
        if r["mode"] == "APC":
            measured = sum(num(r[k + "_transfer_s"]) for k in ("tiles", "allreduce", "reduce"))
            t = apc_compact(p, a["tiles"], a["covered_tile_pixels"], c)
            model = t[0] + t[1] + t[2]
            alone = mpi_alone(comm, p, "APC", a, True) + \
                measured_at(comm, p, "allreduce", "float", a["tiles"])
            name = "compact wire: transfer (best algorithms)"
        else:
            measured = sum(num(r[k + "_transfer_s"]) for k in ("exchange", "gather"))
            model = sum(direct_send_pass(p, a, c))
            alone = mpi_alone(comm, p, "SEGMENTS", a)
            name = "as run: transfer (pairwise rounds)"
        groups.setdefault((p, r["mode"], name), []).append((measured, model, alone))


def waiting_rows(scaling):
    """Per rank count and mode, medians over the cameras: the compositing time (APC: tiles +
    allreduce + reduce; segments: exchange + gather; mean over ranks), the wait for the
    slowest rank in it, the transfer (max over ranks), the wait's share, the render
    imbalance (slowest / mean render) and the transfer of the smallest collective (the 16-byte
    gather of the ranks' times: one collective's latency, whatever its bytes)."""
    groups = {}
    for r in scaling:
        if int(r["ranks"]) >= 2 and has_transfer(r):
            groups.setdefault((int(r["ranks"]), r["mode"]), []).append(r)
    rows = []
    for (p, mode), rs in sorted(groups.items()):
        stages = ("tiles", "allreduce", "reduce") if mode == "APC" else ("exchange", "gather")
        comp = median([num(r["compositing_mean_s"]) for r in rs])
        wait = median([num(r["compositing_wait_mean_s"]) for r in rs])
        transfer = median([sum(num(r[k + "_transfer_s"]) for k in stages) for r in rs])
        share = median([num(r["compositing_wait_mean_s"]) / num(r["compositing_mean_s"])
                        for r in rs if num(r["compositing_mean_s"]) > 0])
        # The ranks' times: a 16-byte gather, so its transfer is one collective's latency.
        floor = median([num(r["ranks_transfer_s"]) for r in rs])
        rows.append([p, mode, len(rs), "oversubscribed" if p > 2 else "2 cores", "%.4g" % comp,
                     "%.4g" % wait, "%.4g" % transfer, "%.3f" % share,
                     "%.3f" % median([num(r["render_imbalance"]) for r in rs]), "%.4g" % floor])
    return rows
