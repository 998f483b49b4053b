"""A floating-point capture brighter than 1 (a renderer's EXR, an HDR merge) is data, not clipping:
`iphong normals` and `iphong fit-material` use every value, as they do for the same scene at
unit intensity. Values at the top of an integer range (or a float file that never passes 1) stay
clipped (tests/solve/test_normals.cc)."""
import json

import pytest

from cli import IPHONG, PHOTOMETRIC_SCENE, binary_available, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")


@pytest.fixture(scope="module")
def bright(tmp_path_factory):
    """The photometric sphere under lights 8 times as bright: EXR values up to 8.6."""
    root = tmp_path_factory.mktemp("hdr")
    scene = json.loads(PHOTOMETRIC_SCENE.read_text())
    scene["lights"][0]["intensity"] = [8, 8, 8]
    (root / "scene.json").write_text(json.dumps(scene))
    code, _, err = run("render", root / "scene.json", "-o", root / "ds", "--per-light")
    assert code == 0, err
    return root / "ds"


@pytest.mark.parametrize("flags, limit", [([], 0.01), (["--ignore-material"], 0.1)])
def test_normals_of_a_bright_float_capture(bright, tmp_path, flags, limit):
    # Before: every value above 0.995 was left out as saturated (11.6° and 19.8° mean).
    code, out, err = run("normals", bright, "-o", tmp_path / "out", "--json", *flags)
    assert code == 0, err
    metrics = json.loads(out)
    assert metrics["mean_angular_error_deg"] < limit, metrics


def test_fit_material_of_a_bright_float_capture(bright, tmp_path):
    code, out, err = run("fit-material", bright, "--normals", bright / "normals.exr", "-o",
                       tmp_path / "fit")
    assert code == 0, err
    material = json.loads((tmp_path / "fit" / "material.json").read_text())
    assert material["ks"] == pytest.approx([0.4] * 3, rel=1e-3)
    assert material["shininess"] == pytest.approx(20, rel=1e-3)
    assert "; 0 observations saturated" in out, out
