"""Section 4.2 of the evaluation report: the default sample distance (quality/spacing.csv,
from apcQualitySweep --spacing), copied to docs/evaluation/spacing.csv.

    /usr/bin/python3 report_spacing.py RESULTS DOCS   (prints the section alone)
"""

import os
import shutil
import sys

from report_common import fmt, read_csv, table
from scaling_model import num

# The rule the default must keep on every bundled data set (Data/: wind, flange).
RULE_PSNR, RULE_SSIM = 40.0, 0.99
BUNDLED = ("wind", "wind-close", "flange")
SHOWN = (("mboit-diag256", "old default: diagonal / 256"),
         ("mboit-diag192", "earlier floor: diagonal / 192"),
         ("mboit-diag128", "diagonal / 128 (the floor)"),
         ("mboit-diag96", "diagonal / 96"),
         ("mboit-default", "**new default**"),
         ("mboit-cell0.75", "0.75 mean cell size"),
         ("mboit-cell1", "1 mean cell size"),
         ("mboit-cell1-jitter", "1 mean cell size, jitter"),
         ("mboit-cell2-jitter", "2 mean cell sizes, jitter"),
         ("mboit-default-weights", "default spacing, Sample End Weights"),
         ("mboit-default-boundary", "default spacing, end weights at the boundary only"),
         ("mboit-cell1.5-weights", "1.5 mean cell sizes, end weights"),
         ("mboit-cell2-weights", "2 mean cell sizes, end weights"),
         ("exact-diag256", "EXACT at diagonal / 256"),
         ("exact-cell1", "EXACT at 1 mean cell size"),
         ("projected-tetra", "projected tetra (ParaView's Volume)"))


class SpacingSection:
    def spacing(self):
        path = os.path.join(self.results, "quality", "spacing.csv")
        kept = os.path.join(self.figures, "spacing.csv")
        rows = read_csv(path)
        if rows:
            shutil.copyfile(path, kept)
            for r in rows:
                if r["scene"] in ("wind", "flange") and r["case"] in (
                        "reference", "mboit-default", "mboit-default-weights", "mboit-diag256",
                        "projected-tetra"):
                    png = "spacing_%s_%s.png" % (r["scene"], r["case"])
                    shutil.copyfile(os.path.join(self.results, "quality", png),
                                    os.path.join(self.figures, png))
        else:
            rows = read_csv(kept)
        if not rows:
            self.add("### 4.2 The default sample distance\n\nNo results "
                     "(quality/spacing.csv missing).\n")
            return
        get = {(r["scene"], r["case"]): r for r in rows}
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        self.add("### 4.2 The default sample distance\n")
        self.add(
            "`apcQualitySweep --spacing`: each scene in ParaView's default setup (the point "
            "array's range, the cool-to-warm map, a linear opacity ramp 0 → 1, the opacity unit "
            "distance of ParaView's approximate cell length, diagonal / cells^⅓), against "
            "`vtkAPCVolumeMapper`'s EXACT mode at a quarter of the finest spacing compared "
            "(≥ 1024 samples along the bounding-box diagonal). APC rows are MBOIT at the "
            "mapper's defaults (β, moments, resolve) unless marked EXACT (the lattice's own "
            "error, without the moments'); the *mean cell size* is the cube root of the "
            "cells' own volume per cell, rounded down to 5 significant bits "
            "(`apcDefaultSpacing.h`); *diagonal / n*: n samples along the bounding-box diagonal. CPU = seconds of the "
            "process (all threads) for one frame after the mesh was converted; projected tetra "
            "= VTK's `vtkProjectedTetrahedraMapper` on VTK's tetrahedralisation (8-bit "
            "blending on the GL side), its second frame. The rule for the default: PSNR ≥ %g dB "
            "and SSIM ≥ %g on every bundled data set (Data/: wind, seen from two distances, "
            "and flange). CSV: [evaluation/spacing.csv](evaluation/spacing.csv).\n"
            % (RULE_PSNR, RULE_SSIM))
        body = []
        for s in scenes:
            old = get.get((s, "mboit-diag256"))
            for case, label in SHOWN:
                r = get.get((s, case))
                if not r:
                    continue
                spacing = num(r["spacing"])
                cpu = num(r["cpu_s"])
                body.append([s, label, fmt(spacing) if spacing else "–",
                             fmt(num(r["samples_per_diagonal"])) if spacing else "–",
                             "%.1f" % num(r["psnr"]), "%.4f" % num(r["ssim"]), fmt(cpu),
                             fmt(cpu / num(old["cpu_s"])) if old else "–"])
        self.add(table(["scene", "case", "spacing", "samples / diagonal", "PSNR dB", "SSIM",
                        "CPU s", "CPU / old default"], body))
        self._spacing_findings(scenes, get)

    def _spacing_findings(self, scenes, get):
        lines = []
        for s in scenes:
            r = get.get((s, "mboit-default"))
            if not r:
                continue
            ok = num(r["psnr"]) >= RULE_PSNR and num(r["ssim"]) >= RULE_SSIM
            tag = ("keeps the rule" if ok else "**misses the rule**") if s in BUNDLED else \
                "(synthetic, not a bundled data set)"
            lines.append("- %s: the default %s (%.1f dB, SSIM %.4f)." % (s, tag, num(r["psnr"]),
                                                                       num(r["ssim"])))
        self.add("\n".join(lines) + "\n")
        self.add(
            "Why the rule is one mean cell size (from the cells' volume) but at least 128 "
            "samples along the diagonal: one sample per mean cell size keeps the rule on the "
            "wind data (331,699 cells; 139 samples along its diagonal) but not on the flange "
            "(5,712 cells, thin walls, its cells fill a quarter of its box: 39.6 dB at 0.75 of "
            "it), which keeps it down to about 96 samples along its diagonal; 128 leaves a "
            "margin. On the wind 1.5 mean cell sizes give 37.7 dB, and the earlier floor "
            "(192 along the diagonal) took 1.38x the samples of the new default for 2.2 dB more. "
            "Lattice Jitter trades bands for noise and does not raise PSNR or SSIM here: it "
            "stays off by default. Grazing silhouettes: the wind's edges show the lattice as a "
            "fine staircase at the new default, and a slightly finer one at 192 along the "
            "diagonal; with Sample End Weights (each cell's end samples weighted by the exact "
            "length of the ray inside it, docs/sampler.md) the staircase is gone and the "
            "silhouettes match the reference's, and PSNR at the same spacing rises on every "
            "bundled data set (the *end weights* rows; wind 41.3 → 51.5 dB at the default, "
            "35.2 → 45.4 dB at 2 mean cell sizes). It stays off by default: at the default spacing "
            "the frame costs 1.6× the CPU with it on the wind at 1024² (40 % more samples: a "
            "cell with no lattice point on a ray samples its middle), a coarser spacing does "
            "not shed those samples (1.5 and 2 mean cell sizes: 1.60× and 1.57× the plain "
            "default) and shows notches along the wind's bottom-right edge; Lattice Jitter turns the staircase into "
            "a noisy edge (docs/sampler.md). On the synthetic puzzle scenes with ParaView's ramp, MBOIT's "
            "own error (the moments) dominates at every spacing (compare the EXACT rows).\n")
        pictures = [s for s in ("wind", "flange") if (s, "reference") in get and os.path.exists(
            os.path.join(self.figures, "spacing_%s_reference.png" % s))]
        if pictures:
            cases = ["reference", "mboit-default", "mboit-diag256", "projected-tetra"]
            heads = ["scene", "exact reference", "new default", "old default", "projected tetra"]
            if all(os.path.exists(os.path.join(
                    self.figures, "spacing_%s_mboit-default-weights.png" % s)) for s in pictures):
                cases.insert(2, "mboit-default-weights")
                heads.insert(3, "new default, end weights")
            body = [[s] + ["![](evaluation/spacing_%s_%s.png)" % (s, c) for c in cases]
                    for s in pictures]
            self.add(table(heads, body))


if __name__ == "__main__":
    class _Print(SpacingSection):
        def __init__(self, results, docs):
            self.results, self.figures, self.parts = results, os.path.join(docs, "evaluation"), []

        def add(self, text):
            self.parts.append(text)

    report = _Print(os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]))
    report.spacing()
    print("\n".join(report.parts))
