"""Normal recovery on Dask: captures larger than one machine's memory, and many captures.

estimate_normals(images, light_directions, ...) takes a dask.array (K, H, W, 3) chunked over H and
W and returns dask arrays. What the whole object decides (the model, its shininess, the ambient
term) is decided once, eagerly, on the plan sample (iphong.plan_sample_indices: every masked pixel
up to 2^17, else 2^17 at an even stride), gathered from the array with a pointwise index; then
each block is fitted by the C++ solver (solve_normals_block) with that plan, which is all that is
shipped to the workers beside the block. A pixel's result depends on its own observations and the
plan only, so the maps are the same, value for value, for any chunking — and the same as
iphong.estimate_normals on the whole array.

process_datasets(paths, output_root, client=None) runs the `iphong normals` command on many
capture folders as independent tasks (on a dask.distributed Client, or Dask's local threads):
each writes its own output folder atomically, and a failure is reported in the summary without
stopping the others.
"""
import os as _os
import pathlib as _pathlib
import shutil as _shutil
import subprocess as _subprocess
import time as _time

import numpy as _np

from . import _core

_MAPS = {"normals": slice(0, 3), "albedo": slice(3, 6), "specular": slice(6, 9),
         "residual": 9, "model_map": 10}


def _solve_block(images, mask, light_directions, light_intensities, plan, threads):
    return _core.solve_normals_block(images, mask, light_directions, light_intensities, plan,
                                     threads)


def _refine_block(images, mask, plan, lights, points, previous, model_map, threads):
    return _core.refine_normals_block(images, mask, plan, lights, points, previous, model_map,
                                      threads)


def _effective_distance(images, mask_np, mask_da, masked, directions, intensities, plan,
                        distant, model, material, discard_dark, discard_bright, fast,
                        shadow_threshold, plan_sample, light_distance, threads):
    """The effective light distance after the distant solve in blocks (its maps computed):
    returns the maps to report (a dask array of the images' chunks) and the choice."""
    import dask.array as da

    k, h, w, _ = images.shape
    by_pixel = images.transpose(1, 2, 0, 3)
    chunks = images.chunks[1:3]

    def observations(sets):
        out = []
        for indices in sets:
            positions = masked[_np.asarray(indices, dtype=_np.int64)]
            rows, cols = _np.divmod(positions, w)
            out.append(by_pixel.vindex[rows, cols].compute() if positions.size
                       else _np.zeros((0, k, 3), _np.float32))
        return out

    def refine(lights, near_plan, previous, model_map):
        points = _np.zeros((h * w, 3))
        surface = lights.pop("points")
        if len(surface):  # none for distant lights (the foil's refit at D = inf)
            points[masked] = surface
        points = da.from_array(points.reshape(h, w, 3), chunks=(*chunks, 3))
        before = da.from_array(previous, chunks=(*chunks, 11))
        blocks = da.blockwise(_refine_block, "hwc", images, "khwd", mask_da, "hw", near_plan, None,
                              lights, None, points, "hwe", before, "hwc", model_map, None,
                              threads, None, concatenate=True, dtype=_np.float32,
                              meta=_np.empty((0, 0, 0), _np.float32))
        return blocks.compute()

    choice = _core.effective_distance_pieces(
        mask_np, directions, intensities, plan, distant, model, material, discard_dark,
        discard_bright, fast, shadow_threshold, plan_sample, light_distance, observations, refine)
    maps = choice.get("maps", distant)
    return da.from_array(maps, chunks=(*chunks, 11)), choice


def estimate_normals(images, light_directions, light_intensities=None, mask=None, model=None,
                     material=None, discard_dark=0.3, discard_bright=0.1, fast=False,
                     shadow_threshold=0.1, plan_sample=131072, threads_per_block=1, *,
                     encoding=None, light_distance="auto", weigh_by_shading=True,
                     per_pixel_model=True):
    """iphong.estimate_normals on a dask.array (K, H, W, 3), chunked over H and W only.

    mask: (H, W) bool (numpy or dask) or None (every pixel). Returns a dict: normals, albedo,
    specular (H, W, 3), residual, model_map (H, W) as lazy dask arrays with the images' chunks;
    model, shininess, ambient_term and the plan (decided now, on the plan sample); ks, a lazy
    (3,) array: the median ks of the plan sample's solved pixels that kept the lobe, as
    estimate_normals reports it.
    light_distance: as iphong.estimate_normals: 'auto' (default) chooses an effective light
    distance when the images say the lights are near (DiLiGenT's cat, ball and harvest do), 'inf'
    keeps them distant, a number (pixels) gives it. Except with 'inf' (unless the plan keeps the
    foil, which is then refitted at every pixel as in memory), the distant maps are computed here
    (the surface that places each pixel's lights needs the whole normal map), D is chosen on the
    same pixels as in memory, and each near pass maps the blocks again; the maps returned are
    then in memory, wrapped as dask arrays with the images' chunks, and equal to
    iphong.estimate_normals' bit for bit; r['effective_distance'] says what was chosen. With
    'inf' and no foil everything stays lazy. weigh_by_shading, per_pixel_model: as
    iphong.estimate_normals.
    Integer images (uint8, uint16) need encoding='linear' or 'srgb', as in
    iphong.estimate_normals (scaled to [0, 1], the sRGB curve undone; each block lazily); float
    images with encoding='srgb' are linearized.
    Raises ValueError for inconsistent shapes or chunks over K or the colour axis.
    """
    import dask
    import dask.array as da

    images = images if isinstance(images, da.Array) else da.from_array(_np.asarray(images))
    if images.ndim != 4 or images.shape[3] != 3:
        raise ValueError(f"images: expected (K, H, W, 3), got shape {images.shape}")
    k, h, w, _ = images.shape
    if len(images.chunks[0]) != 1 or len(images.chunks[3]) != 1:
        raise ValueError("images: chunk over H and W only (every block needs all K images and "
                         "all 3 channels): use images.rechunk({0: -1, 3: -1})")
    if encoding not in (None, "linear", "srgb"):
        raise ValueError(f"encoding: expected None, 'linear' or 'srgb', got {encoding!r}")
    if images.dtype.kind not in "fiu" or images.dtype == bool:
        raise TypeError(f"images: expected numbers, got an array of {images.dtype}")
    if images.dtype.kind in "iu":
        top = _np.iinfo(images.dtype).max
        if encoding is None:  # the same refusal as iphong.estimate_normals
            raise ValueError(
                f"images: {images.dtype} values (0-{top}) would be used unscaled; pass floats in "
                f"[0, 1] (images / {top}), or encoding='linear' or 'srgb' to have them scaled "
                "(and the sRGB curve undone)")
        images = images.astype(_np.float32) / _np.float32(top)
    if images.dtype != _np.float32:
        images = images.astype(_np.float32)
    if encoding == "srgb":
        images = images.map_blocks(_core._srgb_to_linear, dtype=_np.float32)
    if mask is None:
        mask_np = _np.ones((h, w), bool)
    else:
        mask_np = _np.asarray(mask.compute() if isinstance(mask, da.Array) else mask).astype(bool)
    if mask_np.shape != (h, w):
        raise ValueError(f"mask: expected ({h}, {w}), got {mask_np.shape}")
    directions = _np.asarray(light_directions, dtype=_np.float64)
    intensities = None if light_intensities is None else _np.asarray(light_intensities,
                                                                     dtype=_np.float64)
    if plan_sample < 1:
        raise ValueError("plan_sample must be >= 1")
    if material is not None:
        from . import Material, _material_dict  # as iphong.estimate_normals takes it
        if isinstance(material, Material) and not any(material.kd):
            material = {key: v for key, v in _material_dict(material).items() if key != "kd"}
        else:
            material = _material_dict(material, extra=("ambient", "model"))

    # The plan sample, gathered pointwise: only its pixels' observations are computed.
    masked = _np.flatnonzero(mask_np)
    positions = masked[_np.asarray(_core.plan_sample_indices(masked.size, plan_sample),
                                   dtype=_np.int64)]
    rows, cols = _np.divmod(positions, w)
    if positions.size:
        sample = images.transpose(1, 2, 0, 3).vindex[rows, cols].compute()  # (n, K, 3)
    else:
        sample = _np.zeros((0, k, 3), _np.float32)
    plan = _core.plan_normals(sample, positions, w, h, directions, intensities, model, material,
                              discard_dark, discard_bright, fast, shadow_threshold,
                              weigh_by_shading=weigh_by_shading, per_pixel_model=per_pixel_model)
    plan["options"]["plan_sample"] = plan_sample

    mask_da = da.from_array(mask_np, chunks=images.chunks[1:3])
    # blockwise passes non-array arguments positionally with index None.
    stacked = da.blockwise(_solve_block, "hwc", images, "khwd", mask_da, "hw", directions, None,
                           intensities, None, plan, None, threads_per_block, None,
                           new_axes={"c": 11}, concatenate=True, dtype=_np.float32,
                           meta=_np.empty((0, 0, 0), _np.float32))
    effective = None
    # Distant lights asked for stay lazy, except with the foil, which is refitted at D = inf as
    # in memory (the effective distance's foil_refit).
    if k >= 3 and (light_distance != "inf" or plan["options"]["model"] == "normal-centred"):
        stacked, effective = _effective_distance(
            images, mask_np, mask_da, masked, directions, intensities, plan, stacked.compute(),
            model, material, discard_dark, discard_bright, fast, shadow_threshold, plan_sample,
            light_distance, threads_per_block)
    out = {name: stacked[..., index] for name, index in _MAPS.items()}
    out["model"] = plan["options"]["model"]
    out["shininess"] = plan["options"]["shininess"]
    out["ambient_term"] = _np.asarray(plan["options"]["ambient_term"])
    out["code_offset"] = plan["options"]["code_offset"]
    out["plan"] = plan
    if effective is not None:
        maps = effective.pop("maps", None)
        out["effective_distance"] = effective
        if maps is not None and "height" in effective:  # a finite D: the last near pass's
            for key in ("model", "shininess", "code_offset"):
                out[key] = effective.pop(key)
            out["ambient_term"] = _np.asarray(effective.pop("ambient_term"))
            out["ks"] = da.from_array(_np.asarray(effective.pop("ks")))
            out["height"] = effective.pop("height")
            return out

    def median_ks(specular, residual, model_map):
        # The pixels the per-pixel test gave to Lambert (model_map 0) have ks 0 by choice: left
        # out, as by the C++ solver.
        solved = specular[(residual >= 0) & (model_map != 0)]
        if plan["options"]["material_known"]:
            return _np.asarray(plan["options"]["ks"])
        if solved.size == 0 or plan["options"]["model"] == "lambert":
            return _np.zeros(3)
        # The upper median, as the C++ solver's nth_element at n/2.
        return _np.sort(solved, axis=0)[solved.shape[0] // 2].astype(_np.float64)

    if positions.size:
        ks = dask.delayed(median_ks)(out["specular"].vindex[rows, cols],
                                     out["residual"].vindex[rows, cols],
                                     out["model_map"].vindex[rows, cols])
    else:
        ks = dask.delayed(median_ks)(_np.zeros((0, 3), _np.float32), _np.zeros(0, _np.float32),
                                     _np.zeros(0, _np.float32))
    out["ks"] = da.from_delayed(ks, shape=(3,), dtype=_np.float64)
    return out


def _binary():
    """The iphong command: $IPHONG_BINARY, the build tree this module sits in, or PATH."""
    if _os.environ.get("IPHONG_BINARY"):
        return _os.environ["IPHONG_BINARY"]
    built = _pathlib.Path(__file__).resolve().parents[2] / "iphong"
    if built.exists():
        return str(built)
    found = _shutil.which("iphong")
    if not found:
        raise FileNotFoundError("no iphong binary: set IPHONG_BINARY or put iphong on PATH")
    return found


def _run_normals(binary, dataset, output, integrate, threads, extra):
    start = _time.monotonic()
    args = [binary, "normals", str(dataset), "-o", str(output), "--quiet", "--threads",
            str(threads), *extra]
    if integrate:
        args.append("--integrate")
    done = _subprocess.run(args, capture_output=True, text=True)
    lines = [line for line in done.stderr.splitlines() if line.startswith("iphong: error: ")]
    return {"dataset": str(dataset), "output": str(output), "ok": done.returncode == 0,
            "exit_code": done.returncode,
            "error": (lines[0][len("iphong: error: "):] if lines else done.stderr.strip())
            if done.returncode else "",
            "seconds": _time.monotonic() - start}


def process_datasets(paths, output_root, client=None, integrate=False, threads=1, extra_args=()):
    """`iphong normals` (and --integrate) on every capture folder in `paths`, one task each.

    Each writes output_root/<folder name> (complete or not at all: the command's own rule; two
    folders with the same name are refused before anything runs). client: a
    dask.distributed.Client (tasks on its workers, which need this module and the iphong binary
    at the same path, or IPHONG_BINARY) or None (Dask's local threads). threads: --threads per
    task. Returns one dict per dataset, in order: dataset, output, ok, exit_code, error (the
    command's one-line message), seconds. A failure does not stop the others.
    """
    import dask

    paths = [_pathlib.Path(p) for p in paths]
    root = _pathlib.Path(output_root)
    names = [p.resolve().name for p in paths]
    if len(set(names)) != len(names):
        raise ValueError("two datasets have the same folder name; their outputs would collide")
    root.mkdir(parents=True, exist_ok=True)
    binary = _binary()
    tasks = [dask.delayed(_run_normals, pure=False)(binary, p, root / n, integrate, threads,
                                                    list(extra_args))
             for p, n in zip(paths, names)]
    if client is not None:
        return list(client.gather(client.compute(tasks)))
    return list(dask.compute(*tasks, scheduler="threads"))
