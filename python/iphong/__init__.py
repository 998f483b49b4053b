"""iphong: surface normals, heights and materials by inverting the Phong reflection model.

Frame: camera frame, x to the right of the image, y up, z toward the viewer. Light and view
directions point from the surface toward the light / the viewer. Images are numpy arrays
(H, W, C) float32, row 0 at the top.
"""

from ._core import (  # noqa: F401
    DirectionalLight,
    Light,
    LightType,
    Material,
    MaterialPreset,
    PointLight,
    __version__,
    material,
    material_presets,
)

import functools as _functools
import json as _json
import os as _os

import numpy as _np

from . import _core


def _short_type_errors(function):
    """pybind11 reports a wrong argument type with the whole call, arrays printed in full; this
    keeps the first line and the expected signature, and names the types that were passed."""
    @_functools.wraps(function)
    def wrapper(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except TypeError as error:
            text = str(error)
            if "incompatible function arguments" not in text:
                raise
            lines = text.split("\n")
            signature = next((line.strip() for line in lines if line.strip().startswith("1.")), "")
            passed = ", ".join([type(a).__name__ for a in args] +
                               [f"{k}={type(v).__name__}" for k, v in kwargs.items()])
            raise TypeError(f"{lines[0]} expected {signature[3:]}; got ({passed})") from None
    return wrapper


integrate = _short_type_errors(_core.integrate)
relight = _short_type_errors(_core.relight)
height_to_mesh = _short_type_errors(_core.height_to_mesh)
normals_from_height = _short_type_errors(_core.normals_from_height)
check_normal_frame = _short_type_errors(_core.check_normal_frame)

_MATERIAL_KEYS = ("ka", "kd", "ks", "shininess")


def _material_dict(value, extra=()):
    """A material given as an iphong.Material or a dict, as a dict; unknown keys are an error."""
    if isinstance(value, Material):
        return {"ka": list(value.ka), "kd": list(value.kd), "ks": list(value.ks),
                "shininess": value.shininess}
    if not isinstance(value, dict):
        raise TypeError(f"material: expected an iphong.Material or a dict, got {type(value).__name__}")
    valid = sorted(_MATERIAL_KEYS + tuple(extra))
    for key in value:
        if key not in valid:
            raise ValueError(f"material: unknown key {key!r} (valid: {', '.join(valid)})")
    return value


@_short_type_errors
def shade(normal, view=(0.0, 0.0, 1.0), material=None, lights=None, ambient=0.0, **kwargs):
    if material is None or lights is None:
        raise TypeError("shade: material and lights are required")
    if isinstance(material, dict):
        material = Material(**_material_dict(material))
    return _core.shade(normal, view, material, lights, ambient, **kwargs)


shade.__doc__ = _core.shade.__doc__


def _image_stack(images, k, encoding, max_memory_gb=None):
    """images as (K, H, W, 3) float32 linear, with a message that says what to do otherwise."""
    if encoding not in (None, "linear", "srgb"):
        raise ValueError(f"encoding: expected None, 'linear' or 'srgb', got {encoding!r}")
    try:
        a = _np.asarray(images)
    except Exception:  # ragged lists and the like
        raise TypeError(f"images: expected a numpy array (K, H, W, 3), got {type(images).__name__}") from None
    if a.dtype.kind not in "fiu" or a.dtype == bool:
        raise TypeError(f"images: expected numbers, got an array of {a.dtype}")
    # A broadcast view (numpy.broadcast_to) costs nothing until it is copied: its float32 RGB copy
    # and iphong's own are counted against the limit first, so a size that cannot fit is
    # iphong's ValueError with the figure, not numpy's MemoryError in the middle of a copy.
    channels = 3 if a.ndim == 3 else 1
    refusal = _core._check_memory(2.0 * 4 * a.size * channels, max_memory_gb,
                                  f"images: copying an array of shape {a.shape} to float32")
    if refusal:
        raise ValueError(refusal)
    if a.dtype.kind in "iu":
        top = _np.iinfo(a.dtype).max
        if encoding is None:
            raise ValueError(
                f"images: {a.dtype} values (0-{top}) would be used unscaled; pass floats in "
                f"[0, 1] (images / {top}), or encoding='linear' or 'srgb' to have them scaled "
                "(and the sRGB curve undone)")
        a = a.astype(_np.float32) / top
    a = a.astype(_np.float32, copy=False)
    if encoding == "srgb":
        a = _core._srgb_to_linear(a)  # io's curve, the one the command line uses
    shape = tuple(a.shape)
    if a.ndim == 3:  # greyscale: (K, H, W)
        if shape[0] != k and shape[2] == k:
            raise ValueError(f"images: shape {shape} looks like (H, W, K); expected (K, H, W, 3) "
                             "or (K, H, W): use numpy.moveaxis(images, 2, 0)")
        a = _np.repeat(a[..., None], 3, axis=3)
    elif a.ndim == 4:
        if shape[0] != k and shape[2] == k:
            raise ValueError(f"images: shape {shape} looks like (H, W, K, 3); expected "
                             "(K, H, W, 3): use numpy.moveaxis(images, 2, 0)")
        if shape[3] == 1:
            a = _np.repeat(a, 3, axis=3)
        elif shape[3] == 4:
            a = a[..., :3]  # alpha is not light
    else:
        raise ValueError(f"images: shape {shape}; expected (K, H, W, 3) or (K, H, W)")
    if a.shape[0] != k:
        raise ValueError(f"images: {a.shape[0]} images for {k} light directions")
    return _np.ascontiguousarray(a)


@_short_type_errors
def estimate_normals(images, light_directions, light_intensities=None, mask=None,
                     model=None, material=None, *args, encoding=None, **kwargs):
    try:
        k = len(light_directions)
    except TypeError:
        raise TypeError("light_directions: expected a (K, 3) array, got "
                        f"{type(light_directions).__name__}") from None
    images = _image_stack(images, k, encoding, kwargs.get("max_memory_gb"))
    if isinstance(material, Material) and not any(material.kd):
        # An iphong.Material made without kd has kd 0: the albedo is unknown, not black.
        material = {k: v for k, v in _material_dict(material).items() if k != "kd"}
    elif material is not None:
        material = _material_dict(material, extra=("ambient", "model"))
    return _core.estimate_normals(images, light_directions, light_intensities, mask, model,
                                  material, *args, **kwargs)


estimate_normals.__doc__ = _core.estimate_normals.__doc__ + """

images may also be (K, H, W) greyscale, or integers (uint8, uint16) with encoding='linear' or
'srgb' (scaled to [0, 1], the sRGB curve undone); float images with encoding='srgb' are
linearized. mask may be (H, W) or an RGB picture (H, W, 3): inside where any channel is non-zero.
material may be an iphong.Material (its kd, when not zero, is the known albedo) or a dict."""


@_short_type_errors
def calibrate_lights(images, mask=None, circles=None, sphere="mirror", normals=None, *args,
                     encoding=None, **kwargs):
    images = _image_stack(images, len(images), encoding)
    return _core.calibrate_lights(images, mask, circles, sphere, normals, *args, **kwargs)


calibrate_lights.__doc__ = _core.calibrate_lights.__doc__


@_short_type_errors
def estimate_intensities(images, light_directions, mask=None, *args, encoding=None, **kwargs):
    images = _image_stack(images, len(light_directions), encoding)
    return _core.estimate_intensities(images, light_directions, mask, *args, **kwargs)


estimate_intensities.__doc__ = _core.estimate_intensities.__doc__


@_short_type_errors
def compare_encodings(images, light_directions, light_intensities=None, mask=None, *args,
                      encoding=None, **kwargs):
    images = _image_stack(images, len(light_directions), encoding)
    return _core.compare_encodings(images, light_directions, light_intensities, mask, *args,
                                   **kwargs)


compare_encodings.__doc__ = _core.compare_encodings.__doc__ + """

images may also be integers (uint8, uint16) with encoding='linear' (scaled to [0, 1])."""


@_short_type_errors
def fit_material(images, light_directions, normals, *args, encoding=None, **kwargs):
    images = _image_stack(images, len(light_directions), encoding)
    return _core.fit_material(images, light_directions, normals, *args, **kwargs)


fit_material.__doc__ = _core.fit_material.__doc__


@_short_type_errors
def angular_error(estimate, ground_truth, mask=None):
    """Angular error between two normal maps (H, W, 3) over the mask where the ground truth is
    non-zero: mean_angular_error_deg, median_angular_error_deg, fraction_below_{5,10,20}_deg,
    evaluated_pixels (the names of metrics.json) and error_deg (H, W)."""
    return _core.angular_error(estimate, ground_truth, mask)


def _python_words(function):
    """The writers' refusals are the command line's, which name its flag; say the argument."""
    @_functools.wraps(function)
    def wrapper(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except OSError as error:
            raise type(error)(str(error).replace("--overwrite", "overwrite=True")) from None
    return wrapper


@_python_words
@_short_type_errors
def save_normals(path, normals, mask=None, *, convention="opengl", overwrite=False):
    """Write a normal map as `iphong normals` does: .exr (or .tif) float xyz, 0 outside the mask;
    .png a 16-bit picture (n + 1)/2 (convention 'opengl': green = +y, or 'directx'). The file
    must be new unless overwrite; it appears complete or not at all."""
    _core._save_normals(_path(path, "path"), normals, mask, convention, overwrite)


@_python_words
@_short_type_errors
def save_mesh(path, height, mask=None, *, normals=None, albedo=None, pixel_size=1.0,
              overwrite=False):
    """Write the mesh of a height map (H, W; NaN = none) as `iphong integrate` does: .ply
    (binary) or .obj, one vertex per pixel, vertex normals from normals (H, W, 3) and sRGB
    vertex colours from albedo (H, W, 3) when given. Returns (vertices, triangles)."""
    return _core._save_mesh(_path(path, "path"), height, mask, normals, albedo, pixel_size,
                            overwrite)


@_python_words
@_short_type_errors
def save_dataset(directory, images, light_directions, light_intensities=None, mask=None,
                 normal_gt=None, *, format="png", bits=16, encoding=None, overwrite=False):
    """Write a photometric-stereo dataset in the DiLiGenT layout, as `iphong render --per-light`
    does (images 001.png ..., filenames.txt, light_directions.txt, light_intensities.txt,
    mask.png; with normal_gt also Normal_gt.mat, normals.exr, normals.png), which load_dataset and
    `iphong normals` read back. The folder must be new or empty (or an earlier save_dataset
    output with overwrite) and appears complete or not at all."""
    try:
        k = len(light_directions)
    except TypeError:
        raise TypeError("light_directions: expected a (K, 3) array, got "
                        f"{type(light_directions).__name__}") from None
    _core._save_dataset(_path(directory, "directory"), _image_stack(images, k, encoding),
                        light_directions, light_intensities, mask, normal_gt, format, bits,
                        overwrite)


@_short_type_errors
def render(scene, per_light=False, max_memory_gb=None):
    """Render a scene (a dict in the scene-file format, or the path of a scene JSON file).

    Returns a dict of numpy arrays, nothing written to disk: image (H, W, 3) float32 linear with
    all lights, images (K, H, W, 3) one per light when per_light, normals (H, W, 3) ground truth
    (0 outside the mask), depth (H, W), albedo (H, W, 3), mask (H, W) bool, light_directions (K, 3)
    and light_intensities (K, 3). Relative paths in a dict resolve against the working directory.
    Raises ValueError naming the field on a bad scene, when nothing is visible (saying why: faces
    seen from behind, faces without area, or objects outside the view), and when the render would
    need more memory than max_memory_gb (default: three quarters of the machine's); TypeError for a
    scene that is neither a dict nor a path.
    """
    if isinstance(scene, dict):
        try:
            text = _json.dumps(scene, allow_nan=False)
        except (TypeError, ValueError) as error:
            raise ValueError(f"scene: not JSON: {error}") from None
        return _core._render_json(text, "scene", _os.getcwd(), per_light, max_memory_gb)
    if not isinstance(scene, (str, bytes, _os.PathLike)):
        raise TypeError(f"scene: expected a dict or a path, got {type(scene).__name__}")
    return _core._render_file(_os.fsdecode(scene), per_light, max_memory_gb)


def _path(value, what):
    if not isinstance(value, (str, bytes, _os.PathLike)):
        raise TypeError(f"{what}: expected a path, got {type(value).__name__}")
    return _os.fsdecode(value)


@_short_type_errors
def load_dataset(directory, max_memory_gb=None, *, lights=None, intensities=None, mask=None,
                 encoding="auto", crop=None, downscale=1, images=None):
    """Read a capture folder into numpy arrays; see _core.load_dataset."""
    files = {name: "" if value is None else _path(value, name)
             for name, value in (("lights", lights), ("intensities", intensities), ("mask", mask),
                                 ("images", images))}
    if not isinstance(encoding, str):
        raise TypeError(f"encoding: expected 'auto', 'linear' or 'srgb', got {type(encoding).__name__}")
    if isinstance(downscale, bool) or not isinstance(downscale, int):
        raise TypeError(f"downscale: expected a whole number, got {type(downscale).__name__}")
    return _core.load_dataset(_path(directory, "directory"), max_memory_gb, encoding=encoding,
                              crop=crop, downscale=downscale, **files)


load_dataset.__doc__ = _core.load_dataset.__doc__

plan_sample_indices = _core.plan_sample_indices
plan_normals = _short_type_errors(_core.plan_normals)
solve_normals_block = _short_type_errors(_core.solve_normals_block)

#: Every named material preset, by name (seed 000's Phong table and seed 004's tutorial table).
materials = {preset.name: preset.material for preset in material_presets()}

__all__ = [
    "DirectionalLight",
    "Light",
    "LightType",
    "Material",
    "MaterialPreset",
    "PointLight",
    "angular_error",
    "calibrate_lights",
    "check_normal_frame",
    "compare_encodings",
    "estimate_intensities",
    "estimate_normals",
    "fit_material",
    "height_to_mesh",
    "integrate",
    "load_dataset",
    "material",
    "material_presets",
    "materials",
    "normals_from_height",
    "plan_normals",
    "plan_sample_indices",
    "relight",
    "render",
    "save_dataset",
    "save_mesh",
    "save_normals",
    "shade",
    "solve_normals_block",
]
