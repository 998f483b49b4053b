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
    angular_error,
    estimate_normals,
    height_to_mesh,
    integrate,
    material,
    material_presets,
    normals_from_height,
    shade,
)

import json as _json
import os as _os

from . import _core


def render(scene, per_light=False, max_memory_gb=None):
    """Render a scene (a dict in the scene-file format, or the path of a scene JSON file).

    Returns a dict of numpy arrays, nothing written to disk: image (H, W, 3) float32 linear with
    all lights, images (K, H, W, 3) one per light when per_light, normals (H, W, 3) ground truth
    (0 outside the mask), depth (H, W), albedo (H, W, 3), mask (H, W) bool, light_directions (K, 3)
    and light_intensities (K, 3). Relative paths in a dict resolve against the working directory.
    Raises ValueError naming the field on a bad scene, and when the render would need more memory
    than max_memory_gb (default: three quarters of the machine's); TypeError for a scene that is
    neither a dict nor a path.
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


def load_dataset(directory, max_memory_gb=None, *, lights=None, intensities=None, mask=None,
                 encoding="auto", crop=None, downscale=1):
    """Read a capture folder into numpy arrays; see _core.load_dataset."""
    files = {name: "" if value is None else _path(value, name)
             for name, value in (("lights", lights), ("intensities", intensities), ("mask", mask))}
    if not isinstance(encoding, str):
        raise TypeError(f"encoding: expected 'auto', 'linear' or 'srgb', got {type(encoding).__name__}")
    if isinstance(downscale, bool) or not isinstance(downscale, int):
        raise TypeError(f"downscale: expected a whole number, got {type(downscale).__name__}")
    return _core.load_dataset(_path(directory, "directory"), max_memory_gb, encoding=encoding,
                              crop=crop, downscale=downscale, **files)


load_dataset.__doc__ = _core.load_dataset.__doc__

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
    "estimate_normals",
    "height_to_mesh",
    "integrate",
    "load_dataset",
    "material",
    "material_presets",
    "materials",
    "normals_from_height",
    "render",
    "shade",
]
