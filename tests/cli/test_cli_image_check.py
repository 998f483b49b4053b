"""Images that disagree with the others (solve/image_check.h): a light file with two lines swapped
or one intensity off is named by what the images say, in a warning naming the files and the
light file's lines, and in metrics.json's "image_check"; the right file says nothing. On iphong's
rendered sphere (12 lights, known coefficients) and, when ../shared/data is there, on DiLiGenT's
cat crop (96 lights) and UW's cat, whose third photo is darker than its light."""
import json
import os
import pathlib

import pytest

from cli import IPHONG, ROOT, binary_available, render_dataset, run

DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")


@pytest.fixture(scope="module")
def sphere(tmp_path_factory):
    folder = tmp_path_factory.mktemp("images") / "sphere"
    render_dataset(folder, "--format", "png")
    return folder


def disagreement(stderr):
    return [line for line in stderr.splitlines() if "disagree" in line]


def check_of(out):
    return json.loads((out / "metrics.json").read_text())["image_check"]


def test_the_right_light_file_says_nothing(sphere, tmp_path):
    code, _, err = run("normals", sphere, "-o", tmp_path / "out")
    assert code == 0, err
    assert disagreement(err) == [], err
    check = check_of(tmp_path / "out")
    assert check["disagreeing"] == [] and check["heldout"]
    assert len(check["images"]) == 12 and check["images"][0]["file"] == "001.png"
    assert max(image["misfit"] for image in check["images"]) < 0.5


@pytest.mark.parametrize("mistake", ["swapped", "intensity"])
def test_a_wrong_light_file_is_named(sphere, tmp_path, mistake):
    lines = (sphere / "light_directions.txt").read_text().splitlines()
    extra = []
    if mistake == "swapped":
        lines[3], lines[9] = lines[9], lines[3]
        expected, said = ["004.png", "010.png"], "lights 4, 10 of"
    else:
        intensities = ["1 1 1"] * len(lines)
        intensities[4] = "0.5 0.5 0.5"
        (tmp_path / "intensities.txt").write_text("\n".join(intensities) + "\n")
        extra = ["--intensities", tmp_path / "intensities.txt"]
        expected, said = ["005.png"], "light 5 of"
    (tmp_path / "lights.txt").write_text("\n".join(lines) + "\n")
    code, _, err = run("normals", sphere, "--lights", tmp_path / "lights.txt", *extra, "-o",
                       tmp_path / "out")
    assert code == 0, err
    warnings = disagreement(err)
    assert len(warnings) == 1, err
    assert warnings[0].startswith(f"iphong: warning: {tmp_path / 'lights.txt'}: "), warnings[0]
    assert ", ".join(expected) in warnings[0] and said in warnings[0], warnings[0]
    assert "intensities" in warnings[0] and "order" in warnings[0], warnings[0]
    assert check_of(tmp_path / "out")["disagreeing"] == expected


@pytest.mark.skipif(not (DATA / "diligent-crop8" / "cat").exists(),
                    reason=f"no DiLiGenT crops in {DATA} (../shared/data)")
def test_two_swapped_lines_of_diligent_cat_are_named(tmp_path):
    source = DATA / "diligent-crop8" / "cat"
    lines = (source / "light_directions.txt").read_text().splitlines()
    lines[24], lines[72] = lines[72], lines[24]
    (tmp_path / "lights.txt").write_text("\n".join(lines) + "\n")
    code, _, err = run("normals", source, "--lights", tmp_path / "lights.txt", "-o",
                       tmp_path / "out")
    assert code == 0, err
    check = check_of(tmp_path / "out")
    assert check["disagreeing"] == ["025.png", "073.png"] and not check["heldout"]
    assert len(disagreement(err)) == 1, err


@pytest.mark.skipif(not (DATA / "uw" / "cat").exists(), reason=f"no UW data in {DATA}")
def test_uw_cats_darker_photo_is_named(tmp_path):
    """UW's cat.2.tga is about 17 % darker than its light and the other eleven say (a fit of the
    light's intensity from the normals: 0.83 where the others give 0.97-1.03)."""
    code, _, err = run("normals", DATA / "uw" / "cat", "-o", tmp_path / "out")
    assert code == 0, err
    check = check_of(tmp_path / "out")
    assert check["disagreeing"] == ["cat.2.tga"]
    assert check["images"][2]["misfit"] > 1 > max(
        image["misfit"] for n, image in enumerate(check["images"]) if n != 2)


def test_near_lights_two_swapped_positions_are_named(tmp_path):
    """A near-light capture (24 LEDs, point lights seen from each pixel's point): its images are
    checked against the near run's result; two lines of light_positions.txt swapped are named."""
    capture = tmp_path / "capture"
    code, _, err = run("render", ROOT / "fixtures" / "scenes" / "near_dome_leds_phong.json", "-o",
                       capture, "--per-light")
    assert code == 0, err
    code, _, err = run("normals", capture, "-o", tmp_path / "right")
    assert code == 0, err
    assert disagreement(err) == [], err
    assert check_of(tmp_path / "right")["disagreeing"] == []
    (capture / ".iphong-manifest.json").unlink()
    (capture / "light_directions.txt").unlink()  # it would contradict the swapped positions
    lines = (capture / "light_positions.txt").read_text().splitlines()
    lines[2], lines[8] = lines[8], lines[2]
    (capture / "light_positions.txt").write_text("\n".join(lines) + "\n")
    code, _, err = run("normals", capture, "-o", tmp_path / "swapped")
    assert code == 0, err
    warnings = disagreement(err)
    assert len(warnings) == 1 and "003.png, 009.png" in warnings[0], err
    assert warnings[0].startswith(f"iphong: warning: {capture / 'light_positions.txt'}: ")
    assert check_of(tmp_path / "swapped")["disagreeing"] == ["003.png", "009.png"]
