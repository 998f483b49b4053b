"""Bad input to the Python module: ValueError (TypeError for a value of the wrong Python type)
with a one-line message naming the argument — never a segfault, RuntimeError or pybind11's
"Unable to cast" (issue 10)."""
import shutil
import subprocess

import numpy as np
import pytest

import iphong

IMAGES = np.zeros((3, 4, 4, 3), np.float32)
LIGHTS = np.eye(3)


@pytest.mark.parametrize("material, error, pattern", [
    ({"ks": "shiny", "shininess": 10}, TypeError, r"material\['ks'\]: expected 3 numbers, got str"),
    ({"ks": {"r": 1}}, TypeError, r"material\['ks'\]: expected 3 numbers, got dict"),
    ({"ks": 0.1, "shininess": "high"}, TypeError, r"material\['shininess'\]: expected a number"),
    ({"ks": [0.1, 0.2]}, ValueError, r"material\['ks'\]: expected 3 numbers, got 2"),
    ({"ks": 0.1, "shininess": float("nan")}, ValueError, r"shininess.*finite"),
    ({"ks": -1}, ValueError, r"ks must be finite and >= 0"),
    ({"kss": 0.1}, ValueError, r"material: unknown key 'kss'"),
    ({"model": 3}, TypeError, r"material\['model'\]: expected a string"),
    ([1, 2], TypeError, r"material: expected an iphong.Material or a dict"),
])
def test_bad_material_dicts(material, error, pattern):
    with pytest.raises(error, match=pattern):
        iphong.estimate_normals(IMAGES, LIGHTS, material=material)


def test_two_images_with_a_string_albedo():
    with pytest.raises(TypeError, match=r"material\['kd'\]: expected 3 numbers, got str"):
        iphong.estimate_normals(np.zeros((2, 4, 4, 3), np.float32), [[0, 0, 1], [0, 1, 1]],
                                material={"kd": "red"})


def test_one_image_is_refused_when_its_global_solve_would_not_fit():
    """One or two images are solved whole at about 4 kB a masked pixel: a 2000 x 2000 image needs
    16 GB, which is refused before the solve starts rather than let it outgrow the machine (a
    12-megapixel photo would need some 45 GB); a small one runs under the same limit."""
    big = np.full((1, 2000, 2000, 3), 0.5, np.float32)
    with pytest.raises(ValueError, match=r"one- and two-image solve of 4000000 pixels needs 16.0 GB, "
                                         r"more than the memory limit of 1.0 GB \(raise it with "
                                         r"max_memory_gb=\)"):
        iphong.estimate_normals(big, [[0, 0, 1]], material={"kd": 0.5}, max_memory_gb=1)
    for bad, why in ((0, "must be a size > 0"), (1e-12, "is less than one byte"),
                     (1e308, "is more than 1e9 GB"), ("16XB", "has an unknown unit 'xb'")):
        with pytest.raises(ValueError, match=f"max_memory_gb: .*{why}"):
            iphong.estimate_normals(big[:, :8, :8], [[0, 0, 1]], material={"kd": 0.5},
                                    max_memory_gb=bad)
    # Sizes as Dask writes them: "512MB" is half a GB, too little for 16 GB.
    with pytest.raises(ValueError, match=r"more than the memory limit of 512 MB"):
        iphong.estimate_normals(big, [[0, 0, 1]], material={"kd": 0.5}, max_memory_gb="512MB")
    small = iphong.estimate_normals(big[:, :16, :16], [[0, 0, 1]], material={"kd": 0.5},
                                    max_memory_gb=1)
    # 0.5 = kd 0.5 x N.L: every normal faces the light, (0, 0, 1).
    assert np.allclose(small["normals"][..., 2], 1, atol=1e-3)


def test_height_to_mesh_with_zero_intrinsics():
    height = np.zeros((4, 4), np.float32)
    with pytest.raises(ValueError, match="intrinsics need fx, fy between 1e-12 and 1e12"):
        iphong.height_to_mesh(height, np.ones((4, 4), bool), intrinsics=(0, 0, 0, 0))
    with pytest.raises(TypeError, match=r"intrinsics \(fx, fy, cx, cy\): expected 4 numbers"):
        iphong.height_to_mesh(height, np.ones((4, 4), bool), intrinsics="wide")
    with pytest.raises(ValueError, match="pixel size must be between 1e-12 and 1e12"):
        iphong.normals_from_height(height, pixel_size=0)
    # 1e308 wrote infinite heights (and an empty mesh from the CLI) behind success.
    with pytest.raises(ValueError, match="pixel size must be between 1e-12 and 1e12"):
        iphong.height_to_mesh(height, np.ones((4, 4), bool), pixel_size=1e308)


def test_render_refuses_what_would_not_fit_naming_the_knob():
    scene = {"width": 65536, "height": 65536, "lights": [{"direction": [0, 0, 1]}],
             "objects": [{"shape": "sphere"}]}
    with pytest.raises(ValueError, match=r"needs [\d.]+ GB, more than the memory limit of [\d.]+ "
                                         r"GB \(raise it with max_memory_gb=\)"):
        iphong.render(scene)
    small = dict(scene, width=64, height=64)
    with pytest.raises(ValueError, match="2097152 triangles .* memory limit of 100 MB"):
        iphong.render(dict(small, objects=[{"shape": "plane", "divisions": 1024}]),
                      max_memory_gb=0.1)
    assert iphong.render(small, max_memory_gb=1)["image"].shape == (64, 64, 3)


def test_render_names_values_that_overflow_together():
    """ks 1e300 and ambient 1e300 are each a valid number; the image they make is not (float):
    said as the scene's, where the writer named only 'image 1'."""
    scene = {"width": 32, "height": 32, "lights": [{"direction": [0, 0, 1]}],
             "objects": [{"shape": "sphere", "material": {"kd": 0.5, "ks": 1e300}}]}
    with pytest.raises(ValueError, match=r"the image overflows float at \d+ pixel\(s\) \(the "
                                         r"first at column \d+, row \d+\): light intensities"):
        iphong.render(scene)
    scene["objects"][0]["material"]["ks"] = 0.5
    with pytest.raises(ValueError, match=r"the image overflows float at 1024 pixel"):
        iphong.render(dict(scene, noise={"gaussian_sigma": 1e300, "seed": 1}), per_light=True)
    assert np.isfinite(iphong.render(scene)["image"]).all()


@pytest.mark.parametrize("scene, error, pattern", [
    ({"width": 4294967328, "lights": [{"direction": [0, 0, 1]}], "objects": [{"shape": "sphere"}]},
     ValueError, r"scene: width: integer out of range"),
    ({"lights": [{"direction": [0, 0, 1]}], "objects": [{"shape": "sphere",
                                                         "material": {"shininess": "high"}}]},
     ValueError, r"objects\[0\]\.material\.shininess: expected a number"),
    ({"lights": [{"direction": [0, 0, 1]}], "objects": [{"shape": "sphere", "radius": float("inf")}]},
     ValueError, r"scene: not JSON"),
    (42, TypeError, r"scene: expected a dict or a path, got int"),
])
def test_bad_scenes(scene, error, pattern):
    with pytest.raises(error, match=pattern):
        iphong.render(scene)


def test_load_dataset_errors(tmp_path):
    with pytest.raises(ValueError, match="no such folder"):
        iphong.load_dataset(tmp_path / "absent")
    (tmp_path / "filenames.txt").write_text("001.png\n")
    (tmp_path / "light_directions.txt").write_text("0 0 1\n")
    with pytest.raises(ValueError, match=r"001\.png: no such file"):
        iphong.load_dataset(tmp_path)
    with pytest.raises(TypeError, match="directory: expected a path, got int"):
        iphong.load_dataset(3)


def test_shade_and_material_arguments():
    with pytest.raises(TypeError, match="shininess: expected a number, got str"):
        iphong.Material(0.1, 0.5, 0.2, "high")
    with pytest.raises(TypeError, match="ambient: expected 3 numbers, got str"):
        iphong.shade([0, 0, 1], [0, 0, 1], iphong.material("jade"),
                     [iphong.DirectionalLight([0, 0, 1])], ambient="x")


def test_coplanar_lights_are_an_error():
    lights = [[np.cos(a), 0, np.sin(a)] for a in (0.3, 0.6, 0.9, 1.2)]
    with pytest.raises(ValueError, match="lie in one plane"):
        iphong.estimate_normals(np.ones((4, 4, 4, 3), np.float32), lights)


def test_calibrate_lights_keeps_the_command_lines_ranges():
    images = np.full((3, 8, 8, 3), 0.5, np.float32)
    with pytest.raises(ValueError, match=r"max_spheres: expected 1 or 2"):
        iphong.calibrate_lights(images, max_spheres=3)
    with pytest.raises(ValueError, match=r"saturation: expected a number in \(0, 1\]"):
        iphong.calibrate_lights(images, saturation=2)


def test_nan_is_refused_by_the_shared_readers_and_writers(tmp_path):
    """A NaN used to pass through Python's writers and readers where the command line refused it:
    save_dataset, save_normals, load_dataset of a float capture, fit_material's float labels."""
    scene = {"width": 32, "height": 32, "lights": [{"type": "hemisphere", "count": 6}],
             "objects": [{"shape": "sphere", "radius": 0.9}]}
    capture = iphong.render(scene, per_light=True)
    images = capture["images"].copy()
    images[2, 10, 11, 1] = np.nan
    with pytest.raises(ValueError, match=r"image 3 has 1 pixel\(s\) that are not finite \(NaN or "
                                         r"infinite; the first at column 11, row 10\)"):
        iphong.save_dataset(tmp_path / "a", images, capture["light_directions"], format="exr")
    assert not (tmp_path / "a").exists()
    normals = capture["normals"].copy()
    normals[5, 6] = np.nan
    with pytest.raises(ValueError, match=r"1 normals are not finite .*column 6, row 5"):
        iphong.save_normals(tmp_path / "n.exr", normals)
    with pytest.raises(ValueError, match=r"normals are not unit length \(\|n\| = 2"):
        iphong.save_normals(tmp_path / "n.exr", 2 * capture["normals"])
    assert not (tmp_path / "n.exr").exists()
    labels = np.where(capture["mask"], 1.0, -1.0)
    labels[16, 16] = np.nan
    with pytest.raises(ValueError, match=r"regions: labels must be whole numbers; the value at "
                                         r"row 16, column 16 is nan"):
        iphong.fit_material(capture["images"], capture["light_directions"], capture["normals"],
                            mask=capture["mask"], albedo="regions", regions=labels)


@pytest.mark.skipif(shutil.which("oiiotool") is None, reason="oiiotool not installed")
def test_a_nan_in_a_float_capture_is_named_on_load(tmp_path):
    scene = {"width": 32, "height": 32, "lights": [{"type": "hemisphere", "count": 6}],
             "objects": [{"shape": "sphere", "radius": 0.9}]}
    capture = iphong.render(scene, per_light=True)
    folder = tmp_path / "cap"
    iphong.save_dataset(folder, capture["images"], capture["light_directions"],
                        mask=capture["mask"], format="exr")
    image = folder / "004.exr"
    subprocess.run(["oiiotool", str(image), "--subc", "2", "--powc", "0.5", "-o", str(image)],
                   check=True)  # the square root of a negative number: NaN everywhere
    inside = int(capture["mask"].sum())
    with pytest.raises(ValueError, match=rf"004\.exr: {inside} pixel\(s\) inside the mask are not "
                                         r"finite \(NaN or infinite; the first at column \d+, "
                                         r"row \d+\)"):
        iphong.load_dataset(folder)


def test_a_huge_broadcast_array_is_iphongs_value_error_not_numpys_memory_error():
    """numpy.broadcast_to makes a 2.9 TB array for free; the wrapper's float32 copy used to fail
    with numpy's MemoryError (or take the machine) before iphong checked the size."""
    huge = np.broadcast_to(np.float32(0.5), (12, 100000, 100000, 3))
    directions = np.tile([[0.0, 0.0, 1.0]], (12, 1))
    with pytest.raises(ValueError, match=r"images: copying an array of shape \(12, 100000, "
                                         r"100000, 3\) to float32 needs 2880\.0 GB, more than the "
                                         r"memory limit of .* \(raise it with max_memory_gb=\)"):
        iphong.estimate_normals(huge, directions)
    with pytest.raises(ValueError, match=r"more than the memory limit of 1 kB"):
        iphong.estimate_normals(huge[:, :8, :8], directions, max_memory_gb="1kB")


def test_a_huge_array_is_refused_with_the_figure_before_it_is_copied():
    """A broadcast view costs nothing until it is copied: 40000 x 40000 normals were copied into
    19 GB and the process was killed by the system. Every array the module converts to float32 is
    checked first, and integrate checks its work against max_memory_gb."""
    huge = np.broadcast_to(np.float32([0, 0, 1]), (40000, 40000, 3))
    with pytest.raises(ValueError, match=r"normals: copying an array of shape \(40000, 40000, 3\) "
                                         r"to float32 needs 38.4 GB, more than the memory limit"):
        iphong.integrate(huge, max_memory_gb=20)
    with pytest.raises(ValueError, match=r"estimate: copying an array of shape"):
        iphong.angular_error(huge, np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match=r"integrating 160000 pixels needs [\d.]+ MB, more than "
                                         r"the memory limit of 10 MB \(raise it with max_memory_gb=\)"):
        iphong.integrate(huge[:400, :400], max_memory_gb=0.01)
    assert iphong.integrate(huge[:400, :400])["height"].shape == (400, 400)


def test_angular_error_counts_estimates_that_are_not_finite():
    """NaN where another tool found no normal: a missing normal (180 degrees), counted and warned
    of; an estimate with no finite normal is refused, not scored 180."""
    truth = np.zeros((2, 3, 3), np.float32)
    truth[..., 2] = 1
    estimate = truth.copy()
    estimate[0, 1] = np.nan
    with pytest.warns(UserWarning, match=r"1 of 6 pixels with ground truth hold no finite normal"):
        m = iphong.angular_error(estimate, truth)
    assert m["not_finite_pixels"] == 1 and m["evaluated_pixels"] == 6
    assert m["mean_angular_error_deg"] == pytest.approx(30.0)
    assert m["error_deg"][0, 1] == 180
    with pytest.raises(ValueError, match=r"holds no finite normal where the ground truth has one "
                                         r"\(NaN or infinite at all 6 such pixels"):
        iphong.angular_error(np.full_like(truth, np.inf), truth)
    assert m["missing_pixels"] == 1
    estimate[1, 2] = 0  # iphong's and DiLiGenT's "no normal": missing, not warned of
    with pytest.warns(UserWarning, match=r"1 of 6 pixels"):  # the NaN still is
        m = iphong.angular_error(estimate, truth)
    assert m["missing_pixels"] == 2 and m["not_finite_pixels"] == 1
    with pytest.raises(ValueError, match=r"holds no normal where the ground truth has one "
                                         r"\(0 at all 6 such pixels\)"):
        iphong.angular_error(np.zeros_like(truth), truth)


def test_a_light_distance_beyond_1e12_pixels_is_refused():
    """Its irradiance 1/D² is below double's sums: it reached the lights' check ("light diffuse
    intensity must be between 0 and 1e30"); inf is the distant lights."""
    rng = np.random.default_rng(3)
    lights = rng.normal(size=(6, 3))
    lights[:, 2] = np.abs(lights[:, 2]) + 1
    lights /= np.linalg.norm(lights, axis=1, keepdims=True)
    images = rng.uniform(0.2, 0.8, size=(6, 8, 8, 3)).astype(np.float32)
    with pytest.raises(ValueError, match=r"distance must be 0 \(choose\), inf \(distant\) or "
                                         r"between 1e-12 and 1e12 pixels"):
        iphong.estimate_normals(images, lights, light_distance=1e300, model="lambert")
