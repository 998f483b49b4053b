"""Normal recovery on surfaces rendered by an independent Phong renderer (numpy, written here from
SPEC.md's model, not iphong's): MATLAB's peaks, a torus seen from above and a dome with ripples,
each with a spatially varying albedo, under 24 lights with an ambient term (issue #12). With the
coefficients known every pixel must come back within 0.1 degrees (the global search leaves no start
in a wrong basin); with them unknown and noise sigma = 0.002, within 0.5 degrees on average."""
import numpy as np
import pytest

import iphong

SIZE = 96
KS, SHININESS, KA, AMBIENT = 0.35, 24.0, 0.1, 0.2


def lights(count=24):
    """A spiral over the hemisphere down to 40 degrees elevation, slightly coloured."""
    golden = np.pi * (3 - np.sqrt(5))
    z = 1 - (1 - np.sin(np.radians(40))) * (np.arange(count) + 0.5) / count
    r = np.sqrt(1 - z ** 2)
    a = golden * np.arange(count)
    directions = np.stack([r * np.cos(a), r * np.sin(a), z], -1)
    intensities = np.tile([1.0, 0.95, 0.9], (count, 1)) * (0.8 + 0.4 * ((np.arange(count) * 7) % 5) / 4)[:, None]
    return directions, intensities


def surface(name):
    """Heights and their gradients on a [-1, 1]² grid (x right, y up, rows from the top), and the
    mask. Gradients are analytic."""
    c = (np.arange(SIZE) + 0.5) / SIZE * 2 - 1
    x, y = np.meshgrid(c, -c)
    if name == "peaks":
        u, v = 3 * x, 3 * y
        e1, e2, e3 = np.exp(-u ** 2 - (v + 1) ** 2), np.exp(-u ** 2 - v ** 2), np.exp(-(u + 1) ** 2 - v ** 2)
        # peaks(u, v) / 10, differentiated in u, v, then times 3 for x, y.
        zu = (-6 * (1 - u) * e1 - 6 * u * (1 - u) ** 2 * e1 - 10 * (0.2 - 3 * u ** 2) * e2
              + 20 * u * (u / 5 - u ** 3 - v ** 5) * e2 + 2 / 3 * (u + 1) * e3)
        zv = (-6 * (v + 1) * (1 - u) ** 2 * e1 + 50 * v ** 4 * e2 + 20 * v * (u / 5 - u ** 3 - v ** 5) * e2
              + 2 / 3 * v * e3)
        return 0.3 * zu, 0.3 * zv, np.ones_like(x, bool)
    if name == "torus":
        ring, tube = 0.55, 0.35
        rho = np.hypot(x, y) + 1e-12
        d = rho - ring
        mask = np.abs(d) < tube * 0.97
        h = np.sqrt(np.clip(tube ** 2 - d ** 2, 1e-9, None))
        dz_drho = -d / h
        return dz_drho * x / rho, dz_drho * y / rho, mask
    if name == "dome":
        radius, b, k = 0.95, 0.03, 14.0
        rho2 = x ** 2 + y ** 2
        mask = rho2 < (0.9 * radius) ** 2
        rho = np.sqrt(rho2) + 1e-12
        g = np.sqrt(np.clip(radius ** 2 - rho2, 1e-9, None))
        dz_drho = -rho / g + b * k * np.cos(k * rho)
        return dz_drho * x / rho, dz_drho * y / rho, mask
    raise ValueError(name)


def scene(name):
    """The surface's unit normals, its mask and a spatially varying albedo (H, W, 3)."""
    zx, zy, mask = surface(name)
    n = np.stack([-zx, -zy, np.ones_like(zx)], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    c = (np.arange(SIZE) + 0.5) / SIZE
    cx, cy = np.meshgrid(c, c)
    kd = np.stack([0.5 + 0.3 * np.sin(6 * cx), 0.4 + 0.25 * np.cos(5 * cy), 0.3 + 0.2 * np.sin(4 * (cx + cy))], -1)
    return n, mask, kd


def render(name, sigma=0.0, seed=0):
    n, mask, kd = scene(name)
    directions, intensities = lights()
    images = []
    for l, e in zip(directions, intensities):
        ndl = n @ l
        r = 2 * ndl[..., None] * n - l
        rdv = np.clip(r[..., 2], 0, None)
        lobe = np.where(ndl > 0, rdv ** SHININESS, 0.0)
        image = KA * AMBIENT + e * (kd * np.clip(ndl, 0, None)[..., None] + KS * lobe[..., None])
        images.append(image)
    images = np.array(images)
    if sigma:
        images = images + np.random.default_rng(seed).normal(0, sigma, images.shape)
    return images.astype(np.float32), directions, intensities, mask, (n * mask[..., None]).astype(np.float32)


@pytest.mark.parametrize("name", ["peaks", "torus", "dome"])
def test_known_coefficients_leave_no_pixel_in_a_wrong_basin(name):
    images, directions, intensities, mask, truth = render(name)
    material = {"model": "phong", "ka": KA, "ks": KS, "shininess": SHININESS, "ambient": AMBIENT}
    r = iphong.estimate_normals(images, directions, intensities, mask, material=material)
    e = iphong.angular_error(r["normals"], truth, mask)
    worst = np.nanmax(np.where(mask, e["error_deg"], np.nan))
    # Measured: mean < 0.001 deg everywhere, worst pixel below 0.01 deg.
    assert e["mean_angular_error_deg"] <= 0.01, name
    assert worst <= 0.1, (name, worst)


@pytest.mark.parametrize("name", ["peaks", "torus", "dome"])
def test_unknown_coefficients_with_noise(name):
    images, directions, intensities, mask, truth = render(name, sigma=0.002, seed=1)
    r = iphong.estimate_normals(images, directions, intensities, mask)
    e = iphong.angular_error(r["normals"], truth, mask)
    assert r["model"] == "phong" or r["model"] == "blinn-phong"
    np.testing.assert_allclose(r["ambient_term"], KA * AMBIENT, atol=0.01)
    assert e["mean_angular_error_deg"] <= 0.5, (name, e["mean_angular_error_deg"])


@pytest.mark.parametrize("name", ["peaks", "torus", "dome"])
def test_unknown_shininess_comes_back_from_an_independent_renderer(name):
    # The model choice predicts held-out lights from refined normals, so the lobe and shininess of
    # a render it did not make come back: measured 24.2, 24.2 and 23.6 for 24 (mean 0.013-0.025
    # deg); from the search grid's normals it was 25.1, 22.7 and Blinn-Phong 92.4 (0.05-0.06 deg).
    images, directions, intensities, mask, truth = render(name)
    r = iphong.estimate_normals(images, directions, intensities, mask)
    e = iphong.angular_error(r["normals"], truth, mask)
    assert r["model"] == "phong", name
    assert abs(r["shininess"] / SHININESS - 1) <= 0.05, (name, r["shininess"])
    assert e["mean_angular_error_deg"] <= 0.03, (name, e["mean_angular_error_deg"])
