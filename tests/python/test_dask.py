"""iphong.dask: normals from a chunked dask.array equal iphong.estimate_normals on the whole array
value for value, for any chunking, on Dask's local scheduler and on a real two-process
distributed.LocalCluster; process_datasets runs `iphong normals` per folder and reports failures
without stopping the others."""
import json
import pathlib
import shutil

import numpy as np
import pytest

import iphong

dask = pytest.importorskip("dask", reason="python3-dask not installed (scripts/setup-debian.sh)")
da = pytest.importorskip("dask.array")
import iphong.dask as idask  # noqa: E402

MATERIAL = {"ka": 0.05, "kd": [0.6, 0.5, 0.4], "ks": 0.3, "shininess": 30}
SCENE = {"width": 48, "height": 40, "ambient": 0.5,
         "lights": [{"type": "hemisphere", "count": 30, "min_elevation_deg": 30}],
         "objects": [{"shape": "sphere", "radius": 0.9, "subdivisions": 5, "material": MATERIAL}],
         "noise": {"gaussian_sigma": 0.003, "seed": 5}}
MAPS = ("normals", "albedo", "specular", "residual", "model_map")


@pytest.fixture(scope="module")
def capture():
    return iphong.render(SCENE, per_light=True)


@pytest.fixture(scope="module")
def whole(capture):
    return iphong.estimate_normals(capture["images"], capture["light_directions"],
                                   capture["light_intensities"], capture["mask"])


def solve(capture, chunks, **kwargs):
    images = da.from_array(capture["images"], chunks=(-1, *chunks, -1))
    return idask.estimate_normals(images, capture["light_directions"],
                                  capture["light_intensities"], capture["mask"], **kwargs)


@pytest.mark.parametrize("chunks", [(40, 48), (7, 11), (13, 48)])
def test_any_chunking_equals_the_whole(capture, whole, chunks):
    r = solve(capture, chunks)
    assert r["normals"].chunks[:2] == da.from_array(capture["images"],
                                                    chunks=(-1, *chunks, -1)).chunks[1:3]
    computed = dask.compute(*(r[m] for m in MAPS), r["ks"], scheduler="threads")
    for name, value in zip(MAPS, computed):
        np.testing.assert_array_equal(value, whole[name], err_msg=name)
    assert r["model"] == whole["model"] and r["shininess"] == whole["shininess"]
    np.testing.assert_array_equal(r["ambient_term"], whole["ambient_term"])
    np.testing.assert_array_equal(computed[-1], whole["ks"])


def test_plan_sample_subset_is_independent_of_chunking(capture):
    """A plan sample smaller than the object (a stride subset): still the same for any chunks."""
    a = solve(capture, (40, 48), plan_sample=200)
    b = solve(capture, (9, 10), plan_sample=200)
    a["plan"].pop("model_seconds"), b["plan"].pop("model_seconds")
    assert a["plan"] == b["plan"]
    for name in MAPS:
        np.testing.assert_array_equal(a[name].compute(), b[name].compute(), err_msg=name)


def test_known_material_and_lambert(capture):
    for kwargs in ({"material": dict(MATERIAL, ambient=0.5)}, {"model": "lambert"}):
        expected = iphong.estimate_normals(capture["images"], capture["light_directions"],
                                           capture["light_intensities"], capture["mask"], **kwargs)
        r = solve(capture, (10, 12), **kwargs)
        for name in ("normals", "albedo", "residual"):
            np.testing.assert_array_equal(r[name].compute(), expected[name], err_msg=name)


def test_without_the_per_pixel_test_too(capture):
    """per_pixel_model=False travels in the plan to every block: the maps equal the whole's."""
    expected = iphong.estimate_normals(capture["images"], capture["light_directions"],
                                       capture["light_intensities"], capture["mask"],
                                       per_pixel_model=False)
    assert "model_map" not in expected
    r = solve(capture, (10, 12), per_pixel_model=False)
    assert r["plan"]["options"]["per_pixel_model"] is False
    for name in ("normals", "albedo", "specular", "residual"):
        np.testing.assert_array_equal(r[name].compute(), expected[name], err_msg=name)


def test_bad_arrays_raise_value_error(capture):
    images = da.from_array(capture["images"], chunks=(10, 20, 20, 3))
    with pytest.raises(ValueError, match="chunk over H and W only"):
        idask.estimate_normals(images, capture["light_directions"])
    with pytest.raises(ValueError, match=r"expected \(K, H, W, 3\)"):
        idask.estimate_normals(da.zeros((3, 4, 4)), np.eye(3))
    with pytest.raises(ValueError, match="mask: expected"):
        idask.estimate_normals(da.from_array(capture["images"]), capture["light_directions"],
                               mask=np.ones((3, 3), bool))
    with pytest.raises(ValueError, match="plan: not a plan"):
        iphong.solve_normals_block(capture["images"], None, capture["light_directions"],
                                   plan={"options": {}})
    # A plan's folds index the lights and size the search's tables: a plan for other lights, or
    # edited, is one line, not a read past the lights or a table of a billion folds.
    mask = np.asarray(capture["mask"], bool)
    positions = np.flatnonzero(mask)
    sample = np.ascontiguousarray(np.asarray(capture["images"])[:, mask].transpose(1, 0, 2))
    plan = iphong.plan_normals(sample, positions, mask.shape[1], mask.shape[0],
                               capture["light_directions"], capture["light_intensities"])
    assert len(plan["fold"]) == 30
    for fold in (plan["fold"][:-1], [10**9] * len(plan["fold"]), [-1] * len(plan["fold"])):
        edited = dict(plan, fold=fold)
        with pytest.raises(ValueError, match="plan: fold must give each of the 30 lights"):
            iphong.solve_normals_block(capture["images"], capture["mask"],
                                       capture["light_directions"], capture["light_intensities"],
                                       plan=edited)


def test_distributed_cluster_equals_the_whole(capture, whole):
    distributed = pytest.importorskip("distributed",
                                      reason="python3-distributed not installed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        r = solve(capture, (10, 24))
        normals, ks = client.compute([r["normals"], r["ks"]], sync=True)
        np.testing.assert_array_equal(normals, whole["normals"])
        np.testing.assert_array_equal(ks, whole["ks"])


def test_process_datasets_reports_each(tmp_path):
    iphong_binary = pathlib.Path(iphong.__file__).resolve().parents[2] / "iphong"
    if not iphong_binary.exists():
        pytest.skip(f"no iphong binary at {iphong_binary}")
    good = tmp_path / "in" / "sphere"
    good.parent.mkdir()
    out = iphong.render(SCENE, per_light=True)
    iphong.save_dataset(str(good), out["images"], out["light_directions"],
                        out["light_intensities"], out["mask"])
    bad = tmp_path / "in" / "broken"
    shutil.copytree(good, bad)
    (bad / "light_directions.txt").write_text("0 0 1\n")  # one light for 30 images
    results = idask.process_datasets([good, bad], tmp_path / "out")
    assert [r["ok"] for r in results] == [True, False]
    assert json.loads((tmp_path / "out" / "sphere" / "metrics.json").read_text())["images"] == 30
    assert "light_directions.txt" in results[1]["error"]
    assert not (tmp_path / "out" / "broken").exists()
    with pytest.raises(ValueError, match="same folder name"):
        idask.process_datasets([good, good], tmp_path / "out2")


def test_integer_images_need_an_encoding_as_in_estimate_normals(capture):
    """uint8 images were taken unscaled (albedo 255 times the float run's); now they are refused
    without encoding=, as iphong.estimate_normals refuses them, and with it the two agree value for
    value."""
    codes = np.clip(np.round(capture["images"] * 255), 0, 255).astype(np.uint8)
    images = da.from_array(codes, chunks=(-1, 20, 24, -1))
    args = (capture["light_directions"], capture["light_intensities"], capture["mask"])
    with pytest.raises(ValueError, match=r"uint8 values \(0-255\) would be used unscaled"):
        idask.estimate_normals(images, *args)
    with pytest.raises(ValueError, match=r"uint8 values \(0-255\) would be used unscaled"):
        iphong.estimate_normals(codes, *args)
    lazy = idask.estimate_normals(images, *args, encoding="linear")
    eager = iphong.estimate_normals(codes, *args, encoding="linear")
    albedo, normals = dask.compute(lazy["albedo"], lazy["normals"], scheduler="threads")
    np.testing.assert_array_equal(normals, eager["normals"])
    np.testing.assert_array_equal(albedo, eager["albedo"])
    # 'srgb' undoes the curve block by block: the same as handing over linearized floats (both
    # lazy: distant lights).
    lazy = idask.estimate_normals(images, *args, encoding="srgb", light_distance="inf")
    floats = iphong._core._srgb_to_linear(codes.astype(np.float32) / 255)
    same = idask.estimate_normals(da.from_array(floats, chunks=(-1, 20, 24, -1)), *args,
                                  light_distance="inf")
    np.testing.assert_array_equal(*dask.compute(lazy["normals"], same["normals"],
                                                scheduler="threads"))


def test_effective_light_distance_equals_the_whole():
    """A matte sphere under a dome of 24 point lights at 1.5 object sizes, given by direction
    only: the in-memory run chooses an effective light distance and runs its near passes; Dask
    chooses the same on the same pixels, maps the blocks for each pass, and gives the same maps
    bit for bit (before, it kept the lights distant and differed)."""
    from test_near_lights import small_dome_scene
    out = iphong.render(small_dome_scene(), per_light=True)
    args = (out["light_directions"], out["light_intensities"], out["mask"])
    whole = iphong.estimate_normals(out["images"], *args)
    assert whole["effective_distance"]["distance_px"] != float("inf")
    r = idask.estimate_normals(da.from_array(out["images"], chunks=(-1, 25, 31, -1)), *args)
    assert r["effective_distance"]["distance_px"] == whole["effective_distance"]["distance_px"]
    assert len(r["effective_distance"]["passes"]) >= 1
    # At its distance the matte sphere's held-out costs tie between Lambert and a lobe with ks near
    # 0 (5.27 each): whichever is chosen, Dask's maps are the in-memory run's; where the in-memory
    # result has no specular or model map (Lambert), Dask's (always all five) carry nothing.
    empty = {"specular": 0.0, "model_map": -1.0}
    for name in MAPS:
        if name in whole:
            np.testing.assert_array_equal(r[name].compute(), whole[name], err_msg=name)
        else:
            assert (r[name].compute() == empty[name]).all(), name
    assert r["model"] == whole["model"] and r["shininess"] == whole["shininess"]
    np.testing.assert_array_equal(r["ks"].compute(), whole["ks"])
    # Distant lights asked for: the in-memory run's maps; lazy unless the plan kept the foil,
    # which is refitted at every pixel (as here: this dome's distant plan keeps it).
    distant = idask.estimate_normals(da.from_array(out["images"], chunks=(-1, 25, 31, -1)), *args,
                                     light_distance="inf")
    far = iphong.estimate_normals(out["images"], *args, light_distance="inf")
    assert ("effective_distance" in distant) == (far["model"] == "normal-centred")
    np.testing.assert_array_equal(distant["normals"].compute(), far["normals"])


def test_the_foils_refit_at_distant_lights_equals_the_whole(tmp_path):
    """A matte sphere under a dome of 12 lights at 1.5 object sizes (numpy's render), read with
    directions only and distant lights asked for: the model choice takes the foil, and every pixel
    is refitted with the foil (effective_distance's foil_refit). Dask does the same refit block by
    block: the same maps bit for bit. (Left to choose, the dome keeps a distance since the
    per-pixel test scales its leave-one-out error: 0.46 deg against 1.63 deg distant.)"""
    from test_near_lights import CASES, write_capture
    shape, lights, phong, sigma, _ = CASES["dome-lambert"]
    normals, _, mask = write_capture(tmp_path / "cap", shape, lights, phong, sigma)
    d = iphong.load_dataset(tmp_path / "cap")
    args = (d["light_directions"], d["light_intensities"], d["mask"])
    chunked = da.from_array(d["images"], chunks=(-1, 25, 31, -1))
    for light_distance in ["inf"]:
        whole = iphong.estimate_normals(d["images"], *args, light_distance=light_distance)
        assert whole["model"] == "normal-centred", whole["model"]
        assert whole["effective_distance"]["foil_refit"]
        assert "model_map" not in whole
        r = idask.estimate_normals(chunked, *args, light_distance=light_distance)
        assert r["effective_distance"]["foil_refit"]
        for name in ("normals", "albedo", "specular", "residual"):
            np.testing.assert_array_equal(r[name].compute(), whole[name], err_msg=name)
        assert (r["model_map"].compute() == -1).all()
        np.testing.assert_array_equal(r["ks"].compute(), whole["ks"])
