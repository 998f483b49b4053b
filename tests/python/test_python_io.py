"""Python arrays as people have them (integers, greyscale, (H, W, K, 3), RGB masks, Material
objects) and the writers: each either does the right thing or says in one short line what to
pass; the files are the command line's."""
import numpy as np
import pytest

import iphong

LIGHTS = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8], [-0.5, -0.3, 0.81]])


@pytest.fixture(scope="module")
def sphere():
    scene = {"width": 48, "height": 40, "camera": {"type": "orthographic", "extent": 2.2},
             "lights": [{"type": "directional", "direction": list(d)} for d in LIGHTS],
             "objects": [{"shape": "sphere", "radius": 0.9, "subdivisions": 4,
                          "material": {"kd": [0.7, 0.7, 0.7]}}]}
    return iphong.render(scene, per_light=True)


def mean_error(result, truth):
    return iphong.angular_error(result["normals"], truth["normals"], truth["mask"])[
        "mean_angular_error_deg"]


def test_integer_images_are_refused_unless_an_encoding_says_how_to_scale_them(sphere):
    codes = np.round(np.clip(sphere["images"], 0, 1) * 255).astype(np.uint8)
    with pytest.raises(ValueError, match=r"uint8 values \(0-255\) would be used unscaled; pass "
                                         r"floats in \[0, 1\] \(images / 255\), or encoding="):
        iphong.estimate_normals(codes, LIGHTS, mask=sphere["mask"], model="lambert")
    scaled = iphong.estimate_normals(codes, LIGHTS, mask=sphere["mask"], model="lambert",
                                     encoding="linear")
    by_hand = iphong.estimate_normals(codes / np.float32(255), LIGHTS, mask=sphere["mask"],
                                      model="lambert")
    np.testing.assert_array_equal(scaled["normals"], by_hand["normals"])
    assert mean_error(scaled, sphere) < 1.0  # 8-bit quantization only
    # encoding="srgb" undoes the sRGB curve (IEC 61966-2-1: 0.04045 -> 0.0031308, 0.5 -> 0.214041).
    np.testing.assert_allclose(iphong._core._srgb_to_linear(np.array([0, 0.04045, 0.5, 1.0])),
                               [0, 0.0031308, 0.214041, 1], atol=2e-6)
    srgb_codes = np.round(np.clip(sphere["images"], 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)
    decoded = iphong.estimate_normals(srgb_codes, LIGHTS, mask=sphere["mask"], model="lambert",
                                      encoding="srgb")
    # Measured 1.23° (sRGB is close to the gamma 2.2 used here); read as linear: 14.1°.
    assert mean_error(decoded, sphere) < 2.0


def test_shapes_people_pass(sphere):
    images, mask = sphere["images"], sphere["mask"]
    reference = iphong.estimate_normals(images, LIGHTS, mask=mask, model="lambert")
    # (H, W, K, 3): a message naming the expected layout and the fix, not the array.
    with pytest.raises(ValueError) as error:
        iphong.estimate_normals(np.moveaxis(images, 0, 2), LIGHTS, mask=mask)
    assert "looks like (H, W, K, 3); expected (K, H, W, 3): use numpy.moveaxis(images, 2, 0)" in \
        str(error.value)
    assert len(str(error.value)) < 200
    # Greyscale stacks (K, H, W) and RGB masks.
    grey = iphong.estimate_normals(images[..., 0], LIGHTS, mask=np.dstack([mask] * 3) * 255,
                                   model="lambert")
    np.testing.assert_allclose(grey["normals"], reference["normals"], atol=1e-6)


def test_materials_as_objects_or_dicts_with_known_keys_only(sphere):
    images, mask = sphere["images"], sphere["mask"]
    as_dict = iphong.estimate_normals(images, LIGHTS, mask=mask,
                                      material={"ks": 0, "shininess": 1})
    as_object = iphong.estimate_normals(images, LIGHTS, mask=mask,
                                        material=iphong.Material(ks=0, shininess=1))
    np.testing.assert_array_equal(as_dict["normals"], as_object["normals"])
    with pytest.raises(ValueError, match=r"material: unknown key 'shiny' \(valid: ambient, ka, kd, "
                                         r"ks, model, shininess\)"):
        iphong.estimate_normals(images, LIGHTS, mask=mask, material={"ks": 0.2, "shiny": 30})
    lights = [iphong.DirectionalLight(direction=[0, 0, 1], intensity=[1, 1, 1])]
    np.testing.assert_allclose(iphong.shade([0, 0, 1], [0, 0, 1], {"kd": [1, 0, 0]}, lights),
                               [1, 0, 0])
    with pytest.raises(ValueError, match=r"unknown key 'shiny' \(valid: ka, kd, ks, shininess\)"):
        iphong.shade([0, 0, 1], [0, 0, 1], {"kd": 1, "shiny": 3}, lights)


def test_a_wrong_argument_type_is_one_short_line(sphere):
    with pytest.raises(TypeError) as error:
        iphong.estimate_normals(sphere["images"], LIGHTS, discard_dark="most")
    text = str(error.value)
    assert "\n" not in text and len(text) < 700 and "[[" not in text
    assert "discard_dark" in text and "got (" in text
    with pytest.raises(TypeError) as error:
        iphong.integrate(sphere["normals"], sphere["mask"], min_cos="small")
    assert "\n" not in str(error.value) and "[[" not in str(error.value)


def test_save_dataset_is_what_load_dataset_and_the_cli_read(sphere, tmp_path):
    folder = tmp_path / "set"
    iphong.save_dataset(folder, sphere["images"], LIGHTS, mask=sphere["mask"],
                        normal_gt=sphere["normals"])
    back = iphong.load_dataset(folder)
    assert back["filenames"] == ["001.png", "002.png", "003.png", "004.png"]
    np.testing.assert_allclose(back["images"], np.clip(sphere["images"], 0, 1), atol=1 / 65535)
    np.testing.assert_allclose(back["light_directions"], LIGHTS / np.linalg.norm(LIGHTS, axis=1)[:, None],
                               atol=1e-8)
    np.testing.assert_array_equal(back["mask"], sphere["mask"])
    np.testing.assert_allclose(back["normal_gt"], sphere["normals"], atol=1e-7)
    # A folder is never written over unless asked, and then only an earlier save_dataset's.
    with pytest.raises(OSError, match="pass overwrite=True to replace its files"):
        iphong.save_dataset(folder, sphere["images"], LIGHTS)
    iphong.save_dataset(folder, sphere["images"], LIGHTS, overwrite=True)


def test_save_normals_and_save_mesh(sphere, tmp_path):
    normals, mask = sphere["normals"], sphere["mask"]
    for name in ["n.exr", "n.png"]:
        iphong.save_normals(tmp_path / name, normals, mask)
        assert (tmp_path / name).stat().st_size > 100
        with pytest.raises(OSError, match="exists; pass overwrite=True"):
            iphong.save_normals(tmp_path / name, normals, mask)
    iphong.save_normals(tmp_path / "n.png", normals, mask, overwrite=True)
    with pytest.raises(ValueError, match=r"expected \.exr or \.tif"):
        iphong.save_normals(tmp_path / "n.jpg", normals, mask)

    height = iphong.integrate(normals, mask)["height"]
    vertices, triangles = iphong.save_mesh(tmp_path / "m.ply", height, mask, normals=normals,
                                           albedo=np.ones(normals.shape, np.float32))
    assert vertices == mask.sum() and triangles > vertices
    header = (tmp_path / "m.ply").read_bytes()[:400]
    assert b"element vertex %d" % vertices in header and b"property uchar red" in header
    iphong.save_mesh(tmp_path / "m.obj", height, mask)
    assert (tmp_path / "m.obj").read_text().count("\nf ") == triangles
