"""The command line never loses or half-writes a user's files (issue 10, part 1).

Every test takes a snapshot (the bytes of every file) of what existed before a run and compares it
after: refused runs change nothing; accepted runs change only the files iphong wrote there before.
"""
import json
import os
import random
import resource
import shutil
import signal
import subprocess
import time

import pytest

from cli import (
    FIXTURES,
    IPHONG,
    PARTIAL,
    PHOTOMETRIC_SCENE,
    assert_one_line_error,
    assert_refused,
    binary_available,
    render_dataset,
    run,
    snapshot,
    user_copy,
)

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    path = tmp_path_factory.mktemp("render") / "sphere"
    render_dataset(path)
    return path


@pytest.fixture
def capture(rendered, tmp_path):
    """A user's capture folder (no iphong manifest): photos, light files, mask, ground truth."""
    return user_copy(rendered, tmp_path / "capture")


def normals_into(out, capture, *extra):
    """An `iphong normals` output that the test then works on."""
    code, _, err = run("normals", capture, "-o", out, *extra)
    assert code == 0, err
    return out


def manifest(folder):
    return json.loads((folder / ".iphong-manifest.json").read_text())["commands"]


def visible(folder):
    return {name for name in os.listdir(folder) if not name.startswith(".")}


def assert_complete(folder, staging_allowed=False):
    """Every file the manifest lists is there with its recorded size, nothing else is visible,
    and (unless allowed: a killed run's, hidden) nothing staged is left."""
    listed = {}
    for files in manifest(folder).values():
        listed.update(files)
    for name, entry in listed.items():
        assert (folder / name).stat().st_size == entry["size"], name
    assert visible(folder) == {name.split("/")[0] for name in listed}
    if not staging_allowed:
        assert not any(PARTIAL.search(name) for name in os.listdir(folder))
        assert not (folder / ".iphong-commit.json").exists()


# --- -o against the inputs -----------------------------------------------------------------


@pytest.mark.parametrize(
    "target, pattern",
    [
        ("capture", r"capture: is the input"),
        (".", r"contains the input"),
        ("capture/results", r"lies inside the input"),
    ],
)
def test_normals_output_over_its_input_is_refused(capture, tmp_path, target, pattern):
    assert_refused(tmp_path, ["normals", "capture", "-o", target], 4, pattern, cwd=tmp_path)


def test_render_into_the_scene_folder_is_refused(tmp_path):
    scene = tmp_path / "scene"
    scene.mkdir()
    shutil.copy(FIXTURES / "scenes/issue3_sphere.json", scene / "scene.json")
    assert_refused(tmp_path, ["render", "scene.json", "-o", "."],
                   4, r"\.: contains the input scene\.json", cwd=scene)


def test_render_output_may_not_hold_its_mesh(tmp_path):
    (tmp_path / "assets").mkdir()
    (tmp_path / "assets" / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"width": 32, "height": 32, "lights": [{"direction": [0, 0, 1]}],
                                 "objects": [{"shape": "mesh", "path": "assets/tri.obj"}]}))
    assert_refused(tmp_path, ["render", scene, "-o", tmp_path / "assets"],
                   4, r"assets: contains the input .*tri\.obj")
    code, _, err = run("render", scene, "-o", tmp_path / "out")
    assert code == 0, err


def test_output_over_a_file_is_refused(capture, tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    assert_refused(tmp_path, ["normals", capture, "-o", tmp_path / "notes.txt"],
                   4, r"notes\.txt: exists and is not a folder")


def test_a_dangling_or_looping_symlink_is_not_replaced(capture, tmp_path):
    os.symlink(tmp_path / "nowhere", tmp_path / "dangling")
    os.symlink("loop-b", tmp_path / "loop-a")
    os.symlink("loop-a", tmp_path / "loop-b")
    before = snapshot(tmp_path)
    for link in ("dangling", "loop-a"):
        code, _, err = run("normals", capture, "-o", tmp_path / link)
        assert_one_line_error(code, err, 4, r"is a symbolic link that leads nowhere")
    assert snapshot(tmp_path) == before
    assert os.readlink(tmp_path / "dangling") == str(tmp_path / "nowhere")


def test_a_folder_iphong_did_not_write_is_refused(capture, tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "normals.exr").write_text("my own file")
    assert_refused(tmp_path, ["normals", capture, "-o", tmp_path / "mine"],
                   4, r"mine: is not empty and was not written by iphong")


def test_an_empty_folder_is_used(capture, tmp_path):
    (tmp_path / "empty").mkdir()
    code, _, err = run("normals", capture, "-o", tmp_path / "empty")
    assert code == 0, err
    assert_complete(tmp_path / "empty")


# --- earlier outputs: --overwrite replaces only iphong's own files ---------------------------


def test_integrate_adds_its_files_beside_the_normals(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture)
    before = snapshot(out)
    code, _, err = run("integrate", out, "-o", out)
    assert code == 0, err
    after = snapshot(out)
    for name, digest in before.items():
        if name != ".iphong-manifest.json":
            assert after[name] == digest, f"{name} changed"
    assert {"height.exr", "mesh.ply", "height.png", "integrate.json"} <= visible(out)
    assert set(manifest(out)) == {"normals", "integrate"}
    assert_complete(out)


def test_overwrite_replaces_only_what_iphong_wrote(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture, "--integrate")
    (out / "notes.txt").write_text("my notes")
    (out / "extra").mkdir()
    (out / "extra" / "a.txt").write_text("more")
    before = snapshot(tmp_path)
    files_before = visible(out)
    code, _, err = run("normals", capture, "-o", out, "--fast")
    assert_one_line_error(code, err, 4,
                          r"holds an earlier `iphong normals` output; pass --overwrite")
    assert snapshot(tmp_path) == before
    code, _, err = run("normals", capture, "-o", out, "--fast", "--overwrite")
    assert code == 0, err
    assert (out / "notes.txt").read_text() == "my notes"
    assert (out / "extra" / "a.txt").read_text() == "more"
    # The earlier run's heights and mesh were its files: gone with it, as this run made none.
    surface = {"height.exr", "mesh.ply", "height.png", "integrate.json"}
    assert surface <= files_before
    assert visible(out) == files_before - surface
    assert set(manifest(out)) == {"normals"}
    assert not surface & set(manifest(out)["normals"])
    after = snapshot(tmp_path)
    for name, digest in before.items():
        if name.startswith("capture/") or name.startswith("out/extra") or name == "out/notes.txt":
            assert after[name] == digest, name


def test_a_changed_output_file_is_not_replaced(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture)
    (out / "metrics.json").write_text("edited by hand")
    assert_refused(tmp_path, ["normals", capture, "-o", out, "--overwrite"],
                   4, r"metrics\.json: changed since `iphong normals` wrote it")


def test_another_commands_output_is_refused(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture)
    assert_refused(tmp_path, ["render", PHOTOMETRIC_SCENE, "-o", out, "--overwrite"],
                   4, r"holds the output of `iphong normals`")


def test_error_map_is_a_new_file_unless_overwrite(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture)
    (tmp_path / "map.png").write_text("not iphong's")
    assert_refused(tmp_path,
                   ["eval", out / "normals.exr", capture, "--error-map", tmp_path / "map.png"],
                   4, r"map\.png: exists; pass --overwrite")
    assert_refused(tmp_path, ["eval", out / "normals.exr", capture, "--error-map",
                              out / "normals.exr", "--overwrite"],
                   4, r"normals\.exr: is an input")
    # Inside the dataset folder, even with --overwrite: its mask would have been replaced.
    assert_refused(tmp_path, ["eval", out / "normals.exr", capture, "--error-map",
                              capture / "mask.png", "--overwrite"],
                   4, r"mask\.png: lies inside the input")
    code, _, err = run("eval", out / "normals.exr", capture, "--error-map", tmp_path / "new.png")
    assert code == 0, err
    assert (tmp_path / "new.png").stat().st_size > 100
    assert not any(PARTIAL.search(name) for name in os.listdir(tmp_path))


# --- full disks and file-size limits: nothing half-written, the old state kept ---------------


def limit_file_size(blocks_bytes):
    def apply():
        resource.setrlimit(resource.RLIMIT_FSIZE, (blocks_bytes, blocks_bytes))
    return apply


def test_file_size_limit_fails_cleanly_and_writes_nothing(capture, tmp_path):
    assert_refused(tmp_path, ["normals", capture, "-o", tmp_path / "out"],
                   4, r"out/[a-z]+\.[a-z]+: cannot write: File too large",
                   preexec_fn=limit_file_size(10000))


def test_file_size_limit_during_overwrite_keeps_the_old_output(capture, tmp_path):
    out = normals_into(tmp_path / "out", capture)
    assert_refused(tmp_path, ["normals", capture, "-o", out, "--overwrite", "--integrate"],
                   4, r"cannot write: File too large", preexec_fn=limit_file_size(100000))


def mounted_tmpfs(folder, size):
    """A tmpfs of `size` at folder (root only; the test is skipped otherwise)."""
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    folder.mkdir()
    result = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)],
                            capture_output=True, text=True)
    if result.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {result.stderr.strip()}")
    return folder


@pytest.fixture
def tiny_disk(tmp_path):
    """A 24 kB disk: nothing iphong writes fits."""
    yield mounted_tmpfs(tmp_path / "disk", "24k")
    subprocess.run(["umount", str(tmp_path / "disk")], check=False)


@pytest.fixture
def small_disk(tmp_path):
    """A 200 kB disk: a 16x16 output fits, a 96x96 one with a mesh does not."""
    yield mounted_tmpfs(tmp_path / "disk", "200k")
    subprocess.run(["umount", str(tmp_path / "disk")], check=False)


@pytest.mark.parametrize("command", ["normals", "integrate", "render", "fit-material", "relight"])
def test_full_disk_fails_cleanly_and_writes_nothing(capture, tiny_disk, tmp_path, command):
    (tiny_disk / "keep.txt").write_text("already here")
    before = snapshot(tiny_disk)
    if command == "relight":
        code, _, err = run("normals", capture, "-o", tmp_path / "n")
        assert code == 0, err
    args = {
        "normals": ["normals", capture],
        "integrate": ["integrate", capture, "--allow-back-facing"],
        "render": ["render", PHOTOMETRIC_SCENE, "--per-light"],
        "fit-material": ["fit-material", capture, "--normals", capture],
        "relight": ["relight", tmp_path / "n", "--light", "0,0,1", "--exposure", "1"],
    }[command]
    out = tiny_disk / ("out.exr" if command == "relight" else "out")
    code, _, err = run(*args, "-o", out)
    assert_one_line_error(code, err, 4, r"disk/out[/.][\w.]+: cannot write: No space left on device")
    assert snapshot(tiny_disk) == before


def test_full_disk_while_replacing_an_output_keeps_it(capture, small_disk, tmp_path):
    tiny_disk = small_disk
    scene = tmp_path / "small.json"
    scene.write_text(json.dumps({"width": 16, "height": 16,
                                 "lights": [{"type": "hemisphere", "count": 4}],
                                 "objects": [{"shape": "sphere", "radius": 0.8}]}))
    code, _, err = run("render", scene, "-o", tmp_path / "small", "--per-light")
    assert code == 0, err
    code, _, err = run("normals", tmp_path / "small", "-o", tiny_disk / "out")
    assert code == 0, err
    assert_refused(tiny_disk,
                   ["normals", capture, "-o", tiny_disk / "out", "--overwrite", "--integrate"],
                   4, r"No space left on device")


# --- interrupted runs ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def slow_dataset(tmp_path_factory):
    """A dataset whose normals take a noticeable time (256x256, 48 lights), to interrupt."""
    folder = tmp_path_factory.mktemp("slow")
    scene = folder / "scene.json"
    scene.write_text(json.dumps({
        "width": 256, "height": 256, "ambient": [1, 1, 1],
        "lights": [{"type": "hemisphere", "count": 48, "min_elevation_deg": 20}],
        "objects": [{"shape": "sphere", "radius": 0.85, "subdivisions": 5,
                     "material": {"ka": 0.02, "kd": [0.7, 0.5, 0.3], "ks": 0.4,
                                  "shininess": 20}}],
        "output": {"format": "png"}}))
    code, _, err = run("render", scene, "-o", folder / "data", "--per-light")
    assert code == 0, err
    (folder / "data" / "material.json").unlink()  # coefficients unknown: the slower path
    return folder / "data"


def start(*args):
    return subprocess.Popen([str(IPHONG), *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def wait_for_staging(folder, process, timeout=30):
    """Waits until the run has started writing (its staging folder exists in `folder`): a signal
    before main() (the libraries' start-up takes ~0.4 s) would only test the default handler."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and process.poll() is None:
        if any(PARTIAL.search(name) for name in os.listdir(folder)):
            return
        time.sleep(0.01)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_removes_the_unfinished_output(slow_dataset, tmp_path, sig):
    before = snapshot(tmp_path)
    process = start("normals", slow_dataset, "-o", tmp_path / "out")
    wait_for_staging(tmp_path, process)
    time.sleep(0.1)
    process.send_signal(sig)
    _, err = process.communicate(timeout=60)
    if process.returncode == 0:
        pytest.skip("the run finished before the signal")
    assert process.returncode == -sig, err
    assert err.count("\n") == 1 and "interrupted" in err, err
    assert snapshot(tmp_path) == before


@pytest.fixture(scope="module")
def busy_scene(tmp_path_factory):
    """A per-light render that writes 32 pictures over a second or so, from several threads."""
    folder = tmp_path_factory.mktemp("busy")
    scene = folder / "scene.json"
    scene.write_text(json.dumps({
        "width": 320, "height": 320, "ambient": [1, 1, 1],
        "lights": [{"type": "hemisphere", "count": 32, "min_elevation_deg": 20}],
        "objects": [{"shape": "sphere", "radius": 0.85, "subdivisions": 5,
                     "material": {"ka": 0.02, "kd": [0.7, 0.5, 0.3], "ks": 0.4,
                                  "shininess": 20}}],
        "output": {"format": "png"}}))
    started = time.monotonic()
    code, _, err = run("render", scene, "-o", folder / "timing", "--per-light")
    assert code == 0, err
    return scene, time.monotonic() - started


@pytest.mark.parametrize("overwrite", [False, True], ids=["new", "overwrite"])
def test_interrupting_writers_at_any_point_leaves_the_folder_as_it_was(busy_scene, tmp_path,
                                                                         overwrite):
    """Signals at eight points of a render whose threads are writing pictures: the staging folder
    used to survive when a writer created a file while it was being removed (7 of 24 runs). Now
    every run leaves the folder as it was (or, when the signal came after the commit, complete and
    said so), prints one line and ends with the signal. A signal that lands before the program
    has started (a loaded machine: the libraries alone take about 0.4 s to load) ends it with
    nothing said and nothing written, which is allowed; most runs must say the line."""
    scene, duration = busy_scene
    out = tmp_path / "out"
    if overwrite:
        code, _, err = run("render", scene, "-o", out, "--per-light")
        assert code == 0, err
    signals = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
    said = unstarted = 0
    for i, fraction in enumerate([0.35, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95]):
        sig = signals[i % 3]
        before = snapshot(tmp_path)
        process = start("render", scene, "-o", out, "--per-light",
                        *(["--overwrite"] if overwrite else []))
        time.sleep(fraction * duration)
        process.send_signal(sig)
        _, err = process.communicate(timeout=60)
        if process.returncode == -sig and err == "":
            # Before its handlers were installed: the default action, and nothing written.
            assert snapshot(tmp_path) == before, sig
            unstarted += 1
        elif process.returncode != 0:  # 0: it finished first
            check_interrupted(process, sig, err, before, tmp_path, out)
            said += 1
        if not overwrite:
            shutil.rmtree(out, ignore_errors=True)
    assert said >= 1, (said, unstarted)


def check_interrupted(process, sig, err, before, tmp_path, out):
    assert process.returncode == -sig, err
    assert err.count("\n") == 1 and err.startswith("iphong: interrupted"), err
    if "after the output was complete" in err:
        assert (out / "render.json").exists()
    else:
        assert snapshot(tmp_path) == before, (sig, err)


def test_interrupt_during_overwrite_keeps_the_old_output(slow_dataset, tmp_path):
    out = tmp_path / "out"
    code, _, err = run("normals", slow_dataset, "-o", out, "--fast")
    assert code == 0, err
    before = snapshot(tmp_path)
    process = start("normals", slow_dataset, "-o", out, "--overwrite")
    wait_for_staging(out, process)
    time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    process.communicate(timeout=60)
    if process.returncode == 0:
        pytest.skip("the run finished before the signal")
    assert snapshot(tmp_path) == before


def test_sigkill_at_any_moment_leaves_the_old_or_the_new_output(slow_dataset, tmp_path):
    """SIGKILL cannot be caught: what is left is the old output, or the new one complete, or (in
    the microseconds between a commit's renames) a journal the next run finishes. Staging folders
    left by the killed run are hidden and removed by the next run."""
    out = tmp_path / "out"
    code, _, err = run("normals", slow_dataset, "-o", out, "--fast")
    assert code == 0, err
    old = snapshot(out)
    duration = time.monotonic()
    code, _, err = run("normals", slow_dataset, "-o", tmp_path / "timing")
    duration = time.monotonic() - duration
    rng = random.Random(10)
    outcomes = {"old": 0, "new": 0, "journal": 0}
    for _ in range(10):
        process = start("normals", slow_dataset, "-o", out, "--overwrite")
        time.sleep(rng.uniform(0.05, 1.2 * duration))
        process.kill()
        process.communicate(timeout=60)
        if (out / ".iphong-commit.json").exists():
            outcomes["journal"] += 1
            code, _, err = run("integrate", out, "-o", tmp_path / "reader", "--overwrite",
                               "--allow-back-facing")  # a reader finishes the commit first
            assert code == 0, err
        state = {k: v for k, v in snapshot(out).items() if not PARTIAL.search(k)}
        if state == old:
            outcomes["old"] += 1
        else:
            assert_complete(out, staging_allowed=True)
            outcomes["new"] += 1
            # Back to the old output for the next round.
            shutil.rmtree(out)
            code, _, err = run("normals", slow_dataset, "-o", out, "--fast")
            old = snapshot(out)
    # The next run removes what killed runs left staged.
    code, _, err = run("normals", slow_dataset, "-o", out, "--overwrite", "--fast")
    assert code == 0, err
    assert_complete(out)
    print(outcomes)


def test_sigkill_of_a_new_output_leaves_nothing_visible(slow_dataset, tmp_path):
    process = start("normals", slow_dataset, "-o", tmp_path / "out")
    time.sleep(0.3)
    process.kill()
    process.communicate(timeout=60)
    if (tmp_path / "out").exists():
        assert_complete(tmp_path / "out")
    leftovers = [name for name in os.listdir(tmp_path) if name != "out"]
    assert all(name.startswith(".out.iphong-partial-") for name in leftovers), leftovers
    code, _, err = run("normals", slow_dataset, "-o", tmp_path / "out", "--overwrite")
    assert code == 0, err
    assert os.listdir(tmp_path) == ["out"]
