"""Near lights on captures rendered by an independent numpy ray caster (written here from
SPEC.md's "Near lights" section, not iphong's renderer): a sphere and an ellipsoid seen by a pinhole
camera (f = 700 px, 320 x 256), lit by LEDs on a dome at 1.5 object sizes (isotropic and mu = 1)
and by a ring round the lens; Lambertian and Phong; stored as 16-bit PNG in the near-light layout
(light_positions.txt, camera.json in OpenCV's convention) and read back as a user would. Issue 28's
targets: with the positions given, within 0.3 degrees noise-free and 1 degree at sigma 0.002, and
the default never worse than its own Lambert run."""
import json
import pathlib

import numpy as np
import pytest

import iphong

W, H, F = 320, 256, 700.0
CX, CY = (W - 1) / 2, (H - 1) / 2  # OpenCV: pixel centres at integers
CENTRE = np.array([0.0, 0.0, -500.0])  # mm, camera frame (z toward the viewer)
RADIUS = 50.0


def rays():
    """Unit rays through the pixel centres, camera frame (x right, y up, z toward the viewer)."""
    u, v = np.meshgrid(np.arange(W, dtype=float), np.arange(H, dtype=float))
    d = np.stack([(u - CX) / F, -(v - CY) / F, -np.ones_like(u)], -1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def intersect(shape):
    """The first hit of every ray with the shape: points X (H, W, 3), unit normals N, mask."""
    d = rays()
    axes = np.array([RADIUS, RADIUS, RADIUS]) if shape == "sphere" else np.array([60.0, 40.0, 45.0])
    # Ellipsoid |(X - C) / axes| = 1 along X = t d: a t² + b t + c = 0.
    q = d / axes
    o = -CENTRE / axes
    a = np.sum(q * q, -1)
    b = 2 * np.sum(q * o, -1)
    c = np.sum(o * o) - 1
    disc = b * b - 4 * a * c
    hit = disc > 0
    t = np.where(hit, (-b - np.sqrt(np.where(hit, disc, 0))) / (2 * a), 0)
    x = t[..., None] * d
    n = (x - CENTRE) / axes ** 2
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    # Pixels whose surface faces the camera at more than a grazing 1°: the outline is left out.
    mask = hit & (np.sum(n * -d, -1) > np.sin(np.radians(1)))
    return x, n, mask


def dome(count, radius, mu):
    """LEDs over a cap round the object's centre, 25-75° above the plane facing the camera, aimed
    at it."""
    golden = np.pi * (3 - np.sqrt(5))
    e = np.radians(25 + 50 * (np.arange(count) + 0.5) / count)
    a = golden * np.arange(count)
    dirs = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], -1)
    positions = CENTRE + radius * dirs
    return positions, -dirs, np.full(count, float(mu))


def ring(count, radius, mu):
    """LEDs on a circle round the lens, in the camera's plane, pointing along the optical axis."""
    a = 2 * np.pi * np.arange(count) / count
    positions = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(count)], -1)
    axes = np.tile([0.0, 0.0, -1.0], (count, 1))
    return positions, axes, np.full(count, float(mu))


def render(shape, lights, phong, sigma, seed=1):
    """Linear images (K, H, W, 3) by SPEC.md's model, E = Φ (a·(X−S)/|X−S|)^μ / |X−S|², and the
    ground truth."""
    positions, axes, mu = lights
    x, n, mask = intersect(shape)
    v = -x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-12)  # toward the eye
    kd = np.array([0.7, 0.6, 0.5])
    ks, shininess = (0.35, 25.0) if phong else (0.0, 1.0)
    images = []
    for s, axis, m in zip(positions, axes, mu):
        to_light = s - x
        dist = np.linalg.norm(to_light, axis=-1, keepdims=True)
        l = to_light / dist
        cos_axis = np.clip(np.sum(-l * axis, -1, keepdims=True), 0, None)
        irradiance = (cos_axis ** m if m > 0 else 1.0) / dist ** 2
        ndl = np.sum(n * l, -1, keepdims=True)
        r = 2 * ndl * n - l
        rdv = np.clip(np.sum(r * v, -1, keepdims=True), 0, None)
        lobe = np.where(ndl > 0, rdv ** shininess, 0) if phong else 0
        images.append(irradiance * (kd * np.clip(ndl, 0, None) + ks * lobe))
    images = np.array(images)
    images *= 0.8 / images[:, mask].max()  # one exposure for all: the brightest value at 0.8
    if sigma > 0:
        images = images + np.random.default_rng(seed).normal(0, sigma, images.shape)
    images = np.clip(images, 0, 1) * mask[None, ..., None]
    depth = np.where(mask, -x[..., 2], 0)
    return images.astype(np.float32), np.where(mask[..., None], n, 0), depth, mask


def write_capture(folder, shape, lights, phong, sigma):
    """The near-light layout, as another tool would write it: 16-bit PNG images through
    iphong.save_dataset, then light_positions.txt, camera.json and the LED files by hand."""
    positions, axes, mu = lights
    images, normals, depth, mask = render(shape, lights, phong, sigma)
    # The directions DiLiGenT's readers expect: toward each light from the object's centre.
    directions = (positions - CENTRE) / np.linalg.norm(positions - CENTRE, axis=-1, keepdims=True)
    iphong.save_dataset(folder, images, directions, mask=mask, normal_gt=normals,
                        format="png", bits=16)
    folder = pathlib.Path(folder)
    np.savetxt(folder / "light_positions.txt", positions)
    (folder / "camera.json").write_text(json.dumps({"fx": F, "fy": F, "cx": CX, "cy": CY}))
    if np.any(mu > 0):
        np.savetxt(folder / "light_axes.txt", axes)
        np.savetxt(folder / "light_anisotropy.txt", mu)
    return normals, depth, mask


def solve(folder, **kwargs):
    d = iphong.load_dataset(folder)
    return d, iphong.estimate_normals(
        d["images"], d["light_directions"], d["light_intensities"], d["mask"],
        light_positions=d["light_positions"], camera=d["camera"], light_axes=d["light_axes"],
        light_anisotropy=d["light_anisotropy"], **kwargs)


CASES = {
    # name: shape, lights, phong, sigma, the object's distance as its user knows it (mm) or None
    "dome-lambert": ("sphere", dome(12, 150, 0), False, 0.0, None),
    "dome-phong": ("ellipsoid", dome(24, 150, 0), True, 0.0, None),
    "led-mu1-phong-noisy": ("sphere", dome(12, 150, 1), True, 0.002, None),
    # A ring round the lens says nothing of the distance (see the next test): a rough one given.
    "ring-lambert-noisy": ("sphere", ring(12, 300, 0), False, 0.002, 400),
}


@pytest.mark.parametrize("name", list(CASES))
def test_near_light_capture_within_the_targets(tmp_path, name):
    shape, lights, phong, sigma, distance = CASES[name]
    normals, depth, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    d, r = solve(tmp_path / "cap", distance=distance)
    assert np.allclose(d["light_positions"], lights[0], atol=1e-6)
    error = iphong.angular_error(r["normals"], normals, mask)["mean_angular_error_deg"]
    _, lambert = solve(tmp_path / "cap", model="lambert", distance=distance)
    lambert_error = iphong.angular_error(lambert["normals"], normals, mask)["mean_angular_error_deg"]
    assert error <= (1.0 if sigma > 0 else 0.3), (error, lambert_error)
    assert error <= lambert_error, (error, lambert_error)
    # The surface's distance comes out: the mean depth within 1 %.
    assert r["near"]["distance"] == pytest.approx(depth[mask].mean(), rel=0.01)
    assert r["depth"].shape == (H, W)
    assert np.nanmean(np.abs(r["depth"][mask] - depth[mask])) < 0.01 * depth[mask].mean()


def test_the_weights_by_shading_are_those_of_the_settled_surface(tmp_path):
    """An exact Lambertian render under a dome has no misfit by N.L once the lights are placed
    on the right surface; the first surface (from Woodham's normals) leaves its bands biased by a
    few thousandths of the brightness, whose offsets would bend the normals by 0.2 deg. They are
    measured again on the settled surface."""
    shape, lights, phong, sigma, distance = CASES["dome-lambert"]
    normals, _, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    _, r = solve(tmp_path / "cap", distance=distance)
    assert np.max(np.abs(r["shading_weights"]["offset"])) < 0.001, r["shading_weights"]
    assert min(r["shading_weights"]["weight"]) > 0.95
    assert iphong.angular_error(r["normals"], normals, mask)["mean_angular_error_deg"] < 0.05


def test_a_ring_without_a_distance_says_so(tmp_path):
    """Lights on a ring round the lens fit a flatter surface nearer as well as the true one: on
    the exact images the true distance still fits best and is found; whichever is taken, the
    result says the images chose it."""
    shape, lights, phong, _, _ = CASES["ring-lambert-noisy"]
    normals, depth, mask = write_capture(tmp_path / "cap", shape, lights, phong, 0.0)
    _, r = solve(tmp_path / "cap")
    assert r["near"]["distance_from_images"]
    assert r["near"]["distance"] == pytest.approx(depth[mask].mean(), rel=0.01)
    assert iphong.angular_error(r["normals"], normals, mask)["mean_angular_error_deg"] < 0.3


def test_the_distant_model_bends_the_normals(tmp_path):
    """The same capture read without its positions: a distant-light solve is far worse."""
    shape, lights, phong, sigma, _ = CASES["dome-lambert"]
    normals, _, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    d, near = solve(tmp_path / "cap")
    distant = iphong.estimate_normals(d["images"], d["light_directions"], d["light_intensities"],
                                      d["mask"], light_distance="inf")
    e_near = iphong.angular_error(near["normals"], normals, mask)["mean_angular_error_deg"]
    e_far = iphong.angular_error(distant["normals"], normals, mask)["mean_angular_error_deg"]
    assert e_far > 10 * e_near, (e_near, e_far)


def test_near_keywords_are_checked():
    images = np.zeros((3, 8, 8, 3), np.float32)
    dirs = np.eye(3)
    with pytest.raises(ValueError, match="behind the camera"):
        iphong.estimate_normals(images, dirs, light_positions=[[0, 0, 100]] * 3,
                                camera={"fx": 10, "fy": 10, "cx": 4, "cy": 4})
    with pytest.raises(ValueError, match="near lights need the camera"):
        iphong.estimate_normals(images, dirs, light_positions=[[0, 0, -100]] * 3)
    with pytest.raises(ValueError, match="missing cx, cy"):
        iphong.estimate_normals(images, dirs, light_positions=[[0, 0, -100]] * 3,
                                camera={"fx": 10, "fy": 10})
    with pytest.raises(ValueError, match="go with light_positions"):
        iphong.estimate_normals(images, dirs, camera={"fx": 10, "fy": 10, "cx": 4, "cy": 4})
    with pytest.raises(ValueError, match="light_distance"):
        iphong.estimate_normals(images, dirs, light_distance="near")


def test_render_and_load_give_the_near_light_arrays(tmp_path):
    scene = json.loads((pathlib.Path(__file__).parents[2] / "fixtures" / "scenes"
                        / "near_dome.json").read_text())
    out = iphong.render(scene, per_light=True)
    assert out["light_positions"].shape == (12, 3)
    assert np.all(out["light_positions"][:, 2] < 0)
    assert out["camera"] == {"fx": 300.0, "fy": 300.0, "cx": 47.5, "cy": 39.5}
    assert out["light_anisotropy"] == [1.0] * 12
    # The capture it writes reads back with the same arrays.
    iphong.save_dataset(tmp_path / "ds", out["images"], out["light_directions"], mask=out["mask"])
    assert iphong.load_dataset(tmp_path / "ds")["light_positions"] is None


def test_an_exact_distant_render_keeps_distant_lights():
    """A glossy sphere under 24 distant lights, noise-free: a Lambertian fit with highlights
    censored predicts held-out lights 1 % better at 31 object sizes (the lobe's tails it cannot
    fit), but the object's own model predicts 3 times worse there, so the lights stay distant.
    Without that veto every normal was 0.8 degrees off, with the coefficients known or not."""
    material = {"kd": 0.5, "ks": 0.3, "shininess": 12.8}
    scene = {"width": 160, "height": 160, "camera": {"type": "orthographic", "extent": 2.0},
             "lights": [{"type": "hemisphere", "count": 24, "min_elevation_deg": 30}],
             "objects": [{"shape": "sphere", "radius": 0.8, "subdivisions": 6,
                          "material": material}]}
    out = iphong.render(scene, per_light=True)
    mask = out["mask"]
    for known in [{"model": "phong", **material}, None]:
        r = iphong.estimate_normals(out["images"], out["light_directions"],
                                    out["light_intensities"], mask, material=known)
        e = iphong.angular_error(r["normals"], out["normals"], mask)
        chosen = r["effective_distance"]
        assert chosen["distance_px"] == float("inf")
        # The diffuse test proposed a D; the object's model refused it, far beyond its noise.
        assert chosen["model_loss_at_diffuse_distance"] > 10 * chosen["model_loss_error"]
        if known:  # every pixel exact
            assert np.nanmax(np.where(mask, e["error_deg"], np.nan)) <= 0.1
        else:  # measured 0.020 (the shininess 12.56 for 12.8)
            assert e["mean_angular_error_deg"] <= 0.05


def ggx_dome(roughness=0.3, f0=0.9, sigma=0.002):
    """test_normals_surfaces' ripple dome and 24 distant lights, shaded by a GGX microfacet lobe
    (Trowbridge-Reitz with Schlick's Fresnel and Smith's shadowing, as Blender and Mitsuba shade)
    written here in numpy: a lobe whose long tails no Phong lobe takes."""
    from test_normals_surfaces import lights, scene
    n, mask, kd = scene("dome")
    directions, intensities = lights()
    a2, k, view = roughness ** 2, roughness / 2, np.array([0.0, 0.0, 1.0])
    images = []
    for l, e in zip(directions, intensities):
        h = (l + view) / np.linalg.norm(l + view)
        ndl, ndv, ndh = n @ l, n[..., 2], np.clip(n @ h, 0, 1)
        d = a2 / (np.pi * (ndh ** 2 * (a2 - 1) + 1) ** 2)
        fresnel = f0 + (1 - f0) * (1 - h @ view) ** 5
        g = ndl / (ndl * (1 - k) + k) * ndv / (ndv * (1 - k) + k)
        specular = np.where(ndl > 0, d * fresnel * g / (4 * ndv), 0.0)  # times N·L already
        images.append(e * (kd * np.clip(ndl, 0, None)[..., None] + specular[..., None]))
    images = np.array(images) + np.random.default_rng(0).normal(0, sigma, (len(directions),) + n.shape)
    images = np.clip(images, 0, None).astype(np.float32)
    return images, directions, intensities, mask, (n * mask[..., None]).astype(np.float32)


def test_a_lobes_tails_are_not_taken_for_near_lights():
    """Distant lights and a GGX lobe: a nearer D predicts held-out lights better by many standard
    errors (the fall-off across a dome bends the fit toward the tails' brightness), and it bent
    every normal: 2.66 degrees against 1.42 with the lights kept distant. Points placed by their
    normals alone predict better still under the object's model — the gain is the lobe's shape,
    not where the points are — so D = infinity stays."""
    images, directions, intensities, mask, gt = ggx_dome()
    r = iphong.estimate_normals(images, directions, intensities, mask)
    chosen = r["effective_distance"]
    assert chosen["distance_px"] == float("inf")
    checks = [c for c in chosen["position_checks"] if c["test"] == "model"]
    assert checks and all(c["refused"] for c in chosen["position_checks"])
    # measured -13.9 and -14.7 standard errors, on the surface each D makes
    assert all(c["heldout_gain"] < -5 * c["heldout_gain_error"] for c in checks)
    assert any(c["test"].endswith("placed by normals") for c in chosen["candidates"])
    e = iphong.angular_error(r["normals"], gt, mask)["mean_angular_error_deg"]
    assert e <= 1.6, e  # measured 1.42; 2.66 at the D it refused



@pytest.mark.parametrize("name, bound", [("dome-lambert", 2.0), ("led-mu1-phong-noisy", 1.2),
                                         ("dome-phong", 1.5)])
def test_near_lights_given_as_directions_only(tmp_path, name, bound):
    """The same captures read as their users often have them, directions from the object's centre
    and no positions: the fall-off across a dome at 1.5 object sizes brightens each pixel under
    the lights nearest its normal. A mirror lobe of the broadest width took that brightening by
    tilting the normals (21.9 and 21.7 degrees off; Lambert 12.7 and 13.3). The effective distance
    now places the lights' centre behind the visible surface, where the directions were measured
    from, and finds D with it (measured 0.68 on the noisy LED sphere, 0.94 on the Phong ellipsoid
    under 24 lights, which had been 9.83 against Lambert's 9.39 with the centre at the surface's
    centroid). The matte sphere is where the position check ties by construction (points placed
    by their normals are the sphere itself): refused, its foil at D = infinity gave 1.75; accepted
    (since the per-pixel test scales its leave-one-out error), 0.46. The near passes end as
    documented: once the normals or the lights, as the new surface sees them, moved under 0.1
    degrees, or after three passes, at the first D and again at the D chosen on their surface."""
    shape, lights, phong, sigma, _ = CASES[name]
    normals, _, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    d = iphong.load_dataset(tmp_path / "cap")
    args = (d["images"], d["light_directions"], d["light_intensities"], d["mask"])
    r = iphong.estimate_normals(*args)
    lambert = iphong.estimate_normals(*args, model="lambert")
    error = iphong.angular_error(r["normals"], normals, mask)["mean_angular_error_deg"]
    lambert_error = iphong.angular_error(lambert["normals"], normals, mask)["mean_angular_error_deg"]
    assert error <= bound and error < lambert_error, (error, lambert_error)
    passes = r["effective_distance"]["passes"]
    if r["effective_distance"]["distance_px"] != float("inf"):
        # Passes at the first D, and at the D chosen again on their surface where it moved: each
        # run of passes at one D ends as documented.
        chosen_px = r["effective_distance"]["distance_px"]
        assert passes[-1]["light_distance_px"] == chosen_px, passes
        runs = {}
        for p in passes:
            runs.setdefault(p["light_distance_px"], []).append(p)
        assert 1 <= len(runs) <= 2, passes
        for run in runs.values():
            assert 1 <= len(run) <= 3, passes
            settled = [p["normals_moved_deg"] < 0.1 or p["lights_moved_deg"] < 0.1 for p in run]
            assert not any(settled[:-1]) and (settled[-1] or len(run) == 3), passes
    if name != "dome-lambert":
        # The dome's radius is 150 mm: D = 150 x 700 / 500 = 210 px; the centre is 2/3 of the
        # depth semi-axis behind the visible cap's centroid, 47 px on the sphere, 42 on the
        # ellipsoid (found 218 and 53, 231 and 49: the perspective images read orthographically
        # move the optimum along its valley).
        e = r["effective_distance"]
        assert 180 < e["distance_px"] < 260, e["distance_px"]
        assert 35 < e["centre_behind_px"] < 70, e["centre_behind_px"]


def test_a_given_light_distance_places_the_centre(tmp_path):
    """--light-distance PX gives D, not where the directions were measured from: the centre's
    depth behind the visible surface is still chosen by the diffuse test. The numpy matte sphere
    at its true D (210 px): the centre 50 px behind the cap's centroid (47 by geometry), the
    normals 1.82 degrees off; with the centre at the centroid they were 6.74."""
    shape, lights, phong, sigma, _ = CASES["dome-lambert"]
    normals, _, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    d = iphong.load_dataset(tmp_path / "cap")
    r = iphong.estimate_normals(d["images"], d["light_directions"], d["light_intensities"],
                                d["mask"], light_distance=210.0)
    e = r["effective_distance"]
    assert not e["chosen"] and e["distance_px"] == 210.0
    assert 40 < e["centre_behind_px"] < 60, e["centre_behind_px"]
    assert iphong.angular_error(r["normals"], normals, mask)["mean_angular_error_deg"] < 2.5


def small_dome_scene():
    """fixtures/scenes/near_dome_lambert.json at 120 x 96 pixels (the same view, a coarser mesh):
    a matte sphere under 24 point lights at 1.5 object sizes."""
    scene = json.loads((pathlib.Path(__file__).parents[2] / "fixtures" / "scenes"
                        / "near_dome_lambert.json").read_text())
    scene.update(width=120, height=96, output={})
    scene["camera"].update(fx=260, fy=260, cx=60, cy=48)
    scene["objects"][0]["subdivisions"] = 5
    return scene


def test_the_foil_does_not_judge_the_distance():
    """iphong's own dome (fixtures/scenes/near_dome_lambert.json: 24 point lights at 1.5 object
    sizes, directions as seen from the surface's centre): under distant lights the foil takes the
    fall-off in, and kept at D = infinity its normals were 8.0 degrees off where Lambert at the
    effective distance is 3.8. The foil is not asked about the distance (it would lose at any
    finite one); the diffuse test finds D and the model is chosen again there (measured 1.78)."""
    out = iphong.render(small_dome_scene(), per_light=True)
    args = (out["images"], out["light_directions"], out["light_intensities"], out["mask"])
    r = iphong.estimate_normals(*args)
    lambert = iphong.estimate_normals(*args, model="lambert")
    e = iphong.angular_error(r["normals"], out["normals"], out["mask"])["mean_angular_error_deg"]
    e_lambert = iphong.angular_error(lambert["normals"], out["normals"],
                                     out["mask"])["mean_angular_error_deg"]
    assert r["effective_distance"]["distance_px"] < 4 * r["effective_distance"]["object_size_px"]
    assert not any(c["test"] == "model" for c in r["effective_distance"]["candidates"])
    assert e <= 2.5 and e < e_lambert, (e, e_lambert)
