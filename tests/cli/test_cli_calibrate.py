"""`iphong calibrate-lights` on small mirror-sphere captures drawn here (8-bit PNG), and every bad
capture of issue 13 with its exact report: no sphere, a sphere clipped by the edge, a missing
highlight (an error: nothing written), a large clipped highlight, two images with the same light
and a light behind the sphere (warnings: the calibration is written)."""
import json
import math
import os
import re
import pathlib
import struct
import zlib

import pytest

from cli import (IPHONG, ROOT, assert_one_line_error, binary_available, render_dataset, run,
                 snapshot)

pytestmark = pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}")

SIZE, CX, CY, RADIUS = 96, 48.0, 48.0, 40.0
UW = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data")) / "uw"
BUNNY = UW.parent / "rps-bunny-lambert"


def png(width, height, rows, channels):
    """An 8-bit PNG (channels 1 or 3) from rows of byte strings."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    raw = b"".join(b"\0" + row for row in rows)
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8,
                                         0 if channels == 1 else 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def mirror_images(light, width=SIZE, centres=(CX,), radius=RADIUS, half_width_deg=4.0,
                  gain=0.8, position=None):
    """Mirror balls (centres along the middle row) under one small round source, drawn with the
    reflection written out here, independently of iphong: a Gaussian highlight in directions,
    its peak `gain` (above 1 the centre is clipped). The picture and the balls' mask. With
    `position` (pixels: x from the image's left, y up from its middle row, z toward the camera,
    the balls' centres at z = 0) the source is a point light there, seen from each surface point
    in its own direction."""
    light = unit(light)
    rows, mask = [], []
    for r in range(SIZE):
        row, inside = bytearray(), bytearray()
        for c in range(width):
            value, on = 0.0, 0
            for cx in centres:
                dx, dy = (c + 0.5 - cx) / radius, -(r + 0.5 - CY) / radius
                if dx * dx + dy * dy < 1:
                    nz = math.sqrt(1 - dx * dx - dy * dy)
                    reflected = [2 * nz * dx, 2 * nz * dy, 2 * nz * nz - 1]
                    if position is not None:
                        point = [cx + dx * radius, dy * radius, nz * radius]
                        light = unit([p - q for p, q in zip(position, point)])
                    cos = max(-1.0, min(1.0, sum(a * b for a, b in zip(reflected, light))))
                    angle = math.degrees(math.acos(cos))
                    value = 0.02 + gain * math.exp(-0.5 * (angle / half_width_deg) ** 2)
                    on = 255
            row += bytes([min(255, round(255 * value))] * 3)
            inside.append(on)
        rows.append(bytes(row))
        mask.append(bytes(inside))
    return png(width, SIZE, rows, 3), png(width, SIZE, mask, 1)


def mirror_image(light, half_width_deg=4.0, gain=0.8, cx=CX):
    return mirror_images(light, centres=(cx,), half_width_deg=half_width_deg, gain=gain)[0]


def disc_mask(cx=CX, radius=RADIUS):
    rows = [bytes(255 if (c + 0.5 - cx) ** 2 + (r + 0.5 - CY) ** 2 < radius ** 2 else 0
                  for c in range(SIZE)) for r in range(SIZE)]
    return png(SIZE, SIZE, rows, 1)


LIGHTS = [(0.3, 0.2, 0.9), (-0.4, 0.3, 0.8), (0.1, -0.5, 0.8), (-0.2, -0.2, 0.95),
          (0.6, -0.1, 0.7), (0.0, 0.6, 0.75)]


def capture(folder, lights=LIGHTS, images=None, mask=True):
    folder.mkdir()
    for j, light in enumerate(lights):
        data = images[j] if images and j in images else mirror_image(light)
        (folder / f"ball.{j + 1}.png").write_bytes(data)
    if mask:
        (folder / "mask.png").write_bytes(disc_mask())
    return folder


def angle_deg(a, b):
    a, b = unit(a), unit(b)
    return math.degrees(math.acos(max(-1.0, min(1.0, sum(x * y for x, y in zip(a, b))))))


def test_mirror_capture_gives_the_lights_the_files_and_the_picture(tmp_path):
    folder = capture(tmp_path / "ball")
    out = tmp_path / "lights"
    code, stdout, err = run("calibrate-lights", folder, "-o", out)
    assert code == 0, err
    assert "Calibrated 6 lights (mirror sphere; intensities measured" in stdout
    directions = [list(map(float, line.split()))
                  for line in (out / "light_directions.txt").read_text().splitlines()]
    # 8-bit values and a 40 px sphere: a pixel spans about 2.9 deg of directions.
    for found, truth in zip(directions, LIGHTS):
        assert angle_deg(found, truth) < 0.3, (found, truth)
    intensities = (out / "light_intensities.txt").read_text().splitlines()
    assert len(intensities) == 6
    lp = (out / "lights.lp").read_text().splitlines()
    assert lp[0] == "6" and lp[1].startswith("ball.1.png ")
    report = json.loads((out / "calibration.json").read_text())
    assert report["method"] == "mirror sphere"
    assert abs(report["spheres"][0]["radius_px"] - RADIUS) < 0.2
    assert [p["file"] for p in report["per_image"]] == [f"ball.{j}.png" for j in range(1, 7)]
    # The reported uncertainty is honest: measured errors 0.07-0.15 deg, reported 0.31-0.33.
    for entry, truth in zip(report["per_image"], LIGHTS):
        highlight = entry["highlights"][0]
        assert angle_deg(entry["light_direction"], truth) < highlight["uncertainty_deg"] < 0.4
    assert (out / "calibration.png").stat().st_size > 1000
    assert not err  # nothing to warn about: unclipped highlights, distinct lights


def test_no_sphere_in_the_mask(tmp_path):
    folder = capture(tmp_path / "ball", mask=False)
    (folder / "mask.png").write_bytes(disc_mask(radius=3))  # a speck, not a sphere
    before = snapshot(tmp_path)
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out")
    assert_one_line_error(code, err, 1,
                          r"ball/mask\.png: no sphere: the mask has no region of radius 6\.0 px "
                          r"or more$")
    assert snapshot(tmp_path) == before


def test_without_a_mask_the_sphere_is_found_in_the_photos(tmp_path):
    folder = capture(tmp_path / "ball", mask=False)
    out = tmp_path / "out"
    code, _, err = run("calibrate-lights", folder, "-o", out)
    assert code == 0, err
    found = re.search(r"^iphong: warning: .*ball: no mask: found a sphere in the photos at "
                      r"\((\S+), (\S+)\), radius (\S+) px; check calibration\.png, or give "
                      r"--mask or --circle$", err, re.M)
    assert found, err
    # The drawn sphere: centre (48, 48), radius 40.
    assert [abs(float(v) - t) < 0.3 for v, t in zip(found.groups(), (CX, CY, RADIUS))] == [True] * 3
    directions = [list(map(float, line.split()))
                  for line in (out / "light_directions.txt").read_text().splitlines()]
    # A circle 0.1 px off on a 40 px sphere moves the lights by up to half a degree.
    for found, truth in zip(directions, LIGHTS):
        assert angle_deg(found, truth) < 0.8, (found, truth)
    # The circle given by hand does the same job as a mask.
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out2",
                       "--circle", f"{CX},{CY},{RADIUS}", "-q")
    assert code == 0 and not err, err


def test_no_sphere_in_the_photos(tmp_path):
    grey = png(SIZE, SIZE, [bytes([90] * 3 * SIZE)] * SIZE, 3)
    folder = capture(tmp_path / "flat", images={j: grey for j in range(6)}, mask=False)
    before = snapshot(tmp_path)
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out")
    assert_one_line_error(code, err, 1,
                          r"flat: no sphere found in the photos \(no circle in their mean\); "
                          r"give --mask or --circle$")
    assert snapshot(tmp_path) == before


def test_sphere_clipped_by_the_image_edge(tmp_path):
    folder = capture(tmp_path / "ball", mask=False)
    (folder / "mask.png").write_bytes(disc_mask(cx=-12))
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out")
    assert_one_line_error(code, err, 1,
                          r"mask\.png: the sphere at \(-1[12]\.\d, 48\.0\) is clipped by the image "
                          r"edge \(\d+% of its outline visible\): too little to fit$")
    assert not (tmp_path / "out").exists()


def test_missing_highlight_is_an_error_naming_the_image(tmp_path):
    black = png(SIZE, SIZE, [bytes(3 * SIZE)] * SIZE, 3)
    folder = capture(tmp_path / "ball", images={3: black})
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out")
    assert_one_line_error(code, err, 1,
                          r"ball\.4\.png: no highlight on the sphere at \(48, 48\): its brightest "
                          r"pixel is black \(the light is behind the sphere or off, or the sphere "
                          r"is not a mirror\)$")
    assert not (tmp_path / "out").exists()


def test_large_clipped_highlight_same_light_and_light_behind_are_warnings(tmp_path):
    behind = (0.95, 0.0, -0.25)
    lights = LIGHTS[:4] + [LIGHTS[0], behind]
    images = {1: mirror_image(LIGHTS[1], half_width_deg=6, gain=4.0)}
    folder = capture(tmp_path / "ball", lights=lights, images=images)
    out = tmp_path / "lights"
    code, _, err = run("calibrate-lights", folder, "-o", out)
    assert code == 0, err
    lines = err.splitlines()
    assert any(line.startswith("iphong: warning: ") and "ball.2.png: the highlight is clipped "
               "over a large blob" in line and "shorten the exposure" in line for line in lines), err
    assert any("ball.1.png and ball.5.png: the same light (0.00 deg apart)" in line
               for line in lines), err
    assert any("ball.6.png: the light is behind the sphere's equator as the camera sees it" in line
               for line in lines), err
    assert any("highlights are clipped: intensities not measured (all 1 written)" in line
               for line in lines), err
    report = json.loads((out / "calibration.json").read_text())
    assert len(report["warnings"]) == 4
    directions = [list(map(float, line.split()))
                  for line in (out / "light_directions.txt").read_text().splitlines()]
    # 52 deg from the view on a 40 px sphere: the highlight is squeezed against the rim.
    assert angle_deg(directions[5], behind) < 1.0
    assert angle_deg(directions[1], LIGHTS[1]) < 0.5  # clipped, but still centred


def test_circle_needs_three_or_six_numbers(tmp_path):
    folder = capture(tmp_path / "ball")
    code, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out", "--circle", "1,2")
    assert_one_line_error(code, err, 2, r"--circle: takes cx,cy,r \(one sphere\) or six numbers")


@pytest.mark.skipif(not (UW / "chrome").is_dir(), reason=f"UW data not found at {UW}")
def test_uw_chrome_calibrates_the_lights_uw_cat_is_solved_with(tmp_path):
    """The issue's done-when: calibrate from the chrome sphere, then solve the cat with it."""
    code, stdout, err = run("calibrate-lights", UW / "chrome", "-o", tmp_path / "lights")
    assert code == 0, err
    for name in ["light_directions.txt", "light_intensities.txt", "lights.lp", "calibration.json",
                 "calibration.png"]:
        assert (tmp_path / "lights" / name).stat().st_size > 0, name
    code, stdout, err = run("normals", UW / "cat", "--lights",
                            tmp_path / "lights" / "light_directions.txt", "-o", tmp_path / "cat")
    assert code == 0, err
    assert "lights/light_directions.txt (directions)" in stdout
    assert (tmp_path / "cat" / "normals.exr").exists()


def test_normals_estimate_intensities_ignores_the_intensity_file(tmp_path):
    dataset = tmp_path / "sphere"
    render_dataset(dataset)
    # An untrusted intensity file: --estimate-intensities must not read it.
    (dataset / "light_intensities.txt").write_text("5 5 5\n" * 12)
    code, stdout, err = run("normals", dataset, "--estimate-intensities", "-o", tmp_path / "out")
    assert code == 0, err
    assert "Estimated the 12 lights' intensities" in stdout
    values = [list(map(float, line.split()))
              for line in (tmp_path / "out" / "light_intensities.txt").read_text().splitlines()]
    assert len(values) == 12
    # Rendered with all 1; measured within 3% (the Lambertian elimination sees the Phong
    # highlights, ks 0.4, and the ambient term through its trims).
    assert all(abs(v - 1) < 0.04 for row in values for v in row), values
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert metrics["estimated_intensities"]["eigen_gap"] > 2
    assert metrics["mean_angular_error_deg"] < 0.5  # 0.29 measured
    # The file is compared with the estimate (up to scale it is right here): said, no warning.
    against = metrics["estimated_intensities"]["against_file"]
    assert against["file"].endswith("light_intensities.txt")
    assert against["normals_moved_deg"] < 1 and "differ from this file" not in err
    assert "the estimated intensities differ from this file's by" in stdout
    # A file off by 30 % on every other light: the estimate disagrees, and the images contradict
    # the file (their brightness follows the lights worse with it than with none), so the
    # estimate is used and the user hears why. The figure bounds how much worse either run can be
    # than the other (a triangle inequality).
    (dataset / "light_intensities.txt").write_text("0.7 0.7 0.7\n1.3 1.3 1.3\n" * 6)
    code, stdout, err = run("normals", dataset, "--estimate-intensities", "-o", tmp_path / "off")
    assert code == 0, err
    assert "light_intensities.txt: the images' brightness follows their lights' directions" in err
    assert re.search(r"light_intensities\.txt: the estimated intensities differ from this file's "
                     r"by [0-9.]+% \(median; at most [0-9.]+%\), and the normals under the two "
                     r"by [0-9.]+ deg on average: the images contradict the file \(said above\), "
                     r"so the estimate is used", err), err
    off = json.loads((tmp_path / "off" / "metrics.json").read_text())
    against = off["estimated_intensities"]["against_file"]
    assert against["median_relative_difference"] > 0.25 and against["normals_moved_deg"] > 1
    assert "no intensity file to check" not in err


def test_an_estimate_with_nothing_to_check_it_against_is_warned(tmp_path):
    dataset = tmp_path / "sphere"
    render_dataset(dataset)
    (dataset / "light_intensities.txt").unlink(missing_ok=True)
    code, stdout, err = run("normals", dataset, "--estimate-intensities", "-o", tmp_path / "out")
    assert code == 0, err
    assert re.search(r"iphong: warning: .*sphere: --estimate-intensities with no intensity file to "
                     r"check the estimate against: .* calibrate the lights", err), err
    estimated = json.loads((tmp_path / "out" / "metrics.json").read_text())[
        "estimated_intensities"]
    assert "against_file" not in estimated
    # Rendered with equal lights, the estimate lies within its own error of equal (3 %), so the
    # run under equal lights is the check: within a degree here, so the estimate is used.
    assert estimated["against_equal"]["max_relative_difference"] < 0.04
    assert estimated["against_equal"]["normals_moved_deg"] < 1


@pytest.mark.skipif(not BUNNY.is_dir(), reason=f"rps-bunny-lambert not found at {BUNNY}")
def test_the_figure_said_bounds_the_two_runs_difference(tmp_path):
    """With an intensity file, the normals' figure is the mean angle between the run under the
    file and the run under the estimate, so it bounds the difference of their mean errors (per
    pixel a triangle inequality). On the rendered bunny the intensities move the model choice (the
    foil under its file, Lambert under the estimate, which reads the renderer's darkening toward
    the terminator as intensity); one plan for both runs said 0.96 deg where the runs' errors are
    0.95 and 4.10 deg, and gave no warning."""
    # Past a degree apart, the images not contradicting the file: refused, nothing written.
    code, _, err = run("normals", BUNNY, "--estimate-intensities", "-o", tmp_path / "refused",
                       timeout=300)
    assert code == 1, err
    found = re.search(r"iphong: error: \S*light_intensities\.txt: the estimated intensities "
                      r"differ from this file's by [0-9.]+% \(median; at most [0-9.]+%\), and the "
                      r"normals under the two by ([0-9.]+) deg on average: the images cannot tell "
                      r"which set is right.*nothing written.*--intensities none", err)
    assert found, err
    assert not (tmp_path / "refused").exists()
    moved = float(found.group(1))
    # The estimate unchecked, as the error offers, and the file's run.
    code, _, est_err = run("normals", BUNNY, "--estimate-intensities", "--intensities", "none",
                           "-o", tmp_path / "est", timeout=300)
    assert code == 0, est_err
    assert "with no intensity file to check the estimate against" in est_err
    code, _, file_err = run("normals", BUNNY, "-o", tmp_path / "file", timeout=300)
    assert code == 0, file_err
    est = json.loads((tmp_path / "est" / "metrics.json").read_text())
    given = json.loads((tmp_path / "file" / "metrics.json").read_text())
    assert est["input"]["intensities"] == "all 1 (--intensities none)"
    apart = abs(est["mean_angular_error_deg"] - given["mean_angular_error_deg"])
    assert moved >= apart > 2, (moved, apart)


@pytest.mark.skipif(not BUNNY.is_dir(), reason=f"rps-bunny-lambert not found at {BUNNY}")
def test_an_estimate_within_its_error_of_equal_lights_that_moves_the_normals_is_refused(
        tmp_path):
    """The bunny without its intensity file: the lights are alike (the estimate within 3.3 % of
    equal, less than its error on calibrated captures), yet the estimate moves the normals 3.7
    degrees from a run under equal lights, which are the right ones: refused, nothing written;
    --intensities none still takes the estimate unchecked."""
    folder = tmp_path / "bunny"
    folder.mkdir()
    for path in BUNNY.iterdir():
        if path.name != "light_intensities.txt":
            (folder / path.name).symlink_to(path)
    code, _, err = run("normals", folder, "--estimate-intensities", "-o", tmp_path / "refused",
                       timeout=300)
    assert code == 1, err
    assert re.search(r"iphong: error: \S*bunny: --estimate-intensities: the estimated intensities "
                     r"are all within [0-3]\.[0-9]% of equal lights, .* move the normals "
                     r"[1-9][0-9.]* deg from equal intensities'.*nothing written", err), err
    assert not (tmp_path / "refused").exists()
    code, _, err = run("normals", folder, "--estimate-intensities", "--intensities", "none",
                       "-o", tmp_path / "unchecked", timeout=300)
    assert code == 0, err
    assert "with no intensity file to check the estimate against" in err


@pytest.mark.parametrize("args, code, pattern", [
    (["--circle", "1000,1000,50"], 2,
     r"--circle: the circle \(1000\.0, 1000\.0, r 50\.0\) lies mostly outside the 96x96 images"),
    (["--intrinsics", "0,0,48,48"], 2,
     r"--intrinsics: fx and fy must be between 1e-12 and 1e12, cx and cy finite"),
    # Every light came out the same direction, exit 0.
    (["--intrinsics", "1e300,1e300,48,48"], 2,
     r"--intrinsics: fx and fy must be between 1e-12 and 1e12, cx and cy finite"),
    (["--sphere-radius", "1e300"], 2, r"--sphere-radius: must be a number between 1e-12 and 1e12"),
    (["--saturation", "0"], 2, r"--saturation: must be a number in \(0, 1\] \(got 0\)"),
])
def test_bad_flags(tmp_path, args, code, pattern):
    folder = capture(tmp_path / "ball")
    before = snapshot(tmp_path)
    result, _, err = run("calibrate-lights", folder, "-o", tmp_path / "out", *args)
    assert_one_line_error(result, err, code, pattern)
    assert snapshot(tmp_path) == before


def test_normals_that_light_no_pixel_are_an_error(tmp_path):
    folder = capture(tmp_path / "ball")
    # A flat normal map facing away from every light: nothing it says can be lit.
    rows = [bytes([128, 128, 0] * SIZE)] * SIZE  # n = (0, 0, -1)
    (tmp_path / "away.png").write_bytes(png(SIZE, SIZE, rows, 3))
    code, _, err = run("calibrate-lights", folder, "--normals", tmp_path / "away.png", "-o",
                       tmp_path / "out")
    assert_one_line_error(code, err, 1,
                          r"ball\.1\.png: no pixel is lit in this photo where the normals of "
                          r".*away\.png say \(6 photos so\)")
    assert not (tmp_path / "out").exists()


def test_two_spheres_under_distant_lights(tmp_path):
    folder = tmp_path / "rig"
    folder.mkdir()
    for j, light in enumerate(LIGHTS):
        image, mask = mirror_images(light, width=176, centres=(44.0, 132.0), radius=36.0)
        (folder / f"rig.{j + 1}.png").write_bytes(image)
    (folder / "mask.png").write_bytes(mask)
    out = tmp_path / "lights"
    code, _, err = run("calibrate-lights", folder, "-o", out)
    assert code == 0, err
    # Distant lights: the two spheres' reflected rays are parallel and meet nowhere.
    assert "no point-light positions: the two spheres' reflected rays do not meet" in err
    assert not (out / "light_positions.txt").exists()
    report = json.loads((out / "calibration.json").read_text())
    assert len(report["spheres"]) == 2
    for entry, truth in zip(report["per_image"], LIGHTS):
        assert len(entry["highlights"]) == 2
        assert angle_deg(entry["light_direction"], truth) < 0.3
        a, b = (h["light_direction"] for h in entry["highlights"])
        assert angle_deg(a, b) < 0.5


COW = UW.parent / "diligent-crop8" / "cow"


@pytest.mark.skipif(not COW.is_dir(), reason=f"DiLiGenT crops not found at {COW.parent}")
def test_estimate_intensities_refuses_a_metallic_object(tmp_path):
    code, _, err = run("normals", COW, "--estimate-intensities", "-o", tmp_path / "out")
    # The reader's warning about black pixels comes first; then the one error line.
    err = "\n".join(line for line in err.splitlines() if not line.startswith("iphong: warning:"))
    assert_one_line_error(code, err, 1,
                          r"cow: --estimate-intensities: the images are too far from Lambertian "
                          r"to estimate their lights' intensities \(median relative residual "
                          r"0\.079, over 0\.05\); give the intensities$")
    assert not (tmp_path / "out").exists()


def test_two_spheres_under_near_lights_write_the_near_light_layout(tmp_path):
    """Calibrate then solve, two commands: the positions come out in the near-light layout (mm
    with --sphere-radius, camera.json), with how near the lights are stated as numbers."""
    folder = tmp_path / "rig"
    folder.mkdir()
    # Lights 300-400 px from the balls (radius 30 px, 30 mm: 1 mm a pixel): 5-7 diameters.
    positions = [(120 + 250, 60, 200), (120 - 200, -90, 250), (120 + 40, 160, 260),
                 (120 - 120, 150, 300), (120 + 150, -170, 220)]
    for j, p in enumerate(positions):
        image, mask = mirror_images((0, 0, 1), width=240, centres=(40.0, 200.0), radius=30.0,
                                    position=p)
        (folder / f"rig.{j + 1}.png").write_bytes(image)
    (folder / "mask.png").write_bytes(mask)
    out = tmp_path / "lights"
    code, stdout, err = run("calibrate-lights", folder, "-o", out, "--sphere-radius", "30")
    assert code == 0, err
    assert "use the near-light layout" in stdout
    report = json.loads((out / "calibration.json").read_text())
    near = report["near_lights"]
    assert near["units"] == "mm" and not near["distant_would_do"]
    assert 3 < near["distance_in_sphere_diameters"]["min"] < near["distance_in_sphere_diameters"]["max"] < 8
    # Orthographic: camera.json's pixel size (mm a pixel), positions centred on the image with
    # their frame's origin in front of every light.
    assert json.loads((out / "camera.json").read_text()) == {"pixel_size": pytest.approx(1.0, rel=0.02)}
    written = [list(map(float, line.split()))
               for line in (out / "light_positions.txt").read_text().splitlines()]
    assert max(w[2] for w in written) < 0  # every light in front of the frame's origin
    # x, y in the image-centred frame; z up to the frame's shift (the nearest light's z less a
    # radius, itself triangulated).
    shift = sum(w[2] - p[2] for w, p in zip(written, positions)) / len(positions)
    for w, p in zip(written, positions):
        truth = [p[0] - 120, p[1], p[2] + shift]
        assert math.dist(w, truth) < 0.03 * math.dist(p, (120, 0, 0)), (w, truth)
