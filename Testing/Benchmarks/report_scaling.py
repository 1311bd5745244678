"""Sections 1 and 2 of the evaluation report: weak scaling (scaling.csv) and the segment
transfers (segment_transfer.csv, heatmaps)."""

import os

import numpy as np

from report_common import APC_STAGES, SEG_STAGES, fmt, mb, plt, read_csv, read_pgm, table
from scaling_model import median, num


class ScalingSections:
    # ---------------------------------------------------------------- weak scaling
    def scaling(self):
        rows = read_csv(os.path.join(self.results, "scaling.csv"))
        if not rows:
            self.add("## 1. Weak scaling\n\nNo results (scaling.csv missing).\n")
            return
        ranks = sorted({int(r["ranks"]) for r in rows})
        size = rows[0]["size"]

        def med(mode, n, key):
            return median([key(r) for r in rows if r["mode"] == mode and int(r["ranks"]) == n])

        apc_comp = lambda r: num(r["allreduce_s"]) + num(r["reduce_s"])  # noqa: E731
        seg_comp = lambda r: num(r["exchange_s"]) + num(r["gather_s"])  # noqa: E731
        self.add("## 1. Weak scaling on the gear teeth\n")
        self.add(
            "One gear-teeth puzzle piece per rank (4 slabs of 32 × 32 × 2 hexahedra, every piece "
            "overlapping every other in depth), %s² pixels, 4 cameras on an orbit (azimuth 0, 90, "
            "180, 270°, 30° elevation), %s timed frame(s) per camera after an untimed one. Times "
            "are the maximum over ranks of each stage, median over frames, then median over the "
            "4 cameras; bytes and messages are summed over all ranks (payloads as sent by "
            "`vtkAPCCompositePass`, whose wire the build decides: section 5 tells the old "
            "from the compact one by these bytes).\n" % (size, rows[0]["frames"]))
        self.add(
            "**Caveat: this machine has %s cores.** Runs on more than 2 ranks are "
            "oversubscribed (`mpirun --oversubscribe`): their times measure ranks taking turns "
            "on 2 cores and waiting for each other in busy-polling MPI collectives, not weak "
            "scaling. Bytes and message counts do not depend on the cores and are exact at "
            "every rank count. The box is fixed, so only the cells are weak-scaled: the samples "
            "per rank fall as 1/N while the pixels stay the same.\n" % os.cpu_count())

        header = ["ranks", "APC pass 1 s", "allreduce s", "pass 2 s", "reduce s", "APC frame s",
                  "SEG render s", "exchange s", "sort+blend s", "gather s", "SEG frame s",
                  "compositing APC/SEG", "APC MB", "SEG MB", "bytes APC/SEG", "APC msgs",
                  "SEG msgs", "max Δ vs 1 process (APC / SEG)"]
        body = []
        summary = {}
        for n in ranks:
            a = {s: med("APC", n, lambda r, s=s: num(r[s + "_s"])) for s in APC_STAGES}
            g = {s: med("SEGMENTS", n, lambda r, s=s: num(r[s + "_s"])) for s in SEG_STAGES}
            ac, gc = med("APC", n, apc_comp), med("SEGMENTS", n, seg_comp)
            ab, gb = med("APC", n, lambda r: num(r["bytes_sent"])), \
                med("SEGMENTS", n, lambda r: num(r["bytes_sent"]))
            am, gm = med("APC", n, lambda r: num(r["messages"])), \
                med("SEGMENTS", n, lambda r: num(r["messages"]))
            ad = max(num(r.get("max_abs_diff_vs_1process"), 0) for r in rows
                     if r["mode"] == "APC" and int(r["ranks"]) == n)
            gd = max(num(r.get("max_abs_diff_vs_1process"), 0) for r in rows
                     if r["mode"] == "SEGMENTS" and int(r["ranks"]) == n)
            summary[n] = dict(apc=ac, seg=gc, apc_bytes=ab, seg_bytes=gb, apc_msgs=am,
                              seg_msgs=gm, a=a, g=g, apc_diff=ad, seg_diff=gd)
            body.append([n, fmt(a["pass1"]), fmt(a["allreduce"]), fmt(a["pass2"]),
                         fmt(a["reduce"]), fmt(med("APC", n, lambda r: num(r["frame_s"]))),
                         fmt(g["segments"]), fmt(g["exchange"]), fmt(g["blend_segments"]),
                         fmt(g["gather"]), fmt(med("SEGMENTS", n, lambda r: num(r["frame_s"]))),
                         fmt(ac / gc if gc > 0 else float("nan")), mb(ab), mb(gb),
                         fmt(ab / gb if gb > 0 else float("nan")), fmt(am), fmt(gm),
                         "%s / %s" % (fmt(ad, 2), fmt(gd, 2))])
        self.add(table(header, body))
        self.add(
            "Compositing time: APC = allreduce + reduce, SEG = exchange + gather (the "
            "communication stages; SEG's sort+blend is listed apart). The last column is the "
            "largest difference of the display rank's float RGBA from one process rendering all "
            "pieces with the same mapper (MBOIT for APC, EXACT for the segments): APC on N ranks "
            "*is* one-process MBOIT.\n")
        top = ranks[-1]
        s = summary[top]
        if top > 1:
            self.headline.append(
                "At %d ranks (gear teeth, %s², oversubscribed): compositing time APC/segments = "
                "%.3f s / %.3f s = **%.2f**; bytes APC/segments = %s MB / %s MB = **%.2f**; "
                "messages %d vs %d." % (top, size, s["apc"], s["seg"], s["apc"] / s["seg"],
                                        mb(s["apc_bytes"]), mb(s["seg_bytes"]),
                                        s["apc_bytes"] / s["seg_bytes"], s["apc_msgs"],
                                        s["seg_msgs"]))

        self._scaling_figures(ranks, summary)

    def _scaling_figures(self, ranks, summary):
        fig, axes = plt.subplots(1, 3, figsize=(15, 4))
        xs = [n for n in ranks if n > 1]
        axes[0].plot(xs, [summary[n]["apc"] for n in xs], "o-", label="APC (allreduce + reduce)")
        axes[0].plot(xs, [summary[n]["seg"] for n in xs], "s-",
                     label="segments (exchange + gather)")
        axes[0].set_xlabel("ranks")
        axes[0].set_ylabel("seconds per frame")
        axes[0].set_title("compositing time (>2 ranks oversubscribed)")
        axes[0].legend()
        axes[1].plot(xs, [summary[n]["apc_bytes"] / 1e6 for n in xs], "o-", label="APC")
        axes[1].plot(xs, [summary[n]["seg_bytes"] / 1e6 for n in xs], "s-", label="segments")
        axes[1].set_xlabel("ranks")
        axes[1].set_ylabel("MB per frame, all ranks")
        axes[1].set_title("bytes sent")
        axes[1].legend()
        axes[2].plot(xs, [summary[n]["apc_msgs"] for n in xs], "o-", label="APC")
        axes[2].plot(xs, [summary[n]["seg_msgs"] for n in xs], "s-", label="segments")
        axes[2].set_xlabel("ranks")
        axes[2].set_ylabel("messages per frame, all ranks")
        axes[2].set_title("messages")
        axes[2].legend()
        for ax in axes:
            ax.set_xticks(xs)
        self.figure(fig, "scaling.png", "Weak scaling on the gear teeth: compositing time, bytes "
                                        "and messages per frame (medians over 4 cameras).")

        fig, ax = plt.subplots(figsize=(10, 4))
        width = 0.38
        colours = dict(pass1="#4c72b0", allreduce="#dd8452", pass2="#55a868", reduce="#c44e52",
                       resolve="#8172b3", segments="#4c72b0", exchange="#dd8452",
                       blend_segments="#937860", gather="#c44e52")
        for k, n in enumerate(ranks):
            for offset, stages, key in ((-width / 2, APC_STAGES, "a"), (width / 2, SEG_STAGES, "g")):
                bottom = 0
                for stage in stages:
                    value = summary[n][key][stage]
                    value = 0 if value != value else value
                    ax.bar(k + offset, value, width * 0.95, bottom=bottom, color=colours[stage],
                           label=stage if k == 0 else None, hatch="" if key == "a" else "//")
                    bottom += value
        ax.set_xticks(range(len(ranks)))
        ax.set_xticklabels(["%d ranks\nAPC | SEG" % n for n in ranks])
        ax.set_ylabel("seconds per frame (max over ranks)")
        ax.set_title("Stage breakdown: APC (left bar) vs segments (right bar, hatched)")
        handles, labels = ax.get_legend_handles_labels()
        unique = dict(zip(labels, handles))
        ax.legend(unique.values(), unique.keys(), ncol=3, fontsize=8)
        self.figure(fig, "scaling_stages.png", "Stage breakdown per rank count.")


    # ---------------------------------------------------------------- segment transfers
    def transfers(self):
        rows = read_csv(os.path.join(self.results, "segment_transfer.csv"))
        if not rows:
            self.add("## 2. Segments and what compositing them moves\n\nNo results.\n")
            return
        self.add("## 2. Segments and what compositing them moves\n")
        self.add(
            "`apcSegmentAnalysis` renders every rank's ray segments for the frames of "
            "sections 1 and 3 (same mapper, bounds, sample lattice and screen rectangle as "
            "`vtkAPCCompositePass`) and counts what exact sort-last compositing moves: **direct "
            "send** to the strip owners (what the `Exact (segments)` mode does) and **binary "
            "swap** (computed, not run; rank i and i xor 2^r swap halves of their region each "
            "round; contiguous runs on the sample lattice are merged, which is exact; "
            "'unmerged' is the same exchange without merging). Counts are per pixel with at "
            "least one segment, as in the paper's table. Bytes: 24 B per segment (the pass's "
            "wire format); APC's payload is the pass's: every rank sends (moments + 1) + 4 "
            "doubles per pixel of the data's screen rectangle (the wire before the compact one; "
            "section 5 models both), the display rank also 4 B of "
            "depth, whatever the number of segments.\n")
        header = ["case", "ranks", "camera", "segments / non-empty px", "max", "direct send",
                  "binary swap", "binary swap unmerged", "APC B / non-empty px",
                  "direct send B / px", "binary swap B / px"]
        body = []
        groups = {}
        for r in rows:
            groups.setdefault((r["case"], int(r["ranks"])), []).append(r)
        for (case, n), rs in groups.items():
            def per(key, rs=rs):
                return median([num(r[key]) / max(num(r["nonempty_pixels"]), 1) for r in rs])
            bs = per("binary_swap_segments")
            body.append([case, n, "median of %d" % len(rs) if len(rs) > 1 else rs[0]["camera"],
                         fmt(per("segments")), max(int(r["max_segments_per_pixel"]) for r in rs),
                         fmt(per("direct_send_segments")), fmt(bs) if bs >= 0 else "– (N not 2^k)",
                         fmt(per("binary_swap_unmerged_segments")) if bs >= 0 else "–",
                         fmt(per("apc_bytes")), fmt(per("direct_send_bytes")),
                         fmt(per("binary_swap_bytes")) if bs >= 0 else "–"])
        self.add(table(header, body))

        # Cross-check against what the MPI runs measured for the same frames.
        checks = []
        scaling = read_csv(os.path.join(self.results, "scaling.csv"))
        for r in scaling:
            if r["mode"] != "SEGMENTS" or int(r["ranks"]) < 2:
                continue
            match = [a for a in rows if a["case"] == "gearteeth" and a["ranks"] == r["ranks"] and
                     a["camera"] == r["camera"] and a["width"] == r["size"]]
            if match:
                checks.append(abs(num(match[0]["avg_segments_per_pixel"]) -
                                  num(r["avg_segments_per_pixel"])) < 1e-3 and
                              match[0]["max_segments_per_pixel"] == r["max_segments_per_pixel"])
        for r in self.realdata_rows():
            if r["case"] != "segments" or int(r["ranks"]) < 2:
                continue
            match = [a for a in rows if a["case"] == "wind-" + r["distance"] and
                     a["ranks"] == r["ranks"]]
            if match and match[0]["width"] == r["image_width"]:
                checks.append(abs(num(match[0]["avg_segments_per_pixel"]) -
                                  num(r["avg_segments_per_pixel"])) < 1e-3 and
                              match[0]["max_segments_per_pixel"] == r["max_segments_per_pixel"])
        if checks:
            self.add("Cross-check: in %d of %d frames that were also run under MPI, the "
                     "average and maximum segments per non-empty pixel measured by the "
                     "distributed `Exact (segments)` compositing equal this analysis's.\n"
                     % (sum(checks), len(checks)))

        self._transfer_heatmaps(rows)

    def _transfer_heatmaps(self, rows):
        heatmaps = [r for r in rows if r["heatmap"]]
        chosen = []
        for case in dict.fromkeys(r["case"] for r in heatmaps):
            rs = [r for r in heatmaps if r["case"] == case]
            chosen.append(max(rs, key=lambda r: int(r["ranks"])))
        chosen = [r for r in chosen if r["case"] in ("gearteeth", "wind-1")] or chosen
        if chosen:
            fig, axes = plt.subplots(1, len(chosen), figsize=(6 * len(chosen), 5), squeeze=False)
            for ax, r in zip(axes[0], chosen):
                counts = read_pgm(os.path.join(self.results, r["heatmap"])).astype(float)
                counts[counts == 0] = np.nan
                im = ax.imshow(counts, cmap="viridis", interpolation="nearest")
                ax.set_title("%s, %s ranks: segments per pixel\n(mean %s over non-empty pixels, "
                             "max %s)" % (r["case"], r["ranks"], fmt(num(r["avg_segments_per_pixel"])),
                                          r["max_segments_per_pixel"]))
                ax.axis("off")
                fig.colorbar(im, ax=ax, fraction=0.046)
            self.figure(fig, "segment_heatmaps.png",
                        "Per-pixel segment counts over all ranks (empty pixels white): the "
                        "paper's heatmap. APC sends the same bytes for every pixel of the "
                        "rectangle, whatever these counts.")

