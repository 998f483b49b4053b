"""compare_encodings: whether photos read as linear were display-encoded, from the data (the check
`iphong normals` runs on files that state no colour space). Real photos, DiLiGenT's 8-bit crops
and UW's TGA files, are linear: the sRGB reading predicts their held-out lights 12-31 standard
errors worse, never better. The same photos put through the sRGB curve, as an editor would save
them, are named on DiLiGenT's ball, cat and pot1 (25-57 standard errors) but not on cow, harvest
or UW's (-4 to 0.4): a lobe's tails, interreflections and 12 noisy lights hide the curve from a
Lambertian fit; noise-free renders are named (tests/cli/test_cli_encoding.py)."""
import os
import pathlib

import numpy as np
import pytest

import iphong

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))


def encode(v):
    v = np.clip(v, 0, 1)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055).astype(np.float32)


def load(name):
    folder = DATA / name
    if not folder.is_dir():
        pytest.skip(f"no real data at {folder} (set IPHONG_DATA_DIR)")
    d = iphong.load_dataset(str(folder))
    assert d["encoding"] == "linear"
    return d, (d["light_directions"], d["light_intensities"], d["mask"])


@pytest.mark.parametrize("name", ["diligent-crop8/pot1", "uw/gray"])
def test_real_photos_read_as_linear_are_not_named(name):
    d, args = load(name)
    linear = iphong.compare_encodings(d["images"], *args)
    # measured -17 (pot1) and -15 (gray) standard errors
    assert not linear["srgb_better"] and linear["gain"] < -5 * linear["gain_error"], linear


def test_real_photos_saved_display_encoded_are_named():
    d, args = load("diligent-crop8/pot1")
    linear = iphong.compare_encodings(d["images"], *args)
    shown = iphong.compare_encodings(encode(d["images"]), *args)
    assert shown["srgb_better"] and shown["gain"] > 5 * shown["gain_error"], shown  # measured 29
    # The decoded reading of the encoded photos is the photos as they were.
    assert shown["heldout_cost_srgb"] == pytest.approx(linear["heldout_cost_as_given"], rel=0.05)


def test_too_few_images_raise_value_error():
    images = np.zeros((5, 8, 8, 3), np.float32)
    lights = np.array([[0, 0, 1], [0.5, 0, 0.87], [0, 0.5, 0.87], [-0.5, 0, 0.87], [0, -0.5, 0.87]])
    with pytest.raises(ValueError, match="6 images"):
        iphong.compare_encodings(images, lights)
