"""`iphong normals` in bands of rows (--band-rows, or whenever the capture does not fit in
--memory-limit): the same maps as the in-memory run, value for value; a memory limit too small
for one row, a file that fails to decode half way and options that need the whole capture are
one line each, and nothing is written."""
import json
import os
import pathlib
import shutil
import subprocess

import pytest

from cli import IPHONG, assert_refused, binary_available, render_dataset, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")
OIIOTOOL = shutil.which("oiiotool")
ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
CAT = DATA / "diligent-crop8" / "cat"


def identical(a, b):
    """oiiotool's verdict on two images with no tolerance at all."""
    done = subprocess.run([OIIOTOOL, "--fail", "0", "--warn", "0", str(a), str(b), "--diff"],
                          capture_output=True, text=True)
    return done.returncode == 0


@pytest.fixture(scope="module")
def captures(tmp_path_factory):
    root = tmp_path_factory.mktemp("bands")
    render_dataset(root / "exr")
    render_dataset(root / "png", "--format", "png", "--bits", "16")
    return root


@pytest.mark.skipif(OIIOTOOL is None, reason="oiiotool (openimageio-tools) not installed")
@pytest.mark.parametrize("layout,rows,flags", [
    ("exr", 5, ["--ignore-material"]),    # model chosen, ks per pixel, model.exr
    ("png", 13, []),                      # known material.json
    ("png", 7, ["--model", "lambert"]),   # Woodham
    ("exr", 4, ["--ignore-material", "--crop", "8,4,80,90", "--downscale", "2"]),
])
def test_bands_equal_the_whole(captures, tmp_path, layout, rows, flags):
    data = captures / layout
    code, _, err = run("normals", data, "-o", tmp_path / "whole", "-q", *flags)
    assert code == 0, err
    code, out, err = run("normals", data, "-o", tmp_path / "bands", "--band-rows", rows,
                         "--json", *flags)
    assert code == 0, err
    metrics = json.loads(out)
    assert metrics["bands"]["rows"] == rows
    whole = json.loads((tmp_path / "whole" / "metrics.json").read_text())
    assert metrics["model"] == whole["model"]
    assert metrics["pixels"] == whole["pixels"]
    # The solve's report is the same too: the model choice with every candidate's score, the
    # weights by N.L, the flagged pixels (bands once left the scores and code step out).
    for key in ("model_choice", "shading_weights", "dark_pixels", "underdetermined_pixels",
                "material", "specular_note", "iterations"):
        assert metrics.get(key) == whole.get(key), key
    assert "scores" in whole.get("model_choice", {"scores": 0}), whole.get("model_choice")
    maps = ["normals.exr", "normals.png", "albedo.exr", "residual.exr"]
    maps += [m for m in ("specular.exr", "model.exr") if (tmp_path / "whole" / m).exists()]
    for name in maps:
        assert (tmp_path / "bands" / name).exists(), name
        assert identical(tmp_path / "whole" / name, tmp_path / "bands" / name), name
    if (tmp_path / "whole" / "material.json").exists():
        a = json.loads((tmp_path / "whole" / "material.json").read_text())
        b = json.loads((tmp_path / "bands" / "material.json").read_text())
        assert a["ks"] == b["ks"] and a["shininess"] == b["shininess"]


@pytest.mark.skipif(OIIOTOOL is None, reason="oiiotool (openimageio-tools) not installed")
@pytest.mark.parametrize("how", [["--trim"], ["--tile", "16", "16"]])
def test_exrs_as_other_tools_store_them(captures, tmp_path, how):
    """EXRs cropped to the pixels each light lit (a data window inside the display window, as
    compositors write them) and tiled EXRs: the normals of the capture as rendered, whole and in
    bands. Before, trimmed photos were read at their data window's size (the mask "is 96x96, the
    images are 82x82"), their bands could not be decoded, and bands of tiled ones crashed."""
    data = tmp_path / "data"
    shutil.copytree(captures / "exr", data)
    for image in sorted(data.glob("0*.exr")):
        subprocess.run([OIIOTOOL, str(captures / "exr" / image.name), *how, "-o", str(image)],
                       check=True)
    if how == ["--trim"]:
        stored = subprocess.run([OIIOTOOL, "--info", "-v", str(data / "001.exr")],
                                capture_output=True, text=True, check=True).stdout
        assert "pixel data origin: x=0, y=0" not in stored, stored  # the case this is about
    # The reading is compared, so the fastest solve serves (Lambert at distant lights).
    lambert = ["--model", "lambert", "--light-distance", "inf"]
    code, _, err = run("normals", captures / "exr", "-o", tmp_path / "plain", "-q", *lambert)
    assert code == 0, err
    for name, flags in [("whole", []), ("bands", ["--band-rows", "5"])]:
        code, _, err = run("normals", data, "-o", tmp_path / name, "-q", *lambert, *flags)
        assert code == 0, (name, err)
        for m in ("normals.exr", "albedo.exr"):
            assert identical(tmp_path / "plain" / m, tmp_path / name / m), (name, m)


def test_bands_say_the_ground_truth_is_not_compared(captures, tmp_path):
    """Bands never hold the whole ground truth: the Read line named it as if it were used."""
    code, out, err = run("normals", captures / "png", "-o", tmp_path / "bands", "--band-rows", "16")
    assert code == 0, err
    read = [line for line in out.splitlines() if line.startswith("Read ")]
    assert len(read) == 1 and "; ground truth Normal_gt." in read[0], out
    note = json.loads((tmp_path / "bands" / "metrics.json").read_text())["ground_truth_note"]
    assert f" ({note})" in read[0] and note.startswith("not compared in bands"), (read, note)


def test_memory_limit_chooses_bands(captures, tmp_path):
    """A limit between one row's need and the whole capture's: bands, within the limit."""
    code, out, err = run("normals", captures / "png", "-o", tmp_path / "one", "--json",
                         "--band-rows", "1")
    assert code == 0, err
    one = json.loads(out)["bands"]
    limit = (one["estimated_band_bytes"] + one["estimated_whole_bytes"]) / 2
    code, out, err = run("normals", captures / "png", "-o", tmp_path / "out", "--json",
                         "--memory-limit", f"{limit / 1e9:.6f}")
    assert code == 0, err
    bands = json.loads(out)["bands"]
    assert 1 < bands["count"] < 96
    assert bands["estimated_band_bytes"] <= limit < bands["estimated_whole_bytes"]


def test_refusals_write_nothing(captures, tmp_path):
    shutil.copytree(captures / "png", tmp_path / "ds")
    (tmp_path / "ds" / ".iphong-manifest.json").unlink()
    out = tmp_path / "out"
    # Less than one row needs: exit 3 with the figure.
    assert_refused(tmp_path, ["normals", tmp_path / "ds", "-o", out, "--memory-limit", "0.19"], 3,
                   r"one row of 96x1 x 12 images needs .* more than the memory limit")
    # Options that need the whole capture.
    for flag in ("--integrate", "--estimate-intensities"):
        assert_refused(tmp_path, ["normals", tmp_path / "ds", "-o", out, "--band-rows", "8", flag],
                       1, r"in bands of rows .*" + flag)
    # An image cut off half way: found only when its rows are decoded, named with the rows.
    image = tmp_path / "ds" / "007.png"
    image.write_bytes(image.read_bytes()[: image.stat().st_size * 2 // 3])
    assert_refused(tmp_path, ["normals", tmp_path / "ds", "-o", out, "--band-rows", "8"], 1,
                   r"007\.png: cannot decode rows \d+\.\.\d+", names=image)


def test_one_image_is_refused_when_its_global_solve_would_not_fit(captures, tmp_path):
    """One or two images are solved whole, at about 4 KB a masked pixel: the estimate counts it,
    so a limit that holds the capture but not the solve is exit 3 with the figure, not a run that
    outgrows it (a 12-megapixel photo would need some 45 GB). The sphere's 5 700 pixels need
    about 23 MB more than the capture's 203 MB."""
    ds = tmp_path / "ds"
    shutil.copytree(captures / "png", ds)
    (ds / ".iphong-manifest.json").unlink()
    (ds / "filenames.txt").write_text("001.png\n")
    for name in ("light_directions.txt", "light_intensities.txt"):
        (ds / name).write_text((ds / name).read_text().splitlines()[0] + "\n")
    assert_refused(tmp_path, ["normals", ds, "-o", tmp_path / "out", "--memory-limit", "0.215"], 3,
                   r"x 1 images would need 2[23]\d MB whole\): one or two images are solved whole")
    code, _, err = run("normals", ds, "-o", tmp_path / "out", "-q", "--memory-limit", "0.25")
    assert code == 0, err


@pytest.mark.skipif(OIIOTOOL is None, reason="oiiotool (openimageio-tools) not installed")
@pytest.mark.skipif(not CAT.is_dir(), reason=f"DiLiGenT cat crop not found at {CAT}")
def test_bands_choose_the_same_light_distance(tmp_path):
    """DiLiGenT's LEDs are about a metre from the cat: in memory a finite effective distance is
    chosen and the near passes run; in bands the same, each pass over the bands, with the same
    maps bit for bit (they were the distant solve's before, up to 0.3 degrees apart)."""
    code, out, err = run("normals", CAT, "-o", tmp_path / "whole", "--json", "-q")
    assert code == 0, err
    whole = json.loads(out)
    assert whole["effective_distance"]["distance_px"] != "inf"
    code, out, err = run("normals", CAT, "-o", tmp_path / "bands", "--band-rows", "9", "--json")
    assert code == 0, err
    bands = json.loads(out)
    assert bands["bands"]["effective_distance_sought"]
    assert bands["effective_distance"]["distance_px"] == whole["effective_distance"]["distance_px"]
    assert len(bands["effective_distance"]["passes"]) == len(whole["effective_distance"]["passes"])
    for name in ["normals.exr", "albedo.exr", "residual.exr", "specular.exr", "model.exr"]:
        assert identical(tmp_path / "whole" / name, tmp_path / "bands" / name), name

    # A limit that leaves a row but not the whole normal map beside it: distant lights, said.
    b = bands["bands"]
    one_row = b["estimated_band_bytes"] - (b["rows"] - 1) * b["estimated_row_bytes"]
    limit = one_row - b["effective_distance_bytes"] / 2
    code, out, err = run("normals", CAT, "-o", tmp_path / "tight", "--json",
                         "--memory-limit", f"{limit / 1e9:.9f}")
    assert code == 0, err
    tight = json.loads(out)
    assert not tight["bands"]["effective_distance_sought"]
    assert "effective_distance" not in tight
    assert "solved with distant lights" in err and "--memory-limit" in err
