#!/usr/bin/python3
"""How Lambertian is a real object's diffuse term, and what does the difference do to the normals?

For every object with ground truth in the real data (../shared/data, or $IPHONG_DATA_DIR), each
observation's luminance (divided by its light's intensity) is compared with the cosine N·L at the
ground-truth normal. Saturated observations, those with N·L < 0.1 (shadow, terminator) and those
within 20° of the mirror direction (N·H, where the sharp highlights are) are left out. A pixel's
ratios y / (N·L) are divided by their median, so the albedo drops out; the report gives the median
of that relative ratio per band of N·L (1.000 everywhere for a Lambertian surface) and the exponent
p of the power law y ∝ (N·L)^p fitted with one intercept per pixel (p = 1: Lambert).

Then the default run's normals (iphong.estimate_normals, the pipeline of `iphong normals`): the
mean signed error of their zenith angle (angle from the view direction) per 15° band of the true
zenith. A diffuse term steeper than the cosine (p > 1) reads as lights far from the normal being
darker than the model predicts, and the fit tilts the normal away from them: the zenith comes out
too large where no highlight constrains it.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/diffuse_falloff.py [--no-normals]
"""
import argparse
import sys

import numpy as np

import iphong
from accuracy import DATA, objects  # every object with ground truth, named alike

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
BANDS = np.round(np.arange(0.1, 1.0, 0.1), 1)


def falloff(d, normal, valid):
    """Relative ratio per N·L band, and the fitted exponent p."""
    lights = np.asarray(d["light_directions"], np.float64)
    intensities = np.asarray(d["light_intensities"], np.float64)
    images = np.asarray(d["images"])
    y = (images[:, valid].astype(np.float64) / intensities[:, None, :]) @ LUMINANCE  # K, P
    saturated = (images[:, valid] >= 0.995).any(axis=2)
    half = lights + np.array([0.0, 0.0, 1.0])
    half /= np.linalg.norm(half, axis=1, keepdims=True)
    n = normal[valid]
    n_dot_l = (n @ lights.T).T  # K, P
    n_dot_h = np.clip((n @ half.T).T, -1, 1)
    use = (n_dot_l > 0.1) & (np.degrees(np.arccos(n_dot_h)) > 20) & ~saturated & (y > 0)
    ratio = np.where(use, y / np.maximum(n_dot_l, 1e-12), np.nan)
    rel = ratio / np.nanmedian(np.where(use.any(axis=0), ratio, 1.0), axis=0, keepdims=True)
    table = []
    for lo in BANDS:
        m = use & (n_dot_l >= lo) & (n_dot_l < lo + 0.1)
        table.append(np.nanmedian(rel[m]) if m.any() else np.nan)
    # y = c_pixel (N·L)^p: log y − mean_pixel = p (log N·L − mean_pixel), least squares.
    counts = use.sum(axis=0)
    keep = counts >= 3
    u = use[:, keep]
    log_y = np.where(u, np.log(np.where(u, y[:, keep], 1.0)), 0.0)
    log_c = np.where(u, np.log(np.where(u, n_dot_l[:, keep], 1.0)), 0.0)
    log_y = np.where(u, log_y - log_y.sum(axis=0) / counts[keep], 0.0)
    log_c = np.where(u, log_c - log_c.sum(axis=0) / counts[keep], 0.0)
    p = (log_y * log_c).sum() / (log_c * log_c).sum()
    return table, p


def zenith_bias(d, normal, valid):
    run = iphong.estimate_normals(d["images"], np.asarray(d["light_directions"]),
                                  d["light_intensities"], d["mask"])
    est = np.asarray(run["normals"], np.float64)
    est /= np.maximum(np.linalg.norm(est, axis=2, keepdims=True), 1e-12)
    true_zenith = np.degrees(np.arccos(np.clip(normal[..., 2], -1, 1)))
    signed = np.degrees(np.arccos(np.clip(est[..., 2], -1, 1))) - true_zenith
    angle = np.degrees(np.arccos(np.clip((est * normal).sum(axis=2), -1, 1)))
    rows = []
    for lo in range(0, 90, 15):
        m = valid & (true_zenith >= lo) & (true_zenith < lo + 15)
        rows.append((signed[m].mean(), angle[m].mean()) if m.any() else (np.nan, np.nan))
    return rows, angle[valid].mean()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--no-normals", action="store_true", help="the falloff table only")
    args = parser.parse_args()
    found = list(objects())
    if not found:
        sys.exit(f"diffuse_falloff.py: no object with Normal_gt.mat under {DATA}")
    print("Observed / Lambert's prediction at the true normal, per band of N·L (1 = Lambertian):")
    print("| object | " + " | ".join(f"{b:.1f}" for b in BANDS) + " | p |")
    print("|---|" + "---|" * (len(BANDS) + 1))
    loaded = []
    for name, folder in found:
        d = iphong.load_dataset(str(folder))
        gt = np.asarray(d["normal_gt"], np.float64)
        length = np.linalg.norm(gt, axis=2, keepdims=True)
        valid = np.asarray(d["mask"]) & (length[..., 0] > 0.5)
        normal = gt / np.maximum(length, 1e-12)
        table, p = falloff(d, normal, valid)
        print(f"| {name} | " + " | ".join(f"{v:.3f}" for v in table) + f" | {p:.3f} |",
              flush=True)
        loaded.append((name, d, normal, valid))
    if args.no_normals:
        return
    print("\nThe default run: mean signed zenith error (mean angular error) per band of the true "
          "zenith, degrees:")
    print("| object | " + " | ".join(f"{lo}–{lo + 15}°" for lo in range(0, 90, 15)) + " | mean |")
    print("|---|" + "---|" * 7)
    for name, d, normal, valid in loaded:
        rows, mean = zenith_bias(d, normal, valid)
        print(f"| {name} | " + " | ".join(f"{s:+.2f} ({a:.2f})" for s, a in rows)
              + f" | {mean:.2f} |", flush=True)


if __name__ == "__main__":
    main()
