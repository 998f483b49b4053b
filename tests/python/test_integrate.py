"""iphong.integrate and the height-map helpers: arrays in, arrays out."""

import numpy as np
import pytest

import iphong


def sphere_cap(width=120, height=100, radius=60.0, extent=45.0):
    """Normals, mask and heights of a sphere cap, in pixels (x right, y up, row 0 at the top)."""
    cols, rows = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    x, y = cols - width / 2, height / 2 - rows
    mask = x**2 + y**2 < extent**2
    z = np.sqrt(np.clip(radius**2 - x**2 - y**2, 1e-9, None))
    normals = np.dstack([x / radius, y / radius, z / radius]).astype(np.float32)
    normals[~mask] = 0
    return normals, mask, np.where(mask, z, np.nan)


def test_sphere_cap_round_trip_within_half_a_percent():
    normals, mask, truth = sphere_cap()
    result = iphong.integrate(normals)  # mask: the pixels with a normal
    height = result["height"]
    assert height.shape == mask.shape and height.dtype == np.float32
    assert np.isnan(height[~mask]).all() and np.isfinite(height[mask]).all()
    assert abs(np.nanmean(height)) < 1e-4  # masked mean 0
    difference = height[mask] - truth[mask]
    rmse = np.sqrt(np.mean((difference - difference.mean()) ** 2))
    assert rmse < 0.005 * (truth[mask].max() - truth[mask].min())
    assert result["summary"]["method"] == "quadratic"
    assert result["summary"]["components"] == 1
    # The surface's own normals agree with the input.
    back = iphong.normals_from_height(height, mask)
    cosine = np.clip(np.sum(back[mask] * normals[mask], axis=1), -1, 1)
    assert np.degrees(np.arccos(cosine)).mean() < 0.5


def test_pixel_size_scales_and_dct_handles_full_rectangles():
    normals, _, _ = sphere_cap(extent=200)  # every pixel inside
    normals = normals / np.linalg.norm(normals, axis=2, keepdims=True)
    unit = iphong.integrate(normals)
    assert unit["summary"]["method"] == "dct"
    half = iphong.integrate(normals, pixel_size=0.5)
    np.testing.assert_allclose(half["height"], 0.5 * unit["height"], atol=1e-4)


def test_mesh_and_errors():
    normals, mask, _ = sphere_cap(40, 30, 30.0, 12.0)
    height = iphong.integrate(normals, mask)["height"]
    vertices, triangles = iphong.height_to_mesh(height, mask, normals)
    assert vertices.shape == (mask.sum(), 3)
    assert triangles.shape[1] == 3 and triangles.max() < len(vertices)
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    assert (np.cross(b - a, c - a)[:, 2] > 0).all()  # facing the viewer
    with pytest.raises(ValueError, match=r"mask must have shape \(H, W\) = \(30, 40\)"):
        iphong.integrate(normals, np.ones((30, 41), bool))
    bad = normals.copy()
    bad[15, 20] = np.nan
    with pytest.raises(ValueError, match=r"non-finite normal at pixel \(col 20, row 15\)"):
        iphong.integrate(bad, mask)
    with pytest.raises(ValueError, match="the mask is empty"):
        iphong.integrate(normals, np.zeros((30, 40), bool))
    with pytest.raises(ValueError, match="unknown integration method"):
        iphong.integrate(normals, method="poisson")


def test_bilateral_keeps_a_fold_whole_and_cuts_a_ball_off_its_floor():
    """A face crossed by a deep V fold, its normals made here in numpy with a small rotational
    (non-integrable) error as recovered normals have: the bilateral heights stay as close to the
    truth as the quadratic ones and no edge is cut. A ball above a tilted floor: its silhouette
    is cut, and the summary counts the cuts the continuity image shows."""
    cols, rows = np.meshgrid(np.arange(160) + 0.5, np.arange(140) + 0.5)
    x, y = cols - 80, 70 - rows
    mask = (x / 60) ** 2 + (y / 66) ** 2 < 1
    dome = np.sqrt(np.clip(1.5 * 60**2 - x**2 - y**2, 1, None))
    inside = np.abs(x - 20) < 6
    z = dome - np.where(inside, 30 * (1 - np.abs(x - 20) / 6), 0)
    p = -x / dome + np.where(inside, 5 * np.sign(x - 20), 0) + 0.003 * y
    q = -y / dome - 0.003 * x
    normals = np.dstack([-p, -q, np.ones_like(p)])
    normals = (normals / np.linalg.norm(normals, axis=2, keepdims=True)).astype(np.float32)
    normals[~mask] = 0

    def rmse(height):
        d = height[mask] - z[mask]
        return np.sqrt(np.mean((d - d.mean()) ** 2))

    quadratic = iphong.integrate(normals, mask, method="quadratic")
    bilateral = iphong.integrate(normals, mask, method="bilateral")
    assert rmse(bilateral["height"]) < 1.05 * rmse(quadratic["height"])
    assert bilateral["summary"]["cut_edges"] == 0
    assert bilateral["summary"]["separated_pixels"] == 0

    ball = x**2 + y**2 < 40**2
    zb = np.sqrt(np.clip(40**2 - x**2 - y**2, 1e-12, None))
    p = np.where(ball, -x / zb, 0.3)
    q = np.where(ball, -y / zb, 0.0)
    normals = np.dstack([-p, -q, np.ones_like(p)])
    normals = (normals / np.linalg.norm(normals, axis=2, keepdims=True)).astype(np.float32)
    result = iphong.integrate(normals, np.ones(ball.shape, bool), method="bilateral")
    continuity = result["continuity"]
    shown = (continuity[:, :-1, 0] < 0.5).sum() + (continuity[:-1, :, 1] < 0.5).sum()
    assert result["summary"]["cut_edges"] == shown > 40
    assert iphong.integrate(normals, np.ones(ball.shape, bool))["summary"]["cut_edges"] == 0


def lumpy_capture(lights, width=96, height=80):
    """A numpy Lambert render (no iphong code) of an ellipsoid with two off-centre bumps: images
    (K, H, W), mask, true normals."""
    cols, rows = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    x, y = cols - width / 2, height / 2 - rows
    a, b = 0.45 * width, 0.42 * height
    e = 1 - (x / a) ** 2 - (y / b) ** 2
    mask = e > 0.01
    r = 0.5 * (a + b)
    root = np.sqrt(np.clip(e, 0.01, None))
    p, q = -r * x / (a * a * root), -r * y / (b * b * root)
    for cx, cy, s in ((12.0, 10.0, 10.0), (-15.0, -6.0, 8.0)):
        g = 0.6 * s * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / s**2)
        p, q = p - 2 * (x - cx) / s**2 * g, q - 2 * (y - cy) / s**2 * g
    n = np.dstack([-p, -q, np.ones_like(p)])
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    n[~mask] = 0
    images = np.clip(np.einsum("hwc,kc->khw", n, lights), 0, None).astype(np.float32)
    return images, mask, n.astype(np.float32)


def test_check_normal_frame_names_the_reading_of_a_slipped_light_file():
    """A light file with y negated gives normals with y negated (the model is symmetric under
    the plane's reflections and turns, which fix the view): Woodham's exactly, and the check names
    the reading that undoes it; the right file gives no message."""
    rng = np.random.default_rng(3)
    lights = rng.normal(size=(12, 3))
    lights[:, 2] = np.abs(lights[:, 2]) + 1.2
    lights /= np.linalg.norm(lights, axis=1, keepdims=True)
    images, mask, truth = lumpy_capture(lights)
    right = iphong.estimate_normals(images, lights, mask=mask, model="lambert")["normals"]
    flip = np.diag([1.0, -1.0, 1.0])
    with pytest.warns(UserWarning, match="look like another frame: read with y negated"):
        slipped = iphong.estimate_normals(images, lights @ flip, mask=mask,
                                          model="lambert")["normals"]
    assert np.abs(slipped[mask] @ flip - right[mask]).max() < 1e-5
    quiet = iphong.check_normal_frame(right, mask)
    assert quiet["better"] == "as given" and quiet["message"] == ""
    assert quiet["readings"][0]["silhouette_cos"] > 0.8
    named = iphong.check_normal_frame(slipped, mask)
    assert named["better"] == "y negated"
    assert named["message"].startswith("read with y negated, the normals fit the object better")
    assert [r["reading"] for r in named["readings"]][:2] == ["as given", "y negated"]
    with pytest.raises(ValueError):
        iphong.check_normal_frame(np.full((4, 4, 3), np.nan, np.float32), np.ones((4, 4), bool))
