"""Section 3 of the evaluation report: the real data in ParaView (realdata/)."""

import glob
import os

import numpy as np

from report_common import fmt, mb, plt, read_csv, read_vti_rgba, table
from scaling_model import num


class RealDataSection:
    # ---------------------------------------------------------------- real data
    def realdata_rows(self):
        rows = []
        for part in sorted(glob.glob(os.path.join(self.results, "realdata",
                                                  "paraview_vs_apc_np*.csv"))):
            rows += read_csv(part)
        for r in rows:
            path = os.path.join(self.results, "realdata", r["image"])
            r["image_width"] = ""
            if os.path.exists(path):
                from PIL import Image
                r["image_width"] = str(Image.open(path).size[0])
        return rows

    def realdata(self):
        rows = self.realdata_rows()
        if not rows:
            self.add("## 3. Real data\n\nNo results.\n")
            return
        self.add("## 3. Real data: OpenFOAM windAroundBuildings in ParaView\n")
        self.add(
            "`paraview_vs_apc.py` in pvbatch under `mpirun`: the 331,699-cell mesh in 8 Scotch "
            "pieces (read by ParaView's own reader: pieces shared out to the ranks), field "
            "U_mag, %s pixels, camera at 0.6 / 1 / 1.6 × the demo's focal distance. Cases: "
            "**APC** (APC Volume, default sample distance = diagonal/256), **segments** (APC "
            "Volume in `Exact (segments)` mode, the exact sort-last baseline), **pt** "
            "(ParaView's own Volume representation with its default Projected tetra mapper: it "
            "tetrahedralises and redistributes the data into a kd-tree in its first frame). "
            "Every case and distance has a fresh view; first frame = the view's first Render "
            "(the reader already updated); later = median of the following frames. Wall clock "
            "on the display rank; 4 ranks are oversubscribed on 2 cores.\n"
            % (rows[0]["image_width"] + "²" if rows[0]["image_width"] else "?"))
        header = ["ranks", "distance", "case", "first frame s", "later frame s",
                  "render s (pass1+pass2 / segments)", "compositing s", "display rank MB",
                  "segments / px (max)", "first / later vs pt"]
        body = []
        by = {(r["ranks"], r["distance"], r["case"]): r for r in rows}
        ratios = {}
        for key in sorted(by, key=lambda k: (int(k[0]), float(k[1]), k[2])):
            r = by[key]
            ranks, distance, case = key
            if r["representation"] == "APC Volume":
                if case == "segments":
                    render = num(r["segments_s"])
                    comp = num(r["exchange_s"]) + num(r["gather_s"])
                    seg = "%s (%s)" % (fmt(num(r["avg_segments_per_pixel"])),
                                       r["max_segments_per_pixel"])
                else:
                    render = num(r["pass1_s"]) + num(r["pass2_s"])
                    comp = num(r["allreduce_s"]) + num(r["reduce_s"])
                    seg = ""
                pt = by.get((ranks, distance, "pt"))
                vs = ""
                if pt:
                    f = num(r["first_frame_s"]) / num(pt["first_frame_s"])
                    later = num(r["frame_s"]) / num(pt["frame_s"])
                    ratios[(ranks, distance, case)] = (f, later)
                    vs = "%.2f / %.2f" % (f, later)
                body.append([ranks, distance, case, r["first_frame_s"], r["frame_s"], fmt(render),
                             fmt(comp), mb(num(r["bytes_display_rank"])), seg, vs])
            else:
                body.append([ranks, distance, case, r["first_frame_s"], r["frame_s"], "", "",
                             "", "", ""])
        self.add(table(header, body))
        notes = [r["note"] for r in rows if r["case"] == "pt"]
        if notes:
            self.add("ParaView's side, from the probe in `paraview_vs_apc.py` (one example): "
                     "%s.\n" % notes[-1])
        for (ranks, distance, case), (f, later) in sorted(ratios.items()):
            if case == "apc-default" and distance == "1":
                self.headline.append(
                    "Real data, %s ranks, middle distance: APC's first frame / ParaView Volume's "
                    "(projected tetra, which redistributes first) = **%.2f**; later frames "
                    "%.2f." % (ranks, f, later))

        self._realdata_identity(by)

        self._realdata_figures(rows, by)

    def _realdata_identity(self, by):
        # N ranks against 1 rank: float images.
        ident = []
        for (ranks, distance, case), r in sorted(by.items()):
            if ranks == "1" or not r.get("float_image"):
                continue
            one = by.get(("1", distance, case))
            if not one or not one.get("float_image"):
                continue
            a = read_vti_rgba(os.path.join(self.results, "realdata", r["float_image"]))
            b = read_vti_rgba(os.path.join(self.results, "realdata", one["float_image"]))
            if a is None or b is None or a.shape != b.shape:
                continue
            ident.append([case, ranks, distance, fmt(float(np.abs(a - b).max()), 2)])
        if ident:
            self.add("\nThe display rank's float RGBA on N ranks against 1 rank (max |Δ| over "
                     "all pixels). APC must be identical to one-process MBOIT (a one-rank "
                     "frame whose pass-1 sample cache exceeds its budget re-marches pass 2 "
                     "instead of replaying it, which differs by float rounding). The segments "
                     "must match to float rounding (<= 1e-5; samples that overlapping cells take "
                     "at one lattice point blend in a fixed order, docs/architecture.md); the "
                     "differences are listed as measured by the run that wrote this report:\n\n")
            self.add(table(["case", "ranks", "distance", "max |Δ| vs 1 rank"], ident))


    def _realdata_figures(self, rows, by):
        # Frame-time plot.
        cases = [c for c in ("apc-default", "segments", "pt") if any(r["case"] == c for r in rows)]
        multi = sorted({k[0] for k in by if k[0] != "1"}, key=int)
        distances = sorted({k[1] for k in by}, key=float)
        if multi:
            fig, axes = plt.subplots(1, len(multi), figsize=(7 * len(multi), 4), squeeze=False)
            for ax, ranks in zip(axes[0], multi):
                width = 0.8 / len(cases)
                for c, case in enumerate(cases):
                    firsts = [num(by[(ranks, d, case)]["first_frame_s"]) if (ranks, d, case) in by
                              else 0 for d in distances]
                    laters = [num(by[(ranks, d, case)]["frame_s"]) if (ranks, d, case) in by
                              else 0 for d in distances]
                    xs = [i + (c - (len(cases) - 1) / 2) * width for i in range(len(distances))]
                    ax.bar(xs, firsts, width * 0.9, color="C%d" % c, alpha=0.35)
                    ax.bar(xs, laters, width * 0.9, color="C%d" % c, label=case)
                ax.set_xticks(range(len(distances)))
                ax.set_xticklabels(["distance %s" % d for d in distances])
                ax.set_ylabel("seconds")
                ax.set_title("%s ranks: later frames (solid), first frame (pale)" % ranks)
                ax.legend()
            self.figure(fig, "realdata_times.png", "Real data: frame times per camera distance.")

        # Pictures at the middle distance, highest rank count.
        if multi:
            ranks = multi[-1]
            d = "1" if "1" in distances else distances[len(distances) // 2]
            cells = []
            for case in cases:
                r = by.get((ranks, d, case))
                if r and os.path.exists(os.path.join(self.results, "realdata", r["image"])):
                    link = self.copy_image(os.path.join(self.results, "realdata", r["image"]),
                                           "realdata_%s.png" % case)
                    cells.append("![%s](%s)" % (case, link))
            if cells:
                self.add("\nThe pictures (%s ranks, distance %s): %s.\n\n" % (
                    ranks, d, ", ".join(cases)))
                self.add(table(cases[:len(cells)], [cells]))

