"""The Python view of the reflection model: seed 002, vectorized shading, presets, errors."""
import json
import math

import numpy as np
import pytest

import iphong
from conftest import FIXTURES


def seed002():
    return json.loads((FIXTURES / "seed002_example.json").read_text())


def seed002_scene():
    f = seed002()
    material = iphong.Material(**f["material"])
    lights = [iphong.DirectionalLight(direction=l["direction"], intensity=l["intensity"])
              for l in f["lights"]]
    view = -np.asarray(f["view_seed"])  # seed 002's V points from the viewer to the surface
    return f, material, lights, view


def test_seed002_worked_example():
    f, material, lights, view = seed002_scene()
    intensity = iphong.shade(f["normal"], view, material, lights, f["ambient"])
    np.testing.assert_allclose(intensity, f["expected_intensity"], atol=f["tolerance"])


def test_issue_snippet_reproduces_seed002():
    material = iphong.Material(ka=[0.1, 0.1, 0.1], kd=[0.9, 0.0, 0.0], ks=[0.5, 0.5, 0.4],
                               shininess=10)
    lights = [iphong.DirectionalLight(direction=[0.57735, 0.57735, 0.57735], intensity=[0.5] * 3),
              iphong.DirectionalLight(direction=[0, 0, -1], intensity=[0.5] * 3)]
    i = iphong.shade([0, 0, 1], [-0.23570, -0.23570, 0.94281], material, lights, [1, 1, 1])
    np.testing.assert_allclose(i, [0.39272, 0.13292, 0.12634], atol=1e-5)


def phong_illumination_seed004(normal, view, material, lights, ambient):
    """Seed 004's reference implementation (per point, numpy), without its final clip."""
    color = np.asarray(material.ka) * ambient
    for light in lights:
        l = np.asarray(light.direction)
        n_dot_l = max(0.0, float(np.dot(normal, l)))
        if n_dot_l > 0:
            color = color + np.asarray(material.kd) * light.diffuse_intensity * n_dot_l
            r = 2.0 * n_dot_l * normal - l
            r = r / np.linalg.norm(r)
            r_dot_v = max(0.0, float(np.dot(r, view)))
            color = color + np.asarray(material.ks) * light.specular_intensity * r_dot_v ** material.shininess
    return color


def test_matches_seed004_reference_on_random_normals():
    rng = np.random.default_rng(5)
    normals = rng.normal(size=(300, 3))
    normals[:, 2] = np.abs(normals[:, 2])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    material = iphong.material("brass")
    lights = [iphong.DirectionalLight(direction=[0.3, 0.4, 0.866], intensity=[1, 0.9, 0.8]),
              iphong.DirectionalLight(direction=[-0.5, 0.1, 0.7], intensity=0.5)]
    ambient = np.array([0.2, 0.2, 0.2])
    view = np.array([0.0, 0.0, 1.0])
    ours = iphong.shade(normals, view, material, lights, ambient)
    assert ours.shape == (300, 3)
    ref = np.array([phong_illumination_seed004(n, view, material, lights, ambient) for n in normals])
    np.testing.assert_allclose(ours, ref, rtol=1e-10, atol=1e-12)


def test_image_shaped_input_keeps_shape_and_float32():
    h, w = 4, 5
    normals = np.zeros((h, w, 3), np.float32)
    normals[..., 2] = 1
    out = iphong.shade(normals, [0, 0, 1], iphong.material("jade"),
                       [iphong.DirectionalLight(direction=[0, 0, 1])], 1.0)
    assert out.shape == (h, w, 3) and out.dtype == np.float32
    jade = iphong.materials["jade"]
    np.testing.assert_allclose(out[2, 3], np.add(jade.ka, jade.kd) + jade.ks, rtol=1e-6)


def test_per_pixel_views_and_mask():
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    views = np.array([[0, 0, 1], [1, 0, 1], [0, 0, 1]], float)
    mask = np.array([True, True, False])
    light = iphong.DirectionalLight(direction=[0, 0, 1])
    m = iphong.Material(ks=1.0, shininess=8)
    out = iphong.shade(normals, views, m, [light], mask=mask)
    assert out[0, 0] == pytest.approx(1.0)
    assert out[1, 0] == pytest.approx(math.cos(math.pi / 4) ** 8)
    assert np.all(out[2] == 0)


def test_blinn_phong_and_lambert_models():
    n = np.array([0.2, -0.1, 0.97])
    n /= np.linalg.norm(n)
    light = iphong.DirectionalLight(direction=n)
    m = iphong.Material(kd=0.5, ks=0.5, shininess=30)
    for model in ("phong", "blinn-phong"):
        assert iphong.shade(n, n, m, [light], model=model)[0] == pytest.approx(1.0)
    assert iphong.shade(n, n, m, [light], model="lambert")[0] == pytest.approx(0.5)
    with pytest.raises(ValueError, match="unknown reflectance model"):
        iphong.shade(n, n, m, [light], model="ward")


def test_point_light_with_falloff_needs_positions():
    light = iphong.PointLight(position=[0, 0, 2], intensity=1.0)
    m = iphong.Material(kd=1.0)
    out = iphong.shade([0, 0, 1], [0, 0, 1], m, [light], position=[1, 0, 0], model="lambert")
    assert out[0] == pytest.approx((2 / math.sqrt(5)) / 5)
    with pytest.raises(ValueError, match="point lights need surface positions"):
        iphong.shade([0, 0, 1], [0, 0, 1], m, [light])


def test_presets_are_published_values():
    assert len(iphong.materials) == 13
    gold = iphong.materials["gold"]
    np.testing.assert_allclose(gold.kd, [0.75, 0.61, 0.23])
    assert gold.shininess == pytest.approx(51.2)
    assert iphong.material("Phong_Chrome").shininess == 150
    with pytest.raises(ValueError, match="known: matte"):
        iphong.material("vantablack")


@pytest.mark.parametrize("kwargs, message", [
    (dict(ka=-0.1), "ka"),
    (dict(kd=[0.5, float("nan"), 0.5]), "kd"),
    (dict(ks=[1, 2]), "ks: expected 3 numbers, got 2"),
    (dict(shininess=-3), "shininess"),
])
def test_bad_materials_raise_value_error(kwargs, message):
    with pytest.raises(ValueError, match=message):
        iphong.Material(**kwargs)


def test_bad_vectors_raise_value_error():
    m = iphong.material("plastic")
    light = iphong.DirectionalLight(direction=[0, 0, 1])
    with pytest.raises(ValueError, match="light direction"):
        iphong.DirectionalLight(direction=[0, 0, 0])
    with pytest.raises(ValueError, match="intensity"):
        iphong.DirectionalLight(direction=[0, 0, 1], intensity=[1, -1, 1])
    with pytest.raises(ValueError, match="normal 1"):
        iphong.shade([[0, 0, 1], [0, 0, 0]], [0, 0, 1], m, [light])
    with pytest.raises(ValueError, match="normal 0"):
        iphong.shade([float("nan"), 0, 1], [0, 0, 1], m, [light])
    with pytest.raises(ValueError, match="view 0"):
        iphong.shade([0, 0, 1], [0, 0, 0], m, [light])
    with pytest.raises(ValueError, match="shape"):
        iphong.shade(np.ones((4, 2)), [0, 0, 1], m, [light])
