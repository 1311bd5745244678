"""An alpha-beta-gamma model of APC's and the segment baselines' compositing, calibrated on
this machine and on a published cluster interconnect, validated against the measured runs.

    /usr/bin/python3 scaling_model.py --results out/evaluation [--out DIR]

Inputs in --results (written by run-evaluation.sh):
  comm.csv              apcCommBenchmark at several rank counts: ping-pong, allreduce, reduce,
                        local copy and sum (alpha, beta, gamma)
  segment_transfer.csv  apcSegmentAnalysis: per configuration the segments, what direct send
                        and binary swap move in total and for the busiest rank, covered tiles
  scaling.csv           apcScalingBenchmark: measured compositing stages at 1-8 ranks
  scaling_old_wire.csv  optional: the same from a build before the compact wire
Outputs in --out (default <results>/model), the CSVs docs/evaluation.md's "Scaling model"
section is made from:
  constants.csv    alpha, beta, gamma per calibration (this machine at each rank count; the
                   interconnect figures)
  collectives.csv  the model's allreduce/reduce times against apcCommBenchmark's
  validation.csv   the model's compositing time against apcScalingBenchmark's, per
                   configuration, with the relative error: against the stages (wait, packing
                   and transfer) and, where the run has them, against the transfer alone
  waiting.csv      per rank count and mode, how much of the compositing time is the wait for
                   the slowest rank (runs with the pass's wait and transfer columns)
  paper_scale.csv  time and bytes per frame at the paper's 2560^2 for every data set, rank
                   count, method and calibration
  crossover.csv    the smallest rank count from which APC is the cheapest, per data set

Model (n: bytes of a rank's buffer, p: ranks; Thakur, Rabenseifner & Gropp 2005):
  allreduce ring          2(p-1) a + 2(p-1)/p n b + (p-1)/p n g
  allreduce rec. doubling ceil(log2 p) (a + n b + n g)
  allreduce Rabenseifner  2 log2 p a + 2(p-1)/p n b + (p-1)/p n g
  reduce binomial tree    ceil(log2 p) (a + n b + n g)
  reduce Rabenseifner     2 log2 p a + 2(p-1)/p n b + (p-1)/p n g   (reduce-scatter + gather)
  bcast                   min(binomial ceil(log2 p) (a + n b),
                              scatter + allgather (log2 p + p - 1) a + 2(p-1)/p n b)
  gather to one rank      (p-1) a + (p-1)/p N b                     (N: the whole result)
An MPI library picks an algorithm per size; "best" is the cheapest of the above.
APC, old wire (main before the compact wire): allreduce of (M+1) doubles and reduce of 4
doubles per pixel of the data's screen rectangle; depth: bcast of 4 B per pixel.
APC, compact wire (main at 0e54ff2): MAX-allreduce of 1 B per 8x8 tile; then over the pixels
of the covered tiles (a tile is covered where some rank has a segment) a MAX-allreduce of a
1-byte exponent per pixel and a SUM-allreduce of (M+1) 32-bit fixed-point moments, and a
reduce of 4 floats of colour; the display rank's depth only where opaque geometry is (none in
these scenes): a 1 B/tile mask bcast. M = 4: 1 + 20 + 16 = 37 B per covered pixel. Packing
costs one copy per byte (g_copy) each way.
Segments: 24 B each. Direct send (ideal: every pair at once, bound by the busiest rank)
(p-1) a + b max(sent, received); as vtkAPCCompositePass runs it (pairs meet in rounds
partner = rank XOR round, one way then the other) ceil(log2 p) a (counts) + g_copy 24 s_own +
sum over rounds (2 a + 24 b (s_pq + s_qp)_max). Binary swap: sum over log2 p rounds of
(a + 24 b max_rank sent). Both then gather 16 B (float RGBA) per rectangle pixel to the
display rank. Local work, on the busiest rank: APC's reductions (g per byte, inside the
collectives) and pack/unpack copies; the segments' packing (a copy of what is sent) and sort
and blend (blend s per segment: the measured sort+blend stage at 2 ranks over the busiest
strip's segments). paper_scale.csv gives the time with local work (time_s) and of latency and
bandwidth alone (time_comm_s). Validation uses the pass's measured exchange + gather, which
has packing but not the sort and blend.

Calibrations: "this machine, N ranks" (medians of the repetitions at N ranks: the validation's,
oversubscribed above 2); at the paper's scale "this machine (2 ranks, min)" (minimum of the
repetitions: the machine without the other users' load) and the interconnect below with that
calibration's local costs.
"""

import argparse
import csv
import math
import os
import statistics
import sys

MOMENTS = 4
SEGMENT_BYTES = 24
PAPER_PIXELS = 2560 * 2560

# A published interconnect: 100 Gb/s InfiniBand (EDR, or HDR100 as on TACC Frontera, the
# paper's machine). OSU micro-benchmarks over EDR/ConnectX-5 report ~1 us small-message
# latency and ~12 GB/s large-message bandwidth (the link's 12.5 GB/s less protocol overhead).
# gamma (a memory-bound local sum) is taken from this machine's measurement.
INFINIBAND = {"name": "InfiniBand 100 Gb/s", "alpha": 1.0e-6, "beta": 1.0 / 12.0e9}


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path) as fh:
        return list(csv.DictReader(fh))


def write_csv(path, header, rows):
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def num(value, default=float("nan")):
    try:
        return float(value)
    except (TypeError, ValueError):
        return default


def median(values):
    values = [v for v in values if v == v]
    return statistics.median(values) if values else float("nan")


def log2c(p):
    return math.ceil(math.log2(p)) if p > 1 else 0


# ------------------------------------------------------------------ calibration
def least_squares(xs, ys):
    """Intercept and slope of y = a + b x."""
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else float("nan")
    return my - b * mx, b


def calibrate(comm, stat="median_s"):
    """alpha, beta, gamma per rank count of comm.csv: alpha = the 8-byte ping-pong, beta = the
    slope of the ping-pong over messages >= 1 MiB (compositing's sizes), gamma = the local
    double sum per byte of one operand, g_copy = memcpy per byte."""
    constants = {}
    for p in sorted({int(r["ranks"]) for r in comm}):
        rows = [r for r in comm if int(r["ranks"]) == p]
        pp = sorted([r for r in rows if r["op"] == "pingpong"], key=lambda r: int(r["bytes"]))
        if not pp:
            continue
        big = [r for r in pp if int(r["bytes"]) >= 1 << 20]
        big = big if len(big) >= 2 else pp[-3:]  # a quick run stops at 1 MiB
        _, beta = least_squares([int(r["bytes"]) for r in big], [num(r[stat]) for r in big])
        if not beta > 0:
            # One descheduled repetition can make a median out of line (a quick run has 3 of
            # them and stops at 1 MiB): no bandwidth is negative, so fit the minima instead.
            _, beta = least_squares([int(r["bytes"]) for r in big],
                                    [num(r["min_s"]) for r in big])
        local = {(r["op"], r["type"]): num(r[stat]) / int(r["bytes"]) for r in rows
                 if r["op"] in ("copy", "sum")}
        constants[p] = {
            "name": "this machine np%d (median)" % p,
            "alpha": num(pp[0][stat]),
            "beta": beta,
            "gamma": local.get(("sum", "double"), float("nan")),
            "gamma_float": local.get(("sum", "float"), float("nan")),
            "copy": local.get(("copy", "byte"), float("nan")),
            "load": median([num(r["load1"]) for r in rows]),
            "ranks": p,
        }
    return constants


def interconnect(machine):
    """The published interconnect's alpha and beta with this machine's gamma and copy."""
    c = dict(INFINIBAND)
    c.update(gamma=machine["gamma"], gamma_float=machine["gamma_float"], copy=machine["copy"],
             blend=machine.get("blend", float("nan")), load=float("nan"), ranks=0)
    return c


# ------------------------------------------------------------------ collectives
def allreduce(alg, p, n, c):
    a, b, g = c["alpha"], c["beta"], c["gamma"]
    if p < 2:
        return 0.0
    if alg == "ring":
        return 2 * (p - 1) * a + 2 * (p - 1) / p * n * b + (p - 1) / p * n * g
    if alg == "recursive doubling":
        return log2c(p) * (a + n * b + n * g)
    if alg == "Rabenseifner":
        return 2 * log2c(p) * a + 2 * (p - 1) / p * n * b + (p - 1) / p * n * g
    raise ValueError(alg)


def reduce(alg, p, n, c):
    a, b, g = c["alpha"], c["beta"], c["gamma"]
    if p < 2:
        return 0.0
    if alg == "binomial":
        return log2c(p) * (a + n * b + n * g)
    if alg == "Rabenseifner":
        return 2 * log2c(p) * a + 2 * (p - 1) / p * n * b + (p - 1) / p * n * g
    raise ValueError(alg)


ALLREDUCE = ("ring", "recursive doubling", "Rabenseifner")
REDUCE = ("binomial", "Rabenseifner")


def best_allreduce(p, n, c):
    return min(allreduce(alg, p, n, c) for alg in ALLREDUCE)


def best_reduce(p, n, c):
    return min(reduce(alg, p, n, c) for alg in REDUCE)


def bcast(p, n, c):
    """The cheaper of a binomial tree and scatter + ring allgather (van de Geijn)."""
    if p < 2:
        return 0.0
    return min(log2c(p) * (c["alpha"] + n * c["beta"]),
               (log2c(p) + p - 1) * c["alpha"] + 2 * (p - 1) / p * n * c["beta"])


def gather(p, total, c):
    return (p - 1) * c["alpha"] + (p - 1) / p * total * c["beta"] if p > 1 else 0.0


# ------------------------------------------------------------------ compositing methods
def apc_old(p, rect, c, alg=None):
    """APC as on main before the compact wire: (stages allreduce, reduce, depth bcast) s."""
    n1, n2 = rect * (MOMENTS + 1) * 8, rect * 4 * 8
    ar = allreduce(alg[0], p, n1, c) if alg else best_allreduce(p, n1, c)
    rd = reduce(alg[1], p, n2, c) if alg else best_reduce(p, n2, c)
    copy = 2 * c["copy"]  # pack and unpack
    return ar + copy * n1, rd + copy * n2, bcast(p, rect * 4, c)


COMPACT_BYTES_PER_PIXEL = 1 + (MOMENTS + 1) * 4 + 4 * 4


def apc_compact(p, tiles, covered, c):
    """The compact wire: (mask allreduce, exponent + moments allreduce, colour reduce, depth
    mask) s. gamma of the 32-bit sums: the float sum's (same width)."""
    n1, n2 = covered * (MOMENTS + 1) * 4, covered * 4 * 4
    cf = dict(c, gamma=c["gamma_float"])
    copy = 2 * c["copy"]
    return (best_allreduce(p, tiles, cf),
            best_allreduce(p, covered, cf) + best_allreduce(p, n1, cf) + copy * (n1 + covered),
            best_reduce(p, n2, cf) + copy * n2, bcast(p, tiles, c))


def apc_bytes_old(p, rect):
    return p * rect * (MOMENTS + 1 + 4) * 8 + rect * 4 if p > 1 else 0.0


def apc_bytes_compact(p, tiles, covered):
    return p * (tiles + covered * COMPACT_BYTES_PER_PIXEL) + tiles if p > 1 else 0.0


def direct_send_ideal(p, row, c):
    worst = max(row["ds_max_sent_segments"], row["ds_max_received_segments"])
    return ((p - 1) * c["alpha"] + SEGMENT_BYTES * worst * c["beta"],
            gather(p, 16 * row["rect_pixels"], c))


def direct_send_pass(p, row, c):
    """vtkAPCCompositePass's direct send: (exchange, gather) s."""
    rounds = (1 << log2c(p)) - 1
    own = row["segments"] / p + row["ds_max_sent_segments"]
    exchange = (log2c(p) * c["alpha"] + SEGMENT_BYTES * own * c["copy"] + 2 * rounds * c["alpha"]
                + SEGMENT_BYTES * row["ds_pairwise_critical_segments"] * c["beta"])
    return exchange, gather(p, 16 * row["rect_pixels"], c)


def binary_swap(p, row, c):
    if row["bs_critical_segments"] < 0:
        return float("nan"), float("nan")
    return (log2c(p) * c["alpha"] + SEGMENT_BYTES * row["bs_critical_segments"] * c["beta"],
            gather(p, 16 * row["rect_pixels"], c))


def segment_bytes(p, segments, rect):
    return SEGMENT_BYTES * segments + 16 * rect * (p - 1) / p if p > 1 and segments >= 0 \
        else float("nan")


# ------------------------------------------------------------------ the analysis rows
COUNT_KEYS = ("rect_pixels", "nonempty_pixels", "segments", "direct_send_segments",
              "binary_swap_segments", "tiles", "covered_tiles", "covered_tile_pixels",
              "ds_max_sent_segments", "ds_max_received_segments",
              "ds_pairwise_critical_segments", "bs_critical_segments")


def analysis_rows(rows):
    """segment_transfer.csv rows with the model's columns as numbers (old CSVs without the
    per-rank columns are skipped)."""
    out = []
    for r in rows:
        if "covered_tiles" not in r or r["covered_tiles"] in ("", None):
            continue
        q = dict(r)
        for k in COUNT_KEYS:
            q[k] = num(r[k])
        q["ranks"] = int(r["ranks"])
        q["pixels"] = int(r["width"]) * int(r["height"])
        out.append(q)
    return out


def dataset(case):
    return "wind" if case.startswith("wind") else case


def scaled(row, pixels):
    """A row's counts at another image size: per-pixel quantities carry over (segments per
    pixel depend on the geometry, not the resolution; 8x8 tiles at a finer resolution cover
    a little less, so APC's compact bytes are slightly overestimated)."""
    f = pixels / row["pixels"]
    q = dict(row)
    for k in COUNT_KEYS:
        q[k] = row[k] * f if row[k] >= 0 else row[k]
    q["pixels"] = pixels
    return q


def communication_only(c):
    """The constants without local work: only latency and bandwidth."""
    return dict(c, gamma=0.0, gamma_float=0.0, copy=0.0, blend=0.0)


def segment_local(p, row, c, method):
    """The segments' local work on the busiest rank: packing what it sends (a copy of 24 B
    each) and sorting and blending what it composites (blend s per segment, calibrated on the
    measured runs' sort+blend stage)."""
    blend = c.get("blend", 0.0)
    blend = 0.0 if blend != blend else blend
    if method == "direct send":
        sent, blended = row["ds_max_sent_segments"], row["ds_max_received_segments"] * p / (p - 1)
    else:
        sent = blended = row["bs_critical_segments"]
    return SEGMENT_BYTES * sent * c["copy"] + blended * blend if sent >= 0 else float("nan")


def methods(p, row, c):
    """Per method for one configuration: (time with local work, time of latency and bandwidth
    alone, bytes of all ranks)."""
    bare = communication_only(c)
    out = {}
    for name, cal in (("total", c), ("comm", bare)):
        ds, bs = sum(direct_send_ideal(p, row, cal)), sum(binary_swap(p, row, cal))
        out[name] = {
            "APC (old wire)": sum(apc_old(p, row["rect_pixels"], cal)),
            "APC (compact wire)": sum(apc_compact(p, row["tiles"], row["covered_tile_pixels"],
                                                  cal)),
            "direct send": ds + segment_local(p, row, cal, "direct send"),
            "binary swap": bs + segment_local(p, row, cal, "binary swap"),
        }
    sizes = {
        "APC (old wire)": apc_bytes_old(p, row["rect_pixels"]),
        "APC (compact wire)": apc_bytes_compact(p, row["tiles"], row["covered_tile_pixels"]),
        "direct send": segment_bytes(p, row["direct_send_segments"], row["rect_pixels"]),
        "binary swap": segment_bytes(p, row["binary_swap_segments"], row["rect_pixels"]),
    }
    return {m: (out["total"][m], out["comm"][m], sizes[m]) for m in sizes}


METHODS = ("APC (old wire)", "APC (compact wire)", "direct send", "binary swap")


# ------------------------------------------------------------------ outputs
def constants_rows(constants, infiniband):
    rows = []
    for c in list(constants.values()) + [infiniband]:
        rows.append([c["name"], c["ranks"], "%.4g" % c["alpha"], "%.4g" % c["beta"],
                     "%.4g" % (1 / c["beta"] / 1e9 if c["beta"] > 0 else float("nan")),
                     "%.4g" % c["gamma"], "%.4g" % c["gamma_float"], "%.4g" % c["copy"],
                     "%.3g" % c["load"], "%.4g" % c.get("blend", float("nan"))])
    return rows


def collectives_rows(comm, constants):
    """The collective microbenchmarks against the model (large sizes: compositing's)."""
    rows = []
    for r in comm:
        if r["op"] not in ("allreduce", "reduce") or int(r["bytes"]) < 1 << 16:
            continue
        p = int(r["ranks"])
        if p not in constants or p < 2:
            continue
        c = dict(constants[p])
        if r["type"] == "float":
            c["gamma"] = c["gamma_float"]
        n = int(r["bytes"])
        algs = ALLREDUCE if r["op"] == "allreduce" else REDUCE
        f = allreduce if r["op"] == "allreduce" else reduce
        model = {alg: f(alg, p, n, c) for alg in algs}
        measured = num(r["median_s"])
        best = min(model, key=lambda k: abs(model[k] - measured))
        rows.append([p, r["op"], r["type"], n, "%.4g" % measured] +
                    ["%.4g" % model[a] for a in algs] + [""] * (3 - len(algs)) +
                    [best, "%.3f" % ((model[best] - measured) / measured)])
    return rows


def measured_at(comm, p, op, kind, n):
    """apcCommBenchmark's median time of op at p ranks for n bytes, interpolated log-log
    between the measured sizes (nan outside them)."""
    pts = sorted((int(r["bytes"]), num(r["median_s"])) for r in comm
                 if int(r["ranks"]) == p and r["op"] == op and r["type"] == kind)
    for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
        if x0 <= n <= x1 and y0 > 0 and y1 > 0:
            w = math.log(n / x0) / math.log(x1 / x0)
            return math.exp((1 - w) * math.log(y0) + w * math.log(y1))
    return float("nan")


def mpi_alone(comm, p, mode, a, compact=False):
    """The same bytes through MPI alone, from apcCommBenchmark (each call after a barrier, so
    without the wait for the slowest rank's render): APC's allreduce and reduce (double, or
    float for the compact wire's covered tiles); the segments' busiest pair rounds and gather
    approximated by ping-pongs of the same sizes."""
    if mode == "APC" and compact:
        return (measured_at(comm, p, "allreduce", "float", a["covered_tile_pixels"]) +
                measured_at(comm, p, "allreduce", "float",
                            a["covered_tile_pixels"] * (MOMENTS + 1) * 4) +
                measured_at(comm, p, "reduce", "float", a["covered_tile_pixels"] * 4 * 4))
    if mode == "APC":
        return (measured_at(comm, p, "allreduce", "double", a["rect_pixels"] * (MOMENTS + 1) * 8)
                + measured_at(comm, p, "reduce", "double", a["rect_pixels"] * 4 * 8))
    rounds = (1 << log2c(p)) - 1
    pair = SEGMENT_BYTES * a["ds_pairwise_critical_segments"] / max(rounds, 1)
    strip = 16 * a["rect_pixels"] / p
    return (rounds * 2 * measured_at(comm, p, "pingpong", "byte", pair / 2) +
            (p - 1) * measured_at(comm, p, "pingpong", "byte", strip))


def compact_wire(p, a, bytes_sent):
    """Whether the measured run shipped the compact wire: its bytes (all ranks, as the pass
    counts them: the summed buffers) are closer to the compact than to the old prediction."""
    old = p * a["rect_pixels"] * (MOMENTS + 1 + 4) * 8
    compact = p * (a["tiles"] + a["covered_tile_pixels"] * COMPACT_BYTES_PER_PIXEL)
    return bytes_sent == bytes_sent and abs(bytes_sent - compact) < abs(bytes_sent - old)


def validation_rows(scaling, analysis, constants, comm):
    """Per rank count and camera, the measured compositing (APC: allreduce + reduce; segments:
    exchange + gather; max over ranks, median over frames) against the model at the rank
    count's own alpha, beta, gamma, and against MPI alone moving the same bytes; per
    configuration the medians over the cameras."""
    groups = {}
    for r in scaling:
        p = int(r["ranks"])
        if p < 2 or p not in constants:
            continue
        match = [a for a in analysis if a["case"] == "gearteeth" and a["ranks"] == p and
                 a["camera"] == r["camera"] and a["width"] == r["size"]]
        if not match:
            continue
        a, c = match[0], constants[p]
        if r["mode"] == "APC" and compact_wire(p, a, num(r["bytes_sent"])):
            # The compact wire: the tile mask's allreduce (its own stage, not in the CSV) is
            # where ranks wait for the slowest pass 1, so allreduce_s is the transfer.
            measured = num(r["allreduce_s"]) + num(r["reduce_s"])
            t = apc_compact(p, a["tiles"], a["covered_tile_pixels"], c)
            model = {"compact wire (best algorithms)": t[1] + t[2]}
            # The allreduce stage alone starts with every rank past the mask's allreduce, so
            # no rank waits there for another's render.
            alone = (measured_at(comm, p, "allreduce", "float", a["covered_tile_pixels"]) +
                     measured_at(comm, p, "allreduce", "float",
                                 a["covered_tile_pixels"] * (MOMENTS + 1) * 4))
            groups.setdefault((p, r["mode"], "compact wire: allreduce stage only"), []).append(
                (num(r["allreduce_s"]), t[1], alone))
        elif r["mode"] == "APC":
            measured = num(r["allreduce_s"]) + num(r["reduce_s"])
            ring = sum(apc_old(p, a["rect_pixels"], c, ("ring", "binomial"))[:2])
            raben = sum(apc_old(p, a["rect_pixels"], c, ("Rabenseifner", "Rabenseifner"))[:2])
            model = {"ring + binomial": ring, "Rabenseifner": raben}
        else:
            measured = num(r["exchange_s"]) + num(r["gather_s"])
            model = {"as run (pairwise rounds)": sum(direct_send_pass(p, a, c))}
        alone = mpi_alone(comm, p, r["mode"], a, compact_wire(p, a, num(r["bytes_sent"])))
        for name, value in model.items():
            groups.setdefault((p, r["mode"], name), []).append((measured, value, alone))
    from scaling_transfer import add_transfer_rows  # noqa: E402  (it uses this module)
    add_transfer_rows(groups, scaling, analysis, constants, comm)
    rows = []
    for (p, mode, name), triples in sorted(groups.items()):
        measured = median([m for m, _, _ in triples])
        model = median([v for _, v, _ in triples])
        alone = median([x for _, _, x in triples])
        errors = [(v - m) / m for m, v, _ in triples if m > 0]
        rows.append([p, mode, name, len(triples), "%.4g" % measured, "%.4g" % model,
                     "%.3f" % ((model - measured) / measured), "%.3f" % median(errors),
                     "%.3f" % max(errors, key=abs), "oversubscribed" if p > 2 else "2 cores",
                     "%.4g" % alone, "%.3f" % ((model - alone) / alone)])
    return rows


def paper_rows(analysis, calibrations):
    """Every data set and rank count at 2560^2, medians over the cameras."""
    rows = []
    groups = {}
    for a in analysis:
        groups.setdefault((dataset(a["case"]), a["case"], a["ranks"]), []).append(a)
    for (data, case, p), rs in sorted(groups.items()):
        if p < 2:
            continue
        per_pixel = lambda f: median([f(a) for a in rs])  # noqa: E731
        nonempty = lambda a: max(a["nonempty_pixels"], 1)  # noqa: E731
        stats = ["%.4g" % per_pixel(lambda a: a["segments"] / nonempty(a)),
                 "%.4g" % per_pixel(lambda a: a["covered_tile_pixels"] / a["rect_pixels"]),
                 "%.4g" % per_pixel(lambda a: (a["tiles"] + a["covered_tile_pixels"] *
                                               COMPACT_BYTES_PER_PIXEL) / nonempty(a)),
                 "%.4g" % per_pixel(lambda a: max(a["ds_max_sent_segments"],
                                                  a["ds_max_received_segments"]) *
                                    SEGMENT_BYTES / nonempty(a))]
        for c in calibrations:
            per_method = {m: ([], [], [], []) for m in METHODS}
            for a in rs:
                big = scaled(a, PAPER_PIXELS)
                values = methods(p, big, c)
                unblended = methods(p, big, dict(c, blend=0.0))
                for m in METHODS:
                    for k in range(3):
                        per_method[m][k].append(values[m][k])
                    # The sort+blend cost per segment at which this baseline would take as
                    # long as APC's compact wire.
                    blended = {"direct send": big["ds_max_received_segments"] * p / (p - 1),
                               "binary swap": big["bs_critical_segments"]}.get(m, 0)
                    per_method[m][3].append(
                        (values["APC (compact wire)"][0] - unblended[m][0]) / blended
                        if blended > 0 else float("nan"))
            for m in METHODS:
                rows.append([data, case, p, c["name"], m, len(rs)] +
                            ["%.5g" % median(v) for v in per_method[m][:3]] + stats +
                            ["%.4g" % median(per_method[m][3])])
    return rows


PAPER_HEADER = ["dataset", "case", "ranks", "calibration", "method", "cameras", "time_s",
                "time_comm_s", "bytes", "segments_per_nonempty_pixel", "covered_fraction_of_rect",
                "apc_compact_bytes_per_nonempty_pixel_per_rank",
                "direct_send_busiest_rank_bytes_per_nonempty_pixel",
                "break_even_blend_s_per_segment"]


def crossover_rows(paper):
    """Per case and calibration: the smallest rank count from which APC (each wire) stays
    cheaper than the cheaper segment baseline, in time (with local work, and latency and
    bandwidth alone) and in bytes."""
    rows = []
    table = {}
    for r in paper:
        values = (float(r[6]), float(r[7]), float(r[8]))
        table.setdefault((r[1], r[3]), {}).setdefault(r[2], {})[r[4]] = values
    for (case, cal), by_p in sorted(table.items()):
        ranks = sorted(by_p)
        for apc in ("APC (old wire)", "APC (compact wire)"):
            result = []
            for k in (0, 1, 2):
                def cheaper(p):
                    seg = [by_p[p][m][k] for m in ("direct send", "binary swap")
                           if by_p[p][m][k] == by_p[p][m][k]]
                    return by_p[p][apc][k] < min(seg) if seg else False
                cross = next((p for i, p in enumerate(ranks)
                              if all(cheaper(q) for q in ranks[i:])), None)
                result.append(str(cross) if cross is not None else "> %d" % ranks[-1])
            for k in (0, 1, 2):  # where APC is the cheaper (real meshes: a fixed mesh cut
                # finer sends fewer segments per rank, so APC can lose again at large N)
                result.append(" ".join(str(p) for p in ranks if cheaper_at(by_p, p, apc, k))
                              or "none")
            rows.append([case, cal, apc, ranks[0], ranks[-1]] + result)
    return rows


def cheaper_at(by_p, p, apc, k):
    seg = [by_p[p][m][k] for m in ("direct send", "binary swap") if by_p[p][m][k] == by_p[p][m][k]]
    return by_p[p][apc][k] < min(seg) if seg else False


def calibrate_blend(scaling, analysis):
    """Seconds per segment of the segments' sort and blend: the measured stage on 2 ranks
    over the busiest strip's segments from the analysis, the median over the frames (it
    varies with the cameras: deeper lists sort slower per segment, and with the load)."""
    per = []
    for r in scaling:
        if r["mode"] != "SEGMENTS" or r["ranks"] != "2" or not r.get("blend_segments_s"):
            continue
        match = [a for a in analysis if a["case"] == "gearteeth" and a["ranks"] == 2 and
                 a["camera"] == r["camera"] and a["width"] == r["size"]]
        if match and match[0]["ds_max_received_segments"] > 0:
            per.append(num(r["blend_segments_s"]) / (2 * match[0]["ds_max_received_segments"]))
    return median(per)


def run(results, out):
    comm = read_csv(os.path.join(results, "comm.csv"))
    analysis = analysis_rows(read_csv(os.path.join(results, "segment_transfer.csv")))
    # scaling_old_wire.csv: a run of the pass before the compact wire, kept to validate the
    # old wire's model too (the wire of each row is told by its bytes).
    scaling = read_csv(os.path.join(results, "scaling.csv")) + \
        read_csv(os.path.join(results, "scaling_old_wire.csv"))
    constants = calibrate(comm)
    if not constants or not analysis:
        print("scaling_model: no comm.csv or per-rank segment counts in %s" % results)
        return 1
    os.makedirs(out, exist_ok=True)
    blend = calibrate_blend(scaling, analysis)
    for c in constants.values():
        c["blend"] = blend
    # At the paper's scale: this machine's 2 ranks (not oversubscribed) at the minimum over
    # the repetitions, the best estimate of the machine without the other users' load.
    machine = dict(calibrate(comm, "min_s")[min(constants)], blend=blend)
    machine["name"] = "this machine np2 (min)"
    infiniband = interconnect(machine)
    write_csv(os.path.join(out, "constants.csv"),
              ["calibration", "ranks", "alpha_s", "beta_s_per_byte", "bandwidth_GBps",
               "gamma_double_s_per_byte", "gamma_float_s_per_byte", "copy_s_per_byte",
               "load1", "blend_s_per_segment"],
              constants_rows(dict(constants, machine=machine), infiniband))
    write_csv(os.path.join(out, "collectives.csv"),
              ["ranks", "op", "type", "bytes", "measured_s", "model_1_s", "model_2_s",
               "model_3_s", "closest", "closest_rel_error"], collectives_rows(comm, constants))
    write_csv(os.path.join(out, "validation.csv"),
              ["ranks", "mode", "model", "cameras", "measured_s", "model_s", "rel_error",
               "median_rel_error_per_camera", "worst_rel_error_per_camera", "cores",
               "mpi_alone_s", "rel_error_vs_mpi_alone"],
              validation_rows(scaling, analysis, constants, comm))
    from scaling_transfer import waiting_rows  # noqa: E402
    write_csv(os.path.join(out, "waiting.csv"),
              ["ranks", "mode", "cameras", "cores", "compositing_mean_s", "wait_mean_s",
               "transfer_s", "wait_share", "render_imbalance", "smallest_collective_s"],
              waiting_rows(scaling))
    paper = paper_rows(analysis, [machine, infiniband])
    write_csv(os.path.join(out, "paper_scale.csv"), PAPER_HEADER, paper)
    write_csv(os.path.join(out, "crossover.csv"),
              ["case", "calibration", "apc", "from_ranks", "to_ranks", "crossover_time",
               "crossover_time_comm", "crossover_bytes", "apc_cheaper_time_at",
               "apc_cheaper_time_comm_at", "apc_cheaper_bytes_at"], crossover_rows(paper))
    print("scaling_model: wrote constants, collectives, validation, waiting, paper_scale, crossover "
          "CSVs to %s" % out)
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", required=True)
    parser.add_argument("--out")
    args = parser.parse_args()
    return run(args.results, args.out or os.path.join(args.results, "model"))


if __name__ == "__main__":
    sys.exit(main())
