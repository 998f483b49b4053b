// The relighting viewer: one self-contained HTML page (no server, no network; the maps embedded
// as PNG data) where dragging the mouse moves the light and a WebGL shader shades the capture
// with the Phong model of render/relight.h, exposure and specular strength as sliders.
//
// The shader is the model's one allowed second spelling (GLSL); tests/cli/test_cli_relight.py
// keeps it equal to `iphong relight` by rendering the page in headless chromium.
// The URL fragment sets the state: page.html#light=x,y,z&exposure=e&specular=s&ui=0 (ui=0 hides
// the controls, for screenshots).
#pragma once

#include <string>

#include "render/relight.h"

namespace iphong::io {

// The page for `input` (its lights: the first one's direction and intensity start the view;
// exposure and specular_scale start the sliders). The maps are quantized to 8 bits: normals as
// (n + 1)/2, kd and ks as sRGB codes of their value over their maximum. Throws
// std::invalid_argument for invalid input.
std::string ViewerPage(const render::RelightInput& input, const std::string& title);

}  // namespace iphong::io
