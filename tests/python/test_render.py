"""iphong.render and iphong.load_dataset: arrays in, arrays out, consistent with iphong.shade."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import iphong
from conftest import FIXTURES, ROOT

ISSUE_SCENE = json.loads((FIXTURES / "scenes" / "issue3_sphere.json").read_text())
BUILD = pathlib.Path(os.environ.get("IPHONG_BUILD_DIR", ROOT / "build"))
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))


def test_render_matches_shading_its_own_ground_truth_normals():
    out = iphong.render(ISSUE_SCENE)
    mask = out["mask"]
    assert out["image"].shape == (256, 256, 3) and out["image"].dtype == np.float32
    assert 0.45 < mask.mean() < 0.55  # a disc of radius 0.8 in a 2.0-wide view: π·0.4² ≈ 0.503
    m = ISSUE_SCENE["objects"][0]["material"]
    material = iphong.Material(**m)
    light = iphong.DirectionalLight(**{k: v for k, v in ISSUE_SCENE["lights"][0].items() if k != "type"})
    again = iphong.shade(out["normals"], [0, 0, 1], material, [light], ISSUE_SCENE["ambient"], mask=mask)
    np.testing.assert_allclose(out["image"][mask], again[mask], atol=2e-6)
    np.testing.assert_allclose(np.linalg.norm(out["normals"][mask], axis=1), 1, atol=1e-6)
    assert np.all(out["normals"][~mask] == 0)
    np.testing.assert_allclose(out["albedo"][mask], np.broadcast_to(m["kd"], (mask.sum(), 3)), atol=1e-7)


def test_per_light_images_sum_to_the_combined_image():
    scene = dict(ISSUE_SCENE, width=64, height=64,
                 lights=[{"type": "ring", "count": 6, "elevation_deg": 40, "intensity": [1, 0.8, 0.6]}])
    out = iphong.render(scene, per_light=True)
    assert out["images"].shape == (6, 64, 64, 3)
    assert out["light_directions"].shape == (6, 3)
    ambient = np.asarray(ISSUE_SCENE["objects"][0]["material"]["ka"])  # Ia = 1
    mask = out["mask"]
    total = ambient + (out["images"] - ambient).sum(axis=0)
    np.testing.assert_allclose(out["image"][mask], total[mask], atol=1e-5)


def test_scene_errors_raise_value_error_naming_the_field():
    bad = dict(ISSUE_SCENE, objects=[dict(ISSUE_SCENE["objects"][0], radius=-1)])
    with pytest.raises(ValueError, match=r"objects\[0\]\.radius: expected a number > 0"):
        iphong.render(bad)
    with pytest.raises(ValueError, match="unknown shading 'toon'"):
        iphong.render(dict(ISSUE_SCENE, shading="toon"))
    with pytest.raises(ValueError, match="no such file"):
        iphong.render("no/such/scene.json")


@pytest.mark.parametrize("name, why", [
    ("nothing_visible.json", "every object is outside the camera's view"),
    ("seen_from_behind.json", "every face in the camera's view is seen from behind"),
    ("faces_of_no_area.json", "every face of the objects has no area"),
])
def test_a_scene_that_shows_nothing_raises_value_error_saying_why(name, why):
    # What `iphong render` refuses (tests/cli/test_cli_bad_inputs.py), from the same library call:
    # a blank image and an empty mask used to come back as a result.
    scene = FIXTURES / "bad" / "scenes" / name
    with pytest.raises(ValueError, match="nothing is visible: " + why):
        iphong.render(scene)


def test_cli_dataset_reads_back_like_the_in_memory_render(tmp_path):
    exe = BUILD / "iphong"
    if not exe.exists():
        pytest.skip(f"no iphong binary at {exe}")
    scene = dict(ISSUE_SCENE, width=64, height=48,
                 lights=[{"type": "hemisphere", "count": 8, "min_elevation_deg": 35}])
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    subprocess.run([str(exe), "render", str(tmp_path / "scene.json"), "-o", str(tmp_path / "set"),
                    "--per-light", "--format", "png", "--bits", "16"], check=True, capture_output=True)
    data = iphong.load_dataset(tmp_path / "set")
    ref = iphong.render(scene, per_light=True)
    assert data["images"].shape == (8, 48, 64, 3)
    np.testing.assert_allclose(data["images"], np.clip(ref["images"], 0, 1), atol=1 / 65535)
    np.testing.assert_allclose(data["light_directions"], ref["light_directions"], atol=1e-8)
    np.testing.assert_array_equal(data["mask"], ref["mask"])
    np.testing.assert_array_equal(data["normal_gt"], ref["normals"])
    assert data["material"]["shininess"] == 10 and data["material"]["model"] == "phong"


def test_load_dataset_errors_name_the_file(tmp_path):
    (tmp_path / "filenames.txt").write_text("a.png\nb.png\n")
    (tmp_path / "light_directions.txt").write_text("0 0 1\n")
    with pytest.raises(ValueError, match=r"light_directions\.txt: has 1 lines for 2 images"):
        iphong.load_dataset(tmp_path)


def test_load_real_diligent_crop():
    ball = DATA / "diligent-crop8" / "ball"
    if not ball.exists():
        pytest.skip(f"no real data at {ball} (set IPHONG_DATA_DIR)")
    d = iphong.load_dataset(ball)
    assert d["images"].shape == (96, 172, 172, 3)
    assert d["images"].dtype == np.float32 and d["images"].max() <= 1.0
    gt = d["normal_gt"][d["mask"]]
    np.testing.assert_allclose(np.linalg.norm(gt, axis=1), 1, atol=1e-3)
    np.testing.assert_allclose(np.linalg.norm(d["light_directions"], axis=1), 1, atol=1e-6)
