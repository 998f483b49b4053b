"""The README's transcript of `iphong demo` is what the demo prints (its timings aside): a figure
in the README that drifted from the program (the normals' mean read 0.046° for 0.045°) fails
here."""
import re

import pytest

from cli import IPHONG, ROOT, binary_available, run

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")

TIMINGS = re.compile(r"\d+ ms")


def readme_transcript():
    text = (ROOT / "README.md").read_text()
    match = re.search(r"^\$ build/iphong demo\n(.*?)^```", text, re.S | re.M)
    assert match, "README.md has no transcript of `build/iphong demo`"
    return match.group(1)


def test_the_readme_shows_what_the_demo_prints(tmp_path):
    code, out, err = run("demo", cwd=tmp_path)
    assert code == 0, err
    expected = TIMINGS.sub("N ms", readme_transcript()).splitlines()
    printed = TIMINGS.sub("N ms", out).splitlines()
    assert printed == expected
