"""Progress in a log: a run piped to a file (not a terminal) printed nothing until the end. With
--progress always it prints plain lines (stage, percent, elapsed, estimate): a stage's first at
once, then every 2 s, and a closing line per stage; auto does so only past 10 s (so short runs stay quiet); never and --quiet
print none."""
import json
import re

import pytest

from cli import IPHONG, binary_available, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")

LINE = re.compile(r"^iphong: (render|write): \d+%, \d+ s(, about \d+ s left)?$")
DONE = re.compile(r"^iphong: (render|write): done, \d+ s$")


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("progress") / "scene.json"
    path.write_text(json.dumps({
        "width": 560, "height": 560, "ambient": [1, 1, 1],
        "lights": [{"type": "hemisphere", "count": 40, "min_elevation_deg": 20}],
        "objects": [{"shape": "sphere", "radius": 0.85, "subdivisions": 5,
                     "material": {"ka": 0.02, "kd": [0.7, 0.5, 0.3], "ks": 0.4,
                                  "shininess": 20}}],
        "output": {"format": "png"}}))
    return path


def test_progress_always_prints_plain_lines_in_a_log(scene, tmp_path):
    code, _, err = run("render", scene, "-o", tmp_path / "out", "--per-light", "--progress",
                       "always")
    assert code == 0, err
    lines = err.splitlines()
    assert any(LINE.match(line) for line in lines), err
    assert any(DONE.match(line) for line in lines), err
    assert all(LINE.match(line) or DONE.match(line) for line in lines), err  # nothing else
    assert "\r" not in err and "\033" not in err  # no terminal codes in a log


def test_progress_always_shows_a_stage_however_short(tmp_path):
    # A stage shorter than the 2 s between lines once printed nothing at all.
    scene = tmp_path / "tiny.json"
    scene.write_text(json.dumps({
        "width": 32, "height": 32, "lights": [{"type": "hemisphere", "count": 3}],
        "objects": [{"shape": "sphere", "radius": 0.8}], "output": {"format": "png"}}))
    code, _, err = run("render", scene, "-o", tmp_path / "out", "--per-light", "--progress",
                       "always")
    assert code == 0, err
    lines = err.splitlines()
    for stage in ("render", "write"):
        assert any(LINE.match(line) and f" {stage}: " in line for line in lines), err
        assert sum(DONE.match(line) is not None and f" {stage}: " in line for line in lines) == 1
    assert all(LINE.match(line) or DONE.match(line) for line in lines), err


@pytest.mark.parametrize("flags", [["--progress", "never"], ["--quiet"], []])
def test_short_runs_and_never_stay_quiet(scene, tmp_path, flags):
    code, _, err = run("render", scene, "-o", tmp_path / "out", "--per-light", *flags)
    assert code == 0 and err == "", err


def test_progress_takes_only_its_three_values(scene, tmp_path):
    code, _, err = run("render", scene, "-o", tmp_path / "out", "--progress", "sometimes")
    assert code == 2 and "--progress: sometimes not in {auto,always,never}" in err, err
