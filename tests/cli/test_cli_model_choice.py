"""The model choice as metrics.json reports it: every model tried, with the pixels it was scored
on — the whole sample, or a quarter of it for a model dropped early for trailing the lowest by
four standard errors (solve/model_choice.h) — and the chosen model scored on the whole sample."""
import json
import math
import shutil
import subprocess

import pytest

from cli import IPHONG, binary_available, render_dataset, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")


def test_metrics_give_each_model_the_pixels_it_was_scored_on(tmp_path):
    render_dataset(tmp_path / "sphere")
    code, _, err = run("normals", tmp_path / "sphere", "--ignore-material", "-o", tmp_path / "out")
    assert code == 0, err
    choice = json.loads((tmp_path / "out" / "metrics.json").read_text())["model_choice"]
    pixels = choice["pixels"]
    assert pixels >= 200  # the race runs on samples of 4 x 50 pixels or more
    scores = choice["scores"]
    assert {s["heldout_pixels"] for s in scores} <= {pixels, math.ceil(pixels / 4)}
    chosen = [s for s in scores if s["model"] == choice["chosen"]
              and s["shininess"] == choice["shininess"] and s["heldout_pixels"] == pixels]
    assert chosen, scores
    lowest = min(s["heldout_cost"] for s in scores if s["heldout_pixels"] == pixels)
    dropped = [s for s in scores if s["heldout_pixels"] < pixels]
    assert dropped  # the glossy sphere's Lambert and broadest lobes trail clearly
    assert all(s["heldout_cost"] > lowest for s in dropped)


@pytest.mark.skipif(shutil.which("oiiotool") is None,
                    reason="oiiotool (openimageio-tools) not installed")
def test_no_pixel_test_gives_every_pixel_the_objects_model_and_changes_nothing_else(tmp_path):
    """--no-pixel-test: the pixels the test gave to Lambert are fitted with the object's model;
    every pixel the test left to that model keeps its normal bit for bit (a pixel depends on its
    own lights and the plan only), and metrics.json says the test was off."""
    render_dataset(tmp_path / "sphere")
    for out, flags in (("tested", []), ("untested", ["--no-pixel-test"])):
        code, _, err = run("normals", tmp_path / "sphere", "--ignore-material",
                           "-o", tmp_path / out, *flags)
        assert code == 0, err
    tested = json.loads((tmp_path / "tested" / "metrics.json").read_text())["model_choice"]
    untested = json.loads((tmp_path / "untested" / "metrics.json").read_text())["model_choice"]
    assert tested["pixel_test"] and not untested["pixel_test"]
    assert "pixels_choosing_lambert" not in untested and "pixels_choosing_it" not in untested
    assert tested["pixels_choosing_lambert"] > 0 and tested["pixels_choosing_it"] > 0, tested
    assert untested["chosen"] == tested["chosen"] and untested["shininess"] == tested["shininess"]
    assert (tmp_path / "tested" / "model.exr").exists()
    assert not (tmp_path / "untested" / "model.exr").exists()

    def largest_difference(*weigh):
        """The largest |tested - untested| of the normals, times `weigh` (oiiotool ops)."""
        done = subprocess.run(
            ["oiiotool", tmp_path / "tested" / "normals.exr", tmp_path / "untested" / "normals.exr",
             "--absdiff", *weigh, "--printstats", "-o", tmp_path / "difference.exr"],
            capture_output=True, text=True, check=True)
        line = next(x for x in done.stdout.splitlines() if "Stats Max:" in x)
        return max(float(v) for v in line.split(":")[1].split()[:3])

    # model.exr: 1 where the object's model won, 0 Lambert, -1 no normal; (m - 0.5) clamped to
    # [0, 1] keeps the first alone.
    kept = [tmp_path / "tested" / "model.exr", "--subc", "0.5", "--clamp:min=0:max=1",
            "--ch", "0,0,0", "--mul"]
    assert largest_difference(*kept) == 0
    assert largest_difference() > 1e-4  # the Lambert pixels were refitted
