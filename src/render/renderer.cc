#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/shade.h"
#include "render/rasterizer.h"
#include "render/shadow_map_internal.h"

namespace iphong::render {
namespace {

using geometry::Camera;
using geometry::CameraType;
using internal::ShadowMap;
using reflectance::Light;
using reflectance::LightType;
using reflectance::Material;

void Require(const std::string& message) {
  if (!message.empty()) throw std::invalid_argument(message);
}

// Bilinear lookup with wrap-around, v = 0 at the texture's top row.
Vec3d SampleTexture(const ImageF& texture, double u, double v) {
  const double x = (u - std::floor(u)) * texture.width - 0.5;
  const double y = (v - std::floor(v)) * texture.height - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  auto texel = [&](int col, int row) {
    col = ((col % texture.width) + texture.width) % texture.width;
    row = ((row % texture.height) + texture.height) % texture.height;
    const float* p = texture.at(col, row);
    return texture.channels >= 3 ? Vec3d(p[0], p[1], p[2]) : Vec3d::Constant(p[0]);
  };
  return (1 - fy) * ((1 - fx) * texel(x0, y0) + fx * texel(x0 + 1, y0)) +
         fy * ((1 - fx) * texel(x0, y0 + 1) + fx * texel(x0 + 1, y0 + 1));
}

Vec3d Albedo(const SceneObject& object, double u, double v) {
  if (object.albedo_texture.pixels.empty()) return object.material.kd;
  return object.material.kd.cwiseProduct(SampleTexture(object.albedo_texture, u, v));
}

// Evaluates ambient + the selected lights (all, or only `only_light`) at one surface point. The
// per-pixel path runs the shared model in float (the image is float; it halves the cost of pow);
// vertex colours use double.
struct PointShader {
  const Scene& scene;
  const Camera& camera;  // the (supersampled) camera the pixels belong to
  const RenderOptions& options;
  const std::vector<std::optional<ShadowMap>>& shadows;
  // Per-light images: lighting j is the ambient and light j alone, so an image of one light
  // evaluates that light only (filtering by visibility alone computed every light's direction,
  // fall-off and LED factor at every pixel of every image). Empty without per-light images.
  std::vector<reflectance::Lighting> single_light;

  template <typename T = double>
  Vec3T<T> Shade(const SceneObject& object, const Vec3d& normal, const Vec3d& position,
                 const Vec3d& albedo, int only_light) const {
    reflectance::MaterialT<T> material = reflectance::CastMaterial<T>(object.material);
    return Shade<T>(material, normal, position, albedo, only_light);
  }

  // With the object's material, the normal, the albedo and the view already in T (the per-pixel
  // path converts the material once per object and reads the rest as the G-buffer stores them).
  template <typename T>
  Vec3T<T> Shade(reflectance::MaterialT<T> material, const Vec3T<T>& normal, const Vec3d& position,
                 const Vec3T<T>& albedo, const Vec3T<T>& view, int only_light) const {
    material.kd = albedo;
    const bool one = only_light >= 0;
    return reflectance::ShadeVisible<T>(
        normal, view, position.cast<T>(), material, one ? single_light[only_light] : scene.lighting,
        options.model, [&](std::size_t j, const Vec3T<T>& light_dir) {
          const std::size_t light = one ? static_cast<std::size_t>(only_light) : j;
          if (!shadows[light]) return true;
          const double n_dot_l =
              normal.template cast<double>().dot(light_dir.template cast<double>());
          return n_dot_l <= 0 || shadows[light]->Lit(position, n_dot_l);  // unlit: no term
        });
  }
  template <typename T>
  Vec3T<T> Shade(const reflectance::MaterialT<T>& material, const Vec3d& normal,
                 const Vec3d& position, const Vec3d& albedo, int only_light) const {
    return Shade<T>(material, normal.cast<T>().eval(), position, albedo.cast<T>().eval(),
                    camera.ViewDirection(position).cast<T>().eval(), only_light);
  }
  Vec3d operator()(const SceneObject& object, const Vec3d& normal, const Vec3d& position,
                   const Vec3d& albedo, int only_light) const {
    return Shade<double>(object, normal, position, albedo, only_light);
  }
};

// Per-corner colours for Gouraud (at each vertex) or flat (at each centroid) shading.
std::vector<Vec3f> CornerColors(const SceneObject& object, const PointShader& shade,
                                Shading shading, int only_light, int threads) {
  const auto& mesh = object.mesh;
  std::vector<Vec3f> colors(3 * mesh.triangles.size());
  ParallelFor(0, mesh.triangles.size(), 1024, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const auto& tri = mesh.triangles[t];
      auto uv = [&](int k) {
        return mesh.uvs.empty() ? Eigen::Vector2d::Zero().eval() : mesh.uvs[tri[k]];
      };
      if (shading == Shading::kFlat) {
        const Vec3d centroid =
            (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0;
        const Eigen::Vector2d c_uv = (uv(0) + uv(1) + uv(2)) / 3.0;
        const Vec3f color = shade(object, geometry::FaceNormal(mesh, t), centroid,
                                  Albedo(object, c_uv.x(), c_uv.y()), only_light)
                                .cast<float>();
        for (int k = 0; k < 3; ++k) colors[3 * t + k] = color;
      } else {
        for (int k = 0; k < 3; ++k) {
          colors[3 * t + k] = shade(object, mesh.corner_normals[3 * t + k], mesh.positions[tri[k]],
                                    Albedo(object, uv(k).x(), uv(k).y()), only_light)
                                  .cast<float>();
        }
      }
    }
  });
  return colors;
}

// Averages s×s blocks. For ground-truth buffers (`covered_only`) only covered samples count and
// the result is 0 where none is covered.
ImageF Downsample(const ImageF& fine, int s, const std::vector<int>* object_id, bool renormalize) {
  const int w = fine.width / s, h = fine.height / s, ch = fine.channels;
  ImageF coarse(w, h, ch);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      float* out = coarse.at(col, row);
      int count = 0;
      for (int dy = 0; dy < s; ++dy) {
        for (int dx = 0; dx < s; ++dx) {
          const int fc = col * s + dx, fr = row * s + dy;
          if (object_id && (*object_id)[static_cast<std::size_t>(fr) * fine.width + fc] < 0) {
            continue;
          }
          const float* in = fine.at(fc, fr);
          for (int c = 0; c < ch; ++c) out[c] += in[c];
          ++count;
        }
      }
      const float scale = object_id ? (count ? 1.0f / count : 0.0f) : 1.0f / (s * s);
      for (int c = 0; c < ch; ++c) out[c] *= scale;
      if (renormalize && count) {
        const float norm = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
        if (norm > 0)
          for (int c = 0; c < 3; ++c) out[c] /= norm;
      }
    }
  }
  return coarse;
}

}  // namespace

Shading ParseShading(const std::string& name) {
  if (name == "flat") return Shading::kFlat;
  if (name == "gouraud") return Shading::kGouraud;
  if (name == "phong") return Shading::kPhong;
  throw std::invalid_argument("unknown shading '" + name + "' (expected flat, gouraud or phong)");
}

std::string ShadingName(Shading shading) {
  switch (shading) {
    case Shading::kFlat:
      return "flat";
    case Shading::kGouraud:
      return "gouraud";
    case Shading::kPhong:
      return "phong";
  }
  return "phong";
}

std::string Scene::Validate() const {
  if (auto m = camera.Validate(); !m.empty()) return m;
  if (auto m = lighting.Validate(); !m.empty()) return m;
  if (objects.empty()) return "the scene has no objects";
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const std::string where = "object " + std::to_string(i) +
                              (objects[i].name.empty() ? "" : " (" + objects[i].name + ")") + ": ";
    if (auto m = objects[i].mesh.Validate(); !m.empty()) return where + m;
    if (objects[i].mesh.corner_normals.size() != 3 * objects[i].mesh.triangles.size()) {
      return where + "mesh has no normals";
    }
    if (auto m = reflectance::ValidateMaterial(objects[i].material); !m.empty()) return where + m;
    const ImageF& tex = objects[i].albedo_texture;
    if (!tex.pixels.empty() && (tex.width <= 0 || tex.height <= 0 || tex.channels <= 0)) {
      return where + "empty albedo texture";
    }
    if (!tex.pixels.empty() && objects[i].mesh.uvs.empty()) {
      return where + "an albedo texture needs uv coordinates on the mesh";
    }
  }
  return "";
}

std::string NoiseOptions::Validate() const {
  if (!std::isfinite(gaussian_sigma) || gaussian_sigma < 0) return "noise sigma must be >= 0";
  if (!std::isfinite(shot_photons) || shot_photons < 0) return "shot-noise photons must be >= 0";
  if (quantization_bits < 0 || quantization_bits > 24) return "quantization bits must be in 0..24";
  return "";
}

std::string RenderOptions::Validate() const {
  if (supersampling < 1 || supersampling > 8) return "supersampling must be in 1..8";
  if (shadow_map_size < 16 || shadow_map_size > 16384) {
    return "shadow map size must be in 16..16384";
  }
  if (!std::isfinite(shadow_bias_texels) || shadow_bias_texels < 0) {
    return "shadow bias must be >= 0";
  }
  if (auto m = reflectance::ValidateModelOptions(model); !m.empty()) return m;
  return noise.Validate();
}

void ApplyNoise(ImageF& image, const NoiseOptions& options, std::uint64_t index) {
  if (!options.enabled()) return;
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ull + index);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const double levels =
      options.quantization_bits > 0 ? std::ldexp(1.0, options.quantization_bits) - 1.0 : 0.0;
  for (float& value : image.pixels) {
    double v = value;
    if (options.shot_photons > 0 && v > 0) {
      std::poisson_distribution<long long> photons(v * options.shot_photons);
      v = photons(rng) / options.shot_photons;
    }
    if (options.gaussian_sigma > 0) v += options.gaussian_sigma * gaussian(rng);
    if (levels > 0) v = std::round(std::clamp(v, 0.0, 1.0) * levels) / levels;
    value = static_cast<float>(v);
  }
}

double EstimateRenderBytes(const Scene& scene, const RenderOptions& options, bool per_light) {
  const double s = options.supersampling;
  const double pixels = static_cast<double>(scene.camera.width) * scene.camera.height;
  const double samples = pixels * s * s;
  const double images = 1.0 + (per_light ? scene.lighting.lights.size() : 0);
  // G-buffer (depth, id, normal, uv, colour, coverage) ≈ 44 bytes, albedo and depth 16, and each
  // image 12, per sample; the same again per output pixel after downsampling; mask and ids.
  const double shadow_texels = options.shadows
                                   ? static_cast<double>(options.shadow_map_size) *
                                         options.shadow_map_size * scene.lighting.lights.size()
                                   : 0.0;
  return samples * (60 + 12 * images) + pixels * (36 + 12 * images) + 4 * shadow_texels;
}

namespace {

// "rendering 64x64 with 2x2 supersampling and 12 per-light images with 12 2048x2048 shadow maps"
std::string DescribeRender(const Scene& scene, const RenderOptions& options, bool per_light) {
  const std::string lights = std::to_string(scene.lighting.lights.size());
  std::string text = "rendering " + SizeText(scene.camera.width, scene.camera.height);
  if (options.supersampling > 1)
    text += " with " + SizeText(options.supersampling, options.supersampling) + " supersampling";
  if (per_light) text += " and " + lights + " per-light images";
  if (options.shadows)
    text += " with " + lights + " " + SizeText(options.shadow_map_size, options.shadow_map_size) +
            " shadow maps";
  return text;
}

}  // namespace

RenderOutput Render(const Scene& scene, const RenderOptions& options, bool per_light) {
  Require(scene.Validate());
  Require(options.Validate());
  RequireMemory(options.memory, EstimateRenderBytes(scene, options, per_light),
                DescribeRender(scene, options, per_light));
  const int s = options.supersampling;
  Camera camera = scene.camera;
  camera.width *= s;
  camera.height *= s;
  camera.fx *= s;
  camera.fy *= s;
  camera.cx *= s;
  camera.cy *= s;

  std::vector<RasterItem> items;
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    items.push_back({&scene.objects[i].mesh, static_cast<int>(i), nullptr});
    for (const Vec3d& p : scene.objects[i].mesh.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const Vec3d center = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 1e-9);

  const auto raster_start = Clock::now();
  std::vector<std::optional<ShadowMap>> shadows(scene.lighting.lights.size());
  if (options.shadows) {
    for (std::size_t j = 0; j < shadows.size(); ++j) {
      shadows[j].emplace(scene.lighting.lights[j], items, center, radius, options);
    }
  }
  RasterOptions raster;
  raster.renormalize_normals = options.renormalize_normals;
  raster.cull_back_faces = !options.two_sided;
  raster.interpolate_uv =
      std::any_of(scene.objects.begin(), scene.objects.end(),
                  [](const SceneObject& o) { return !o.albedo_texture.pixels.empty(); });
  raster.threads = options.threads;
  GBuffer gbuffer = internal::RasterizeValidatedMeshes(items, camera, raster);
  double raster_seconds = SecondsSince(raster_start);

  const auto shade_start = Clock::now();
  PointShader shade{scene, camera, options, shadows, {}};
  if (per_light) {
    for (const reflectance::Light& light : scene.lighting.lights) {
      shade.single_light.push_back({scene.lighting.ambient, {light}});
    }
  }
  std::vector<reflectance::MaterialT<float>> materials_f;
  for (const SceneObject& object : scene.objects) {
    materials_f.push_back(reflectance::CastMaterial<float>(object.material));
  }
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  const int lights = static_cast<int>(scene.lighting.lights.size());

  // Positions are reconstructed from depth only where something depends on them.
  const bool need_position =
      camera.type == CameraType::kPerspective || options.shadows || scene.lighting.HasPointLights();
  const bool orthographic = camera.type == CameraType::kOrthographic;
  const Vec3f view_f = camera.view_cam().cast<float>();  // the one view of an orthographic camera
  auto position_at = [&](std::size_t p) {
    return need_position ? gbuffer.Position(camera, p) : Vec3d::Zero().eval();
  };

  // Ground truth at full (supersampled) resolution.
  ImageF albedo(camera.width, camera.height, 3), depth(camera.width, camera.height, 1);
  ParallelFor(0, pixels, 8192, options.threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) {
      if (!gbuffer.covered(p)) continue;
      const bool has_uv = !gbuffer.uv.pixels.empty();
      const Vec3d a =
          Albedo(scene.objects[gbuffer.object_id[p]], has_uv ? gbuffer.uv.pixels[2 * p] : 0.0,
                 has_uv ? gbuffer.uv.pixels[2 * p + 1] : 0.0);
      for (int c = 0; c < 3; ++c) albedo.pixels[3 * p + c] = static_cast<float>(a[c]);
      depth.pixels[p] = gbuffer.depth[p];
    }
  });

  // One image per requested light set: −1 = all lights, j = light j alone.
  std::vector<int> light_sets = {-1};
  if (per_light)
    for (int j = 0; j < lights; ++j) light_sets.push_back(j);
  std::vector<ImageF> images;
  const double steps = light_sets.size() + 1.0;  // the first step: raster and shadow maps
  if (options.progress) options.progress(1 / steps);
  for (int only_light : light_sets) {
    ImageF image(camera.width, camera.height, 3);
    if (options.shading == Shading::kPhong) {
      ParallelFor(0, pixels, 4096, options.threads, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
          if (!gbuffer.covered(p)) continue;
          const Vec3d position = position_at(p);
          const Vec3f color = shade.Shade<float>(
              materials_f[gbuffer.object_id[p]],
              Eigen::Map<const Vec3f>(gbuffer.normal_cam.pixels.data() + 3 * p), position,
              Eigen::Map<const Vec3f>(albedo.pixels.data() + 3 * p),
              orthographic ? view_f : camera.ViewDirection(position).cast<float>().eval(),
              only_light);
          for (int c = 0; c < 3; ++c) image.pixels[3 * p + c] = color[c];
        }
      });
    } else {
      // Gouraud and flat: colours at the corners, interpolated by the rasterizer.
      std::vector<std::vector<Vec3f>> colors(scene.objects.size());
      std::vector<RasterItem> colored = items;
      for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        colors[i] =
            CornerColors(scene.objects[i], shade, options.shading, only_light, options.threads);
        colored[i].corner_colors = &colors[i];
      }
      const auto t0 = Clock::now();
      const GBuffer colored_buffer = internal::RasterizeValidatedMeshes(colored, camera, raster);
      raster_seconds += SecondsSince(t0);
      for (std::size_t p = 0; p < pixels; ++p) {
        if (!colored_buffer.covered(p)) continue;
        for (int c = 0; c < 3; ++c)
          image.pixels[3 * p + c] = colored_buffer.color.pixels[3 * p + c];
      }
    }
    images.push_back(std::move(image));
    if (options.progress) options.progress((images.size() + 1) / steps);
  }

  RenderOutput out;
  const auto* ids = &gbuffer.object_id;
  const bool fine = s > 1;
  for (std::size_t k = 0; k < images.size(); ++k) {
    ImageF image = fine ? Downsample(images[k], s, nullptr, false) : std::move(images[k]);
    ApplyNoise(image, options.noise, k);
    // Each value is valid alone, but their products (intensity x coefficient, noise) can pass
    // float's range: said here, as the scene's, not as an image a writer refuses.
    std::size_t bad = 0, first = 0;
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      const float* v = image.pixels.data() + image.channels * p;
      if (std::all_of(v, v + image.channels, [](float x) { return std::isfinite(x); })) continue;
      if (bad++ == 0) first = p;
    }
    if (bad > 0) {
      throw std::invalid_argument(
          std::string(k == 0 ? "the image" : "light " + std::to_string(k) + "'s image") +
          " overflows float at " + std::to_string(bad) + " pixel(s) (the first at column " +
          std::to_string(first % image.width) + ", row " + std::to_string(first / image.width) +
          "): light intensities, ambient, coefficients or noise too large together");
    }
    if (k == 0) {
      out.image = std::move(image);
    } else {
      out.per_light.push_back(std::move(image));
    }
  }
  out.normal_cam =
      fine ? Downsample(gbuffer.normal_cam, s, ids, true) : std::move(gbuffer.normal_cam);
  out.albedo = fine ? Downsample(albedo, s, ids, false) : std::move(albedo);
  out.depth = fine ? Downsample(depth, s, ids, false) : std::move(depth);
  out.mask = Mask(scene.camera.width, scene.camera.height, false);
  for (int row = 0; row < scene.camera.height; ++row) {
    for (int col = 0; col < scene.camera.width; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * scene.camera.width + col;
      if (fine) {
        int covered = 0;
        for (int dy = 0; dy < s; ++dy)
          for (int dx = 0; dx < s; ++dx)
            covered += gbuffer.covered(static_cast<std::size_t>(row * s + dy) * camera.width +
                                       col * s + dx);
        out.mask.inside[p] = 2 * covered > s * s;
      } else {
        out.mask.inside[p] = gbuffer.covered(p);
      }
      if (!out.mask.inside[p]) {  // ground truth is 0 outside the mask
        for (int c = 0; c < 3; ++c)
          out.normal_cam.pixels[3 * p + c] = out.albedo.pixels[3 * p + c] = 0;
        out.depth.pixels[p] = 0;
      }
    }
  }
  out.raster_seconds = raster_seconds;
  out.shade_seconds = SecondsSince(shade_start);
  return out;
}

std::string NothingVisibleReason(const Scene& scene, const RenderOptions& options) {
  // Faces seen from behind are culled: a mesh wound clockwise as the camera sees it is in view
  // but hidden, which the scene's positions do not explain. One pass drawing both sides tells.
  RenderOptions both = options;
  both.two_sided = true;
  both.progress = nullptr;
  if (Render(scene, both, false).mask.count() > 0) {
    return "every face in the camera's view is seen from behind (a mesh whose faces are wound "
           "clockwise as the camera sees them, or an object turned away: flip the mesh's faces "
           "or turn it)";
  }
  bool flat = true;  // every face has no area: its corners on a line
  for (const SceneObject& object : scene.objects) {
    for (std::size_t t = 0; t < object.mesh.triangle_count() && flat; ++t) {
      flat = geometry::FaceNormal(object.mesh, t).isZero();
    }
  }
  return flat ? "every face of the objects has no area (its corners on a line): check the meshes"
              : "every object is outside the camera's view (check the camera and the objects' "
                "positions and sizes)";
}

}  // namespace iphong::render
