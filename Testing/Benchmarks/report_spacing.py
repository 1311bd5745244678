"""Section 4.2 of the evaluation report: the default sample distance (quality/spacing.csv,
from apcQualitySweep --spacing), copied to docs/evaluation/spacing.csv.

    /usr/bin/python3 report_spacing.py RESULTS DOCS   (prints the section alone)
"""

import os
import shutil
import sys

import crop_pictures
from report_common import fmt, read_csv, table
from scaling_model import num

# The rule the default must keep on every bundled data set (Data/: wind, flange).
RULE_PSNR, RULE_SSIM = 40.0, 0.99
BUNDLED = ("wind", "wind-close", "flange")
SHOWN = (("mboit-diag256", "first default: diagonal / 256, plain lattice"),
         ("mboit-default-off", "Sample End Weights Off, its default (1 mean cell size, ≥ 128)"),
         ("exact-default", "EXACT, its default (1 mean cell size, ≥ 128)"),
         ("mboit-cell1.25", "Sample End Weights Off at 1.25 mean cell sizes"),
         ("exact-cell1.25", "EXACT at 1.25 mean cell sizes"),
         ("mboit-previous-boundary", "previous default (1 mean cell size, ≥ 128), Boundary"),
         ("mboit-default", "**new default** (Boundary, 1.25 mean cell sizes, ≥ 96)"),
         ("mboit-cell1.25-boundary", "Boundary, 1.25 mean cell sizes (no floor)"),
         ("mboit-cell1.25-boundary-jitter", "Boundary, 1.25 mean cell sizes, jitter"),
         ("mboit-cell1.5-boundary", "Boundary, 1.5 mean cell sizes"),
         ("mboit-cell1.5-boundary-jitter", "Boundary, 1.5 mean cell sizes, jitter"),
         ("mboit-cell2-boundary", "Boundary, 2 mean cell sizes"),
         ("mboit-cell2-boundary-jitter", "Boundary, 2 mean cell sizes, jitter"),
         ("mboit-cell3-boundary", "Boundary, 3 mean cell sizes"),
         ("mboit-diag128-boundary", "Boundary, diagonal / 128"),
         ("mboit-diag96-boundary", "Boundary, diagonal / 96"),
         ("mboit-diag64-boundary", "Boundary, diagonal / 64"),
         ("mboit-diag64-boundary-jitter", "Boundary, diagonal / 64, jitter"),
         ("mboit-default-weights", "Sample End Weights All, its default (as Boundary's)"),
         ("projected-tetra", "projected tetra (ParaView's Volume)"))
# Whole pictures, and crops (crop_pictures.py) where the lattice shows: (scene, x0, y0, w, h,
# scale, cases). The wind's bottom-right edge, where the rays graze the ground layer, and the
# flange's upper silhouette.
PICTURES = ("reference", "mboit-default", "mboit-default-off", "projected-tetra")
CROPS = (("wind", 352, 384, 128, 96, 2, ("reference", "mboit-default-off", "mboit-default",
                                         "mboit-cell1.5-boundary", "mboit-cell2-boundary")),
         ("flange", 200, 110, 128, 128, 2, ("reference", "mboit-default-off", "mboit-default",
                                            "mboit-diag64-boundary")))
LABELS = {"reference": "exact reference", "mboit-default": "new default (Boundary)",
          "mboit-default-off": "Off, its default (1, ≥ 128)",
          "mboit-cell1.5-boundary": "Boundary, 1.5", "mboit-cell2-boundary": "Boundary, 2",
          "mboit-diag64-boundary": "Boundary, diagonal / 64",
          "projected-tetra": "projected tetra"}


class SpacingSection:
    def spacing(self):
        path = os.path.join(self.results, "quality", "spacing.csv")
        kept = os.path.join(self.figures, "spacing.csv")
        rows = read_csv(path)
        if rows:
            shutil.copyfile(path, kept)
            for r in rows:
                if r["scene"] in ("wind", "flange") and r["case"] in PICTURES:
                    png = "spacing_%s_%s.png" % (r["scene"], r["case"])
                    shutil.copyfile(os.path.join(self.results, "quality", png),
                                    os.path.join(self.figures, png))
            for scene, x0, y0, w, h, scale, cases in CROPS:
                pngs = [os.path.join(self.results, "quality", "spacing_%s_%s.png" % (scene, c))
                        for c in cases]
                if all(os.path.exists(p) for p in pngs):
                    crop_pictures.main(["", os.path.join(self.figures, "spacing_%s_crops.png" % scene),
                                        str(x0), str(y0), str(w), str(h), str(scale)] + pngs)
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
            "(`apcDefaultSpacing.h`); *diagonal / n*: n samples along the bounding-box diagonal; "
            "*Boundary*: Sample End Weights = Boundary (the default), otherwise the plain "
            "lattice unless marked. CPU = seconds of the "
            "process (all threads) for one frame after the mesh was converted (one frame each, "
            "on a shared machine: a rough guide; the sampler's own measurement is in "
            "docs/performance.md, *The default sample distance with Boundary*); projected tetra "
            "= VTK's `vtkProjectedTetrahedraMapper` on VTK's tetrahedralisation (8-bit "
            "blending on the GL side), its second frame. The rule for the default: PSNR ≥ %g dB "
            "and SSIM ≥ %g on every bundled data set (Data/: wind, seen from two distances, "
            "and flange). CSV: [evaluation/spacing.csv](evaluation/spacing.csv).\n"
            % (RULE_PSNR, RULE_SSIM))
        body = []
        for s in scenes:
            old = get.get((s, "mboit-previous-boundary"))
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
                        "CPU s", "CPU / previous default"], body))
        self._spacing_findings(scenes, get)

    def _spacing_findings(self, scenes, get):
        lines = []
        for s in scenes:
            for case, what in (("mboit-default", "the default"),
                               ("mboit-default-off", "Sample End Weights Off's default"),
                               ("exact-default", "EXACT's default")):
                r = get.get((s, case))
                if not r:
                    continue
                ok = num(r["psnr"]) >= RULE_PSNR and num(r["ssim"]) >= RULE_SSIM
                tag = ("keeps the rule" if ok else "**misses the rule**") if s in BUNDLED else \
                    "(synthetic, not a bundled data set)"
                lines.append("- %s: %s %s (%.1f dB, SSIM %.4f)." % (s, what, tag, num(r["psnr"]),
                                                                   num(r["ssim"])))
        self.add("\n".join(lines) + "\n")
        self.add(
            "Why 1.25 mean cell sizes (from the cells' volume), at least 96 samples along the "
            "diagonal, with Sample End Weights = Boundary: the rule was chosen with a margin "
            "(PSNR ≥ 43 dB and SSIM ≥ 0.995 on every bundled data set) and no visible "
            "staircase, ripple or speckle in the pictures (the crops below). The plain "
            "lattice's error was its staircase where rays graze the mesh's boundary; Boundary "
            "weights those ends by the exact length of the ray inside the cell "
            "(docs/sampler.md), so the same spacing scores about 10 dB more on the wind "
            "overview, and a coarser one keeps the rule. Coarser still scores well but shows "
            "itself: at 1.5 mean cell sizes a faint ripple and at 2 notches along the wind's "
            "bottom-right edge (where the rays graze the ground layer), and at 64 samples along "
            "its diagonal speckles on the flange's upper silhouette, although its scores there "
            "are as high as at 96. Lattice Jitter does not raise the scores with Boundary "
            "either (the *jitter* rows): it stays off. The plain lattice (Sample End Weights "
            "Off, the exact modes, the Hybrid resolve) keeps its own default, one mean cell "
            "size and at least 128 samples: at 1.25 mean cell sizes its staircase costs the "
            "wind overview the rule (the *Off at 1.25* and *EXACT at 1.25* rows), so every "
            "mode's default keeps it. The flange takes the floor (96 samples along its "
            "diagonal; 128 on the plain lattice), the wind its mean cell size. On the "
            "synthetic puzzle scenes with ParaView's ramp, MBOIT's own error (the moments) "
            "dominates at every spacing (compare the EXACT rows).\n")
        pictures = [s for s in ("wind", "flange") if (s, "reference") in get and os.path.exists(
            os.path.join(self.figures, "spacing_%s_reference.png" % s))]
        if pictures:
            body = [[s] + ["![](evaluation/spacing_%s_%s.png)" % (s, c) for c in PICTURES]
                    for s in pictures]
            self.add(table(["scene"] + [LABELS[c] for c in PICTURES], body))
        for scene, x0, y0, w, h, scale, cases in CROPS:
            if os.path.exists(os.path.join(self.figures, "spacing_%s_crops.png" % scene)):
                self.add("%s, pixels (%d, %d) to (%d, %d) from the top left, %d× enlarged, left to "
                         "right: %s.\n\n![](evaluation/spacing_%s_crops.png)\n"
                         % (scene, x0, y0, x0 + w, y0 + h, scale,
                            "; ".join(LABELS[c] for c in cases), scene))


if __name__ == "__main__":
    class _Print(SpacingSection):
        def __init__(self, results, docs):
            self.results, self.figures, self.parts = results, os.path.join(docs, "evaluation"), []

        def add(self, text):
            self.parts.append(text)

    report = _Print(os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]))
    report.spacing()
    print("\n".join(report.parts))
