"""Light calibration on the real data: UW's chrome sphere against its lights.txt and against an
independent calibration from UW's matte gray sphere; DiLiGenT ball's photos and ground truth as a
calibration target for cat; semi-calibrated intensities on DiLiGenT cat and ball."""
import numpy as np
import pytest

import iphong
from test_capture import fit_circle
from test_render import DATA

UW = DATA / "uw"
DILIGENT = DATA / "diligent"
CROP = DATA / "diligent-crop8"
needs_uw = pytest.mark.skipif(not (UW / "chrome").is_dir(), reason=f"UW data not found at {UW}")
needs_diligent = pytest.mark.skipif(not (DILIGENT / "ball").is_dir() or not (CROP / "cow").is_dir(),
                                    reason=f"DiLiGenT data not found at {DATA}")


def angles_deg(a, b):
    a = a / np.linalg.norm(a, axis=1)[:, None]
    b = b / np.linalg.norm(b, axis=1)[:, None]
    return np.degrees(np.arccos(np.clip((a * b).sum(1), -1, 1)))


@needs_uw
def test_uw_chrome_sphere_against_lights_txt_and_the_gray_sphere():
    chrome = iphong.load_dataset(UW / "chrome")
    mirror = iphong.calibrate_lights(chrome["images"], mask=chrome["mask"])
    # The sphere against a plain fit to the mask's boundary pixels (half a pixel inside the edge).
    cx, cy, r = fit_circle(chrome["mask"])
    sphere = mirror["spheres"][0]
    assert np.hypot(sphere["center_px"][0] - cx, sphere["center_px"][1] - cy) < 0.2
    assert 0.2 < sphere["radius_px"] - r < 0.8
    assert any("highlights are clipped" in w for w in mirror["warnings"])
    published = chrome["light_directions"]  # uw/lights.txt
    to_published = angles_deg(mirror["light_directions"], published)
    listing = ", ".join(f"{name} {e:.2f}" for name, e in zip(chrome["filenames"], to_published))
    # Measured 3.06 deg mean (max 8.5 on chrome.1, whose highlight is 15 px right of the centre
    # where lights.txt puts it 6 px): lights.txt fits the highlights only with a circle of
    # radius 133 px, but the mask and the photos show 120.
    assert to_published.mean() < 3.2, listing

    # Without the mask the sphere is found in the photos: radius 118.75 px (1.4 px short: the
    # chrome's rim is dark), directions 0.40 deg mean from the masked run.
    found = iphong.calibrate_lights(chrome["images"], max_spheres=1)
    assert abs(found["spheres"][0]["radius_px"] - r) < 2
    assert angles_deg(found["light_directions"], mirror["light_directions"]).mean() < 0.5
    assert any("no mask: found a sphere in the photos" in w for w in found["warnings"])

    # The matte gray sphere, calibrated from its shading alone, sides with the mirror.
    gray = iphong.load_dataset(UW / "gray")
    matte = iphong.calibrate_lights(gray["images"], mask=gray["mask"], sphere="matte")
    gray_to_chrome = angles_deg(matte["light_directions"], mirror["light_directions"])
    gray_to_published = angles_deg(matte["light_directions"], published)
    # Measured 1.99 deg and 3.57 deg.
    assert gray_to_chrome.mean() < 2.2
    assert gray_to_chrome.mean() < gray_to_published.mean() - 1.0


@needs_diligent
def test_diligent_ball_is_a_calibration_target_for_cat():
    ball = iphong.load_dataset(DILIGENT / "ball")
    calibrated = iphong.calibrate_lights(ball["images"], mask=ball["mask"],
                                         normals=ball["normal_gt"], uniform_albedo=True)
    assert calibrated["converged"]
    to_published = angles_deg(calibrated["light_directions"], ball["light_directions"])
    published_intensities = ball["light_intensities"] / ball["light_intensities"].mean(0)
    ratios = calibrated["light_intensities"] / published_intensities
    # Measured: directions 1.35 deg mean (max 2.29), each about 1 deg further from the camera's
    # axis than the published ones; intensity ratios 1.4 % mean.
    assert to_published.mean() < 1.5
    assert np.abs(ratios - 1).mean() < 0.02

    # The ball's highlights (it is shiny) through the mirror method: 0.66 deg mean from the
    # published directions (max 1.40), which came from a chrome sphere too.
    highlights = iphong.calibrate_lights(ball["images"], mask=ball["mask"])
    from_highlights = angles_deg(highlights["light_directions"], ball["light_directions"])
    assert from_highlights.mean() < 0.8 and from_highlights.max() < 1.6

    # Cat, with the ball's lights instead of the published ones: measured 5.75 -> 5.23 deg
    # (the default model) and 7.27 -> 6.82 (Lambert) on the 8-bit crop.
    cat = iphong.load_dataset(CROP / "cat")
    errors = {}
    for name, directions, intensities in [
            ("published", cat["light_directions"], cat["light_intensities"]),
            ("calibrated", calibrated["light_directions"], calibrated["light_intensities"])]:
        result = iphong.estimate_normals(cat["images"], directions, intensities, mask=cat["mask"])
        errors[name] = iphong.angular_error(result["normals"], cat["normal_gt"],
                                            cat["mask"])["mean_angular_error_deg"]
    assert errors["calibrated"] < errors["published"] + 0.3, errors
    assert errors["calibrated"] < 5.4, errors


@needs_diligent
@pytest.mark.parametrize("name, intensity_bound, measured", [("cat", 0.032, 0.0224),
                                                             ("ball", 0.025, 0.0197)])
def test_semi_calibrated_intensities(name, intensity_bound, measured):
    d = iphong.load_dataset(CROP / name)
    estimate = iphong.estimate_intensities(d["images"], d["light_directions"], mask=d["mask"])
    published = d["light_intensities"] / d["light_intensities"].mean(0)
    error = np.abs(estimate["light_intensities"] / published - 1).mean()
    assert error < intensity_bound, f"{error:.4f} (measured {measured})"
    assert estimate["eigen_gap"] > 8  # accepted: above the refusal's gap
    errors = []
    for intensities in [d["light_intensities"], estimate["light_intensities"]]:
        result = iphong.estimate_normals(d["images"], d["light_directions"], intensities,
                                         mask=d["mask"], light_distance="inf")
        errors.append(iphong.angular_error(result["normals"], d["normal_gt"],
                                           d["mask"])["mean_angular_error_deg"])
    # Compared with the lights distant, as the intensities were estimated: measured cat 4.93 ->
    # 4.98 deg, ball 1.65 -> 1.83 (the crops are truncated 8-bit codes: intensities estimated on
    # them as recorded made the normals 5.74 and 2.75). An estimate made under distant lights
    # takes in the fall-off an effective distance would explain (the ball's published intensities
    # find D = 4400 px and 1.08 deg; the estimated ones keep D = infinity): the default with them
    # is its distant run or better.
    assert errors[1] < errors[0] + 0.3, errors
    default = iphong.estimate_normals(d["images"], d["light_directions"],
                                      estimate["light_intensities"], mask=d["mask"])
    assert iphong.angular_error(default["normals"], d["normal_gt"],
                                d["mask"])["mean_angular_error_deg"] <= errors[1] + 0.02
    assert estimate["code_offset"] == pytest.approx(0.5 / 255)
    # The docstring carries the library's account of an unchecked estimate (the command line's
    # warning says the same constant, calibrate::kUncheckedEstimateNote).
    assert "estimate's normals were 1.2-3.7 deg from theirs" in iphong.estimate_intensities.__doc__


def test_calibrate_lights_bad_arguments():
    images = np.zeros((3, 20, 20, 3), np.float32)
    with pytest.raises(ValueError, match=r"no sphere found in the photos \(no circle"):
        iphong.calibrate_lights(images)
    with pytest.raises(ValueError, match="sphere must be 'mirror' or 'matte'"):
        iphong.calibrate_lights(images, circles=[(10, 10, 5)], sphere="glass")
    with pytest.raises(ValueError, match=r"circles must have shape \(1, 3\) or \(2, 3\)"):
        iphong.calibrate_lights(images, circles=[10, 10, 5])
    with pytest.raises(ValueError, match="image 0: no highlight on the sphere at \\(10, 10\\)"):
        iphong.calibrate_lights(images, circles=[(10, 10, 8)])
    with pytest.raises(ValueError, match=r"normals must have shape \(H, W, 3\)"):
        iphong.calibrate_lights(images, normals=np.zeros((10, 10, 3)))
    with pytest.raises(ValueError, match="needs 4 images or more"):
        iphong.estimate_intensities(images, [(0, 0, 1), (0, 1, 1), (1, 0, 1)])


@needs_diligent
@pytest.mark.parametrize("name", ["cow", "harvest"])
def test_semi_calibrated_refuses_what_is_not_lambertian(name):
    # Metallic cow (median relative residual 0.079) and harvest's shadowed concavities (0.25):
    # the estimates were 50 % off and the normals 20 deg worse (cow 8.4 -> 30.2 deg, harvest
    # 17.5 -> 33.9), so the estimate is refused rather than used.
    d = iphong.load_dataset(CROP / name)
    with pytest.raises(ValueError, match=r"too far from Lambertian to estimate their lights' "
                                         r"intensities \(median relative residual 0\.\d+, over "
                                         r"0\.05\); give the intensities"):
        iphong.estimate_intensities(d["images"], d["light_directions"], mask=d["mask"])


@needs_uw
@needs_diligent
@pytest.mark.parametrize("name", ["uw/gray", "uw/cat", "diligent-crop8/pot1"])
def test_semi_calibrated_refuses_what_the_images_cannot_pin(name):
    """A small eigenvalue gap: another set of intensities explains the images almost as well, and
    what Lambert leaves unexplained chose one that made the normals 16-28 deg off (UW cat and
    gray; gray 29.6 deg from its mask's sphere against 5.8 calibrated) or 2.2 deg worse (pot1)."""
    d = iphong.load_dataset(DATA / name)
    with pytest.raises(ValueError, match=r"cannot pin their lights' intensities \(eigenvalue gap "
                                         r"[0-7]\.\d, under 8: another set of intensities "
                                         r"explains them almost as well\); give the intensities"):
        iphong.estimate_intensities(d["images"], d["light_directions"], mask=d["mask"])
