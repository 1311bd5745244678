"""Runs apcCatalystMiniApp under mpirun and checks what it did.

  TestCatalystMiniApp.py --ranks N --out DIR [--reference DIR] [--expect-error TEXT] -- APP ARGS

Without --expect-error: the run must end with "apcCatalystMiniApp: done" and exit 0, and write
one PNG per processed step (steps 0, every, 2 every, ..., steps), each showing the tracer (a
reddish volume over the grey buildings); with --reference, each PNG must equal the reference
run's PNG of the same step to 1/255 per channel.
--count TEXT N: TEXT must appear exactly N times in the output; --any-picture: the PNGs need
not show the tracer (only exist).
With --expect-error: the run must stop by itself (no timeout) with a non-zero exit code, print
TEXT and "apcCatalystMiniApp: stopped", and no rank may have crashed.
Prints APC-TEST-PASSED or APC-TEST-FAILED.
"""
import argparse
import glob
import os
import shutil
import subprocess
import sys

import numpy as np
from PIL import Image


def fail(message):
    print("APC-TEST-FAILED: " + message)
    sys.exit(1)


def run(args, app):
    if os.path.isdir(args.out):
        shutil.rmtree(args.out)
    os.makedirs(args.out)
    command = [args.mpiexec, "-np", str(args.ranks), "--oversubscribe"] + app + [
        "--output", args.out]
    print("running: " + " ".join(command), flush=True)
    try:
        result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                timeout=args.timeout, text=True)
    except subprocess.TimeoutExpired as timeout:
        print(timeout.output or "")
        fail("no end after %d s: a rank hangs" % args.timeout)
    print(result.stdout)
    return result


def image(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.int16)


def check_images(args):
    pngs = sorted(glob.glob(os.path.join(args.out, "tracer_*.png")))
    if not pngs:
        fail("no image in " + args.out)
    for png in pngs:
        picture = image(png)
        # The tracer (inferno: red and yellow dominate) and the buildings (grey) must show.
        warm = np.count_nonzero((picture[..., 0] > 120) & (picture[..., 0] > picture[..., 2] + 40))
        grey = np.count_nonzero((abs(picture[..., 0] - picture[..., 2]) < 12) & (picture[..., 0] > 150))
        print("%s: %d tracer pixels, %d building pixels" % (os.path.basename(png), warm, grey))
        if not args.any_picture and (warm < 200 or grey < 200):
            fail("%s does not show the tracer over the buildings" % png)
        if args.reference:
            ref = os.path.join(args.reference, os.path.basename(png))
            if not os.path.isfile(ref):
                fail("the reference run has no " + os.path.basename(png))
            diff = abs(picture - image(ref))
            print("  vs the reference: max %d/255, %d pixels differ" % (diff.max(),
                                                                      np.count_nonzero(diff)))
            if diff.max() > 1:
                fail("%s differs from the reference by %d/255" % (png, diff.max()))
    if args.reference:
        refs = glob.glob(os.path.join(args.reference, "tracer_*.png"))
        if len(refs) != len(pngs):
            fail("%d images, the reference run wrote %d" % (len(pngs), len(refs)))
    if args.expect_images and len(pngs) != args.expect_images:
        fail("%d images, expected %d" % (len(pngs), args.expect_images))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--mpiexec", default="mpiexec")
    parser.add_argument("--ranks", type=int, required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--reference")
    parser.add_argument("--expect-error")
    parser.add_argument("--expect-images", type=int, default=0)
    parser.add_argument("--timeout", type=int, default=240)
    parser.add_argument("--count", nargs=2, action="append", default=[])
    parser.add_argument("--any-picture", action="store_true")
    parser.add_argument("app", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    app = args.app[1:] if args.app and args.app[0] == "--" else args.app
    result = run(args, app)
    crashed = any(s in result.stdout for s in ("Segmentation fault", "signal 11", "core dumped",
                                                "exited on signal"))
    if crashed:
        fail("a rank crashed")
    for text, times in args.count:
        found = result.stdout.count(text)
        print("'%s': %d times" % (text, found))
        if found != int(times):
            fail("'%s' appears %d times, expected %s" % (text, found, times))
    if args.expect_error:
        if result.returncode == 0:
            fail("exit code 0, expected a failure")
        if args.expect_error not in result.stdout:
            fail("no message '%s'" % args.expect_error)
        if "apcCatalystMiniApp: stopped" not in result.stdout:
            fail("the mini-app did not stop cleanly")
    else:
        if result.returncode != 0 or "apcCatalystMiniApp: done" not in result.stdout:
            fail("exit code %d" % result.returncode)
        check_images(args)
    print("APC-TEST-PASSED")


main()
