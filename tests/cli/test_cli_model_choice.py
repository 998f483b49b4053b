"""The model choice as metrics.json reports it: every model tried, with the pixels it was scored
on — the whole sample, or a quarter of it for a model dropped early for trailing the lowest by
four standard errors (solve/model_choice.h) — and the chosen model scored on the whole sample."""
import json
import math

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
