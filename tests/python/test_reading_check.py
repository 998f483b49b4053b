"""compare_encodings: whether photos read as linear were display-encoded, from the data (the check
`iphong normals` runs on files that state no colour space). Real photos, DiLiGenT's 8-bit crops
and UW's TGA files, are linear: the sRGB reading's held-out log-likelihood is 9.6-61 standard
errors lower. The same photos put through the sRGB curve, as an editor would save them, are
named, glossy, interreflecting and noisy ones included (cow, harvest, UW gray: 6.5-23 standard
errors); held-out costs without the curve's Jacobian named none of those three."""
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
    # measured -20.5 (pot1) and -13.5 (gray) standard errors
    assert not linear["srgb_better"], linear
    assert linear["loglik_gain"] < -5 * linear["loglik_gain_error"], linear


@pytest.mark.parametrize("name", ["diligent-crop8/pot1", "diligent-crop8/cow", "uw/gray"])
def test_real_photos_saved_display_encoded_are_named(name):
    d, args = load(name)
    linear = iphong.compare_encodings(d["images"], *args)
    shown = iphong.compare_encodings(encode(d["images"]), *args)
    # measured 47, 6.5 and 23 standard errors
    assert shown["srgb_better"], shown
    assert shown["loglik_gain"] > 4 * shown["loglik_gain_error"], shown
    # The decoded reading of the encoded photos is the photos as they were.
    assert shown["heldout_cost_srgb"] == pytest.approx(linear["heldout_cost_as_given"], rel=0.05)


def test_too_few_images_raise_value_error():
    images = np.zeros((5, 8, 8, 3), np.float32)
    lights = np.array([[0, 0, 1], [0.5, 0, 0.87], [0, 0.5, 0.87], [-0.5, 0, 0.87], [0, -0.5, 0.87]])
    with pytest.raises(ValueError, match="6 images"):
        iphong.compare_encodings(images, lights)


def test_the_shadow_threshold_is_the_one_given():
    lights = np.array([[0, 0, 1], [0.5, 0, 0.87], [0, 0.5, 0.87], [-0.5, 0, 0.87], [0, -0.5, 0.87],
                       [0.4, 0.4, 0.82]])
    with pytest.raises(ValueError, match="shadow threshold"):
        iphong.compare_encodings(np.full((6, 8, 8, 3), 0.5, np.float32), lights, shadow_threshold=0)
    d, args = load("diligent-crop8/pot1")
    default = iphong.compare_encodings(d["images"], *args)
    wider = iphong.compare_encodings(d["images"], *args, shadow_threshold=0.3)
    # The costs are in units of each pixel's t², t the threshold's fraction of its brightness.
    assert wider["heldout_cost_as_given"] < 0.5 * default["heldout_cost_as_given"], (default, wider)
    assert not wider["srgb_better"], wider
