#include "render/rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/parallel.h"

namespace iphong::render {
namespace {

// Interpolated per vertex, each divided by w (w = depth under perspective, 1 orthographic):
// [0] 1/w, [1] depth/w, [2..4] normal, [5..7] position, [8..9] uv, [10..12] colour.
constexpr int kAttrs = 13;
using Attrs = std::array<double, kAttrs>;

struct TriangleRef {
  int item;
  int triangle;
};

struct ActiveEdge {
  int slot;      // which triangle of the band
  int last_row;  // inclusive
  double x, dxdy;
  Attrs a, da;  // at the current scan line, and the step per scan line (seed 001, stage 1)
};

struct Vertex {
  double x, y;  // screen
  Attrs a;
};

// The rows whose pixel centres (row + 0.5) fall in [y_top, y_bottom): top edge in, bottom out.
inline int FirstRow(double y) { return static_cast<int>(std::ceil(y - 0.5)); }

class BandRasterizer {
 public:
  BandRasterizer(const std::vector<RasterItem>& items,
                 const std::vector<std::vector<Vec3d>>& screen, const geometry::Camera& camera,
                 const RasterOptions& options, GBuffer& out)
      : items_(items),
        screen_(screen),
        camera_(camera),
        options_(options),
        out_(out),
        attrs_(options.depth_only ? 2 : kAttrs) {}

  void Run(int row_begin, int row_end, const std::vector<TriangleRef>& triangles) {
    // Edge table: every edge of the band's triangles, bucketed by its first scan line here.
    edge_table_.assign(row_end - row_begin, {});
    for (std::size_t slot = 0; slot < triangles.size(); ++slot) {
      AddTriangleEdges(static_cast<int>(slot), triangles[slot], row_begin, row_end);
    }
    active_.clear();
    for (int row = row_begin; row < row_end; ++row) {
      auto& starting = edge_table_[row - row_begin];
      active_.insert(active_.end(), starting.begin(), starting.end());
      // A triangle has exactly two active edges on a scan line it covers: pair them into a span.
      std::sort(active_.begin(), active_.end(), [](const ActiveEdge& a, const ActiveEdge& b) {
        return a.slot != b.slot ? a.slot < b.slot : a.x < b.x;
      });
      for (std::size_t i = 0; i + 1 < active_.size();) {
        if (active_[i].slot != active_[i + 1].slot) {
          ++i;
          continue;
        }
        FillSpan(row, triangles[active_[i].slot], active_[i], active_[i + 1]);
        i += 2;
      }
      // Step the survivors to the next scan line (stage 1 increments).
      std::size_t kept = 0;
      for (ActiveEdge& e : active_) {
        if (e.last_row <= row) continue;
        e.x += e.dxdy;
        for (int k = 0; k < attrs_; ++k) e.a[k] += e.da[k];
        active_[kept++] = e;
      }
      active_.resize(kept);
    }
  }

 private:
  void AddTriangleEdges(int slot, const TriangleRef& ref, int row_begin, int row_end) {
    const RasterItem& item = items_[ref.item];
    const auto& mesh = *item.mesh;
    const auto& tri = mesh.triangles[ref.triangle];
    std::array<Vertex, 3> v;
    for (int k = 0; k < 3; ++k) {
      const Vec3d& s = screen_[ref.item][tri[k]];
      const double inv_w = camera_.type == geometry::CameraType::kPerspective ? 1.0 / s.z() : 1.0;
      v[k].x = s.x();
      v[k].y = s.y();
      Attrs& a = v[k].a;
      a[0] = inv_w;
      a[1] = s.z() * inv_w;
      if (options_.depth_only) continue;
      const Vec3d& n = mesh.corner_normals[3 * ref.triangle + k];
      const Vec3d& p = mesh.positions[tri[k]];
      for (int c = 0; c < 3; ++c) {
        a[2 + c] = n[c] * inv_w;
        a[5 + c] = p[c] * inv_w;
      }
      const Eigen::Vector2d uv = mesh.uvs.empty() ? Eigen::Vector2d::Zero() : mesh.uvs[tri[k]];
      a[8] = uv.x() * inv_w;
      a[9] = uv.y() * inv_w;
      const Vec3f color =
          item.corner_colors ? (*item.corner_colors)[3 * ref.triangle + k] : Vec3f::Zero();
      for (int c = 0; c < 3; ++c) a[10 + c] = color[c] * inv_w;
    }
    for (int e = 0; e < 3; ++e) {
      const Vertex* top = &v[e];
      const Vertex* bottom = &v[(e + 1) % 3];
      if (top->y == bottom->y) continue;  // horizontal edges cover no scan line
      if (top->y > bottom->y) std::swap(top, bottom);
      // Clamped before rounding so far off-screen vertices cannot overflow an int.
      const int first = std::max(FirstRow(std::max(top->y, row_begin - 1.0)), row_begin);
      const int last = std::min(FirstRow(std::min(bottom->y, row_end + 1.0)) - 1, row_end - 1);
      if (first > last) continue;
      ActiveEdge edge;
      edge.slot = slot;
      edge.last_row = last;
      const double inv_dy = 1.0 / (bottom->y - top->y);
      const double t = first + 0.5 - top->y;
      edge.dxdy = (bottom->x - top->x) * inv_dy;
      edge.x = top->x + t * edge.dxdy;
      for (int k = 0; k < attrs_; ++k) {
        edge.da[k] = (bottom->a[k] - top->a[k]) * inv_dy;
        edge.a[k] = top->a[k] + t * edge.da[k];
      }
      edge_table_[first - row_begin].push_back(edge);
    }
  }

  // Seed 001, stage 2: constant attribute steps along the span, one pixel at a time.
  void FillSpan(int row, const TriangleRef& ref, const ActiveEdge& left, const ActiveEdge& right) {
    const double width = right.x - left.x;
    if (!(width > 0)) return;
    const int c0 = std::max(0, static_cast<int>(std::ceil(std::max(left.x - 0.5, -1.0))));
    const int c1 =
        std::min(out_.width - 1, static_cast<int>(std::ceil(std::min(right.x - 0.5, 1e9))) - 1);
    if (c0 > c1) return;
    Attrs a, da;
    const double t = c0 + 0.5 - left.x;
    for (int k = 0; k < attrs_; ++k) {
      da[k] = (right.a[k] - left.a[k]) / width;
      a[k] = left.a[k] + t * da[k];
    }
    const int object = items_[ref.item].object_id;
    const bool has_color = items_[ref.item].corner_colors != nullptr;
    std::size_t pixel = static_cast<std::size_t>(row) * out_.width + c0;
    for (int col = c0; col <= c1; ++col, ++pixel) {
      if (options_.count_fragments) ++out_.fragments[pixel];
      const double w = 1.0 / a[0];
      const double depth = a[1] * w;
      if (depth < out_.depth[pixel]) {
        out_.depth[pixel] = static_cast<float>(depth);
        out_.object_id[pixel] = object;
        out_.triangle[pixel] = ref.triangle;
        if (!options_.depth_only) WriteAttributes(pixel, a, w, has_color);
      }
      for (int k = 0; k < attrs_; ++k) a[k] += da[k];
    }
  }

  void WriteAttributes(std::size_t pixel, const Attrs& a, double w, bool has_color) {
    Vec3d n(a[2] * w, a[3] * w, a[4] * w);
    if (options_.renormalize_normals) {
      const double norm = n.norm();
      if (norm > 0) n /= norm;
    }
    float* normal = out_.normal_cam.pixels.data() + 3 * pixel;
    float* position = out_.position_cam.pixels.data() + 3 * pixel;
    for (int c = 0; c < 3; ++c) {
      normal[c] = static_cast<float>(n[c]);
      position[c] = static_cast<float>(a[5 + c] * w);
    }
    out_.uv.pixels[2 * pixel] = static_cast<float>(a[8] * w);
    out_.uv.pixels[2 * pixel + 1] = static_cast<float>(a[9] * w);
    if (has_color) {
      float* color = out_.color.pixels.data() + 3 * pixel;
      for (int c = 0; c < 3; ++c) color[c] = static_cast<float>(a[10 + c] * w);
    }
  }

  const std::vector<RasterItem>& items_;
  const std::vector<std::vector<Vec3d>>& screen_;
  const geometry::Camera& camera_;
  const RasterOptions& options_;
  GBuffer& out_;
  const int attrs_;
  std::vector<std::vector<ActiveEdge>> edge_table_;
  std::vector<ActiveEdge> active_;
};

}  // namespace

std::string RasterOptions::Validate() const {
  if (band_rows < 1) return "band_rows must be >= 1";
  return "";
}

GBuffer Rasterize(const std::vector<RasterItem>& items, const geometry::Camera& camera,
                  const RasterOptions& options) {
  if (auto m = camera.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  bool any_color = false;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto* mesh = items[i].mesh;
    if (mesh == nullptr) throw std::invalid_argument("raster item without a mesh");
    if (auto m = mesh->Validate(); !m.empty()) throw std::invalid_argument("mesh: " + m);
    if (!options.depth_only && mesh->corner_normals.size() != 3 * mesh->triangles.size()) {
      throw std::invalid_argument("mesh has no corner normals");
    }
    if (items[i].corner_colors != nullptr) {
      if (items[i].corner_colors->size() != 3 * mesh->triangles.size()) {
        throw std::invalid_argument("expected 3 corner colours per triangle");
      }
      any_color = true;
    }
  }

  const int w = camera.width, h = camera.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  GBuffer out;
  out.width = w;
  out.height = h;
  out.depth.assign(pixels, std::numeric_limits<float>::infinity());
  out.object_id.assign(pixels, -1);
  out.triangle.assign(pixels, -1);
  if (options.count_fragments) out.fragments.assign(pixels, 0);
  if (!options.depth_only) {
    out.normal_cam = ImageF(w, h, 3);
    out.position_cam = ImageF(w, h, 3);
    out.uv = ImageF(w, h, 2);
    if (any_color) out.color = ImageF(w, h, 3);
  }

  // Project every vertex once.
  std::vector<std::vector<Vec3d>> screen(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto& positions = items[i].mesh->positions;
    screen[i].resize(positions.size());
    ParallelFor(0, positions.size(), 4096, options.threads, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) screen[i][v] = camera.Project(positions[v]);
    });
  }

  // Each band of scan lines gets the triangles that overlap it; bands run in parallel and write
  // disjoint rows.
  const int band_rows = options.band_rows;
  const int bands = (h + band_rows - 1) / band_rows;
  std::vector<std::vector<TriangleRef>> band_triangles(bands);
  const bool perspective = camera.type == geometry::CameraType::kPerspective;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto& mesh = *items[i].mesh;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      const Vec3d& a = screen[i][tri[0]];
      const Vec3d& b = screen[i][tri[1]];
      const Vec3d& c = screen[i][tri[2]];
      if (perspective && (a.z() <= 1e-9 || b.z() <= 1e-9 || c.z() <= 1e-9)) continue;
      if (!(a.allFinite() && b.allFinite() && c.allFinite())) continue;
      const double area2 = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
      if (area2 == 0) continue;
      const double y_min = std::min({a.y(), b.y(), c.y()});
      const double y_max = std::max({a.y(), b.y(), c.y()});
      const double x_min = std::min({a.x(), b.x(), c.x()});
      const double x_max = std::max({a.x(), b.x(), c.x()});
      if (y_max < 0 || y_min > h || x_max < 0 || x_min > w) continue;
      const int first = std::max(0, FirstRow(std::max(y_min, -1.0)));
      const int last = std::min(h - 1, FirstRow(std::min(y_max, h + 1.0)) - 1);
      if (first > last) continue;
      for (int band = first / band_rows; band <= last / band_rows; ++band) {
        band_triangles[band].push_back({static_cast<int>(i), static_cast<int>(t)});
      }
    }
  }

  ParallelFor(0, bands, 1, options.threads, [&](std::size_t b, std::size_t e) {
    BandRasterizer rasterizer(items, screen, camera, options, out);
    for (std::size_t band = b; band < e; ++band) {
      const int row_begin = static_cast<int>(band) * band_rows;
      rasterizer.Run(row_begin, std::min(h, row_begin + band_rows), band_triangles[band]);
    }
  });
  return out;
}

}  // namespace iphong::render
