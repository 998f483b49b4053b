"""Reading captures from Python: UW's gray sphere, whose analytic normals tell which encoding is
right, and load_dataset's capture options."""
import numpy as np
import pytest

import iphong
from test_render import DATA

GRAY = DATA / "uw" / "gray"
needs_uw = pytest.mark.skipif(not GRAY.is_dir(), reason=f"UW data not found at {GRAY}")


def fit_circle(mask):
    """(cx, cy, r) in pixels of the circle through the centres of the mask's boundary pixels
    (algebraic least squares): independent of iphong's own sphere finder, and about half a pixel
    small, since boundary pixels sit inside the edge."""
    inner = mask.copy()
    inner[1:-1, 1:-1] = (mask[1:-1, 1:-1] & mask[:-2, 1:-1] & mask[2:, 1:-1] & mask[1:-1, :-2]
                         & mask[1:-1, 2:])
    ys, xs = np.nonzero(mask & ~inner)
    xs, ys = xs + 0.5, ys + 0.5
    a = np.c_[2 * xs, 2 * ys, np.ones_like(xs)]
    cx, cy, c = np.linalg.lstsq(a, xs ** 2 + ys ** 2, rcond=None)[0]
    return cx, cy, np.sqrt(c + cx ** 2 + cy ** 2)


def sphere_normals(mask):
    """The sphere seen by an orthographic camera, fitted to the mask's outline (least squares)."""
    cx, cy, r = fit_circle(mask)
    h, w = mask.shape
    x, y = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    nx, ny = (x - cx) / r, -(y - cy) / r
    nz = np.sqrt(np.clip(1 - nx ** 2 - ny ** 2, 0, None))
    return (np.stack([nx, ny, nz], -1) * mask[..., None]).astype(np.float32)


@needs_uw
def test_uw_gray_reads_linear_and_linear_is_right():
    d = iphong.load_dataset(GRAY)
    assert d["encoding"] == "linear"
    assert d["filenames"][:3] == ["gray.0.tga", "gray.1.tga", "gray.2.tga"]
    assert "mask gray.mask.tga" in d["description"]
    truth = sphere_normals(d["mask"])
    errors = {}
    for encoding in ["linear", "srgb"]:
        images = iphong.load_dataset(GRAY, encoding=encoding)["images"]
        result = iphong.estimate_normals(images, d["light_directions"], mask=d["mask"])
        errors[encoding] = iphong.angular_error(result["normals"], truth, d["mask"])
    # Measured: linear 6.16° mean, 4.37° median (5.1° and 4.2° before shadows were censored: on a
    # convex sphere with no cast shadow, censoring only gives away the darker observations;
    # plain least squares gives 5.46°); sRGB 16.4° and 16.5°.
    assert errors["linear"]["median_angular_error_deg"] <= 5.0
    assert errors["linear"]["mean_angular_error_deg"] <= 6.5
    assert errors["srgb"]["mean_angular_error_deg"] >= 12.0


@needs_uw
def test_load_dataset_capture_options():
    d = iphong.load_dataset(GRAY, crop=(100, 20, 300, 260), downscale=2)
    assert d["images"].shape == (12, 130, 150, 3)
    assert d["mask"].shape == (130, 150)
    assert len(d["image_counts"]) == 12
    with pytest.raises(ValueError, match="reaches outside the 512x340 image"):
        iphong.load_dataset(GRAY, crop=(400, 0, 200, 10))
    with pytest.raises(ValueError, match="encoding must be auto, linear or srgb"):
        iphong.load_dataset(GRAY, encoding="gamma")
    with pytest.raises(TypeError, match="crop"):
        iphong.load_dataset(GRAY, crop="0,0,10,10")


CROP_BALL = DATA / "diligent-crop8" / "ball"


@pytest.mark.skipif(not CROP_BALL.is_dir(), reason=f"DiLiGenT crops not found at {CROP_BALL}")
def test_intensities_none_sets_the_capture_file_aside():
    """intensities="none" reads every light as 1 although the folder holds light_intensities.txt
    (DiLiGenT's range from 0.38 to 2.3), without touching the folder."""
    def listing():
        return sorted((f.name, f.stat().st_size, f.stat().st_mtime_ns) for f in CROP_BALL.iterdir())

    before = listing()
    with_file = iphong.load_dataset(CROP_BALL)
    assert with_file["light_intensities"].max() > 2 * with_file["light_intensities"].min()
    none = iphong.load_dataset(CROP_BALL, intensities="none")
    assert listing() == before
    np.testing.assert_array_equal(none["light_intensities"], np.ones((96, 3)))
    assert "intensities all 1 (--intensities none)" in none["description"]
    np.testing.assert_array_equal(none["images"], with_file["images"])
