#include "render/relight.h"

#include <cmath>
#include <stdexcept>

#include "core/parallel.h"
#include "reflectance/material.h"

namespace iphong::render {

std::string RelightInput::Validate() const {
  if (!normals_cam || !albedo) return "relighting needs normals and an albedo";
  const int w = normals_cam->width, h = normals_cam->height;
  if (normals_cam->channels != 3) return "normals need 3 channels (x, y, z)";
  if (albedo->width != w || albedo->height != h || albedo->channels != 3) {
    return "the albedo is " + SizeText(albedo->width, albedo->height) + "x" +
           std::to_string(albedo->channels) + ", the normals " + SizeText(w, h) + "x3";
  }
  if (specular && (specular->width != w || specular->height != h || specular->channels != 3)) {
    return "the specular map is " + SizeText(specular->width, specular->height) + ", the normals " +
           SizeText(w, h);
  }
  if (!ambient_term.allFinite() || (ambient_term.array() < 0).any()) {
    return "the ambient term must be finite and >= 0";
  }
  if (!ks.allFinite() || (ks.array() < 0).any()) return "ks must be finite and >= 0";
  if (!(shininess >= 0 && std::isfinite(shininess))) return "shininess must be finite and >= 0";
  if (!(specular_scale >= 0 && std::isfinite(specular_scale))) {
    return "the specular scale must be finite and >= 0";
  }
  if (!(exposure > 0 && std::isfinite(exposure))) return "exposure must be finite and > 0";
  // A pixel with a normal and a NaN albedo was left black without a word (a whole NaN map gave a
  // black image behind success).
  for (const auto& [map, name] :
       {std::pair{albedo, "albedo"}, std::pair{specular, "specular map"}}) {
    if (!map) continue;
    std::size_t bad = 0, first = 0;
    for (std::size_t p = 0; p < static_cast<std::size_t>(w) * h; ++p) {
      const float* n = normals_cam->pixels.data() + 3 * p;
      const float* v = map->pixels.data() + 3 * p;
      if (!(std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2])) ||
          (n[0] == 0 && n[1] == 0 && n[2] == 0)) {
        continue;
      }
      if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) continue;
      if (bad++ == 0) first = p;
    }
    if (bad > 0) {
      return std::string("the ") + name + " is not finite at " + std::to_string(bad) +
             " pixel(s) with a normal (the first at column " + std::to_string(first % w) +
             ", row " + std::to_string(first / w) + ")";
    }
  }
  if (lights.empty()) return "no light";
  for (const reflectance::Light& light : lights) {
    if (light.type != reflectance::LightType::kDirectional)
      return "relighting takes directional lights";
    if (std::string m = light.Validate(); !m.empty()) return m;
  }
  return "";
}

RelightCoverage LitPixels(const RelightInput& in) {
  RelightCoverage c;
  if (!in.normals_cam || in.normals_cam->channels != 3) return c;  // Validate says why
  for (std::size_t p = 0; p < in.normals_cam->pixel_count(); ++p) {
    const float* n = in.normals_cam->pixels.data() + 3 * p;
    const Vec3d normal(n[0], n[1], n[2]);
    if (!normal.allFinite() || normal.squaredNorm() == 0) continue;
    ++c.surface;
    for (const reflectance::Light& light : in.lights) {
      if (normal.dot(light.direction_cam) > 0) {
        ++c.lit;
        break;
      }
    }
  }
  return c;
}

std::string LightsBehindNote(const RelightInput& in) {
  const RelightCoverage c = LitPixels(in);
  if (c.surface == 0 || 100 * c.lit > c.surface) return "";
  const bool one = in.lights.size() == 1;
  return std::string(one ? "the light lights " : "the lights light ") + std::to_string(c.lit) +
         " of " + std::to_string(c.surface) + " pixels (N.L > 0): " + (one ? "it is" : "they are") +
         " behind the surface. A light direction points from the surface toward the light (x "
         "right, y up, z toward the camera)";
}

ImageF Relight(const RelightInput& in) {
  if (std::string m = in.Validate(); !m.empty()) throw std::invalid_argument(m);
  const int w = in.normals_cam->width, h = in.normals_cam->height;
  ImageF image(w, h, 3);
  reflectance::ModelOptions model;
  model.lobe = in.lobe;
  const Vec3d view(0, 0, 1);
  ParallelFor(0, static_cast<std::size_t>(h), 16, in.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t row = b; row < e; ++row)
      for (int col = 0; col < w; ++col) {
        const float* n = in.normals_cam->at(col, static_cast<int>(row));
        const float* kd = in.albedo->at(col, static_cast<int>(row));
        Vec3d normal(n[0], n[1], n[2]);
        const Vec3d albedo(kd[0], kd[1], kd[2]);
        if (!normal.allFinite() || normal.squaredNorm() == 0 || !albedo.allFinite()) continue;
        reflectance::Material material;
        material.kd = albedo;
        material.shininess = in.shininess;
        if (in.specular) {
          const float* ks = in.specular->at(col, static_cast<int>(row));
          material.ks = Vec3d(ks[0], ks[1], ks[2]);
          if (!material.ks.allFinite()) material.ks.setZero();
        } else {
          material.ks = in.ks;
        }
        material.ks *= in.specular_scale;
        normal.normalize();
        Vec3d value = in.ambient_term;
        for (const reflectance::Light& light : in.lights) {
          value += reflectance::LightTerm<double>(normal, view, light.direction_cam,
                                                  light.diffuse_intensity, light.specular_intensity,
                                                  material, model);
        }
        float* out = image.at(col, static_cast<int>(row));
        for (int c = 0; c < 3; ++c) out[c] = static_cast<float>(in.exposure * value[c]);
      }
  });
  return image;
}

}  // namespace iphong::render
