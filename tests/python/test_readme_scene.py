"""The rendering guide's example scene (docs/guides/rendering.md) is the fixture it shows, and renders a picture a person would want:
nothing blown out, every object inside the frame."""
import json
import re

import numpy as np

import iphong
from conftest import FIXTURES, ROOT

SCENE = FIXTURES / "scenes" / "readme_example.json"


def test_the_readme_shows_the_fixture():
    readme = (ROOT / "docs" / "guides" / "rendering.md").read_text()
    blocks = [json.loads(b) for b in re.findall(r"```json\n(.*?)```", readme, re.S)]
    assert json.loads(SCENE.read_text()) in blocks


def test_the_example_renders_well_exposed_and_in_frame():
    out = iphong.render(SCENE)
    image, mask = out["image"], out["mask"]
    inside = image[mask]
    assert np.percentile(inside.max(axis=1), 99) < 1.0  # at most 1% of the pixels clip
    assert np.mean(inside.max(axis=1) >= 1.0) < 0.01
    assert np.median(inside.max(axis=1)) > 0.15  # and not dark either
    # Nothing cut by the frame: no object pixel on the border.
    assert not (mask[0].any() or mask[-1].any() or mask[:, 0].any() or mask[:, -1].any())


def test_the_readme_links_resolve():
    """The front page links into the docs: every relative link names a file that exists."""
    readme = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(([^)#:]+)(?:#[^)]*)?\)", readme)
    assert len(links) > 20
    missing = [link for link in links if not (ROOT / link).exists()]
    assert not missing, missing
