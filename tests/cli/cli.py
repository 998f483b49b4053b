"""Running the iphong command line from tests: the binary, snapshots of folders, one-line errors.

The command-line tests need only the binary ($IPHONG_BUILD_DIR/iphong, default build/iphong), not
the Python module, so they also run against a sanitizer build (scripts/sanitize.sh). pytest puts
this folder on the path (no conftest here: it would shadow tests/python's), so tests import it
as `cli`."""
import hashlib
import os
import pathlib
import re
import shutil
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
BUILD = pathlib.Path(os.environ.get("IPHONG_BUILD_DIR", ROOT / "build"))
IPHONG = BUILD / "iphong"
PHOTOMETRIC_SCENE = FIXTURES / "scenes" / "photometric_sphere.json"
PARTIAL = re.compile(r"\.iphong-partial-\d+-\d+")


def run(*args, cwd=None, env=None, timeout=120, preexec_fn=None):
    """Runs iphong; returns (exit code, stdout, stderr)."""
    result = subprocess.run(
        [str(IPHONG), *map(str, args)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=preexec_fn,
    )
    return result.returncode, result.stdout, result.stderr


def snapshot(root):
    """Every file and folder under root, hidden ones included: path -> sha256 (None: a folder)."""
    root = pathlib.Path(root)
    state = {}
    for path in sorted(root.rglob("*")):
        relative = str(path.relative_to(root))
        if path.is_dir() and not path.is_symlink():
            state[relative + "/"] = None
        elif path.is_file():
            state[relative] = hashlib.sha256(path.read_bytes()).hexdigest()
        else:  # a FIFO or a socket: reading would block
            state[relative] = "special"
    return state


def assert_one_line_error(code, stderr, expected_code, pattern, names=None):
    """A clean failure: the exit code, exactly one stderr line 'iphong: error: ...' matching
    pattern, naming `names` when given."""
    lines = stderr.splitlines()
    assert code == expected_code, f"exit {code}, expected {expected_code}; stderr: {stderr!r}"
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}: {stderr!r}"
    assert lines[0].startswith("iphong: error: "), lines[0]
    assert re.search(pattern, lines[0]), f"{pattern!r} not in {lines[0]!r}"
    if names is not None:
        assert str(names) in lines[0], f"{names} not named in {lines[0]!r}"


def assert_refused(root, args, expected_code, pattern, names=None, ignore_warnings=False,
                   **run_options):
    """Runs `iphong ARGS`: it must fail cleanly (assert_one_line_error; warnings before the error
    left out when asked) and leave every file under root, byte for byte, as it was."""
    before = snapshot(root)
    code, _, err = run(*args, **run_options)
    if ignore_warnings:
        err = "".join(line + "\n" for line in err.splitlines()
                      if not line.startswith("iphong: warning: "))
    assert_one_line_error(code, err, expected_code, pattern, names)
    assert snapshot(root) == before


def render_dataset(path, *extra):
    """The 12-light, 96x96 photometric sphere (ground truth and material.json) at path."""
    code, _, err = run("render", PHOTOMETRIC_SCENE, "-o", path, "--per-light", *extra)
    assert code == 0, err


def user_copy(src, dst):
    """A copy of an iphong output as a user's own folder: without iphong's manifest."""
    shutil.copytree(src, dst)
    (pathlib.Path(dst) / ".iphong-manifest.json").unlink()
    return pathlib.Path(dst)


def binary_available():
    return IPHONG.exists()
