#!/usr/bin/python3
"""Holds APC's C++ image metrics (Rendering/Core/apcImageMetrics) against scikit-image.

Usage: /usr/bin/python3 TestImageMetricsSkimage.py <path to apcImageMetricsTool>

scikit-image is an independent implementation of the same definitions; SSIM is compared with
the settings that reproduce Wang et al. 2004 (Gaussian window, sigma 1.5, population
covariance), which is what apc::StructuralSimilarity promises. The images cross over as
float32 (the precision of APC's framebuffers), but scikit-image is handed them widened to
float64: given float32 arrays it would do its arithmetic in float32, and the test would then
measure scikit-image's rounding rather than disagreement between the two implementations.
The full SSIM maps are compared too: the mean leaves out the border strip, so only the map
shows whether the borders are filtered as scikit-image does (scipy's mode 'reflect').

Prints every number, exits 1 and prints APC-TEST-FAILED on a mismatch, prints
APC-TEST-PASSED on success.
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import warnings

import numpy as np
from skimage.metrics import (mean_squared_error, peak_signal_noise_ratio,
                             structural_similarity)

SSIM_TOL = 1e-6  # for the mean and for every pixel of the map
MSE_REL_TOL = 1e-9
PSNR_TOL = 1e-6  # dB


def grid(h, w):
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    return x / max(w - 1, 1), y / max(h - 1, 1)


def smooth(h, w, c, phase=0.0):
    u, v = grid(h, w)
    chans = [0.5 + 0.25 * (u - v) + 0.2 * np.sin(7 * u + 5 * v + k + phase) for k in range(c)]
    return np.stack(chans, axis=-1)


def box_blur(img, passes=2):
    out = img
    for _ in range(passes):
        p = np.pad(out, ((1, 1), (1, 1), (0, 0)), mode="edge")
        out = sum(p[dy:dy + out.shape[0], dx:dx + out.shape[1]]
                  for dy in range(3) for dx in range(3)) / 9.0
    return out


def blob_render(h, w, c):
    """Mostly-empty frame with a soft blob, like a volume rendering over black."""
    u, v = grid(h, w)
    r2 = (u - 0.45) ** 2 + (v - 0.55) ** 2
    base = np.exp(-r2 / 0.03)
    chans = [base * (0.6 + 0.3 * k / max(c - 1, 1)) for k in range(c)]
    return np.stack(chans, axis=-1)


def cases():
    rng = np.random.default_rng(20250117)
    clip = lambda a: np.clip(a, 0.0, 1.0)
    out = []

    a = smooth(48, 64, 3)
    out.append(("gradient+noise", a, clip(a + rng.normal(0, 0.05, a.shape)), 1.0))

    out.append(("noise vs noise", rng.random((32, 32, 1)), rng.random((32, 32, 1)), 1.0))

    a = clip(smooth(70, 50, 4) + rng.normal(0, 0.1, (70, 50, 4)))
    out.append(("blurred copy", a, box_blur(a), 1.0))

    a = clip(smooth(40, 40, 3) + rng.normal(0, 0.02, (40, 40, 3)))
    out.append(("shifted copy", a, np.roll(a, (2, -1), axis=(0, 1)), 1.0))

    a = smooth(21, 33, 3)
    out.append(("identical", a, a.copy(), 1.0))

    a = smooth(30, 45, 1)
    out.append(("constant offset", a, a + 0.05, 1.0))

    out.append(("flat offset", np.full((12, 16, 1), 0.5), np.full((12, 16, 1), 0.625), 1.0))

    a = rng.random((11, 11, 1))
    out.append(("11x11 minimum, C=1", a, clip(a + rng.normal(0, 0.1, a.shape)), 1.0))
    a = smooth(11, 11, 3)
    out.append(("11x11 minimum, C=3", a, clip(a + rng.normal(0, 0.1, a.shape)), 1.0))

    a = smooth(97, 11, 1)
    out.append(("11 wide, 97 high", a, box_blur(a), 1.0))
    a = smooth(17, 123, 4)
    out.append(("123 wide, 17 high", a, clip(a + rng.normal(0, 0.03, a.shape)), 1.0))

    a = 255.0 * smooth(40, 60, 3)
    out.append(("data range 255", a, np.clip(a + rng.normal(0, 8, a.shape), 0, 255), 255.0))

    a = blob_render(200, 256, 3)
    b = clip(a * (1 + rng.normal(0, 0.01, a.shape)) + rng.normal(0, 0.002, a.shape))
    out.append(("blob render, small error", a, b, 1.0))

    a = blob_render(64, 64, 4)
    out.append(("blob vs empty", a, np.zeros_like(a), 1.0))
    return out


def run_tool(tool, tmp, a32, b32, data_range):
    h, w, c = a32.shape
    pa, pb = os.path.join(tmp, "a.raw"), os.path.join(tmp, "b.raw")
    pm = os.path.join(tmp, "map.raw")
    if os.path.exists(pm):
        os.remove(pm)
    a32.astype("<f4").tofile(pa)
    b32.astype("<f4").tofile(pb)
    res = subprocess.run([tool, pa, pb, str(w), str(h), str(c), repr(data_range), pm],
                         capture_output=True, text=True)
    ssim_map = np.fromfile(pm, dtype="<f8").reshape(h, w, c) if res.returncode == 0 else None
    return res, ssim_map


def reference(a64, b64, data_range):
    with warnings.catch_warnings(), np.errstate(divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        mse = mean_squared_error(a64, b64)
        psnr = peak_signal_noise_ratio(a64, b64, data_range=data_range)
    ssim, ssim_map = structural_similarity(a64, b64, data_range=data_range,
                                           gaussian_weights=True, sigma=1.5,
                                           use_sample_covariance=False, channel_axis=-1,
                                           full=True)
    return float(mse), float(psnr), float(ssim), ssim_map


def main():
    if len(sys.argv) != 2:
        print("usage: TestImageMetricsSkimage.py <apcImageMetricsTool>")
        print("APC-TEST-FAILED")
        return 1
    tool = sys.argv[1]
    failures = []
    worst = {"ssim": 0.0, "map": 0.0, "mse_rel": 0.0, "psnr": 0.0}

    with tempfile.TemporaryDirectory() as tmp:
        for name, a, b, data_range in cases():
            a32, b32 = a.astype(np.float32), b.astype(np.float32)
            h, w, c = a32.shape
            res, got_map = run_tool(tool, tmp, a32, b32, data_range)
            if res.returncode != 0:
                print(f"{name}: tool failed ({res.returncode}): {res.stderr.strip()}")
                failures.append(name)
                continue
            got = json.loads(res.stdout)
            mse, psnr, ssim, ref_map = reference(a32.astype(np.float64), b32.astype(np.float64),
                                        data_range)
            d_ssim = abs(got["ssim"] - ssim)
            d_map = float(np.max(np.abs(got_map - ref_map)))
            d_mse = abs(got["mse"] - mse) / mse if mse != 0 else (0.0 if got["mse"] == 0
                                                                    else math.inf)
            if math.isinf(psnr) or math.isinf(got["psnr"]):
                d_psnr = 0.0 if got["psnr"] == psnr else math.inf
            else:
                d_psnr = abs(got["psnr"] - psnr)
            ok = d_ssim <= SSIM_TOL and d_map <= SSIM_TOL and d_mse <= MSE_REL_TOL and d_psnr <= PSNR_TOL
            worst["ssim"] = max(worst["ssim"], d_ssim)
            worst["map"] = max(worst["map"], d_map)
            worst["mse_rel"] = max(worst["mse_rel"], d_mse)
            worst["psnr"] = max(worst["psnr"], d_psnr)
            print(f"{name} ({w}x{h}x{c}, range {data_range:g}): "
                  f"ssim apc {got['ssim']:.15f} skimage {ssim:.15f} |d| {d_ssim:.3e}, "
                  f"map max |d| {d_map:.3e}; "
                  f"mse apc {got['mse']:.15e} skimage {mse:.15e} rel {d_mse:.3e}; "
                  f"psnr apc {got['psnr']:.12f} skimage {psnr:.12f} |d| {d_psnr:.3e}"
                  f"{'' if ok else '  MISMATCH'}")
            if not ok:
                failures.append(name)

        # Below the 11 x 11 window both implementations must refuse rather than make up a
        # number.
        rng = np.random.default_rng(7)
        for h, w, c in ((7, 7, 1), (10, 40, 3), (40, 10, 4)):
            a = rng.random((h, w, c))
            b = rng.random((h, w, c))
            res, _ = run_tool(tool, tmp, a.astype(np.float32), b.astype(np.float32), 1.0)
            try:
                reference(a, b, 1.0)
                skimage_refuses = False
            except ValueError:
                skimage_refuses = True
            ok = res.returncode != 0 and skimage_refuses
            print(f"too small ({w}x{h}x{c}): tool exit {res.returncode} "
                  f"({res.stderr.strip()}), skimage refuses: {skimage_refuses}"
                  f"{'' if ok else '  MISMATCH'}")
            if not ok:
                failures.append(f"too small {w}x{h}x{c}")

    print(f"max |d ssim| {worst['ssim']:.3e} (tol {SSIM_TOL:g}), "
          f"max |d ssim map| {worst['map']:.3e} (tol {SSIM_TOL:g}), "
          f"max rel |d mse| {worst['mse_rel']:.3e} (tol {MSE_REL_TOL:g}), "
          f"max |d psnr| {worst['psnr']:.3e} dB (tol {PSNR_TOL:g})")
    if failures:
        print("mismatches: " + ", ".join(failures))
        print("APC-TEST-FAILED")
        return 1
    print("APC-TEST-PASSED")
    return 0


if __name__ == "__main__":
    sys.exit(main())
