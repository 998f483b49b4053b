#include "render/rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/parallel.h"

namespace iphong::render {
namespace {

// Interpolated values, each divided by w (w = depth under perspective, 1 orthographic), in this
// order; only the first `count` are carried: [1/w, depth/w | normal (3) | uv (2) | colour (3)].
constexpr int kMaxAttrs = 10;
using Attrs = std::array<double, kMaxAttrs>;
constexpr int kNormal = 2;

struct Layout {
  int count = 2;
  int uv = -1;     // first uv slot, −1 when absent
  int color = -1;  // first colour slot, −1 when absent
};

struct TriangleRef {
  int item;
  int triangle;
};

// An edge of the edge table. It stays where it is; the active list holds indices into the band's
// edges, so a scan line moves ints, not attribute blocks.
struct Edge {
  int slot;       // which triangle of the band
  int first_row;  // first scan line of the band it covers
  int last_row;   // inclusive
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
                 const RasterOptions& options, const Layout& layout, GBuffer& out)
      : items_(items),
        screen_(screen),
        camera_(camera),
        options_(options),
        layout_(layout),
        out_(out) {}

  void Run(int row_begin, int row_end, const std::vector<TriangleRef>& triangles) {
    // Edge table: the band's edges ordered by their first scan line here, then by triangle.
    edges_.clear();
    edges_.reserve(3 * triangles.size());
    for (std::size_t slot = 0; slot < triangles.size(); ++slot) {
      AddTriangleEdges(static_cast<int>(slot), triangles[slot], row_begin, row_end);
    }
    starts_.assign(row_end - row_begin + 1, 0);
    for (const Edge& e : edges_) ++starts_[e.first_row - row_begin + 1];
    for (std::size_t r = 1; r < starts_.size(); ++r) starts_[r] += starts_[r - 1];
    table_.resize(edges_.size());
    fill_.assign(starts_.begin(), starts_.end() - 1);
    for (std::size_t i = 0; i < edges_.size(); ++i) {
      table_[fill_[edges_[i].first_row - row_begin]++] = static_cast<int>(i);  // slot order kept
    }

    active_.clear();
    for (int row = row_begin; row < row_end; ++row) {
      // Active edge list, ordered by triangle: merge in the edges starting on this scan line.
      const int* begin = table_.data() + starts_[row - row_begin];
      const int* end = table_.data() + starts_[row - row_begin + 1];
      merged_.clear();
      std::merge(active_.begin(), active_.end(), begin, end, std::back_inserter(merged_),
                 [&](int a, int b) { return edges_[a].slot < edges_[b].slot; });
      active_.swap(merged_);
      // A triangle has exactly two active edges on a scan line it covers: they bound its span.
      for (std::size_t i = 0; i + 1 < active_.size();) {
        const Edge& e0 = edges_[active_[i]];
        const Edge& e1 = edges_[active_[i + 1]];
        if (e0.slot != e1.slot) {
          ++i;
          continue;
        }
        if (e0.x <= e1.x) {
          FillSpan(row, triangles[e0.slot], e0, e1);
        } else {
          FillSpan(row, triangles[e0.slot], e1, e0);
        }
        i += 2;
      }
      // Drop finished edges, step the rest to the next scan line (stage 1 increments).
      std::size_t kept = 0;
      for (int index : active_) {
        Edge& e = edges_[index];
        if (e.last_row <= row) continue;
        e.x += e.dxdy;
        for (int k = 0; k < layout_.count; ++k) e.a[k] += e.da[k];
        active_[kept++] = index;
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
      // A vertex at the camera's centre or beyond double range projects to inf/NaN: such a
      // triangle has no pixels to give, and rounding its edges to int would be undefined.
      if (!screen_[ref.item][tri[k]].allFinite()) return;
    }
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
      for (int c = 0; c < 3; ++c) a[kNormal + c] = n[c] * inv_w;
      if (layout_.uv >= 0) {
        const Eigen::Vector2d uv = mesh.uvs.empty() ? Eigen::Vector2d::Zero() : mesh.uvs[tri[k]];
        a[layout_.uv] = uv.x() * inv_w;
        a[layout_.uv + 1] = uv.y() * inv_w;
      }
      if (layout_.color >= 0) {
        const Vec3f color =
            item.corner_colors ? (*item.corner_colors)[3 * ref.triangle + k] : Vec3f::Zero();
        for (int c = 0; c < 3; ++c) a[layout_.color + c] = color[c] * inv_w;
      }
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
      Edge edge;
      edge.slot = slot;
      edge.first_row = first;
      edge.last_row = last;
      const double inv_dy = 1.0 / (bottom->y - top->y);
      const double t = first + 0.5 - top->y;
      edge.dxdy = (bottom->x - top->x) * inv_dy;
      edge.x = top->x + t * edge.dxdy;
      for (int k = 0; k < layout_.count; ++k) {
        edge.da[k] = (bottom->a[k] - top->a[k]) * inv_dy;
        edge.a[k] = top->a[k] + t * edge.da[k];
      }
      edges_.push_back(edge);
    }
  }

  // Seed 001, stage 2: constant attribute steps along the span, one pixel at a time.
  void FillSpan(int row, const TriangleRef& ref, const Edge& left, const Edge& right) {
    const double width = right.x - left.x;
    if (!(width > 0) || !std::isfinite(width)) return;  // also NaN and overflowed edges
    // Clamped to the image in double before the cast, so far-off spans cannot overflow an int.
    const int c0 =
        std::max(0, static_cast<int>(std::ceil(std::clamp(left.x - 0.5, -1.0, out_.width + 1.0))));
    const int c1 = std::min(
        out_.width - 1,
        static_cast<int>(std::ceil(std::clamp(right.x - 0.5, -1.0, out_.width + 1.0))) - 1);
    if (c0 > c1) return;
    const int n = layout_.count;
    Attrs a, da;
    const double t = c0 + 0.5 - left.x;
    for (int k = 0; k < n; ++k) {
      da[k] = (right.a[k] - left.a[k]) / width;
      a[k] = left.a[k] + t * da[k];
    }
    const int object = items_[ref.item].object_id;
    const bool perspective = camera_.type == geometry::CameraType::kPerspective;
    std::size_t pixel = static_cast<std::size_t>(row) * out_.width + c0;
    for (int col = c0; col <= c1; ++col, ++pixel) {
      if (options_.count_fragments) ++out_.fragments[pixel];
      const double w = perspective ? 1.0 / a[0] : 1.0;
      const double depth = a[1] * w;
      if (depth < out_.depth[pixel]) {
        out_.depth[pixel] = static_cast<float>(depth);
        out_.object_id[pixel] = object;
        if (!options_.depth_only) WriteAttributes(pixel, a, w);
      }
      for (int k = 0; k < n; ++k) a[k] += da[k];
    }
  }

  void WriteAttributes(std::size_t pixel, const Attrs& a, double w) {
    Vec3d normal(a[kNormal] * w, a[kNormal + 1] * w, a[kNormal + 2] * w);
    if (options_.renormalize_normals) {
      const double norm = normal.norm();
      if (norm > 0) normal /= norm;
    }
    float* out_normal = out_.normal_cam.pixels.data() + 3 * pixel;
    for (int c = 0; c < 3; ++c) out_normal[c] = static_cast<float>(normal[c]);
    if (layout_.uv >= 0) {
      out_.uv.pixels[2 * pixel] = static_cast<float>(a[layout_.uv] * w);
      out_.uv.pixels[2 * pixel + 1] = static_cast<float>(a[layout_.uv + 1] * w);
    }
    if (layout_.color >= 0) {
      float* color = out_.color.pixels.data() + 3 * pixel;
      for (int c = 0; c < 3; ++c) color[c] = static_cast<float>(a[layout_.color + c] * w);
    }
  }

  const std::vector<RasterItem>& items_;
  const std::vector<std::vector<Vec3d>>& screen_;
  const geometry::Camera& camera_;
  const RasterOptions& options_;
  const Layout layout_;
  GBuffer& out_;
  std::vector<Edge> edges_;
  std::vector<int> starts_, fill_, table_, active_, merged_;
};

}  // namespace

std::string RasterOptions::Validate() const {
  if (band_rows < 1) return "band_rows must be >= 1";
  return "";
}

GBuffer Rasterize(const std::vector<RasterItem>& items, const geometry::Camera& camera,
                  const RasterOptions& options) {
  for (const RasterItem& item : items) {
    if (item.mesh == nullptr) throw std::invalid_argument("raster item without a mesh");
    if (auto m = item.mesh->Validate(); !m.empty()) throw std::invalid_argument("mesh: " + m);
  }
  return internal::RasterizeValidatedMeshes(items, camera, options);
}

namespace internal {

GBuffer RasterizeValidatedMeshes(const std::vector<RasterItem>& items,
                                 const geometry::Camera& camera, const RasterOptions& options) {
  if (auto m = camera.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  bool any_color = false, any_uv = false;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const auto* mesh = items[i].mesh;
    if (mesh == nullptr) throw std::invalid_argument("raster item without a mesh");
    if (!options.depth_only && mesh->corner_normals.size() != 3 * mesh->triangles.size()) {
      throw std::invalid_argument("mesh has no corner normals");
    }
    if (items[i].corner_colors != nullptr) {
      if (items[i].corner_colors->size() != 3 * mesh->triangles.size()) {
        throw std::invalid_argument("expected 3 corner colours per triangle");
      }
      any_color = true;
    }
    any_uv = any_uv || (options.interpolate_uv && !mesh->uvs.empty());
  }
  Layout layout;
  if (!options.depth_only) {
    layout.count = kNormal + 3;
    if (any_uv) {
      layout.uv = layout.count;
      layout.count += 2;
    }
    if (any_color) {
      layout.color = layout.count;
      layout.count += 3;
    }
  }

  const int w = camera.width, h = camera.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  GBuffer out;
  out.width = w;
  out.height = h;
  out.depth.assign(pixels, std::numeric_limits<float>::infinity());
  out.object_id.assign(pixels, -1);
  if (options.count_fragments) out.fragments.assign(pixels, 0);
  if (!options.depth_only) {
    out.normal_cam = ImageF(w, h, 3);
    if (any_uv) out.uv = ImageF(w, h, 2);
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
      // Screen y points down, so a triangle wound counter-clockwise toward the viewer has
      // negative signed area here.
      const double area2 = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
      if (area2 == 0 || (options.cull_back_faces && area2 > 0)) continue;
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
    BandRasterizer rasterizer(items, screen, camera, options, layout, out);
    for (std::size_t band = b; band < e; ++band) {
      const int row_begin = static_cast<int>(band) * band_rows;
      rasterizer.Run(row_begin, std::min(h, row_begin + band_rows), band_triangles[band]);
    }
  });
  return out;
}

}  // namespace internal
}  // namespace iphong::render
