#!/usr/bin/python3
"""What would cast shadows traced from the surface be worth? (issue 29, item 2.) Measures, on
captures with ground truth, how much the normals gain when the observations a surface shadows
are left out of the fit instead of censored, before anything is built into the solver.

Every solve here uses one plan (iphong.plan_normals on the capture as recorded: distant lights,
the model and weights the default chooses), so only the per-pixel fits see the change. An
observation is left out by setting it to 1.0: a recorded value at the top of data within [0, 1]
counts as clipped, and clipped observations are unused by every fit (the solver's one way of
leaving an observation out; the captures used here stay within 1).

Shadows are traced by a height-map ray march (x right, y up, z toward the camera; heights in
pixel widths, orthographic): a pixel is shadowed from light L when the surface rises above the
ray from it toward L by more than EPS pixel widths before the ray leaves the object or clears its
highest point. Rows of the table:
  plan fixed      the default's per-pixel fits, nothing left out: the baseline.
  true, all       shadows traced on the surface integrated from the ground-truth normals, every
                  traced observation left out.
  true, lit       the same, only where the true normal faces the light (N·L > 0.05): a traced
                  ray also starts into the surface wherever the light is behind its tangent
                  plane, and those attached shadows say something about the normal.
  loop, lit       the mechanism as it would be built: the surface integrated from the default's
                  own normals, its shadows (where those normals face the light) left out, the
                  fits redone, twice.
  dark oracle     every observation darker than half of what the true normal and the pixel's
                  albedo predict with N·L > 0.05 left out: all a perfect knowledge of cast shadows
                  could remove.
Measured 2026-11-28 (docs/accuracy.md has the table): the loop moves the normals by at most
0.03°, and even the true surface's lit shadows gain 0.03–0.33°.

    PYTHONPATH=build/python /usr/bin/python3 bench/shadow_trace_probe.py [FOLDER...]
"""
import os
import pathlib
import sys
import warnings

import numpy as np

import iphong

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
OBJECTS = ["rps-bunny-lambert", "diligent-crop8/harvest", "diligent-crop8/pot1", "diligent-crop8/cow",
           "diligent-crop8/cat", "diligent-crop8/ball"]
EPS = 0.5  # pixel widths the surface must rise above a ray to shadow it
FACING = 0.05  # N·L above which a traced shadow is a cast one


def angle(a, b, mask):
    return np.degrees(np.arccos(np.clip((a * b).sum(-1), -1, 1)))[mask]


def shadows(height, mask, light):
    """(H, W) bool: the pixels of `mask` whose ray toward `light` meets the surface."""
    rows, cols = height.shape
    surface = np.where(mask, height, -np.inf)
    reach = np.hypot(light[0], light[1])
    out = np.zeros((rows, cols), bool)
    if reach < 1e-6:  # a light on the axis shadows nothing on a height map
        return out
    step_x, step_y, rise = light[0] / reach, -light[1] / reach, light[2] / reach
    ys, xs = np.nonzero(mask)
    start = height[ys, xs]
    top = np.nanmax(height[mask])
    active = np.ones(len(ys), bool)
    hit = np.zeros(len(ys), bool)
    s = 0.5
    while active.any():
        x, y = xs + step_x * s, ys + step_y * s
        ray = start + rise * s
        active &= (x >= 0) & (x <= cols - 1) & (y >= 0) & (y <= rows - 1) & (ray < top)
        xi = np.clip(np.rint(x).astype(int), 0, cols - 1)
        yi = np.clip(np.rint(y).astype(int), 0, rows - 1)
        blocked = active & (surface[yi, xi] > ray + EPS)
        hit |= blocked
        active &= ~blocked
        s += 0.5
    out[ys, xs] = hit
    return out


def traced(normals, mask, lights):
    height = iphong.integrate(np.where(mask[..., None], normals, 0), mask=mask, method="quadratic")["height"]
    return np.stack([shadows(height, mask, light) for light in lights])


def main(folders):
    print(f"{'object':28s} {'plan fixed':>10s} {'true, all':>10s} {'true, lit':>10s} {'loop, lit':>16s} {'dark oracle':>11s}")
    for folder in folders:
        path = DATA / folder
        if not path.is_dir():
            print(f"{folder}: not found under {DATA}, skipped")
            continue
        ds = iphong.load_dataset(str(path))
        images, lights, intensities, mask, truth = (ds[k] for k in ("images", "light_directions",
                                                                     "light_intensities", "mask", "normal_gt"))
        if truth is None or images.max() > 1:
            print(f"{folder}: no ground truth or values above 1, skipped")
            continue
        k, rows, cols, _ = images.shape
        scored = mask & (np.linalg.norm(truth, axis=-1) > 0.5)
        flat = np.flatnonzero(mask.ravel())
        positions = flat[np.array(iphong.plan_sample_indices(len(flat)))]
        sample = np.ascontiguousarray(images.reshape(k, -1, 3)[:, positions].transpose(1, 0, 2))
        plan = iphong.plan_normals(sample, positions, cols, rows, lights, intensities)

        def solve(left_out):
            kept = images.copy()
            kept[left_out] = 1.0
            out = iphong.solve_normals_block(kept, mask, lights, intensities, plan=plan, threads=0)
            normals = out[..., :3]
            found = mask & (out[..., 9] >= 0) & (np.linalg.norm(normals, axis=-1) > 0.5)
            return normals, found

        facing_true = np.einsum("kc,hwc->khw", lights, truth) > FACING
        base, found = solve(np.zeros(images.shape[:3], bool))
        true_shadows = traced(truth, scored, lights)
        row = [angle(base, truth, scored).mean()]
        row.append(angle(solve(true_shadows)[0], truth, scored).mean())
        row.append(angle(solve(true_shadows & facing_true)[0], truth, scored).mean())
        normals, loop = base, []
        for _ in range(2):
            left_out = traced(normals, found, lights) & (np.einsum("kc,hwc->khw", lights, normals) > FACING)
            normals, found = solve(left_out)
            loop.append(angle(normals, truth, scored).mean())
        brightness = (images / intensities[:, None, None, :]).mean(-1)
        shading = np.einsum("kc,hwc->khw", lights, truth)
        ratio = np.where(scored & (shading > 0.3), brightness / np.maximum(shading, 1e-3), np.nan)
        with warnings.catch_warnings():  # pixels dark in every image have no albedo (NaN)
            warnings.simplefilter("ignore", RuntimeWarning)
            albedo = np.nanmedian(ratio, axis=0)
        dark = facing_true & scored[None] & (brightness < 0.5 * albedo[None] * np.maximum(shading, 0))
        row.append(angle(solve(dark)[0], truth, scored).mean())
        print(f"{folder:28s} {row[0]:10.2f} {row[1]:10.2f} {row[2]:10.2f} {loop[0]:7.2f} → {loop[1]:6.2f} {row[3]:11.2f}",
              flush=True)


if __name__ == "__main__":
    main(sys.argv[1:] or OBJECTS)
