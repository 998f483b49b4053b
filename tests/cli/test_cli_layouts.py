"""Captures in the layouts people have (UW, RTI .lp, AliceVision JSON, a plain folder), read as
they are and giving the same normals as the DiLiGenT layout of the same data; what the reader
chose is printed; --downscale, --crop, --json and --quiet. Uses ../shared/data (skips when absent);
the test folders hold symbolic links to it, never copies."""
import json
import os
import pathlib
import subprocess

import pytest

from cli import IPHONG, ROOT, binary_available, run

DATA = pathlib.Path(os.environ.get("IPHONG_DATA_DIR", ROOT.parent / "shared" / "data"))
UW = DATA / "uw"
CROP_CAT = DATA / "diligent-crop8" / "cat"
# What these tests compare is how files are read, which every solve depends on alike: the fastest
# one (Lambert at distant lights) shows a light, an intensity or a pixel read differently.
LAMBERT = ("--model", "lambert", "--light-distance", "inf")

pytestmark = [
    pytest.mark.skipif(not binary_available(), reason=f"no iphong binary at {IPHONG}"),
    pytest.mark.skipif(not (UW / "cat").is_dir() or not CROP_CAT.is_dir(),
                       reason=f"real data not found at {DATA} (set IPHONG_DATA_DIR)"),
]


def normals(dataset, out, *flags):
    code, stdout, stderr = run("normals", dataset, "-o", out, *flags, timeout=300)
    assert code == 0, stderr
    return stdout, json.loads((pathlib.Path(out) / "metrics.json").read_text())


def angle_between(a, b):
    """Mean angle (degrees) between two normal maps, by iphong eval."""
    code, stdout, stderr = run("eval", a, b)
    assert code == 0, stderr
    return json.loads(stdout)["mean_angular_error_deg"]


def link(target, name):
    pathlib.Path(name).symlink_to(target)


def uw_as_diligent(obj, folder, order):
    """UW's `obj` in the DiLiGenT layout, its images listed in `order` (indices)."""
    folder.mkdir()
    lights = (UW / "lights.txt").read_text().split("\n")[1:13]
    for i in range(12):
        link(UW / obj / f"{obj}.{i}.tga", folder / f"{obj}.{i}.tga")
    link(UW / obj / f"{obj}.mask.tga", folder / "mask.tga")
    (folder / "filenames.txt").write_text("".join(f"{obj}.{i}.tga\n" for i in order))
    (folder / "light_directions.txt").write_text("\n".join(lights) + "\n")
    return folder


def test_a_camera_beside_light_directions_is_said_not_read(tmp_path):
    plain = uw_as_diligent("cat", tmp_path / "plain", range(12))
    normals(plain, tmp_path / "plain-out", *LAMBERT)
    with_camera = uw_as_diligent("cat", tmp_path / "camera", range(12))
    (with_camera / "camera.json").write_text('{"fx": 800, "fy": 800, "cx": 256, "cy": 256}\n')
    code, _, stderr = run("normals", with_camera, "-o", tmp_path / "camera-out", *LAMBERT,
                          timeout=300)
    assert code == 0, stderr
    assert "camera.json: not read: a camera is read with light_positions.txt" in stderr
    assert "(V = (0, 0, 1), an orthographic view)" in stderr
    assert angle_between(tmp_path / "plain-out" / "normals.exr",
                         tmp_path / "camera-out" / "normals.exr") < 1e-6
    # Without the file, no such line.
    code, _, stderr = run("normals", plain, "-o", tmp_path / "again", *LAMBERT, timeout=300)
    assert code == 0 and "camera.json" not in stderr, stderr


def test_uw_cat_runs_as_it_is_and_says_what_it_read(tmp_path):
    stdout, metrics = normals(UW / "cat", tmp_path / "out", *LAMBERT)
    line = stdout.splitlines()[0]
    assert "12 images (folder layout, natural order: cat.0.tga ... cat.11.tga)" in line
    assert "lights.txt (count + directions)" in line
    assert "mask cat.mask.tga" in line
    assert "encoding linear (8-bit targa states no colour space" in line
    assert metrics["input"]["mask"].endswith("cat.mask.tga")
    assert [i["file"] for i in metrics["input"]["images"]][:3] == [
        "cat.0.tga", "cat.1.tga", "cat.2.tga"]

    # The same data in the DiLiGenT layout gives the same normals; in ls order it does not.
    same = uw_as_diligent("cat", tmp_path / "listed", range(12))
    normals(same, tmp_path / "listed-out", *LAMBERT)
    assert angle_between(tmp_path / "out" / "normals.exr", tmp_path / "listed-out" / "normals.exr") \
        < 1e-6
    ls_order = uw_as_diligent("cat", tmp_path / "ls", sorted(range(12), key=str))
    normals(ls_order, tmp_path / "ls-out", *LAMBERT)
    assert angle_between(tmp_path / "out" / "normals.exr", tmp_path / "ls-out" / "normals.exr") > 10


def uw_as_shipped(root, obj="cat", listed=True):
    """UW's archive as it is shipped (psmImages/): the photos, the mask and the companions
    NAME.albedo.tga, NAME.normals.dat and NAME.depths.dat in psmImages/NAME/, lights.txt and
    NAME.txt (a count line, then the photos and the mask as paths from the course's folder) in
    psmImages/. The object is called buddha; its photos are UW's cat."""
    psm = root / "psmImages"
    folder = psm / "buddha"
    folder.mkdir(parents=True)
    link(UW / "lights.txt", psm / "lights.txt")
    for i in range(12):
        link(UW / obj / f"{obj}.{i}.tga", folder / f"buddha.{i}.tga")
    link(UW / obj / f"{obj}.mask.tga", folder / "buddha.mask.tga")
    link(UW / obj / f"{obj}.3.tga", folder / "buddha.albedo.tga")
    (folder / "buddha.normals.dat").write_bytes(b"\0" * 64)
    (folder / "buddha.depths.dat").write_bytes(b"\0" * 64)
    if listed:
        entries = [f"psmImages/buddha/buddha.{i}.tga" for i in range(12)]
        (psm / "buddha.txt").write_text("12\n" + "\n".join(entries) +
                                        "\npsmImages/buddha/buddha.mask.tga\n")
    return folder


@pytest.mark.parametrize("listed", [True, False])
def test_uw_archive_as_shipped_runs_as_it_is(tmp_path, listed):
    """The list one folder up (count line, paths from elsewhere, the mask last) or none: the
    albedo picture is not a 13th photo, the companions are named as not read, and the normals
    are those of UW's cat folder."""
    folder = uw_as_shipped(tmp_path, listed=listed)
    stdout, metrics = normals(folder, tmp_path / "out", *LAMBERT)
    line = stdout.splitlines()[0]
    if listed:
        assert f"12 images (listed layout, {folder.parent / 'buddha.txt'}: " in line
    else:
        assert "12 images (folder layout, natural order: buddha.0.tga ... buddha.11.tga)" in line
    assert "mask buddha.mask.tga" in line
    assert line.endswith("not read: buddha.albedo.tga, buddha.depths.dat, buddha.normals.dat")
    normals(UW / "cat", tmp_path / "cat", *LAMBERT)
    assert angle_between(tmp_path / "out" / "normals.exr", tmp_path / "cat" / "normals.exr") < 1e-6


def test_images_list_names_the_photos_and_a_count_mismatch_says_how(tmp_path):
    folder = uw_as_shipped(tmp_path, listed=False)
    listing = tmp_path / "order.txt"  # the user's own list, outside the data folder
    listing.write_text("".join(f"buddha.{i}.tga\n" for i in range(12)))
    stdout, _ = normals(folder, tmp_path / "out", "--images", listing, *LAMBERT)
    assert f"listed layout, {listing}: buddha.0.tga ... buddha.11.tga" in stdout
    listing.write_text("12\n" + "".join(f"buddha.{i}.tga\n" for i in range(11)))
    code, _, err = run("normals", folder, "-o", tmp_path / "bad", "--images", listing)
    assert code == 1 and err.strip() == (f"iphong: error: {listing}:1: says 12 images, but lists "
                                         "11 photographs"), err
    # Eleven photos and twelve lights: the advice names a flag, not a file to write into the data.
    (folder / "buddha.11.tga").unlink()
    code, _, err = run("normals", folder, "-o", tmp_path / "bad")
    assert code == 1 and "list them in light order in a file given with --images LIST" in err, err
    assert "filenames.txt" not in err


def crop_cat_run(tmp_path):
    out = tmp_path / "diligent-out"
    _, metrics = normals(CROP_CAT, out, *LAMBERT)
    return out, metrics


def test_rti_lp_plain_folder_and_alicevision_json_match_the_diligent_layout(tmp_path):
    reference, reference_metrics = crop_cat_run(tmp_path)
    names = (CROP_CAT / "filenames.txt").read_text().split()
    directions = [line.split() for line in (CROP_CAT / "light_directions.txt").read_text().splitlines()]
    intensities = [line.split() for line in (CROP_CAT / "light_intensities.txt").read_text().splitlines()]
    common = ["--intensities", CROP_CAT / "light_intensities.txt", "--mask", CROP_CAT / "mask.png",
              *LAMBERT]

    # RTI: images renamed as a camera names them, the .lp in RTIBuilder's assembly-files/ with
    # the absolute Windows paths of the machine it ran on.
    rti = tmp_path / "rti"
    (rti / "assembly-files").mkdir(parents=True)
    lp = [str(len(names))]
    for i, (name, d) in enumerate(zip(names, directions)):
        link(CROP_CAT / name, rti / f"IMG_{i + 1:04d}.png")
        lp.append(f"C:\\Users\\someone\\capture\\jpeg-exports\\IMG_{i + 1:04d}.png {' '.join(d)}")
    (rti / "assembly-files" / "capture.lp").write_text("\n".join(lp) + "\n")
    stdout, _ = normals(rti, tmp_path / "rti-out", *common)
    assert "RTI .lp layout, capture.lp" in stdout
    assert angle_between(reference / "normals.exr", tmp_path / "rti-out" / "normals.exr") < 1e-6
    # Against the ground truth, the same figure.
    code, out, _ = run("eval", tmp_path / "rti-out" / "normals.exr", CROP_CAT)
    assert json.loads(out)["mean_angular_error_deg"] == pytest.approx(
        reference_metrics["mean_angular_error_deg"], abs=1e-6)

    # A plain folder of images, the light file elsewhere.
    plain = tmp_path / "plain"
    plain.mkdir()
    for name in names:
        link(CROP_CAT / name, plain / name)
    normals(plain, tmp_path / "plain-out", "--lights", CROP_CAT / "light_directions.txt", *common)
    assert angle_between(reference / "normals.exr", tmp_path / "plain-out" / "normals.exr") < 1e-6

    # AliceVision's lights JSON (its camera frame: y down, z away from the camera), intensities in it.
    lights = {"lights": [{"lightId": i, "type": "directional",
                          "direction": [float(d[0]), -float(d[1]), -float(d[2])],
                          "intensity": [float(v) for v in e]}
                         for i, (d, e) in enumerate(zip(directions, intensities))]}
    (tmp_path / "lights.json").write_text(json.dumps(lights))
    normals(plain, tmp_path / "json-out", "--lights", tmp_path / "lights.json", "--mask",
            CROP_CAT / "mask.png", *LAMBERT)
    assert angle_between(reference / "normals.exr", tmp_path / "json-out" / "normals.exr") < 1e-5


def test_mask_names_people_use(tmp_path):
    base = uw_as_diligent("cat", tmp_path / "cat", range(12))
    _, with_mask = normals(base, tmp_path / "a", *LAMBERT)
    for name in ["mask.png", "cat.mask.tga", "cat_mask.tga"]:
        current = next(p for p in base.iterdir() if "mask" in p.name)
        current.rename(base / name)
        stdout, metrics = normals(base, tmp_path / name, *LAMBERT)
        assert f"mask {name}" in stdout
        assert metrics["pixels"] == with_mask["pixels"] < 512 * 340 / 2
    next(p for p in base.iterdir() if "mask" in p.name).unlink()
    stdout, metrics = normals(base, tmp_path / "none", *LAMBERT)
    assert "mask none (the whole image)" in stdout and metrics["pixels"] == 512 * 340


def test_masks_as_photo_editors_save_them_and_commented_light_files(tmp_path):
    """A cut-out (the photo, its background transparent), a mask saved as JPEG and light files
    with '#' comments (numpy.savetxt's header) read as the DiLiGenT files do."""
    names = (CROP_CAT / "filenames.txt").read_text().split()
    reference = tmp_path / "reference"
    _, expected = normals(CROP_CAT, reference, *LAMBERT)
    folder = tmp_path / "cat"
    folder.mkdir()
    for name in names:
        link(CROP_CAT / name, folder / name)
    (folder / "filenames.txt").write_text("# the photos, in light order\n" + "\n".join(names))
    for text in ("light_directions", "light_intensities"):
        lines = (CROP_CAT / f"{text}.txt").read_text()
        (folder / f"{text}.txt").write_text("# x y z\n" + lines.replace("\n", "\n# next\n", 3))
    subprocess.run(["oiiotool", CROP_CAT / names[0], "--ch", "R,G,B", CROP_CAT / "mask.png",
                    "--ch", "0", "--chappend", "--chnames", "R,G,B,A", "-d", "uint8", "-o",
                    folder / "mask.png"], check=True)
    stdout, cutout = normals(folder, tmp_path / "cutout", *LAMBERT)
    assert "mask mask.png (its alpha channel: transparent = background)" in stdout
    assert cutout["pixels"] == expected["pixels"]
    assert angle_between(reference / "normals.exr", tmp_path / "cutout" / "normals.exr") < 1e-6

    (folder / "mask.png").unlink()
    subprocess.run(["oiiotool", CROP_CAT / "mask.png", "-d", "uint8", "-o", folder / "mask.jpg"],
                   check=True)
    stdout, jpeg = normals(folder, tmp_path / "jpeg", *LAMBERT, "--mask",
                           folder / "mask.jpg")
    assert "(above half its largest value: lossy compression" in stdout
    assert jpeg["pixels"] == pytest.approx(expected["pixels"], abs=expected["pixels"] * 0.002)


def test_an_intensity_file_a_line_off_is_named_and_the_right_one_is_not(tmp_path):
    """DiLiGenT's cat with its intensity file a line off (a line added at the top, the last one
    lost): it fits the images better than no file, so only its own re-readings show it."""
    names = (CROP_CAT / "filenames.txt").read_text().split()
    folder = tmp_path / "cat"
    folder.mkdir()
    for name in names + ["filenames.txt", "light_directions.txt", "mask.png"]:
        link(CROP_CAT / name, folder / name)
    lines = (CROP_CAT / "light_intensities.txt").read_text().split("\n")[:len(names)]
    (folder / "light_intensities.txt").write_text("\n".join([lines[-1]] + lines[:-1]) + "\n")
    code, _, stderr = run("normals", folder, "-o", tmp_path / "off", *LAMBERT)
    assert code == 0, stderr
    assert ("light_intensities.txt: the images' brightness follows their lights' directions "
            "better with these intensities read 1 line further down (image 1 on line 2) than "
            "as listed") in stderr
    code, _, stderr = run("normals", CROP_CAT, "-o", tmp_path / "right", *LAMBERT)
    assert code == 0, stderr
    assert "light_intensities.txt" not in stderr


def test_downscale_and_crop_keep_the_error(tmp_path):
    _, full = crop_cat_run(tmp_path)
    _, half = normals(CROP_CAT, tmp_path / "half", "--downscale", "2", *LAMBERT)
    assert half["input"]["size"] == [148, 160] and half["input"]["file_size"] == [296, 320]
    assert half["mean_angular_error_deg"] == pytest.approx(full["mean_angular_error_deg"], abs=1.0)
    stdout, cut = normals(CROP_CAT, tmp_path / "cut", "--crop", "0,0,296,160", *LAMBERT)  # top half
    assert "296x320 read as 296x160" in stdout
    assert cut["pixels"] < full["pixels"] and cut["evaluated_pixels"] == cut["pixels"]
    assert cut["mean_angular_error_deg"] == pytest.approx(full["mean_angular_error_deg"], abs=2.0)
    code, _, stderr = run("normals", CROP_CAT, "-o", tmp_path / "bad", "--crop", "200,0,200,10")
    assert code == 1 and "reaches outside the 296x320 image" in stderr
    assert not (tmp_path / "bad").exists()


def test_json_and_quiet(tmp_path):
    code, stdout, stderr = run("normals", UW / "gray", "-o", tmp_path / "j", "--json")
    assert code == 0, stderr
    assert json.loads(stdout) == json.loads((tmp_path / "j" / "metrics.json").read_text())
    code, stdout, stderr = run("normals", UW / "gray", "-o", tmp_path / "q", "--quiet")
    assert code == 0 and stdout == ""


def test_eval_reads_png_normal_maps_in_both_conventions(tmp_path):
    exr = None
    for convention in ["opengl", "directx"]:
        out = tmp_path / convention
        _, metrics = normals(CROP_CAT, out, "--normal-map-convention", convention, *LAMBERT)
        exr = exr or metrics["mean_angular_error_deg"]
        code, stdout, stderr = run("eval", out / "normals.png", CROP_CAT,
                                   "--normal-map-convention", convention)
        assert code == 0, stderr
        assert json.loads(stdout)["mean_angular_error_deg"] == pytest.approx(exr, abs=0.01)
    # DiLiGenT's own 8-bit picture of its ground truth: the quantization only.
    code, stdout, _ = run("eval", CROP_CAT / "Normal_gt.png", CROP_CAT)
    assert json.loads(stdout)["mean_angular_error_deg"] < 0.5
    # The albedo handed in for the normals (the file next to it) is said, scored by direction.
    code, stdout, stderr = run("eval", out / "albedo.exr", CROP_CAT)
    assert code == 0 and json.loads(stdout)["mean_angular_error_deg"] > 30
    assert stderr.startswith(f"iphong: warning: {out / 'albedo.exr'}: ")
    assert "is it a normal map" in stderr
    code, _, stderr = run("eval", out / "normals.exr", CROP_CAT)
    assert code == 0 and stderr == ""


def test_integrate_takes_diligent_ground_truth_without_flags(tmp_path):
    for source in [CROP_CAT, CROP_CAT / "Normal_gt.png"]:
        out = tmp_path / source.name
        code, stdout, stderr = run("integrate", source, "-o", out, "--json")
        assert code == 0, stderr
        report = json.loads((out / "integrate.json").read_text())
        assert json.loads(stdout) == report
        # A few silhouette normals tip past 90°: clamped to grazing and counted.
        assert 0 < report["back_facing_pixels"] < 0.02 * report["pixels"]
        assert "face away from the camera: taken as grazing" in stderr



def test_an_output_folder_may_not_hold_a_file_the_capture_flags_name(tmp_path):
    normals(UW / "gray", tmp_path / "out")
    mask = tmp_path / "out" / "my-mask.tga"  # the user keeps the mask in an earlier output
    mask.write_bytes((UW / "gray" / "gray.mask.tga").read_bytes())
    before = {p: p.read_bytes() for p in (tmp_path / "out").iterdir() if p.is_file()}
    code, _, stderr = run("normals", UW / "gray", "-o", tmp_path / "out", "--overwrite",
                          "--mask", mask)
    assert code == 4 and "input" in stderr, stderr
    assert {p: p.read_bytes() for p in (tmp_path / "out").iterdir() if p.is_file()} == before
