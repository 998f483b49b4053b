"""A corpus of bad inputs, one or more per class of issue 10: every one ends in exactly one line
`iphong: error: FILE[:LINE]: ...` naming the file, the documented exit code, nothing written and
nothing changed — never a crash, a hang, a traceback or a library's own lines.

Datasets are made at test time from a rendered one and then broken; scenes are the small files in
fixtures/bad/scenes.
"""
import json
import math
import os
import resource
import shutil
import struct
import subprocess
import zlib

import pytest

from cli import (
    FIXTURES,
    IPHONG,
    assert_refused,
    binary_available,
    run,
    user_copy,
)

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")

BAD_SCENES = FIXTURES / "bad" / "scenes"


def np_cos(step):
    return math.cos(0.2 + 0.1 * step)


def np_sin(step):
    return math.sin(0.2 + 0.1 * step)


def png_header(width, height):
    """A valid PNG signature and IHDR that declare width x height, then almost no data."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\0" * 16)) + chunk(b"IEND", b""))


def grey_png(width, height, value=255):
    rows = b"".join(b"\0" + bytes([value]) * width for _ in range(height))
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bad") / "sphere"
    code, _, err = run("render", FIXTURES / "scenes" / "photometric_sphere.json", "-o", folder,
                       "--per-light", "--format", "png")
    assert code == 0, err
    return folder


def replace_line(path, index, text):
    lines = path.read_text().splitlines()
    lines[index] = text
    path.write_text("\n".join(lines) + "\n")


# Each case breaks a copy of the dataset `ds` and returns the exit code, a pattern the one line
# must match and the file it must name (relative to the work folder).
def short_light_file(ds):
    lines = (ds / "light_directions.txt").read_text().splitlines()
    (ds / "light_directions.txt").write_text("\n".join(lines[:11]) + "\n")
    return 1, r"has 11 lines for 12 images", "ds/light_directions.txt"


def nan_light(ds):
    replace_line(ds / "light_directions.txt", 2, "nan 0 1")
    return 1, r":3: not a finite number", "ds/light_directions.txt:3"


def huge_intensity(ds):
    replace_line(ds / "light_intensities.txt", 1, "1e308 1 1")
    return 1, r"light intensities must be between 1e-30 and 1e30", "ds/light_intensities.txt:2"


def tiny_intensity(ds):
    # 1e-300 went through: the observations divided by it overflow float (albedo inf, 45 deg off).
    replace_line(ds / "light_intensities.txt", 1, "1e-300 1 1")
    return 1, r"light intensities must be between 1e-30 and 1e30", "ds/light_intensities.txt:2"


def zero_direction(ds):
    replace_line(ds / "light_directions.txt", 4, "0 0 0")
    return 1, r"zero light direction", "ds/light_directions.txt:5"


def denormal_direction(ds):
    """1e-320 0 0 used to be normalized to (1, 0, 0): a slip, not a direction."""
    replace_line(ds / "light_directions.txt", 2, "1e-320 0 0")
    return 1, r"light direction has length 1e-320: not a direction", "ds/light_directions.txt:3"


def garbage_light_file(ds):
    (ds / "light_directions.txt").write_bytes(bytes(range(256)) * 4)
    return 1, r"expected 3 numbers|not a text file", "ds/light_directions.txt"


def fifo_light_file(ds):
    (ds / "light_intensities.txt").unlink()
    os.mkfifo(ds / "light_intensities.txt")  # reading it would block forever
    return 1, r"not a regular file", "ds/light_intensities.txt"


def folder_as_light_file(ds):
    (ds / "light_directions.txt").unlink()
    (ds / "light_directions.txt").mkdir()
    return 1, r"is a folder, not a file", "ds/light_directions.txt"


def coplanar_lights(ds):
    (ds / "light_directions.txt").write_text("".join(f"{np_cos(a)} 0 {np_sin(a)}\n"
                                                     for a in range(12)))
    return 1, r"the 12 light directions lie in one plane", "ds/light_directions.txt"


def black_mask(ds):
    (ds / "mask.png").write_bytes(grey_png(96, 96, 0))
    return 1, r"selects no pixel", "ds/mask.png"


def empty_filenames(ds):
    (ds / "filenames.txt").write_text("\n\n")
    return 1, r"lists no images", "ds/filenames.txt"


def missing_filenames(ds):
    # Without filenames.txt the folder's images are paired with the lights in natural order,
    # so an image too few is a count mismatch naming what was found.
    (ds / "filenames.txt").unlink()
    (ds / "002.png").unlink()
    return 1, r"has 12 lights, but .* holds 11 images \(001\.png \.\.\. 012\.png\)", \
        "ds/light_directions.txt"


def as_rti(ds, lines):
    """The dataset without its DiLiGenT lists, its lights in an RTI .lp."""
    for name in ["filenames.txt", "light_directions.txt", "light_intensities.txt"]:
        (ds / name).unlink()
    (ds / "capture.lp").write_text("\n".join(lines) + "\n")


def zero_count_lp(ds):
    as_rti(ds, ["0"])
    return 1, r"lists no lights", "ds/capture.lp"


def lp_names_a_missing_image(ds):
    as_rti(ds, ["3", "001.png 0 0 1", "C:\\shots\\IMG_9.png 0.6 0 0.8", "003.png 0 0.6 0.8"])
    # The .lp's folder is the capture's: named once (it read "in neither ds nor ds").
    return 1, r"names C:\\shots\\IMG_9\.png, which is not in \S*ds$", "ds/capture.lp"


def fifo_lp_file(ds):
    """A pipe named capture.lp was passed over as not a file, and the error named the folder."""
    as_rti(ds, ["1", "001.png 0 0 1"])
    (ds / "capture.lp").unlink()
    os.mkfifo(ds / "capture.lp")  # reading it would block forever
    return 1, r"not a regular file", "ds/capture.lp"


def two_lp_files(ds):
    as_rti(ds, ["1", "001.png 0 0 1"])
    (ds / "other.lp").write_text("1\n001.png 0 0 1\n")
    return 1, r"holds several \.lp files", "ds"


def missing_image(ds):
    (ds / "002.png").unlink()
    return 1, r"no such file", "ds/002.png"


def corrupt_png(ds):
    data = (ds / "002.png").read_bytes()
    (ds / "002.png").write_bytes(data[:60] + b"\0" * 40 + data[100:200])  # libpng complains aloud
    return 1, r".", "ds/002.png"


def forged_png_header(ds):
    (ds / "003.png").write_bytes(png_header(100000, 100000))
    return 1, r"declares 100000x100000 pixels but has only \d+ bytes: truncated or corrupt", \
        "ds/003.png"


def image_of_another_size(ds):
    (ds / "004.png").write_bytes(grey_png(8, 8))
    return 1, r"is 8x8, but mask\.png is 96x96", "ds/004.png"


def small_mask(ds):
    (ds / "mask.png").write_bytes(grey_png(20, 20))
    return 1, r"mask\.png: is 20x20, the images are 96x96", "ds/mask.png"


def truncated_ground_truth(ds):
    data = (ds / "Normal_gt.mat").read_bytes()
    (ds / "Normal_gt.mat").write_bytes(data[: len(data) // 2])
    return 1, r"truncated", "ds/Normal_gt.mat"


def zero_ground_truth(ds):
    (ds / "Normal_gt.mat").unlink()
    (ds / "normal.txt").write_text("0 0 0\n" * (96 * 96))
    return 1, r"holds no normal \(all zeros\)", "ds/normal.txt"


def bad_material(ds):
    (ds / "material.json").write_text('{"model": "phong", "ks": [0.1, -0.2, 0.1]}')
    return 1, r"material ks must be finite and >= 0", "ds/material.json"


def overflowing_material(ds):
    (ds / "material.json").write_text('{"model": "phong", "shininess": 1e400}')
    return 1, r"parse error: number overflow", "ds/material.json"


def encoding_not_a_string(ds):
    meta = json.loads((ds / "render.json").read_text())
    meta["encoding"] = 5
    (ds / "render.json").write_text(json.dumps(meta))
    return 1, r"render\.json: encoding: expected a string", "ds/render.json"


def one_image_unknown_albedo(ds):
    (ds / "filenames.txt").write_text("001.png\n")
    for name in ("light_directions.txt", "light_intensities.txt"):
        (ds / name).write_text((ds / name).read_text().splitlines()[0] + "\n")
    (ds / "material.json").unlink()
    return 1, r"with 1 image\(s\) the coefficients must be known", "ds/material.json"


DATASET_CASES = [
    short_light_file, nan_light, huge_intensity, tiny_intensity, zero_direction, denormal_direction,
    garbage_light_file,
    coplanar_lights, black_mask,
    fifo_light_file, folder_as_light_file, empty_filenames, missing_filenames, missing_image,
    zero_count_lp, lp_names_a_missing_image, fifo_lp_file, two_lp_files,
    corrupt_png, forged_png_header, image_of_another_size, small_mask, truncated_ground_truth,
    zero_ground_truth, bad_material, overflowing_material, encoding_not_a_string,
    one_image_unknown_albedo,
]


@pytest.mark.parametrize("case", DATASET_CASES, ids=lambda f: f.__name__)
def test_bad_dataset(rendered, tmp_path, case):
    ds = user_copy(rendered, tmp_path / "ds")
    code, pattern, named = case(ds)
    assert_refused(tmp_path, ["normals", "ds", "-o", "out"], code, pattern, named, cwd=tmp_path,
                   timeout=60)


# Scenes: (file, exit code, pattern). plane_size_1e10 is not an error: it renders (it crashed).
SCENE_CASES = [
    ("cylinder_radius_1e19.json", 1, r"objects\[0\]: coordinates beyond 1e15 scene units"),
    ("width_wraps_32bit.json", 1, r"width: integer out of range"),
    ("fov_180.json", 1, r"camera\.fov_deg: expected a number in \(0, 180\)"),
    ("size_65536.json", 3, r"rendering 65536x65536 .* needs [\d.]+ GB, more than the memory limit"),
    ("ring_100000_lights.json", 3, r"100000 per-light images needs [\d.]+ GB"),
    ("plane_divisions_8192.json", 3,
     r"a mesh of 134217728 triangles .* more than the memory limit"),
    ("heightfield_resolution_1e10.json", 1, r"resolution\[0\]: integer out of range"),
    ("shininess_1e400.json", 1, r"parse error: number overflow parsing '1e400'"),
    ("key_with_newline.json", 1, r"unknown field 'name x'"),
    ("nothing_visible.json", 1, r"nothing is visible: every object is outside the camera's view"),
    # It said "outside the camera's view" of a mesh in the middle of it.
    ("seen_from_behind.json", 1, r"nothing is visible: every face in the camera's view is seen "
                                 r"from behind"),
    ("faces_of_no_area.json", 1, r"nothing is visible: every face of the objects has no area"),
    ("point_light_per_light.json", 1, r"light 1 is a point light without falloff"),
    ("corrupt_mesh.json", 1, r"not_a_mesh\.ply: declares 1000000000 vertex and 1000000000 face"),
    ("ks_is_a_string.json", 1, r"objects\[0\]\.material\.ks: expected 3 numbers"),
    ("encoding_not_a_string.json", 1, r"output\.encoding: expected a string"),
    ("syntax_error.json", 1, r"parse error at line 3, column \d+"),
    ("binary_garbage.json", 1, r"parse error at line 1, column 1"),
    ("key_given_twice.json", 1, r"objects\[0\]: the key 'radius' is given twice in one object"),
]


@pytest.mark.parametrize("name, code, pattern", SCENE_CASES, ids=[c[0] for c in SCENE_CASES])
def test_bad_scene(tmp_path, name, code, pattern):
    assert_refused(tmp_path, ["render", BAD_SCENES / name, "-o", tmp_path / "out", "--per-light"],
                   code, pattern, name, timeout=60)


def test_huge_plane_renders_instead_of_crashing(tmp_path):
    code, _, err = run("render", BAD_SCENES / "plane_size_1e10.json", "-o", tmp_path / "out")
    assert code == 0, err


@pytest.fixture(scope="module")
def small_height(tmp_path_factory):
    """A 4x4 one-channel EXR (a height map), the wrong size and channel count for most inputs."""
    folder = tmp_path_factory.mktemp("small")
    code, _, err = run("integrate", FIXTURES / "integrate" / "back_facing_normals.png",
                       "-o", folder / "int", "--allow-back-facing")
    assert code == 0, err
    return folder / "int" / "height.exr"


@pytest.mark.parametrize("args, code, pattern", [
    (["normals", "ds", "-o", "out", "--bogus"], 2, r"not expected: --bogus"),
    (["normals"], 2, r"dataset is required"),
    (["frobnicate"], 2, r"frobnicate: no such command"),
    (["normals", "ds", "-o", "out", "--threads", "100000"], 2, r"--threads: Value 100000"),
    (["normals", "ds", "-o", "out", "--max-memory", "-1"], 2, r"--(memory-limit|max-memory)"),
    (["normals", "ds", "-o", "out", "--max-memory", "0.0001"], 3, r"more than the memory limit"),
    (["normals", "nowhere", "-o", "out"], 1, r"nowhere: no such folder"),
    (["normals", "ds/001.png", "-o", "out"], 1, r"ds/001\.png: is a file, not a folder"),
    (["integrate", "ds", "-o", "out", "--intrinsics", "0,0,0,0"], 1, r"intrinsics"),
    (["integrate", "ds/mask.png", "-o", "out"], 1,
     r"ds/mask\.png: has 1 channel\(s\); a normal map needs 3"),
    (["integrate", "ds", "-o", "out", "--depth-prior", "small.exr", "--allow-back-facing"], 1,
     r"small\.exr: is 4x4, the normal map is 96x96"),
    (["eval", "small.exr", "ds"], 1, r"small\.exr: has 1 channel"),
    (["eval", "ds/normals.exr", "ds", "--mask", "small_mask.png"], 1,
     r"small_mask\.png: is 20x20, the normal maps are 96x96"),
    (["render", "nowhere.json", "-o", "out"], 1, r"nowhere\.json: no such file"),
    (["demo", "--size", "1000000", "-o", "out"], 2, r"--size: Value 1000000 not in range 8 to 8192"),
    (["normals", "ds", "--light", "x", "-o", "out"], 2, r"\(--light: did you mean --lights\?\)"),
    (["normals", "empty", "-o", "out"], 1, r"empty: holds no images \(no image files, "
                                           r"filenames\.txt or \.lp\)"),
    (["calibrate-lights", "ds", "--normals", "ds/normals.exr", "-o", "out", "--saturation", "2"], 2,
     r"--saturation: must be a number in \(0, 1\] \(got 2\)"),
    # Infinite heights and an empty mesh behind exit 0, before the range.
    (["integrate", "ds/normals.exr", "-o", "out", "--pixel-size", "1e308"], 2,
     r"--pixel-size: must be a number between 1e-12 and 1e12 \(got 1e308\)"),
    # The options' own "no crop": given, it ran on the whole image.
    (["normals", "ds", "-o", "out", "--crop", "0,0,0,0"], 2,
     r"--crop: x,y,w,h needs w, h > 0 \(got 0x0\)"),
    # It reached the lights' check: "light diffuse intensity must be between 0 and 1e30".
    (["normals", "ds", "-o", "out", "--light-distance", "1e300"], 1,
     r"--light-distance: expected auto, inf or a distance in pixels between 1e-12 and 1e12, "
     r"got '1e300'"),
    # It reached "light direction 1 is not a finite unit vector" (1e-300: "reference depth").
    (["normals", "ds", "-o", "out", "--distance", "1e300"], 2,
     r"--distance: must be a number between 1e-12 and 1e12 \(got 1e300\)"),
    # Heights of 0 everywhere behind exit 0: the solvers' squares overflowed.
    (["integrate", "ds/normals.exr", "-o", "out", "--depth-prior", "small.exr", "--prior-weight",
      "1e300"], 2, r"--prior-weight: must be a number between 1e-12 and 1e12 \(got 1e300\)"),
])
def test_bad_command_line(rendered, small_height, tmp_path, args, code, pattern):
    user_copy(rendered, tmp_path / "ds")
    (tmp_path / "small_mask.png").write_bytes(grey_png(20, 20))
    (tmp_path / "empty").mkdir()
    shutil.copy(small_height, tmp_path / "small.exr")
    assert_refused(tmp_path, args, code, pattern, cwd=tmp_path, timeout=60)


def test_fit_material_refuses_photos_that_are_black_wherever_the_object_is(rendered, tmp_path):
    """Eight black photos were fitted (ka 0, ks 0, n 1) behind a warning: nothing to fit."""
    ds = user_copy(rendered, tmp_path / "ds")
    for name in (ds / "filenames.txt").read_text().split():
        (ds / name).write_bytes(grey_png(96, 96, 0))
    assert_refused(tmp_path, ["fit-material", "ds", "--normals", "ds/normals.exr", "-o", "out"],
                   1, r"ds: the photos are black \(0\) wherever the object is: nothing to fit",
                   cwd=tmp_path, ignore_warnings=True)


MEMORY_COMMANDS = [
    ["normals", "ds", "-o", "out"],
    ["render", str(FIXTURES / "scenes" / "photometric_sphere.json"), "-o", "out"],
    ["integrate", "ds/normals.exr", "-o", "out"],
    ["relight", "ds", "--light", "0,0,1", "-o", "relit.png"],
    ["fit-material", "ds", "--normals", "ds/normals.exr", "-o", "out"],
    ["calibrate-lights", "ds", "--normals", "ds/normals.exr", "-o", "out"],
    ["eval", "ds/normals.exr", "ds"],
]


@pytest.mark.parametrize("args", MEMORY_COMMANDS, ids=lambda a: a[0])
def test_memory_limit_takes_units_and_refuses_what_no_work_fits(rendered, tmp_path, args):
    """--memory-limit as people write it (16GB, 512M; plain numbers are GB). A limit below a byte
    used to truncate to 0, "unset", and the work ran; now it is a usage error (exit 2), and a limit
    no work fits is exit 3 with the figure, for every command, with nothing written."""
    user_copy(rendered, tmp_path / "ds")
    assert_refused(tmp_path, args + ["--memory-limit", "1e-12"], 2,
                   r"--memory-limit: '1e-12' is less than one byte", cwd=tmp_path)
    assert_refused(tmp_path, args + ["--memory-limit", "1e308"], 2,
                   r"--memory-limit: '1e308' is more than 1e9 GB", cwd=tmp_path)
    assert_refused(tmp_path, args + ["--memory-limit", "100B"], 3,
                   r"needs \d+ [kM]B, more than the memory limit of 100 B \(raise it with "
                   r"--memory-limit\)", cwd=tmp_path)
    code, _, err = run(*args, "--memory-limit", "512M", cwd=tmp_path)
    assert code == 0, err


@pytest.mark.skipif("ASAN_OPTIONS" in os.environ,
                    reason="AddressSanitizer's shadow memory does not fit in the 3 GB limit")
def test_many_threads_under_a_memory_limit_still_run(rendered, tmp_path):
    """Threads that cannot start (8 MB stacks in a 3 GB address space) are not a crash: the run
    goes on with those that did."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
    code, _, err = run("normals", rendered, "-o", tmp_path / "out", "--threads", "1000",
                       preexec_fn=limit)
    assert code == 0, err


def test_warnings_do_not_hide_errors_and_stdout_holds_the_report(rendered, tmp_path):
    ds = user_copy(rendered, tmp_path / "ds")
    lines = (ds / "light_directions.txt").read_text().splitlines()
    lines[0] = " ".join(str(2 * float(v)) for v in lines[0].split())
    (ds / "light_directions.txt").write_text("\n".join(lines) + "\n")
    code, out, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert err.splitlines() == [f"iphong: warning: {ds}/light_directions.txt:1: light direction "
                                "has length 2; normalized"]  # the other 11 are unit
    assert "Angular error against the ground truth" in out


def test_lights_in_a_y_down_z_into_the_scene_frame_are_named(rendered, tmp_path):
    """Every light behind the camera's side of the object: a file in another frame. It still runs
    (a rim-lit capture has a few such lights) but says so, instead of normals 86 degrees off
    without a word."""
    ds = user_copy(rendered, tmp_path / "ds")
    lines = (ds / "light_directions.txt").read_text().splitlines()
    flipped = [f"{x} {-float(y)} {-float(z)}" for x, y, z in (line.split() for line in lines)]
    (ds / "light_directions.txt").write_text("\n".join(flipped) + "\n")
    code, _, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert err.splitlines() == [
        f"iphong: warning: {ds}/light_directions.txt: 12 of 12 light directions point away from "
        "the camera (z < 0); iphong's frame has x right, y up, z toward the camera: a file with "
        "y down and z into the scene needs y and z negated"]
    code, _, err = run("normals", rendered, "-o", tmp_path / "plain")
    assert code == 0 and "point away" not in err


def test_an_image_listed_for_two_lights_is_named(rendered, tmp_path):
    ds = user_copy(rendered, tmp_path / "ds")
    lines = (ds / "filenames.txt").read_text().splitlines()
    lines[5] = lines[4]  # a line pasted twice: 005.png under lights 5 and 6
    (ds / "filenames.txt").write_text("\n".join(lines) + "\n")
    code, _, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    said = err.splitlines()
    assert said[0] == (
        f"iphong: warning: {ds}/filenames.txt: lists 005.png 2 times (2 of 12 entries name an "
        "image listed more than once): each light needs its own photograph")
    # Then which of the two is out of place: the photo under light 6 (solve/image_check.h).
    assert len(said) == 2 and said[1].startswith(
        f"iphong: warning: {ds}/light_directions.txt: image 005.png disagrees with the other 11"), said
    assert "light 6 of" in said[1], said[1]


def test_one_photo_under_two_names_is_named_and_one_photo_under_every_name_refused(rendered,
                                                                                    tmp_path):
    """A photo copied over another (two names, one content) gives that light no shading of its
    own: said, with the pair. Every image the same carries no shading at all: refused, nothing
    written (the solve gave 56 degrees behind exit 0)."""
    ds = user_copy(rendered, tmp_path / "ds")
    (ds / "006.png").unlink()
    shutil.copy(ds / "005.png", ds / "006.png")
    code, _, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    said = err.splitlines()
    assert said[0] == (
        "iphong: warning: 1 of 12 images repeat another pixel for pixel inside the mask (005.png "
        "and 006.png are identical): one photo saved under two names? Each light needs its own")
    # Then which of the pair is out of place: 006.png, under light 6 (solve/image_check.h).
    assert len(said) == 2 and said[1].startswith(
        f"iphong: warning: {ds}/light_directions.txt: image 006.png disagrees with the other 11"), said
    assert "light 6 of" in said[1], said[1]
    pixels = json.loads((tmp_path / "out" / "metrics.json").read_text())["pixels"]
    for name in (ds / "filenames.txt").read_text().split():
        if name != "005.png":
            (ds / name).unlink()
            shutil.copy(ds / "005.png", ds / name)
    code, _, err = run("normals", ds, "-o", tmp_path / "same")
    assert code == 1
    assert err.splitlines() == [
        "iphong: warning: all 12 images are identical inside the mask: the light did not change "
        "between the photographs, or one photo was saved under every name",
        f"iphong: error: {ds}: the 12 images are the same at each of the "
        f"{pixels} pixels sampled (the light did not change between the photographs, or "
        "one photo was saved under every name): no normal can be recovered"]
    assert not (tmp_path / "same").exists()
    # In bands, with the coefficients known (no plan sample: each band is checked), the same.
    assert (ds / "material.json").exists()  # the render's coefficients: known, read
    for flags in (["--band-rows", "16"], ["--band-rows", "16", "--model", "lambert"]):
        code, _, err = run("normals", ds, "-o", tmp_path / "same", *flags)
        assert code == 1, flags
        assert err.splitlines()[-1].startswith(
            f"iphong: error: {ds}: the 12 images are the same at each of the "), flags
        assert not (tmp_path / "same").exists()


def test_an_image_in_other_units_is_named(rendered, tmp_path):
    """One photo stored 0-255 among 0-1 photos (read as linear floats): no light's shading makes an
    image 255 times as bright as the median one, so it is named; the capture as rendered is not."""
    ds = user_copy(rendered, tmp_path / "ds")
    subprocess.run(["oiiotool", str(ds / "005.png"), "--mulc", "255", "-d", "float", "-o",
                    str(ds / "005.exr")], check=True)
    (ds / "005.png").unlink()
    names = (ds / "filenames.txt").read_text().replace("005.png", "005.exr")
    (ds / "filenames.txt").write_text(names)
    code, _, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert ("1 of 12 images are more than 100 times as bright as the median image, after their "
            "lights' intensities (most: 005.exr, ") in err, err
    code, _, err = run("normals", rendered, "-o", tmp_path / "plain")
    assert code == 0 and "as bright as the median" not in err, err


def test_float_values_above_one_in_a_mixed_capture_are_not_clipped(rendered, tmp_path):
    """A capture of PNGs with one EXR whose values pass 1: a float file does not clip there. The
    clipped count took the first file's sample type for every file and named the EXR clipped."""
    ds = user_copy(rendered, tmp_path / "ds")

    def to_exr(name):
        subprocess.run(["oiiotool", str(ds / name), "--mulc", "4", "-d", "float", "-o",
                        str(ds / name.replace(".png", ".exr"))], check=True)
        (ds / name).unlink()
        names = (ds / "filenames.txt").read_text().replace(name, name.replace(".png", ".exr"))
        (ds / "filenames.txt").write_text(names)

    to_exr("005.png")
    code, _, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert "clipped" not in err, err
    # An EXR first: the PNGs are still integer codes, and none of them clips either.
    to_exr("001.png")
    code, _, err = run("normals", ds, "-o", tmp_path / "out2")
    assert code == 0, err
    assert "clipped" not in err, err


def test_a_mask_marking_the_background_is_refused(rendered, tmp_path):
    """A mask drawn the wrong way round selects only the black background: every pixel dark in
    every image went through with exit 0 and empty maps. Refused, in memory and in bands."""
    ds = user_copy(rendered, tmp_path / "ds")
    subprocess.run(["oiiotool", str(ds / "mask.png"), "--invert", "-o", str(ds / "mask.png")],
                   check=True)
    (ds / "Normal_gt.mat").unlink(missing_ok=True)
    for flags in ([], ["--band-rows", "16"]):
        assert_refused(tmp_path, ["normals", ds, "-o", tmp_path / "out", *flags], 1,
                       r"every pixel inside the mask is black \(0\) in every image: no normal "
                       r"can be recovered \(a mask marking the background\? Nonzero marks the "
                       r"object\)", "ds", ignore_warnings=True)


def test_a_ground_truth_beside_every_solved_pixel_is_named_not_fatal(rendered, tmp_path):
    """A ground truth that holds normals only where nothing was solved (here one corner pixel,
    outside the mask): the normals stand, the file is named, nothing compared. It failed with a
    line naming no file and discarded the run."""
    ds = user_copy(rendered, tmp_path / "ds")
    (ds / "Normal_gt.mat").unlink()
    (ds / "normal.txt").write_text("0 0 1\n" + "0 0 0\n" * (96 * 96 - 1))
    code, out, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert err.splitlines() == [
        f"iphong: warning: {ds}/normal.txt: not compared: no pixel has both an estimate and ground "
        "truth"], err
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert "mean_angular_error_deg" not in metrics and metrics["ground_truth_note"].startswith("not compared")
    assert not (tmp_path / "out" / "error.png").exists()


def test_eval_names_normals_that_are_not_finite(rendered, tmp_path):
    """Other tools write NaN where they found no normal. Scored as missing (180 degrees, as a 0
    is) with a warning that counts them; a map with no finite normal where the ground truth has
    one is refused: its mean of 180 degrees was printed as a result."""
    exact = rendered / "normals.exr"
    code, out, err = run("eval", exact, rendered)
    assert code == 0 and err == "", err
    assert json.loads(out)["mean_angular_error_deg"] < 0.01
    holes = tmp_path / "holes.exr"
    subprocess.run(["oiiotool", str(exact), "--crop", "8x8+44+44", "--mulc", "nan", str(exact),
                    "--paste", "+0+0", "-o", str(holes)], check=True)
    code, out, err = run("eval", holes, rendered)
    assert code == 0, err
    metrics = json.loads(out)
    (line,) = err.splitlines()
    assert line.startswith(f"iphong: warning: {holes}: 64 of {metrics['evaluated_pixels']} pixels "
                           "with ground truth hold no finite normal (NaN or infinite; the first "
                           "at column 44, row 44): scored as missing, 180 degrees"), line
    assert metrics["mean_angular_error_deg"] == pytest.approx(
        180 * 64 / metrics["evaluated_pixels"], abs=0.01)
    nothing = tmp_path / "nothing.exr"
    subprocess.run(["oiiotool", str(exact), "--mulc", "nan", "-o", str(nothing)], check=True)
    assert_refused(tmp_path, ["eval", nothing, rendered, "--error-map", tmp_path / "e.png"], 1,
                   r"holds no finite normal where the ground truth has one \(NaN or infinite at "
                   r"all \d+ such pixels; the first at column \d+, row \d+\)", str(nothing))
    assert not (tmp_path / "e.png").exists()


def test_text_files_from_windows_editors_are_read(rendered, tmp_path):
    """A UTF-8 byte-order mark and CRLF line ends are what Notepad writes: not an error."""
    ds = user_copy(rendered, tmp_path / "ds")
    for name in ("filenames.txt", "light_directions.txt", "light_intensities.txt"):
        text = (ds / name).read_text().replace("\n", "\r\n")
        (ds / name).write_bytes(b"\xef\xbb\xbf" + text.encode())
    code, out, err = run("normals", ds, "-o", tmp_path / "out")
    assert code == 0, err
    assert "mean 0.00 deg" in out


def test_bare_iphong_prints_the_help():
    code, stdout, stderr = run()
    assert code == 0 and stderr == ""
    assert stdout.startswith("iphong: ") and "Usage: iphong" in stdout and "normals" in stdout


@pytest.mark.skipif(shutil.which("oiiotool") is None, reason="oiiotool not installed")
def test_a_depth_prior_beyond_1e12_pixels_is_refused_naming_its_file(rendered, tmp_path):
    """A prior of 1e30 gave a surface flat at 1e30, exit 0 (its relief below float's precision
    there); the error named the normal map, not the prior."""
    user_copy(rendered, tmp_path / "ds")
    subprocess.run(["oiiotool", "-pattern", "constant:color=1e30", "96x96", "1", "-o",
                    str(tmp_path / "huge.exr")], check=True)
    assert_refused(tmp_path, ["integrate", "ds/normals.exr", "-o", "out", "--depth-prior",
                              "huge.exr"], 1,
                   r"huge\.exr: the depth prior holds 1e\+30 at pixel \(col \d+, row \d+\): beyond "
                   r"1e12 pixels no height map keeps its relief", ignore_warnings=True,
                   cwd=tmp_path, timeout=60)
