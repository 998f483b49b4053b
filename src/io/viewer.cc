#include "io/viewer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "io/image_io.h"
#include "reflectance/material.h"

namespace iphong::io {
namespace {

// Base64 (RFC 4648) for the data URLs; OpenCV has none public and it is eight lines.
std::string Base64(const std::vector<unsigned char>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0) |
                       (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

std::string PngDataUrl(const cv::Mat& bgra) {
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", bgra, png)) throw std::runtime_error("viewer: PNG encoding failed");
  return "data:image/png;base64," + Base64(png);
}

unsigned char Code(double v) {
  return static_cast<unsigned char>(std::clamp(v, 0.0, 1.0) * 255 + 0.5);
}

// The largest finite channel value of a colour map where there is a surface (at least 1e-6).
double MapScale(const ImageF& map, const ImageF& normals) {
  double top = 1e-6;
  for (std::size_t p = 0; p < map.pixel_count(); ++p) {
    const float* n = normals.pixels.data() + 3 * p;
    if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;
    for (int c = 0; c < 3; ++c) {
      const float v = map.pixels[3 * p + c];
      if (std::isfinite(v)) top = std::max(top, static_cast<double>(v));
    }
  }
  return top;
}

// A colour map as sRGB codes of value / scale, alpha 255 (OpenCV's BGRA order).
cv::Mat ColourCodes(const ImageF& map, double scale) {
  cv::Mat m(map.height, map.width, CV_8UC4);
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) {
      const float* v = map.at(x, y);
      cv::Vec4b& o = m.at<cv::Vec4b>(y, x);
      for (int c = 0; c < 3; ++c) {
        const double value = std::isfinite(v[c]) ? v[c] / scale : 0.0;
        o[2 - c] = Code(LinearToSrgb(static_cast<float>(std::max(0.0, value))));
      }
      o[3] = 255;
    }
  return m;
}

std::string Replace(std::string text, const std::string& key, const std::string& value) {
  for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at)) {
    text.replace(at, key.size(), value);
    at += value.size();
  }
  return text;
}

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

std::string Vec(const Vec3d& v) {
  return "[" + Number(v[0]) + "," + Number(v[1]) + "," + Number(v[2]) + "]";
}

// The page. The fragment shader is render::Relight's formula, per pixel of the canvas (one
// texel each, NEAREST), with seed 003's rules: the diffuse term where N·L > 0, the lobe only
// there and where its cosine is positive.
constexpr const char* kPage = R"html(<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>@TITLE@ - iphong relight</title>
<style>
body{margin:0;background:#111;color:#ddd;font:14px sans-serif}
canvas{display:block;cursor:crosshair;touch-action:none}
#ui{padding:8px 10px}#ui label{margin-right:18px}#ui input{vertical-align:middle}
</style></head><body>
<canvas id="view" width="@W@" height="@H@"></canvas>
<div id="ui">
<div>@TITLE@: drag on the image to move the light. L = <span id="light"></span></div>
<label>exposure <input id="exposure" type="range" step="0.01"> <span id="exposure_value"></span></label>
<label>specular <input id="specular" type="range" min="0" max="3" step="0.01"> <span id="specular_value"></span></label>
<div>Model @MODEL@, shininess @SHININESS_TEXT@; the shading is iphong's Phong model (render/relight.h) in a WebGL shader. Made by iphong relight --viewer.</div>
</div>
<script>
"use strict";
const W = @W@, H = @H@;
const state = {light: @LIGHT@, exposure: @EXPOSURE@, specular: @SPECULAR@};
const fragment = `
precision highp float;
uniform sampler2D normals, albedo, specmap;
uniform vec2 size;
uniform vec3 light, intensity, ambient, ks;
uniform float shininess, albedoScale, specScale, specular, exposure;
uniform int lobe;          // 0 Phong, 1 Blinn-Phong, 2 Lambert, 3 normal-centred, 4 Oren-Nayar
uniform bool useSpecMap;
float decode(float c) { return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4); }
vec3 decode3(vec3 c) { return vec3(decode(c.r), decode(c.g), decode(c.b)); }
float encode(float v) {
  v = clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
void main() {
  vec2 uv = vec2(gl_FragCoord.x / size.x, 1.0 - gl_FragCoord.y / size.y);
  vec4 n = texture2D(normals, uv);
  if (n.a < 0.5) { gl_FragColor = vec4(0.0, 0.0, 0.0, 1.0); return; }
  vec3 N = normalize(n.rgb * 2.0 - 1.0);
  vec3 kd = decode3(texture2D(albedo, uv).rgb) * albedoScale;
  vec3 k = (useSpecMap ? decode3(texture2D(specmap, uv).rgb) * specScale : ks) * specular;
  vec3 L = normalize(light), V = vec3(0.0, 0.0, 1.0);
  vec3 c = ambient;
  float ndl = dot(N, L);
  if (ndl > 0.0) {
    float s = 0.0, d = ndl;
    if (lobe == 0) {
      float rv = dot(2.0 * ndl * N - L, V);
      if (rv > 0.0) s = pow(rv, shininess);
    } else if (lobe == 1) {
      float nh = dot(N, normalize(L + V));
      if (nh > 0.0) s = pow(nh, shininess);
    } else if (lobe == 3) {
      s = pow(ndl, shininess);
    } else if (lobe == 4) {
      // reflectance::OrenNayarDiffuse, the facets' slope in the shininess' place.
      float ndv = dot(N, V), s2 = shininess * shininess;
      float spread = max(0.0, dot(L, V) - ndl * ndv);
      d = ndv > 0.0 ? ndl * (1.0 - 0.5 * s2 / (s2 + 0.33) +
                             0.45 * s2 / (s2 + 0.09) * spread / max(ndl, ndv)) : 0.0;
    }
    c += intensity * (kd * d + k * s);
  }
  c *= exposure;
  gl_FragColor = vec4(encode(c.r), encode(c.g), encode(c.b), 1.0);
}`;
const vertex = `attribute vec2 p; void main() { gl_Position = vec4(p, 0.0, 1.0); }`;
const canvas = document.getElementById("view");
const gl = canvas.getContext("webgl", {preserveDrawingBuffer: true, antialias: false});
function compile(type, text) {
  const s = gl.createShader(type);
  gl.shaderSource(s, text);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
  return s;
}
const program = gl.createProgram();
gl.attachShader(program, compile(gl.VERTEX_SHADER, vertex));
gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fragment));
gl.linkProgram(program);
gl.useProgram(program);
const buffer = gl.createBuffer();
gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
const where = gl.getAttribLocation(program, "p");
gl.enableVertexAttribArray(where);
gl.vertexAttribPointer(where, 2, gl.FLOAT, false, 0, 0);
const u = name => gl.getUniformLocation(program, name);
gl.uniform2f(u("size"), W, H);
gl.uniform3fv(u("intensity"), @INTENSITY@);
gl.uniform3fv(u("ambient"), @AMBIENT@);
gl.uniform3fv(u("ks"), @KS@);
gl.uniform1f(u("shininess"), @SHININESS@);
gl.uniform1f(u("albedoScale"), @ALBEDO_SCALE@);
gl.uniform1f(u("specScale"), @SPEC_SCALE@);
gl.uniform1i(u("lobe"), @LOBE@);
gl.uniform1i(u("useSpecMap"), @USE_SPEC_MAP@);
function texture(unit, url, name) {
  return new Promise(resolve => {
    const image = new Image();
    image.onload = () => {
      const t = gl.createTexture();
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(gl.TEXTURE_2D, t);
      // The codes as stored: no colour management, no premultiplication.
      gl.pixelStorei(gl.UNPACK_COLORSPACE_CONVERSION_WEBGL, gl.NONE);
      gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, false);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, image);
      for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
      for (const p of [gl.TEXTURE_WRAP_S, gl.TEXTURE_WRAP_T]) gl.texParameteri(gl.TEXTURE_2D, p, gl.CLAMP_TO_EDGE);
      gl.uniform1i(u(name), unit);
      resolve();
    };
    image.src = url;
  });
}
function draw() {
  const l = state.light, n = Math.hypot(l[0], l[1], l[2]) || 1;
  gl.uniform3f(u("light"), l[0] / n, l[1] / n, l[2] / n);
  gl.uniform1f(u("exposure"), state.exposure);
  gl.uniform1f(u("specular"), state.specular);
  gl.viewport(0, 0, W, H);
  gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
  document.getElementById("light").textContent = l.map(v => (v / n).toFixed(3)).join(", ");
  document.getElementById("exposure_value").textContent = state.exposure.toFixed(2);
  document.getElementById("specular_value").textContent = state.specular.toFixed(2);
}
for (const part of location.hash.slice(1).split("&")) {
  const [key, value] = part.split("=");
  if (key === "light") state.light = value.split(",").map(Number);
  if (key === "exposure") state.exposure = Number(value);
  if (key === "specular") state.specular = Number(value);
  if (key === "ui" && value === "0") document.getElementById("ui").style.display = "none";
}
const exposure = document.getElementById("exposure"), specular = document.getElementById("specular");
exposure.min = Math.log(state.exposure) - 3;
exposure.max = Math.log(state.exposure) + 3;
exposure.value = Math.log(state.exposure);
specular.value = state.specular;
exposure.oninput = () => { state.exposure = Math.exp(Number(exposure.value)); draw(); };
specular.oninput = () => { state.specular = Number(specular.value); draw(); };
let dragging = false;
function move(event) {
  const r = canvas.getBoundingClientRect();
  let x = (event.clientX - r.left) / r.width * 2 - 1, y = 1 - (event.clientY - r.top) / r.height * 2;
  const d = Math.hypot(x, y);
  if (d > 1) { x /= d; y /= d; }
  state.light = [x, y, Math.sqrt(Math.max(0, 1 - x * x - y * y))];
  draw();
}
canvas.onpointerdown = e => { dragging = true; canvas.setPointerCapture(e.pointerId); move(e); };
canvas.onpointermove = e => { if (dragging) move(e); };
canvas.onpointerup = () => { dragging = false; };
Promise.all([texture(0, "@NORMALS@", "normals"), texture(1, "@ALBEDO@", "albedo"),
             texture(2, "@SPECMAP@", "specmap")]).then(() => { draw(); document.title += " (ready)"; });
</script></body></html>
)html";

}  // namespace

std::string ViewerPage(const render::RelightInput& input, const std::string& title) {
  if (std::string m = input.Validate(); !m.empty()) throw std::invalid_argument(m);
  const ImageF& normals = *input.normals_cam;
  const int w = normals.width, h = normals.height;
  cv::Mat normal_codes(h, w, CV_8UC4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* n = normals.at(x, y);
      Vec3d v(n[0], n[1], n[2]);
      const bool surface = v.allFinite() && v.squaredNorm() > 0 &&
                           input.albedo->at(x, y)[0] == input.albedo->at(x, y)[0];
      if (surface) v.normalize();
      cv::Vec4b& o = normal_codes.at<cv::Vec4b>(y, x);
      for (int c = 0; c < 3; ++c) o[2 - c] = surface ? Code((v[c] + 1) / 2) : 0;
      o[3] = surface ? 255 : 0;
    }
  const double albedo_scale = MapScale(*input.albedo, normals);
  const double spec_scale = input.specular ? MapScale(*input.specular, normals) : 1.0;
  const ImageF blank(1, 1, 3);
  const reflectance::Light& light = input.lights.front();
  std::string page = kPage;
  page = Replace(page, "@NORMALS@", PngDataUrl(normal_codes));
  page = Replace(page, "@ALBEDO@", PngDataUrl(ColourCodes(*input.albedo, albedo_scale)));
  page = Replace(page, "@SPECMAP@",
                 PngDataUrl(ColourCodes(input.specular ? *input.specular : blank, spec_scale)));
  std::string safe_title;
  for (char c : title) safe_title += (c == '<' || c == '>' || c == '&' || c == '"') ? '_' : c;
  page = Replace(page, "@TITLE@", safe_title);
  page = Replace(page, "@W@", std::to_string(w));
  page = Replace(page, "@H@", std::to_string(h));
  page = Replace(page, "@LIGHT@", Vec(light.direction_cam));
  page = Replace(page, "@INTENSITY@", Vec(light.diffuse_intensity));
  page = Replace(page, "@EXPOSURE@", Number(input.exposure));
  page = Replace(page, "@SPECULAR@", Number(input.specular_scale));
  page = Replace(page, "@AMBIENT@", Vec(input.ambient_term));
  page = Replace(page, "@KS@", Vec(input.ks));
  page = Replace(page, "@SHININESS@", Number(input.shininess));
  char shininess_text[32];
  std::snprintf(shininess_text, sizeof shininess_text, "%.3g", input.shininess);
  page = Replace(page, "@SHININESS_TEXT@", shininess_text);
  page = Replace(page, "@ALBEDO_SCALE@", Number(albedo_scale));
  page = Replace(page, "@SPEC_SCALE@", Number(spec_scale));
  page = Replace(page, "@LOBE@",
                 input.lobe == reflectance::Lobe::kPhong        ? "0"
                 : input.lobe == reflectance::Lobe::kBlinnPhong ? "1"
                 : input.lobe == reflectance::Lobe::kLambert    ? "2"
                 : input.lobe == reflectance::Lobe::kOrenNayar  ? "4"
                                                                : "3");
  page = Replace(page, "@MODEL@", reflectance::LobeName(input.lobe));
  page = Replace(page, "@USE_SPEC_MAP@", input.specular ? "true" : "false");
  return page;
}

}  // namespace iphong::io
