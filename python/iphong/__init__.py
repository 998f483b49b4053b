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


def render(scene, per_light=False):
    """Render a scene (a dict in the scene-file format, or the path of a scene JSON file).

    Returns a dict of numpy arrays, nothing written to disk: image (H, W, 3) float32 linear with
    all lights, images (K, H, W, 3) one per light when per_light, normals (H, W, 3) ground truth
    (0 outside the mask), depth (H, W), albedo (H, W, 3), mask (H, W) bool, light_directions (K, 3)
    and light_intensities (K, 3). Relative paths in a dict resolve against the working directory.
    Raises ValueError naming the field on a bad scene.
    """
    if isinstance(scene, dict):
        return _core._render_json(_json.dumps(scene), "scene", _os.getcwd(), per_light)
    return _core._render_file(_os.fspath(scene), per_light)


def load_dataset(directory):
    """Read a dataset directory (DiLiGenT layout) into numpy arrays; see _core.load_dataset."""
    return _core.load_dataset(_os.fspath(directory))


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
