"""Section 5 of the evaluation report: the scaling model (model/*.csv from scaling_model.py)."""

import os
import shutil
from types import SimpleNamespace


from report_common import fmt, mb, plt, read_csv, table
from scaling_model import num


def model_panel(ax, paper, cases, calibration, key, scale, ylabel):
    """One panel of the model's plot: key (times scale) against ranks, a line per method and
    case, on log axes."""
    styles = {"APC (old wire)": ("C0", ":"), "APC (compact wire)": ("C0", "-"),
              "direct send": ("C1", "-"), "binary swap": ("C2", "-")}
    markers = {c: m for c, m in zip(cases, "os^vDP<>*")}
    for case in cases:
        for method, (colour, line) in styles.items():
            pts = sorted((int(r["ranks"]), num(r[key])) for r in paper
                         if r["case"] == case and r["calibration"] == calibration and
                         r["method"] == method and num(r[key]) == num(r[key]))
            if pts:
                ax.plot([p for p, _ in pts], [v * scale for _, v in pts], line, color=colour,
                        marker=markers[case], markersize=4, label="%s, %s" % (method, case),
                        alpha=1 if case == "gearteeth" else 0.55)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("ranks")
    ax.set_ylabel(ylabel)


class ModelSection:
    # ---------------------------------------------------------------- scaling model
    def model(self):
        """Section 5, from the CSVs of scaling_model.py (results/model), which are copied with
        the model's inputs to docs/evaluation/model/ so that the section can be checked, and
        recomputed, without rerunning: scaling_model.py --results docs/evaluation/model."""
        source = os.path.join(self.results, "model")
        get = lambda name: read_csv(os.path.join(source, name))  # noqa: E731
        m = SimpleNamespace(constants=get("constants.csv"), validation=get("validation.csv"),
                            paper=get("paper_scale.csv"), crossover=get("crossover.csv"),
                            collectives=get("collectives.csv"), waiting=get("waiting.csv"))
        self.add("## 5. Scaling model: compositing at the paper's scale\n")
        if not m.constants or not m.paper:
            self.add("No results (run scaling_model.py: it needs comm.csv and the per-rank "
                     "columns of segment_transfer.csv).\n")
            return
        self._model_keep_inputs(source)
        paper = m.paper
        m.gear = [r for r in paper if r["case"] == "gearteeth"]
        calibrations = list(dict.fromkeys(r["calibration"] for r in paper))
        m.machine, m.cluster = calibrations[0], calibrations[-1]
        m.at = {(r["case"], int(r["ranks"]), r["calibration"], r["method"]): r for r in paper}
        m.ranks = sorted({int(r["ranks"]) for r in m.gear})
        m.cases = list(dict.fromkeys(r["case"] for r in paper))
        for part in (self._model_intro, self._model_constants, self._model_collectives,
                     self._model_validation, self._model_waiting, self._model_gear,
                     self._model_plots,
                     self._model_crossover, self._model_validation_headline,
                     self._model_meshes):
            part(m)

    def _model_keep_inputs(self, source):
        """The model's inputs and outputs, copied next to the report."""
        kept = os.path.join(self.figures, "model")
        os.makedirs(kept, exist_ok=True)
        for name in ("comm.csv", "segment_transfer.csv", "scaling.csv", "scaling_old_wire.csv"):
            if os.path.exists(os.path.join(self.results, name)):
                shutil.copyfile(os.path.join(self.results, name), os.path.join(kept, name))
        for name in sorted(os.listdir(source)):
            if name.endswith(".csv"):
                shutil.copyfile(os.path.join(source, name), os.path.join(kept, name))

    def _model_intro(self, m):
        constants = m.constants
        self.add(
            "An α–β–γ (latency–inverse bandwidth–reduction cost) model of one frame's "
            "compositing, `Testing/Benchmarks/scaling_model.py` (its docstring has every "
            "formula). α and β come from `apcCommBenchmark`'s MPI ping-pong (α: 8-byte "
            "messages; β: the slope over 1–64 MiB, compositing's sizes), γ from a local "
            "in-place sum (double: %s); the collectives are modelled as in Thakur, Rabenseifner "
            "& Gropp, *Optimization of Collective Communication Operations in MPICH* (IJHPCA "
            "2005): ring, recursive doubling and Rabenseifner allreduce, binomial and "
            "Rabenseifner reduce, the cheapest taken as an MPI library's choice. The segment "
            "baselines' traffic per rank comes from `apcSegmentAnalysis` (section 2): ideal "
            "direct send is bound by the busiest rank's sent or received segments, binary swap "
            "by the busiest rank of each round, both then gather 16 B per pixel to the display "
            "rank; their sort and blend is not counted (as in section 1's compositing time), "
            "which favours them. APC is modelled with the wire of main before the compact "
            "format (72 B per pixel of the data's screen rectangle: (M+1)+4 doubles, M = 4) "
            "and with the compact wire that replaced it (a 1-byte-per-8×8-tile MAX allreduce, "
            "then per pixel of the tiles some rank covers a 1-byte exponent, 20 B of 32-bit "
            "fixed-point moments and 16 B of float colour: 37 B; no opaque geometry here, so "
            "the depth is a tile mask). Every CSV is in "
            "[evaluation/model/](evaluation/model/).\n" % fmt(num(constants[0]
                                                                  ["gamma_double_s_per_byte"])))

    def _model_constants(self, m):
        constants = m.constants
        # Constants.
        body = []
        for c in constants:
            body.append([c["calibration"], fmt(num(c["alpha_s"]) * 1e6), fmt(num(
                c["bandwidth_GBps"])), fmt(num(c["gamma_double_s_per_byte"]) * 1e9),
                fmt(num(c["gamma_float_s_per_byte"]) * 1e9),
                fmt(num(c["copy_s_per_byte"]) * 1e9), c["load1"],
                fmt(num(c.get("blend_s_per_segment")) * 1e9)])
        self.add(table(["calibration", "α µs", "1/β GB/s", "γ double ns/B", "γ float ns/B",
                        "copy ns/B", "load average (1 min)", "segment sort+blend ns"], body))
        self.add(
            "Medians of the repetitions (the machine is shared: the load average is the one "
            "during the measurement; 4 and 8 ranks share 2 cores, so their α and β include the "
            "time slices lost to the other ranks' busy polling). The interconnect row assumes "
            "100 Gb/s InfiniBand (EDR, or HDR100 as on TACC Frontera, the paper's machine): "
            "α = 1 µs, 1/β = 12 GB/s. These are assumed published figures, not measured here: "
            "the NVIDIA ConnectX-5 adapter datasheet gives 100 Gb/s and sub-600 ns adapter "
            "latency, and the OSU micro-benchmarks' published MVAPICH2 results over EDR show "
            "~1 µs MPI latency and ~12 GB/s large-message bandwidth "
            "(<https://mvapich.cse.ohio-state.edu/performance/pt_to_pt/>). It uses this "
            "machine's γ and copy cost.\n")

    def _model_collectives(self, m):
        collectives = m.collectives
        if collectives:
            big = {}
            for r in collectives:
                key = (r["ranks"], r["op"], r["type"])
                if key not in big or int(r["bytes"]) > int(big[key]["bytes"]):
                    big[key] = r
            body = [[r["ranks"], r["op"], r["type"], mb(num(r["bytes"])), fmt(num(
                r["measured_s"])), fmt(num(r["model_1_s"])), fmt(num(r["model_2_s"])),
                fmt(num(r["model_3_s"])), r["closest"], fmt(num(r["closest_rel_error"]), 2)]
                for r in big.values()]
            self.add("First check: the model of the collectives against `apcCommBenchmark`'s own "
                     "allreduce and reduce at the largest size (allreduce models: ring, "
                     "recursive doubling, Rabenseifner; reduce: binomial, Rabenseifner; "
                     "all sizes ≥ 64 KiB in `collectives.csv`):\n\n")
            self.add(table(["ranks", "op", "type", "MB per rank", "measured s", "model 1 s",
                            "model 2 s", "model 3 s", "closest", "its error"], body))

    def _model_validation(self, m):
        validation = m.validation
        # Validation.
        if validation:
            pct = lambda v: "%+.0f %%" % (100 * v) if v == v else "–"  # noqa: E731
            body = [[r["ranks"], r["cores"], r["mode"], r["model"], r["cameras"],
                     fmt(num(r["model_s"])), fmt(num(r.get("mpi_alone_s"))),
                     pct(num(r.get("rel_error_vs_mpi_alone"))), fmt(num(r["measured_s"])),
                     pct(num(r["rel_error"])), pct(num(r["worst_rel_error_per_camera"]))]
                    for r in validation]
            self.add("Validation against the measured compositing of section 1 (APC: allreduce + "
                     "reduce, of the old wire from `scaling_old_wire.csv` when present, of the "
                     "compact wire otherwise, told apart by the bytes sent; segments: exchange + "
                     "gather as "
                     "`vtkAPCCompositePass` runs them, pairs in rounds, one way then the "
                     "other), for the same frames (rank count and camera; the analysis gives "
                     "the bytes), each rank count with the constants measured at that rank "
                     "count. *MPI alone* is the same bytes through `apcCommBenchmark`'s "
                     "measured collectives or ping-pongs (interpolated between its sizes), each "
                     "after a barrier. Errors = (model − measured) / measured, of the medians "
                     "over the cameras:\n\n")
            self.add(table(["ranks", "cores", "mode", "model", "frames (cameras × runs)",
                            "model s",
                            "MPI alone s", "model vs MPI alone", "pass measured s",
                            "model vs pass", "worst camera vs pass"], body))
            self.add(
                "The *transfer* rows compare like with like: `vtkAPCCompositePass` starts each "
                "collective with a barrier, so its time after the barrier (the transfer, max "
                "over ranks) holds neither the wait for the slowest rank's render nor the "
                "packing around the collectives, and the model is taken without its packing "
                "copies. The other rows are the older comparison with whole stages:\n\n"
                "The pass's stage times are the slowest rank's lap from the end of its render "
                "to the end of the collective. On the old wire (and for the segments, whose "
                "counts allgather opens the exchange) that lap includes the wait for the "
                "slowest rank's render, which a communication model does not see: the "
                "collective synchronises, and the ranks' renders differ by a large part of a "
                "second on this loaded machine. The compact wire's tile-mask allreduce takes "
                "that wait in its own stage (not in the CSV), so its *allreduce stage only* row "
                "compares transfer with transfer; the reduce still waits for the slowest pass "
                "2. That allreduce stage, and the transfer alone, are still 10–100× the model "
                "and MPI alone here: each collective of a frame costs about the latency of the "
                "smallest one (the 16-byte gather in the table below), the time for every rank "
                "of a loaded machine to be given a core, which back-to-back MPI calls do not "
                "pay; re-run `run-evaluation.sh --model-only` on a quiet machine. The model "
                "against *MPI alone* (the same bytes through the same MPI, each call after a "
                "barrier) is the model's own error. Above 2 ranks the ranks share 2 cores: "
                "read the 2-rank rows as the model's accuracy and the 4–8-rank rows as how "
                "far oversubscription is from it.\n")

    def _model_waiting(self, m):
        """How much of the compositing is the wait for the slowest rank (waiting.csv)."""
        if not m.waiting:
            return
        body = [[r["ranks"], r["cores"], r["mode"], r["cameras"],
                 fmt(num(r["compositing_mean_s"])), fmt(num(r["wait_mean_s"])),
                 fmt(num(r["transfer_s"])), "%.0f %%" % (100 * num(r["wait_share"])),
                 fmt(num(r["render_imbalance"])), fmt(num(r.get("smallest_collective_s")))]
                for r in m.waiting]
        self.add("How much of the compositing is waiting in the weak-scaling runs behind "
                 "this section (`evaluation/model/scaling.csv`; APC: tiles + "
                 "allreduce + reduce; segments: exchange + gather), per rank count, medians "
                 "over the cameras: the stages and the wait in them are means over the ranks "
                 "(the display rank waits for the others, the others for it), the transfer "
                 "after the last arrival the slowest rank's; render imbalance = slowest / mean "
                 "render (pass 1 + pass 2, or segments + sort and blend):\n\n")
        self.add(table(["ranks", "cores", "mode", "cameras", "compositing s (mean over ranks)",
                        "of it waiting s", "transfer s", "waiting share", "render imbalance",
                        "16-byte gather s"], body))
        self.add("The last column is the transfer of the frame's smallest collective, the "
                 "16-byte gather of the ranks' times: one collective's latency on this machine "
                 "as the pass meets it. A frame runs about 7 collectives (agreement, depth, "
                 "tiles, two for the moments, colours, the ranks' times), so that latency times "
                 "7 is a floor under the transfer that the α–β model, calibrated by "
                 "back-to-back MPI calls, does not see: where the machine is loaded, a "
                 "collective completes only when every rank has been given a core again. "
                 "Oversubscribed (4 and 8 ranks on 2 cores), every step of a rank (its render, "
                 "its packing, each collective) is spread over the time slices the other ranks "
                 "leave it: the transfer and the ranks' own work in these stages grow with the "
                 "rank count as well as the wait, so the waiting share is not a measure of "
                 "imbalance there; at 2 ranks it is.\n")

    def _model_gear(self, m):
        constants, crossover, gear = m.constants, m.crossover, m.gear
        machine, cluster, at, ranks = m.machine, m.cluster, m.at, m.ranks
        trio = ("APC (compact wire)", "direct send", "binary swap")
        # The gear teeth's per-rank traffic from the analysis, at the paper's size.
        if gear:
            body = []
            for n in ranks:
                first = at[("gearteeth", n, cluster, "direct send")]
                row = [n, fmt(num(first["segments_per_nonempty_pixel"])),
                       fmt(num(first["covered_fraction_of_rect"])),
                       fmt(num(first["apc_compact_bytes_per_nonempty_pixel_per_rank"])),
                       fmt(num(first["direct_send_busiest_rank_bytes_per_nonempty_pixel"]))]
                for m in ("APC (old wire)",) + trio:
                    row.append(mb(num(at[("gearteeth", n, cluster, m)]["bytes"])))
                for cal in (machine, cluster):
                    row.append(" / ".join(fmt(num(at[("gearteeth", n, cal, m)]["time_comm_s"]))
                                          for m in trio))
                    row.append(" / ".join(fmt(num(at[("gearteeth", n, cal, m)]["time_s"]))
                                          for m in trio))
                body.append(row)
            self.add("The gear teeth at 2560² (counts from the analysis at its size, scaled "
                     "by the pixels; up to 8 ranks at 512² and the benchmark's sample distance, "
                     "beyond at 256² with the sample distance 0.08/N, see section 2). Times "
                     "are APC (compact) / direct send / binary swap, first latency and "
                     "bandwidth alone, then with the local work:\n\n")
            self.add(table(["ranks", "segments / non-empty px", "covered fraction of rect",
                            "APC compact B / non-empty px / rank",
                            "direct send: busiest rank's B sent or received / non-empty px",
                            "APC old MB",
                            "APC compact MB", "direct send MB", "binary swap MB",
                            "s, α β only (%s)" % machine, "s, with local work (%s)" % machine,
                            "s, α β only (%s)" % cluster, "s, with local work (%s)" % cluster],
                           body))

            top = ranks[-1]
            last = at[("gearteeth", top, cluster, "direct send")]

            def cross(key):
                return next((r[key] for r in crossover if r["case"] == "gearteeth" and
                             r["apc"] == "APC (compact wire)" and r["calibration"] == cluster),
                            "?")
            self.add(
                "Reading it: under weak scaling every rank's own traffic stays about constant "
                "for both approaches: at %d ranks APC's compact wire moves %s B per non-empty "
                "pixel per rank and direct send's busiest rank %s B sent or received (a rank "
                "sends only its own segments, ~4 slabs' worth per pixel, and a strip owner "
                "receives its strip's, whatever N; medians over the cameras). So with a "
                "full-bisection "
                "network the two's latency–bandwidth times stay close (APC / direct send = "
                "%.2f at %d ranks; crossover in α–β time: %s, in bytes: %s); what "
                "grows with N for the segments is the total traffic (%s MB at %d ranks, the "
                "paper's O(m)), which a tapered network would feel, and the depth of every "
                "pixel's list (%s segments per non-empty pixel at %d ranks) that the strip "
                "owners sort and blend. With the local work counted (the sort and blend cost "
                "per segment measured here, linear: the log factor of deeper sorts is left "
                "out, which favours the segments), the crossover is at %s ranks (%s): APC's "
                "compact wire is the cheaper at %d ranks as soon as sorting and blending "
                "costs the busiest strip owner more than %s ns per segment (direct send; "
                "binary swap %s ns), against %s ns measured here (median over the 2-rank "
                "frames, section 1's sort+blend stage).\n" % (
                    top, fmt(num(last["apc_compact_bytes_per_nonempty_pixel_per_rank"])),
                    fmt(num(last["direct_send_busiest_rank_bytes_per_nonempty_pixel"])),
                    num(at[("gearteeth", top, cluster, "APC (compact wire)")]["time_comm_s"]) /
                    num(last["time_comm_s"]), top, cross("crossover_time_comm"),
                    cross("crossover_bytes"), mb(num(last["bytes"])), top,
                    fmt(num(last["segments_per_nonempty_pixel"])),
                    top, cross("crossover_time"), cluster, top,
                    fmt(1e9 * num(last["break_even_blend_s_per_segment"])),
                    fmt(1e9 * num(at[("gearteeth", top, cluster, "binary swap")][
                        "break_even_blend_s_per_segment"])),
                    fmt(1e9 * num(constants[-1].get("blend_s_per_segment")))))

    def _model_plots(self, m):
        paper, machine, cluster, cases = m.paper, m.machine, m.cluster, m.cases
        # Plots: time and bytes vs ranks, per calibration, gear teeth (lines) and real data.
        fig, axes = plt.subplots(1, 4, figsize=(22, 4.6))
        panels = ((machine, "time_s", "with local work"), (cluster, "time_s", "with local work"),
                  (cluster, "time_comm_s", "latency and bandwidth only"))
        for ax, (cal, key, what) in zip(axes[:3], panels):
            model_panel(ax, paper, cases, cal, key, 1.0, "modelled compositing s per frame")
            ax.set_title("%s: %s" % (cal, what), fontsize=9)
        model_panel(axes[3], paper, cases, cluster, "bytes", 1e-6, "MB per frame, all ranks")
        axes[3].set_title("bytes sent")
        axes[3].legend(fontsize=6, ncol=2, loc="upper left")
        self.figure(fig, "model_scaling.png",
                    "The model at 2560² against ranks: compositing time with local work on "
                    "this machine's 2-rank constants and with 100 Gb/s InfiniBand, the "
                    "InfiniBand time of latency and bandwidth alone, and bytes of all ranks. "
                    "Solid blue: APC with the compact wire; dotted blue: the old wire; orange: "
                    "direct send; green: binary swap; markers: data sets (gear teeth opaque, "
                    "real meshes pale).")

    def _model_crossover(self, m):
        constants, crossover, at = m.constants, m.crossover, m.at
        if crossover:
            body = [[r["case"], r["calibration"], r["apc"], "%s–%s" % (r["from_ranks"],
                                                                       r["to_ranks"]),
                     r["crossover_time"], r.get("crossover_time_comm", "–"),
                     r["crossover_bytes"], r.get("apc_cheaper_time_at", "–"),
                     r.get("apc_cheaper_time_comm_at", "–")] for r in crossover]
            self.add("Crossover: the smallest rank count from which APC stays cheaper than the "
                     "cheaper segment baseline (direct send or binary swap) up to the largest "
                     "rank count analysed; '> N' = not within the range; '2' = from the "
                     "start:\n\n")
            self.add(table(["case", "calibration", "APC wire", "ranks analysed",
                            "crossover (time with local work)", "crossover (α β time only)",
                            "crossover (bytes)", "APC cheaper at (time with local work)",
                            "APC cheaper at (α β time)"], body))
            for r in crossover:
                if r["case"] == "gearteeth" and r["apc"] == "APC (compact wire)":
                    top = int(r["to_ranks"])
                    be = at.get(("gearteeth", top, r["calibration"], "direct send"), {})
                    self.headline.append(
                        "Scaling model, gear teeth at 2560², %d ranks, APC's compact wire vs the "
                        "cheaper segment baseline, %s: crossover in latency and bandwidth alone "
                        "at %s ranks, in bytes at %s (every rank's traffic stays "
                        "about constant for both under weak scaling); APC wins on the segments' "
                        "sort+blend, once that costs more than **%s ns per segment** (section "
                        "1's sort+blend stage: %s ns per segment, median, on this loaded 2-core "
                        "machine), which makes APC the cheaper from **%s** ranks." % (
                            top, r["calibration"], r.get("crossover_time_comm", "–"),
                            r["crossover_bytes"],
                            fmt(1e9 * num(be.get("break_even_blend_s_per_segment"))),
                            fmt(1e9 * num(constants[-1].get("blend_s_per_segment"))),
                            r["crossover_time"]))

    def _model_validation_headline(self, m):
        validation = m.validation
        if validation:
            two = [r for r in validation if r["ranks"] == "2"]
            if two:
                self.headline.append(
                    "Scaling model vs measured at 2 ranks (model error vs MPI alone moving the "
                    "same bytes / vs the pass's stage, which includes waiting for the slowest "
                    "render; *transfer* rows: against the collectives' time after every rank "
                    "arrived): %s." % "; ".join(
                        "%s %s %+.0f %% / %+.0f %%" % (
                            r["mode"], r["model"], 100 * num(r.get("rel_error_vs_mpi_alone")),
                            100 * num(r["rel_error"])) for r in two))
            if m.waiting:
                self.headline.append(
                    "Waiting share of the compositing time (APC, mean over ranks): %s." %
                    ", ".join("%s ranks %.0f %%" % (r["ranks"], 100 * num(r["wait_share"]))
                              for r in m.waiting if r["mode"] == "APC"))

    def _model_meshes(self, m):
        paper, crossover, cluster, at, cases = m.paper, m.crossover, m.cluster, m.at, m.cases
        for case in [c for c in cases if "metis" in c]:
            rs = sorted({int(r["ranks"]) for r in paper if r["case"] == case})
            lo = at[(case, rs[0], cluster, "direct send")]
            hi = at[(case, rs[-1], cluster, "direct send")]
            row = next((r for r in crossover if r["case"] == case and
                        r["apc"] == "APC (compact wire)" and r["calibration"] == cluster), {})
            self.add(
                "%s (a fixed mesh cut finer, i.e. strong scaling): direct send's busiest rank "
                "moves %s B per non-empty pixel at %d ranks and %s B at %d, APC's compact wire "
                "%s B whatever N (every rank sends the union of covered tiles); the segments "
                "per pixel grow only from %s to %s. APC is the cheaper in α–β time at: %s; "
                "in bytes at: %s; with the measured sort+blend at: %s (%s).\n" % (
                    case, fmt(num(lo["direct_send_busiest_rank_bytes_per_nonempty_pixel"])),
                    rs[0], fmt(num(hi["direct_send_busiest_rank_bytes_per_nonempty_pixel"])),
                    rs[-1], fmt(num(hi["apc_compact_bytes_per_nonempty_pixel_per_rank"])),
                    fmt(num(lo["segments_per_nonempty_pixel"])),
                    fmt(num(hi["segments_per_nonempty_pixel"])),
                    row.get("apc_cheaper_time_comm_at", "–"),
                    row.get("apc_cheaper_bytes_at", "–"),
                    row.get("apc_cheaper_time_at", "–"), cluster))
        if any("metis" in r["case"] for r in paper):
            self.add("The real meshes appear twice: in their stored pieces (wind: 8 Scotch "
                     "pieces, flange: 4; cases wind-<distance>, flange) and cut by "
                     "`vtkAPCGraphPartition` (METIS on the cell dual graph, K = N; cases "
                     "wind-metis-<distance>, flange-metis), the latter at the analysis's "
                     "partition size and scaled to 2560² like the gear teeth.\n")
        else:
            self.add("The real meshes stop at their stored pieces (wind 8, flange 4): this "
                     "build has no graph partitioner (`vtkAPCGraphPartition`) to cut them "
                     "further.\n")
