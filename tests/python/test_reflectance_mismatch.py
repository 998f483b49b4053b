"""Normals from data that iphong's model did not make: surfaces shaded by other renderers' and real
materials' reflectance (brdf_zoo.py, numpy, from the papers), to check the default's mechanisms
against reflectance they were not built on, and to pin where the default still loses to Lambert
(docs/accuracy.md, "Reflectance that is not Phong's"; bench/reflectance_mismatch.py has the table).
"""
import numpy as np
import pytest

import iphong
from brdf_zoo import burley_diffuse, ggx, oren_nayar, oren_nayar_full, render, sphere
from test_normals_surfaces import SIZE, lights
from test_normals_surfaces import scene as surface_scene


def test_the_zoo_reduces_to_lambert_where_its_papers_say():
    """Oren-Nayar with smooth facets is Lambert; Burley's diffuse at roughness 1/4 is Lambert for
    a light at the viewer (F90 = 1); GGX is Schlick's F0 times D G / (4 cos v) at the mirror."""
    n, mask = sphere(SIZE)
    rng = np.random.default_rng(0)
    for _ in range(5):
        l = rng.normal(size=3)
        l[2] = abs(l[2]) + 0.3
        l /= np.linalg.norm(l)
        lambert = np.clip(n @ l, 0, None)
        assert np.allclose(oren_nayar(n, l, 0.0)[mask], lambert[mask], atol=1e-12)
    v = np.array([0.0, 0.0, 1.0])
    assert np.allclose(burley_diffuse(n, v, 0.25)[mask], np.clip(n[..., 2], 0, None)[mask])
    # At the centre pixel's mirror configuration, n = h = l = v: D = 1 / (pi a^2), G = 1, F = F0.
    assert ggx(np.array([[0.0, 0.0, 1.0]]), v, 0.3, 0.04)[0] == pytest.approx(
        0.04 / (np.pi * 0.09) / 4)
    # Rough matte is brighter than Lambert toward grazing light on the viewer's side.
    tilted = np.array([[np.sin(1.0), 0.0, np.cos(1.0)]])
    grazing = np.array([-np.sin(0.4), 0.0, np.cos(0.4)])
    assert oren_nayar(tilted, grazing, 0.3)[0] > (tilted @ grazing)[0]


def test_rough_matte_of_the_full_model_takes_the_qualitative_term():
    """Oren and Nayar's full model (its C3 and interreflection terms, which the qualitative term
    leaves out, as a renderer's rough diffuse may keep them): the two halves of the sample agree
    on the slope within the refinement's resolution, and the term is kept. Measured: 0.47 deg,
    slope 0.283, against Lambert's 5.60 (7.38 before the family held the term)."""
    images, directions, mask, truth = scene(lambda n, l: oren_nayar_full(n, l, 0.3))
    r = solve(images, directions, mask)
    lambert = error(solve(images, directions, mask, model="lambert"), truth, mask)
    assert r["model"] == "oren-nayar"
    assert error(r, truth, mask) < 0.2 * lambert, (error(r, truth, mask), lambert)


def test_the_models_rough_term_is_the_zoos():
    """iphong's Oren-Nayar term (reflectance/phong.h, in vectors) against brdf_zoo's spelling of
    the paper (angles and azimuths), on a sphere's normals under lights from every side."""
    n, mask = sphere(SIZE)
    rng = np.random.default_rng(1)
    white = iphong.Material(kd=[1.0, 1.0, 1.0], ks=[0.0, 0.0, 0.0], shininess=0.0)
    for slope in (0.0, 0.3, 0.6, 1.2):
        white.shininess = slope
        for _ in range(4):
            l = rng.normal(size=3)
            l[2] = abs(l[2]) + 0.2
            l /= np.linalg.norm(l)
            ours = iphong.shade(n[mask], [0.0, 0.0, 1.0], white, [iphong.DirectionalLight(l)],
                                model="oren-nayar")
            assert np.allclose(ours[:, 0], oren_nayar(n[mask], l, slope), atol=1e-9)


def solve(images, directions, mask, **kwargs):
    return iphong.estimate_normals(images, directions, None, mask, **kwargs)


def error(result, normals, mask):
    return iphong.angular_error(result["normals"], normals, mask)["mean_angular_error_deg"]


def scene(reflectance, count=24, **kwargs):
    n, mask = sphere(SIZE)
    albedo = surface_scene("peaks")[2]  # the surfaces' varying albedo, on the sphere
    directions = lights(count)[0]
    images = render(n, mask, albedo, directions, reflectance, sigma=0.002, **kwargs)
    return images, directions, mask, (n * mask[..., None]).astype(np.float32)


def test_the_weights_by_shading_follow_a_diffuse_term_that_falls_off_by_n_dot_l():
    """Burley's smooth diffuse darkens toward grazing incidence by a factor of N.L (and of N.V,
    which the albedo takes): the misfit the weights by N.L are built for, here from a renderer
    that is not iphong's. Measured: weighted 0.41 deg, uniform 1.20, Lambert 0.86."""
    images, directions, mask, truth = scene(lambda n, l: burley_diffuse(n, l, 0.0))
    weighted = error(solve(images, directions, mask), truth, mask)
    uniform = error(solve(images, directions, mask, weigh_by_shading=False), truth, mask)
    lambert = error(solve(images, directions, mask, model="lambert"), truth, mask)
    assert weighted < 0.7 * uniform, (weighted, uniform)
    assert weighted < lambert, (weighted, lambert)


def ggx_sphere():
    return scene(lambda n, l: np.clip(n @ l, 0, None), specular=lambda n, l: ggx(n, l, 0.15),
                 ks=0.5 * np.pi)


def test_a_ggx_highlight_is_taken_for_a_lobe():
    """A GGX lobe over a Lambertian base, under distant lights: the default's Phong-family lobe
    explains it far better than Lambert's censoring. Measured: 0.27 deg against Lambert's 1.73."""
    images, directions, mask, truth = ggx_sphere()
    default = error(solve(images, directions, mask, light_distance="inf"), truth, mask)
    lambert = error(solve(images, directions, mask, model="lambert"), truth, mask)
    assert default < 0.5, default
    assert default < 0.5 * lambert, (default, lambert)


@pytest.mark.xfail(strict=True, reason="known: on a sphere the effective distance's position check "
                   "ties by construction, and here its lobe's misfit takes D = 32 object sizes (0.76 "
                   "deg against 0.27 distant); docs/guides/near-lights.md, 'A known cliff'")
def test_a_distant_ggx_sphere_keeps_its_lights_distant():
    images, directions, mask, truth = ggx_sphere()
    r = solve(images, directions, mask)
    assert r["effective_distance"]["distance_px"] == float("inf")
    assert error(r, truth, mask) < 0.5


def rough_matte():
    return scene(lambda n, l: oren_nayar(n, l, 0.3))


def test_rough_matte_without_the_weights_is_ahead_of_lambert():
    """--uniform-weights on a rough matte surface: the rough diffuse term is chosen either way.
    Measured: 0.28 deg against Lambert's 5.57 (3.55 before the family held the term, both then
    flattening the sphere)."""
    images, directions, mask, truth = rough_matte()
    uniform = error(solve(images, directions, mask, weigh_by_shading=False), truth, mask)
    lambert = error(solve(images, directions, mask, model="lambert"), truth, mask)
    assert uniform < 0.8 * lambert, (uniform, lambert)


@pytest.mark.parametrize("slope, shape", [(0.3, "sphere"), (0.6, "torus")])
def test_rough_matte_takes_the_rough_diffuse_term(slope, shape):
    """Oren and Nayar's surfaces, rendered by brdf_zoo's trigonometric form of their paper: the
    model choice takes the rough diffuse term with the facets' slope it was rendered with, and the
    normals come back within noise. Before the family held the term the default was behind
    Lambert here (7.5 deg against 5.5 on the sphere of slope 0.3), its weights by N.L doubling
    the flattening. Measured: 0.30 deg, slope 0.307 (sphere, 0.3); 0.28 deg (torus, 0.6)."""
    n, mask, albedo = (*sphere(SIZE), surface_scene("peaks")[2]) if shape == "sphere" \
        else surface_scene(shape)
    truth = (n * mask[..., None]).astype(np.float32)
    directions = lights(24)[0]
    images = render(n, mask, albedo, directions, lambda n, l: oren_nayar(n, l, slope),
                    sigma=0.002)
    r = solve(images, directions, mask)
    lambert = error(solve(images, directions, mask, model="lambert"), truth, mask)
    assert r["model"] == "oren-nayar"
    assert r["shininess"] == pytest.approx(slope, rel=0.05)
    assert error(r, truth, mask) < 0.5
    assert error(r, truth, mask) < 0.15 * lambert, lambert
