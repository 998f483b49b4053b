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
    shade,
)

#: Every named material preset, by name (seed 000's Phong table and seed 004's tutorial table).
materials = {preset.name: preset.material for preset in material_presets()}

__all__ = [
    "DirectionalLight",
    "Light",
    "LightType",
    "Material",
    "MaterialPreset",
    "PointLight",
    "material",
    "material_presets",
    "materials",
    "shade",
]
