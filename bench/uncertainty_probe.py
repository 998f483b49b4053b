#!/usr/bin/python3
"""What can predict each normal's error? Scores per-pixel error predictions against the ground
truth on captures that have one: Spearman's rank correlation with the true angular error and the
median of true error / predicted error (an honest map needs both: ≥ 0.5 and within [0.5, 2],
issue 29). No prediction is iphong output yet (docs/accuracy.md says why); this is the probe to
try one with.

For the default run's normals (iphong.estimate_normals with distant lights), the fitted
luminance model kd·d_j + ks·s_j of each pixel is rebuilt from the library's own shading
(iphong.shade, kd = 1 for d, ks = 1 for s; no second spelling of the model), its residuals and
its Jacobian in the normal's tangent plane (central differences) and in kd and ks, with the
solver's censoring (darker than the model by more than 0.1 of the pixel's brightness: left out).
Two predictions, each the expected angle √(π/4 · tr C) of the normal block of a covariance C:
  classic     σ² (JᵀWJ)⁻¹, σ² the pixel's residual variance: the error if the misfit were
              independent noise from light to light;
  misfit-cov  (JᵀWJ)⁻¹ JᵀW Σ W J (JᵀWJ)⁻¹ with Σ the object's second moment of the relative
              residuals between lights (over its pixels), scaled to the pixel's own misfit: the
              error if every pixel's misfit were drawn from the object's, correlated between
              lights as the object's is.
  lambert-angle  the angle between the default's normal and Lambert's: how far the model moves it;
  halves      half the angle between the normals of two runs, on the even and on the odd lights.
Measured 2026-11-27 on the eight shared captures: classic 1.5–7.9 times too small (median of
true/predicted), misfit-cov 0.6–5.3 times; Spearman 0.02–0.57 and −0.07–0.49, under 0.5 on every
DiLiGenT object for both. 2026-12-02: lambert-angle Spearman −0.26 to 0.43 on the DiLiGenT runs
(0.86 on the bunny, whose error is where Lambert's shadows are), halves −0.22 to 0.42.

    PYTHONPATH=build/python /usr/bin/python3 bench/uncertainty_probe.py [FOLDER...]
"""
import os
import pathlib
import sys

import numpy as np

import iphong

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def ranks(a):
    r = np.empty(len(a))
    r[np.argsort(a, kind="stable")] = np.arange(len(a))
    return r


def spearman(a, b):
    return np.corrcoef(ranks(a), ranks(b))[0, 1]


def angle(a, b):
    return np.degrees(np.arccos(np.clip((a * b).sum(-1), -1, 1)))


def factors(normals, lights, model, shininess):
    """Each light's diffuse and specular factor at each normal (P, K), by iphong.shade."""
    d = np.empty((len(normals), len(lights)))
    s = np.zeros_like(d)
    diffuse = iphong.Material(kd=1.0, ks=0.0, shininess=1.0)
    lobe = iphong.Material(kd=0.0, ks=1.0, shininess=shininess)
    for j, light in enumerate(lights):
        one = [iphong.DirectionalLight(light)]
        d[:, j] = iphong.shade(normals, material=diffuse, lights=one, model="phong")[:, 0]
        if model != "lambert":
            s[:, j] = iphong.shade(normals, material=lobe, lights=one, model=model)[:, 0]
    return d, s


def probe(folder):
    d = iphong.load_dataset(str(folder))
    mask = d["mask"].astype(bool)
    lights = np.asarray(d["light_directions"], float)
    intensities = np.asarray(d["light_intensities"], float)
    r = iphong.estimate_normals(d["images"], lights, intensities, mask, light_distance="inf")
    n = r["normals"][mask].astype(float)
    error = angle(n, d["normal_gt"][mask])
    kd = r["albedo"][mask] @ LUMINANCE
    ks = r["specular"][mask] @ LUMINANCE if "specular" in r else np.zeros(len(n))
    model, shininess = r["model"], r["shininess"]
    rgb = d["images"][:, mask, :].astype(float)
    usable = (rgb.max(-1) < 0.995).T
    y = ((rgb / intensities[:, None, :]) @ LUMINANCE).T
    diffuse, specular = factors(n, lights, model, shininess)
    residual = y - kd[:, None] * diffuse - ks[:, None] * specular
    top = max(1, len(lights) // 10)
    brightness = np.sort(np.where(usable, y, -np.inf), axis=1)[:, -top:].mean(1)
    lit = np.isfinite(brightness) & (brightness > 0)  # pixels with a usable bright observation
    brightness = np.where(lit, brightness, 1.0)
    w = (usable & lit[:, None] & (residual >= -0.1 * brightness[:, None])).astype(float)
    # The Jacobian: the tangent plane's two directions, then kd and ks.
    other = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(n, other)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    step = 1e-5
    jac = np.zeros((len(n), len(lights), 4))
    for i, t in enumerate([t1, t2]):
        sides = []
        for sign in (1, -1):
            moved = n + sign * step * t
            sides.append(factors(moved / np.linalg.norm(moved, axis=1, keepdims=True), lights,
                                 model, shininess))
        (dp, sp), (dm, sm) = sides
        jac[:, :, i] = (kd[:, None] * (dp - dm) + ks[:, None] * (sp - sm)) / (2 * step)
    jac[:, :, 2], jac[:, :, 3] = diffuse, specular
    lobed = ks > 1e-6
    jac[~lobed, :, 3] = 0
    free = np.where(lobed, 4, 3)
    wj = w[..., None] * jac
    bread = np.linalg.pinv(np.einsum("pkq,pkr->pqr", wj, jac))
    variance = (w * residual**2).sum(1) / np.maximum(w.sum(1) - free, 1)
    classic = variance[:, None, None] * bread
    relative = np.where(w > 0, residual / brightness[:, None], 0.0)
    second = (relative.T @ relative) / np.maximum(w.T @ w, 1)
    own = (w * relative**2).sum(1) / np.maximum((w * np.diag(second)[None]).sum(1), 1e-30)
    meat = np.einsum("pjq,jk,pkr->pqr", wj, second, wj) * (own * brightness**2)[:, None, None]
    misfit = bread @ meat @ bread
    where = folder.resolve()
    name = where.relative_to(DATA.resolve()) if where.is_relative_to(DATA.resolve()) else folder
    # Two predictions from other runs, not from the fit: how far the normal moves with the model
    # (the default against Lambert's) and with the lights (two runs on the even and the odd
    # lights, half their angle).
    lambert = iphong.estimate_normals(d["images"], lights, intensities, mask, model="lambert")
    k = np.arange(len(lights)) % 2 == 0
    halves = [iphong.estimate_normals(d["images"][s], lights[s], intensities[s], mask,
                                      light_distance="inf")["normals"][mask] for s in (k, ~k)]
    other = {"lambert-angle": angle(n, lambert["normals"][mask].astype(float)),
             "halves": angle(halves[0].astype(float), halves[1].astype(float)) / 2}
    for label, c in [("classic", classic), ("misfit-cov", misfit), *other.items()]:
        if label in other:
            predicted = c
        else:
            predicted = np.degrees(np.sqrt(np.maximum(np.pi / 4 * (c[:, 0, 0] + c[:, 1, 1]), 0)))
        ok = np.isfinite(predicted) & (predicted > 0) & np.isfinite(error)
        print(f"| {name} | {label} | {error[ok].mean():.2f} | {np.median(predicted[ok]):.2f} | "
              f"{spearman(error[ok], predicted[ok]):.2f} | "
              f"{np.median(error[ok] / predicted[ok]):.2f} |", flush=True)


def main():
    folders = [pathlib.Path(a) for a in sys.argv[1:]]
    if not folders:
        folders = sorted(p.parent for p in DATA.glob("**/Normal_gt.mat"))
    if not folders:
        sys.exit(f"uncertainty_probe.py: no capture with Normal_gt.mat under {DATA}")
    print("| capture | prediction | true mean ° | predicted median ° | Spearman | median true/predicted |")
    print("|---|---|---|---|---|---|")
    for folder in folders:
        probe(folder)


if __name__ == "__main__":
    main()
