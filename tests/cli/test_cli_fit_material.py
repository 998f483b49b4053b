"""`iphong fit-material`: a known material recovered from a render and rendered straight back
(fit -> material.json -> render -> fit), the files and pictures it writes, DiLiGenT's ball with
its ground truth (Phong must beat Lambert on held-out lights), and the bad inputs of issue 14:
one line, nothing written."""
import json
import os
import pathlib
import shutil
import subprocess

import pytest

from cli import (FIXTURES, IPHONG, ROOT, assert_refused, binary_available, render_dataset, run,
                 snapshot)

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")

DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
JADE = {"ka": [0.14, 0.22, 0.16], "kd": [0.54, 0.89, 0.63], "ks": [0.32, 0.32, 0.32],
        "shininess": 12.8}  # seed 004's jade, as the preset has it


def pixel(image, x, y):
    """One pixel's values, as oiiotool reads them."""
    out = subprocess.run(["oiiotool", str(image), "--cut", f"1x1+{x}+{y}", "--printstats"],
                         capture_output=True, text=True, check=True).stdout
    return [float(v) for v in out.split("Stats Avg:")[1].split("(")[0].split()]


def sphere_scene(path, material, lights=24, model="phong"):
    """A sphere under `lights` hemisphere lights and ambient 1, 80x80, EXR."""
    path.write_text(json.dumps({
        "width": 80, "height": 80, "ambient": [1, 1, 1], "model": model,
        "lights": [{"type": "hemisphere", "count": lights, "min_elevation_deg": 30}],
        "objects": [{"shape": "sphere", "radius": 0.85, "subdivisions": 6,
                     "material": material}],
        "output": {"format": "exr"}}))
    return path


def fit(dataset, out, *extra):
    code, stdout, err = run("fit-material", dataset, "--normals", dataset, "-o", out, *extra)
    assert code == 0, err
    return json.loads((pathlib.Path(out) / "material.json").read_text()), stdout


def test_round_trip_fit_render_fit(tmp_path):
    render = tmp_path / "render"
    code, _, err = run("render", sphere_scene(tmp_path / "scene.json", JADE), "-o", render,
                       "--per-light")
    assert code == 0, err
    first, stdout = fit(render, tmp_path / "fit1", "--albedo", "uniform")
    assert "Chosen: phong" in stdout
    for key in ("ka", "kd", "ks"):
        assert first[key] == pytest.approx(JADE[key], rel=5e-3), key
    assert first["shininess"] == pytest.approx(JADE["shininess"], rel=5e-3)
    assert first["model"] == "phong" and first["ambient"] == [1, 1, 1]

    # The fitted material.json renders straight back, and fits to the same coefficients.
    scene2 = sphere_scene(tmp_path / "scene2.json", {"file": str(tmp_path / "fit1/material.json")})
    code, _, err = run("render", scene2, "-o", tmp_path / "render2", "--per-light")
    assert code == 0, err
    second, _ = fit(tmp_path / "render2", tmp_path / "fit2", "--albedo", "uniform")
    for key in ("ka", "kd", "ks"):
        assert second[key] == pytest.approx(first[key], rel=1e-3), key
    assert second["shininess"] == pytest.approx(first["shininess"], rel=1e-3)


def test_files_pictures_and_the_report(tmp_path):
    render_dataset(tmp_path / "d")
    code, stdout, err = run("fit-material", tmp_path / "d", "--normals", tmp_path / "d", "-o",
                            tmp_path / "fit", "--json")
    assert code == 0, err
    report = json.loads(stdout)
    for name in ("material.json", "fit.json", "albedo.exr", "albedo.png", "normals.exr",
                 "compare.png", "lobe.png"):
        assert (tmp_path / "fit" / name).stat().st_size > 0, name
    assert [m["model"] for m in report["models"]] == ["lambert", "phong", "blinn-phong"]
    assert report["chosen"] == "phong"
    assert report["fold_of_light"] == [j % 2 for j in range(12)]
    phong = report["models"][1]
    assert phong["shininess"] == pytest.approx(20, rel=5e-3)
    assert phong["ks"] == pytest.approx([0.4] * 3, rel=5e-3)
    assert phong["heldout_rmse"] < report["models"][0]["heldout_rmse"]
    # Every standard error present, and a lobe plot's bins.
    assert all(v is not None and v >= 0 for v in phong["ks_se"] + [phong["shininess_se"]])
    assert len(report["lobe"]["bins"]) > 5
    # The per-pixel albedo is the render's kd (fixtures/scenes/photometric_sphere.json), read
    # back by oiiotool at a few pixels of the sphere.
    for x, y in [(48, 48), (30, 60), (65, 35)]:
        assert pixel(tmp_path / "fit/albedo.exr", x, y) == pytest.approx([0.7, 0.5, 0.3], rel=5e-3)


def test_one_kd_per_region_of_a_label_image(tmp_path):
    left = dict(JADE, kd=[0.7, 0.2, 0.2])
    right = dict(JADE, kd=[0.2, 0.3, 0.8])
    scene = tmp_path / "two.json"
    scene.write_text(json.dumps({
        "width": 96, "height": 64, "ambient": [1, 1, 1],
        "camera": {"type": "orthographic", "extent": 3.0},
        "lights": [{"type": "hemisphere", "count": 24, "min_elevation_deg": 30}],
        "objects": [{"shape": "sphere", "radius": 0.7, "subdivisions": 6, "material": m,
                     "transform": {"translate": [x, 0, 0]}}
                    for m, x in ((left, -0.75), (right, 0.75))],
        "output": {"format": "exr"}}))
    code, _, err = run("render", scene, "-o", tmp_path / "d", "--per-light")
    assert code == 0, err
    labels = tmp_path / "labels.png"
    subprocess.run(["oiiotool", "--pattern", "constant:color=0.2", "48x64", "1", "--pattern",
                    "constant:color=0.6", "48x64", "1", "--mosaic", "2x1", "-d", "uint8", "-o",
                    str(labels)], check=True)
    code, _, err = run("fit-material", tmp_path / "d", "--normals", tmp_path / "d", "--regions",
                       labels, "--model", "phong", "-o", tmp_path / "fit")
    assert code == 0, err
    report = json.loads((tmp_path / "fit/fit.json").read_text())
    assert report["region_values"] == pytest.approx([0.2, 0.6], abs=0.01)
    kd = report["models"][0]["kd"]
    assert kd[0] == pytest.approx(left["kd"], rel=5e-3)
    assert kd[1] == pytest.approx(right["kd"], rel=5e-3)
    assert all(se > 0 for se in report["models"][0]["kd_se"][0])


def test_normals_from_an_iphong_normals_output_folder(tmp_path):
    render_dataset(tmp_path / "d")
    code, _, err = run("normals", tmp_path / "d", "-o", tmp_path / "n")  # its material.json: exact
    assert code == 0, err
    code, stdout, err = run("fit-material", tmp_path / "d", "--normals", tmp_path / "n", "-o",
                            tmp_path / "fit")
    assert code == 0, err
    assert f"Normals: {tmp_path / 'n'}/normals.exr" in stdout
    material = json.loads((tmp_path / "fit/material.json").read_text())
    assert material["shininess"] == pytest.approx(20, rel=5e-3)
    assert material["ks"] == pytest.approx([0.4] * 3, rel=5e-3)


def test_sphere_normals_from_the_mask(tmp_path):
    render_dataset(tmp_path / "d")
    code, stdout, err = run("fit-material", tmp_path / "d", "--sphere", "-o", tmp_path / "fit",
                            "--model", "phong")
    assert code == 0, err
    assert "the sphere fitted to" in stdout
    material = json.loads((tmp_path / "fit/material.json").read_text())
    # The circle fitted to a 96-pixel mask is a pixel-level estimate: a few percent.
    assert material["shininess"] == pytest.approx(20, rel=0.1)
    assert material["ks"] == pytest.approx([0.4] * 3, rel=0.1)


def test_bad_inputs_one_line_nothing_written(tmp_path):
    render_dataset(tmp_path / "d")
    out = tmp_path / "out"
    # Normals of another size.
    small = tmp_path / "small.json"
    small.write_text(json.dumps({
        "width": 64, "height": 64, "lights": [{"type": "hemisphere", "count": 4}],
        "objects": [{"shape": "sphere", "radius": 0.8}], "output": {"format": "exr"}}))
    code, _, err = run("render", small, "-o", tmp_path / "small", "--per-light")
    assert code == 0, err
    assert_refused(tmp_path, ["fit-material", tmp_path / "d", "--normals",
                              tmp_path / "small/normals.exr", "-o", out], 1,
                   r"is 64x64, the images are 96x96", tmp_path / "small/normals.exr")
    # A normal map with NaN (x = sqrt(-1)).
    nan_map = tmp_path / "nan.exr"
    subprocess.run(["oiiotool", "--pattern", "constant:color=-1,0,1", "96x96", "3", "--powc",
                    "0.5", "-d", "float", "-o", str(nan_map)], check=True)
    assert_refused(tmp_path, ["fit-material", tmp_path / "d", "--normals", nan_map, "-o", out],
                   1, r"not finite", nan_map)
    # A mask with no pixels.
    black = tmp_path / "black.png"
    subprocess.run(["oiiotool", "--pattern", "constant:color=0", "96x96", "1", "-d", "uint8",
                    "-o", str(black)], check=True)
    assert_refused(tmp_path, ["fit-material", tmp_path / "d", "--normals", tmp_path / "d",
                              "--mask", black, "-o", out], 1, r"no pixel|empty|mask")
    # Too few lights for the model, saying how many are needed.
    three = tmp_path / "three.json"
    three.write_text(json.dumps({
        "width": 48, "height": 48, "lights": [{"type": "hemisphere", "count": 3}],
        "objects": [{"shape": "sphere", "radius": 0.8}], "output": {"format": "exr"}}))
    code, _, err = run("render", three, "-o", tmp_path / "three", "--per-light")
    assert code == 0, err
    assert_refused(tmp_path, ["fit-material", tmp_path / "three", "--normals", tmp_path / "three",
                              "-o", out], 1, r"3 light\(s\): the phong model needs at least 4")
    # Every lit observation saturated (8-bit codes within 0-1, so the level applies), no black
    # one left: refused before (no usable observation), and by the same line now.
    render_dataset(tmp_path / "png", "--format", "png")
    assert_refused(tmp_path, ["fit-material", tmp_path / "png", "--normals", tmp_path / "png",
                              "--saturation", "1e-9", "-o", out], 1,
                   r"every lit observation is at or above the saturation level 1e-09: nothing "
                   r"to fit", tmp_path / "png")
    # Neither or both geometries.
    assert_refused(tmp_path, ["fit-material", tmp_path / "d", "-o", out], 2, r"--normals N or --sphere")
    # A scene's material file without kd says how to give one.
    code, _, err = run("fit-material", tmp_path / "d", "--normals", tmp_path / "d", "-o",
                       tmp_path / "perpixel")
    assert code == 0, err
    scene = sphere_scene(tmp_path / "s.json", {"file": str(tmp_path / "perpixel/material.json")})
    assert_refused(tmp_path, ["render", scene, "-o", out], 1, r"has no kd.*add \"kd\"")


@pytest.mark.skipif(not (DATA / "diligent" / "ball").is_dir(),
                    reason=f"DiLiGenT ball not found under {DATA} (see ../shared/data/README.md)")
def test_diligent_ball_specular_beats_lambert_on_held_out_lights(tmp_path):
    ball = DATA / "diligent" / "ball"
    code, stdout, err = run("fit-material", ball, "--normals", ball, "-o", tmp_path / "fit",
                            "--json", timeout=300)
    assert code == 0, err
    report = json.loads(stdout)
    scores = {m["model"]: m["heldout_rmse"] for m in report["models"]}
    assert report["chosen"] in ("phong", "blinn-phong")
    assert scores["phong"] < 0.5 * scores["lambert"], scores
    assert scores["blinn-phong"] < 0.5 * scores["lambert"], scores
    chosen = next(m for m in report["models"] if m["model"] == report["chosen"])
    assert chosen["heldout_rmse_over_noise"] < 1.3  # predicted to within 30 % of the noise


@pytest.mark.skipif(not (DATA / "diligent-crop8" / "ball").is_dir(),
                    reason=f"DiLiGenT ball crop not found under {DATA} (see ../shared/data/README.md)")
def test_photos_saturated_wherever_lit_are_refused(tmp_path):
    """Every lit observation at or above --saturation, the shadows' black ones left: every model
    explained those with zero coefficients at a held-out error of 0 (a NaN noise ratio), and that
    material was written with exit 0."""
    ball = DATA / "diligent-crop8" / "ball"
    assert_refused(tmp_path, ["fit-material", ball, "--normals", ball, "--saturation", "1e-9",
                              "-o", tmp_path / "out"], 1,
                   r"every lit observation is at or above the saturation level 1e-09: nothing "
                   r"to fit", str(ball), ignore_warnings=True)
