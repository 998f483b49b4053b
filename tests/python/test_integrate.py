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
