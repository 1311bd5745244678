"""Writes docs/evaluation.md and its plots from the CSVs of run-evaluation.sh.

    /usr/bin/python3 make_evaluation_report.py --results out/evaluation --docs docs

Everything in the report is computed here from the result files; nothing is typed in by hand.
Inputs (written by run-evaluation.sh):
  quality/quality.csv          apcQualitySweep: scene,beta,moments,resolve,ssim,psnr,mse,...
  quality/*.png                its exact and MBOIT pictures
  scaling.csv                  apcScalingBenchmark rows (one per ranks x mode x camera)
  segment_transfer.csv         apcSegmentAnalysis rows, heatmap_*.pgm
  realdata/paraview_vs_apc_np*.csv, realdata/*.png, realdata/*.vti   paraview_vs_apc.py
  model/*.csv                  scaling_model.py (section 5)
  quality/defaults.csv         apcQualitySweep --defaults: the mapper's defaults, from the build
  quality/spacing.csv, *.png   apcQualitySweep --spacing: the default sample distance (4.2)
Outputs: <docs>/evaluation.md, <docs>/evaluation/*.png and <docs>/evaluation/model/*.csv (the
model's inputs and outputs, kept next to the report).

One file per section: report_scaling.py (1, 2), report_realdata.py (3), report_quality.py (4),
report_spacing.py (4.2), report_model.py (5); report_common.py has what they share.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report_common import ReportBase, read_vti_rgba  # noqa: E402,F401  (TestEvaluationQuick)
from report_model import ModelSection  # noqa: E402
from report_quality import QualitySections  # noqa: E402
from report_realdata import RealDataSection  # noqa: E402
from report_scaling import ScalingSections  # noqa: E402
from report_spacing import SpacingSection  # noqa: E402
from scaling_model import num  # noqa: E402,F401  (TestEvaluationQuick)


class Report(ScalingSections, RealDataSection, QualitySections, SpacingSection, ModelSection,
             ReportBase):
    """The report: one section class per file (report_*.py), ReportBase for the rest."""


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", required=True)
    parser.add_argument("--docs", required=True)
    parser.add_argument("--machine", default="")
    parser.add_argument("--seconds", type=float, default=0)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--model-only", action="store_true")
    args = parser.parse_args()
    report = Report(os.path.abspath(args.results), os.path.abspath(args.docs), args.quick,
                    args.model_only)
    report.scaling()
    report.transfers()
    report.realdata()
    report.quality()
    report.hybrid()
    report.spacing()
    report.model()
    report.write(args.machine, args.seconds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
