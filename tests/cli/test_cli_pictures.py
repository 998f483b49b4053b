"""Pictures people compare side by side: --error-range puts error maps of different runs on one
colour scale (each used to pick its own, so a 0.5 deg map and a 5 deg map looked alike)."""
import shutil
import subprocess

import pytest

from cli import IPHONG, binary_available, render_dataset, run

pytestmark = [
    pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}"),
    pytest.mark.skipif(shutil.which("oiiotool") is None or shutil.which("idiff") is None,
                       reason="oiiotool and idiff (OpenImageIO's tools) not installed"),
]


def legend(picture, out):
    """The scale bar: everything right of the 96-pixel-wide map."""
    subprocess.run(["oiiotool", str(picture), "--cut", "96,0,10000,95", "-o", str(out)],
                   check=True, capture_output=True)
    return out


def same_pixels(a, b):
    return subprocess.run(["idiff", str(a), str(b)], capture_output=True).returncode == 0


def test_error_range_puts_maps_of_different_runs_on_one_scale(tmp_path):
    data = tmp_path / "sphere"
    render_dataset(data)
    # Two runs whose errors differ a lot: the default and a Lambert fit of a shiny sphere.
    for name, flags in (("phong", []), ("lambert", ["--model", "lambert", "--ignore-material"])):
        for scale in ("own", "fixed"):
            extra = ["--error-range", "10"] if scale == "fixed" else []
            code, _, err = run("normals", data, "-o", tmp_path / f"{name}-{scale}", *flags, *extra)
            assert code == 0, err
    bars = {key: legend(tmp_path / key / "error.png", tmp_path / f"{key}-bar.png")
            for key in ("phong-own", "lambert-own", "phong-fixed", "lambert-fixed")}
    assert not same_pixels(bars["phong-own"], bars["lambert-own"])  # each picked its own
    assert same_pixels(bars["phong-fixed"], bars["lambert-fixed"])
    # eval's picture takes the same flag and draws the same scale.
    code, _, err = run("eval", tmp_path / "lambert-own" / "normals.exr", data, "--error-map",
                       tmp_path / "eval.png", "--error-range", "10")
    assert code == 0, err
    assert same_pixels(legend(tmp_path / "eval.png", tmp_path / "eval-bar.png"),
                       bars["phong-fixed"])
    code, _, err = run("eval", tmp_path / "lambert-own" / "normals.exr", data, "--error-range", "0")
    assert code == 2 and "--error-range" in err, err
