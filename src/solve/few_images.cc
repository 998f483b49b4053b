#include "solve/few_images.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

#include <cmath>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/phong.h"
#include "solve/internal.h"
#include "solve/pyramid.h"
#include "solve/search.h"

namespace iphong::solve {
namespace {

// The pyramid: halved until a level has at most this many pixels (its full solve then takes a
// fraction of a second), at most kMaxLevels levels.
constexpr std::size_t kCoarsestPixels = 4000;
constexpr int kMaxLevels = 8;
// Levels up to this many pixels are solved with exact sparse Cholesky steps, larger ones with
// conjugate gradients (a third of the time per step on the demo sphere's 33 000 pixels).
constexpr std::size_t kCholeskyPixels = 12000;
// Candidate directions of the start's search (NearestConsistentNormals): ~2.2° apart. 16 384
// (1.1°) gave the same normals on the demo sphere at twice the search's time.
constexpr int kStartCandidates = 4096;
// The coarsest level, cheap, is solved to Ceres's default tolerance; each finer one starts from
// the converged level below it and stops when an iteration lowers its cost by less than
// kRefineTolerance: on the demo sphere from two images the normals move by less than 0.02° mean
// past it, where the full tolerance spent 150 iterations creeping by 1 %.
// The outline's outward direction is measured over a disk of this radius (pixels).
constexpr int kOutlineRadius = 3;
constexpr double kCoarsestTolerance = 1e-6;
// Iterations a level's solve typically takes (10–30 on the demo sphere): its progress is
// reported against these, and holds at its end if it takes more.
constexpr int kTypicalIterations = 25;
constexpr double kRefineTolerance = 1e-3;

using internal::Luminance;

// Image j's shading at one pixel through the shared model, against the observation.
struct DataCost {
  Vec3d observed, light_dir, intensity, ambient;
  reflectance::Material material;
  reflectance::ModelOptions model;
  double weight = 1;

  template <typename T>
  bool operator()(const T* n, T* residual) const {
    const Vec3T<T> normal(n[0], n[1], n[2]);
    const Vec3T<T> predicted =
        ambient.cast<T>() +
        reflectance::LightTerm<T>(normal, internal::ViewCam().cast<T>(), light_dir.cast<T>(),
                                  intensity.cast<T>(), intensity.cast<T>(),
                                  reflectance::CastMaterial<T>(material), model);
    for (int c = 0; c < 3; ++c) residual[c] = T(weight) * (predicted[c] - T(observed[c]));
    return true;
  }
};

struct SmoothnessCost {
  double weight;
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    for (int c = 0; c < 3; ++c) residual[c] = T(weight) * (a[c] - b[c]);
    return true;
  }
};

// Curl of the gradient field p = −nx/nz, q = −ny/nz over a 2×2 cell (y up: row r lies above
// row r + 1). Cells where a normal is near the occluding contour are left out by value.
struct IntegrabilityCost {
  double weight;
  template <typename T>
  bool operator()(const T* tl, const T* tr, const T* bl, const T* br, T* residual) const {
    const T* cell[4] = {tl, tr, bl, br};
    for (const T* n : cell) {
      if (n[2] < T(0.2)) {
        residual[0] = T(0);
        return true;
      }
    }
    auto p = [](const T* n) { return -n[0] / n[2]; };
    auto q = [](const T* n) { return -n[1] / n[2]; };
    const T dp_dy = T(0.5) * ((p(tl) - p(bl)) + (p(tr) - p(br)));
    const T dq_dx = T(0.5) * ((q(tr) - q(tl)) + (q(br) - q(bl)));
    residual[0] = T(weight) * (dp_dy - dq_dx);
    return true;
  }
};

struct PriorCost {
  Vec3d target;
  double weight;
  template <typename T>
  bool operator()(const T* n, T* residual) const {
    for (int c = 0; c < 3; ++c) residual[c] = T(weight) * (n[c] - T(target[c]));
    return true;
  }
};

struct VisibilityCost {  // nz ≥ 0, softly
  double weight;
  template <typename T>
  bool operator()(const T* n, T* residual) const {
    residual[0] = n[2] < T(0) ? T(weight) * n[2] : T(0);
    return true;
  }
};

// Normals consistent with the data alone, per pixel: the angle they span.
double Ambiguity(const PhotometricData& data, std::size_t p, const FewImageOptions& o) {
  const float* obs = data.pixel(p);
  double c[2];
  for (int j = 0; j < data.images; ++j) {
    const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
    const double kd = Luminance(o.material.kd.cwiseProduct(data.light_intensities[j]));
    c[j] = std::clamp(Luminance(rgb - o.ambient_term) / std::max(kd, 1e-12), -1.0, 1.0);
  }
  if (data.images == 1) return 2 * std::acos(c[0]) * 180 / M_PI;  // the cone's full opening
  // Two cones: N = a L1 + b L2 + g (L1 × L2); a, b from N·Lj = cj, g from |N| = 1.
  const Vec3d& l1 = data.light_directions[0];
  const Vec3d& l2 = data.light_directions[1];
  const double d = l1.dot(l2);
  if (std::abs(1 - d * d) < 1e-9) return 2 * std::acos(c[0]) * 180 / M_PI;  // same light twice
  const double a = (c[0] - d * c[1]) / (1 - d * d), b = (c[1] - d * c[0]) / (1 - d * d);
  const Vec3d in_plane = a * l1 + b * l2;
  const double rest = 1 - in_plane.squaredNorm();
  if (rest <= 0) return 0;  // the cones touch: one solution
  const double g = std::sqrt(rest) / l1.cross(l2).norm();
  const Vec3d n1 = in_plane + g * l1.cross(l2), n2 = in_plane - g * l1.cross(l2);
  return std::atan2(n1.cross(n2).norm(), n1.dot(n2)) * 180 / M_PI;
}

}  // namespace

std::array<Eigen::Vector2d, 2> ProfileNormals(double shading, const Eigen::Vector2d& light_xz) {
  const double norm = light_xz.norm();
  if (!(norm > 0) || !light_xz.allFinite()) throw std::invalid_argument("zero light direction");
  if (!(std::abs(shading) <= 1)) {
    throw std::invalid_argument("shading " + std::to_string(shading) + " is not in [-1, 1]");
  }
  const Eigen::Vector2d l = light_xz / norm;
  const Eigen::Vector2d perp(l.y(), -l.x());  // L rotated toward +x
  const double s = std::sqrt(1 - shading * shading);
  return {shading * l + s * perp, shading * l - s * perp};
}

std::string FewImageOptions::Validate() const {
  if (auto m = reflectance::ValidateMaterial(material); !m.empty()) return m;
  if (!(Luminance(material.kd) > 0)) return "one or two images need a known albedo kd > 0";
  if (!(smoothness_weight >= 0 && integrability_weight >= 0 && boundary_weight >= 0)) {
    return "prior weights must be >= 0";
  }
  if (max_iterations < 1) return "max_iterations must be >= 1";
  return "";
}

namespace {

// Scalar parameters of every level's problem: each normal as 3 numbers on the unit sphere.
using NormalBlocks = std::vector<std::array<double, 3>>;

// The weights of one pyramid level whose pixels are h fine pixels wide. Smoothness and
// integrability sum differences between neighbours, whose count grows as 1/h² while each
// difference shrinks as h: their sums do not depend on h (a Dirichlet energy in 2-D). The data
// and visibility terms count pixels (1/h²) and the boundary counts outline pixels (1/h), so their
// residuals are scaled by h and √h to keep every level's balance the fine level's.
struct LevelScale {
  double data = 1, boundary = 1;
};
LevelScale ScaleOf(int level) {
  const double h = std::ldexp(1.0, level);
  return {h, std::sqrt(h)};
}

// A level's pixel grid: each masked pixel's neighbours and, on the occluding outline (a
// neighbour inside the image but outside the mask), the outward direction the normal must take.
struct Grid {
  std::vector<int> index;      // row-major over the image: masked pixel number, or −1
  std::vector<Vec3d> outward;  // per masked pixel: unit, in the image plane, or zero
  int width = 0, height = 0;
  // Masked pixel number at (col, row); −1 outside the mask, −2 outside the image.
  int at(int col, int row) const {
    return col < 0 || row < 0 || col >= width || row >= height
               ? -2
               : index[static_cast<std::size_t>(row) * width + col];
  }
};

Grid GridOf(const PhotometricData& data) {
  Grid g;
  g.width = data.width;
  g.height = data.height;
  g.index.assign(static_cast<std::size_t>(data.width) * data.height, -1);
  for (std::size_t i = 0; i < data.pixel_count(); ++i)
    g.index[data.pixels[i]] = static_cast<int>(i);
  g.outward.assign(data.pixel_count(), Vec3d::Zero());
  for (std::size_t i = 0; i < data.pixel_count(); ++i) {
    const int col = data.pixels[i] % data.width, row = data.pixels[i] / data.width;
    bool outline = false;
    const int dc[4] = {1, -1, 0, 0}, dr[4] = {0, 0, 1, -1};
    for (int k = 0; k < 4; ++k) outline = outline || g.at(col + dc[k], row + dr[k]) == -1;
    if (!outline) continue;
    // The outline's normal, from the background within kOutlineRadius pixels: the direction
    // of its centroid. Four neighbours alone give it in steps of 45°, and a sphere's rim then
    // came out up to 40° off. Only offsets whose opposite also lies in the image count, so an
    // image edge that cuts the disk does not tilt it (one light on a cylinder through the
    // image's top and bottom: two tilted rows there made every normal 5–20° off).
    Vec3d outward = Vec3d::Zero();
    for (int r = -kOutlineRadius; r <= kOutlineRadius; ++r) {
      for (int c = -kOutlineRadius; c <= kOutlineRadius; ++c) {
        if (c * c + r * r <= kOutlineRadius * kOutlineRadius && g.at(col + c, row + r) == -1 &&
            g.at(col - c, row - r) != -2) {
          outward += Vec3d(c, -r, 0);  // y up
        }
      }
    }
    if (outward.norm() > 0) g.outward[i] = outward.normalized();
  }
  return g;
}

void AddPriors(ceres::Problem& problem, const PhotometricData& data, const Grid& grid,
               NormalBlocks& normals, const FewImageOptions& options, const LevelScale& scale) {
  const int w = data.width;
  const std::size_t pixels = data.pixel_count();
  const auto at = [&](int col, int row) { return grid.at(col, row); };
  for (std::size_t i = 0; i < pixels; ++i) {
    problem.AddParameterBlock(normals[i].data(), 3, new ceres::SphereManifold<3>());
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    const int col = data.pixels[i] % w, row = data.pixels[i] / w;
    double* n = normals[i].data();
    if (!grid.outward[i].isZero()) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(new PriorCost{
                                   grid.outward[i], options.boundary_weight * scale.boundary}),
                               nullptr, n);
    }
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<VisibilityCost, 1, 3>(
                                 new VisibilityCost{10.0 * scale.data}),
                             nullptr, n);
    for (int k = 0; k < 2; ++k) {  // right and down neighbours, each pair once
      const int j = at(col + (k == 0), row + (k == 1));
      if (j < 0) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SmoothnessCost, 3, 3, 3>(
                                   new SmoothnessCost{options.smoothness_weight}),
                               nullptr, n, normals[j].data());
    }
    const int tr = at(col + 1, row), bl = at(col, row + 1), br = at(col + 1, row + 1);
    if (tr >= 0 && bl >= 0 && br >= 0 && options.integrability_weight > 0) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<IntegrabilityCost, 1, 3, 3, 3, 3>(
                                   new IntegrabilityCost{options.integrability_weight}),
                               nullptr, n, normals[tr].data(), normals[bl].data(),
                               normals[br].data());
    }
  }
}

void AddData(ceres::Problem& problem, const PhotometricData& data, NormalBlocks& normals,
             const FewImageOptions& options, const LevelScale& scale) {
  reflectance::ModelOptions model;
  model.lobe = options.model;
  for (std::size_t i = 0; i < data.pixel_count(); ++i) {
    const float* obs = data.pixel(i);
    for (int j = 0; j < data.images; ++j) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<DataCost, 3, 3>(new DataCost{
                                   Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]),
                                   data.light_directions[j], data.light_intensities[j],
                                   options.ambient_term, options.material, model, scale.data}),
                               nullptr, normals[i].data());
    }
  }
}

// Per pixel, the normal nearest `prior` among those its data allow. With one or two lights a
// pixel's shading is explained by a cone (one light) or a few isolated normals (two: mirror
// images across the lights' plane, more near a highlight), and a local solver keeps whichever
// branch it starts on: started from a smooth prior, it keeps a wrong one wherever the prior lies
// on the wrong side of a saddle (on the demo sphere from its first two images, a crescent beside
// the highlight ended 10–20° off). So every pixel starts on the branch nearest the prior: of the
// prior itself and the candidate directions on the visible hemisphere (search.h's table,
// kStartCandidates of them), the one minimizing
//   Σ_j (y_j − kd·d_j − ks·s_j)² / σ²  +  |N − prior|² / τ²
// on the luminance y_j = lum((I_j − Ia⊙ka)/E_j), with σ what the directions' spacing δ can
// leave unexplained (δ/2 times the shading's steepest slope, kd + 1.2·ks·√n per radian) and τ =
// 0.5 (30°): data that rule a direction out outweigh any prior, and among the directions they
// allow the prior decides.
std::vector<Vec3d> NearestConsistentNormals(const PhotometricData& data,
                                            const std::vector<Vec3d>& prior,
                                            const FewImageOptions& o, const CandidateTable& table,
                                            double spacing_rad) {
  const double kd = Luminance(o.material.kd), ks = Luminance(o.material.ks);
  const bool lobe = o.model != reflectance::Lobe::kLambert;
  const double slope = kd + (lobe ? 1.2 * ks * std::sqrt(std::max(o.material.shininess, 1.0)) : 0);
  const double sigma = std::max(0.5 * spacing_rad * slope, 1e-6);
  const double inv_sigma2 = 1 / (sigma * sigma), inv_tau2 = 1 / (0.5 * 0.5);
  const int k = data.images;
  reflectance::ModelOptions model;
  model.lobe = o.model;
  std::vector<Vec3d> out(prior);
  ParallelFor(0, data.pixel_count(), 256, o.threads, [&](std::size_t b, std::size_t e) {
    std::vector<double> y(k);
    std::vector<std::pair<double, int>> coarse;
    for (std::size_t i = b; i < e; ++i) {
      const float* obs = data.pixel(i);
      for (int j = 0; j < k; ++j) {
        const Vec3d rgb(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]);
        y[j] = Luminance((rgb - o.ambient_term).cwiseQuotient(data.light_intensities[j]));
      }
      const auto misfit = [&](int j, double d, double s) {
        const double r = y[j] - kd * d - (lobe ? ks * s : 0.0);
        return r * r * inv_sigma2;
      };
      const auto score = [&](int c) {
        const float *d = table.diffuse(c), *s = table.specular(c);
        double v = 2 * (1 - table.normal(c).dot(prior[i])) * inv_tau2;
        for (int j = 0; j < k; ++j) v += misfit(j, d[j], s[j]);
        return v;
      };
      // The prior competes unsnapped: where it already explains the data it is kept.
      double best = 0;
      for (int j = 0; j < k; ++j) {
        const auto f = reflectance::ShadingFactors<double>(
            prior[i], internal::ViewCam(), data.light_directions[j], o.material.shininess, model);
        best += misfit(j, f.diffuse, f.specular);
      }
      coarse.clear();
      for (int c = table.fine_count(); c < table.size(); ++c) coarse.emplace_back(score(c), c);
      const std::size_t top = std::min<std::size_t>(8, coarse.size());
      std::partial_sort(coarse.begin(), coarse.begin() + top, coarse.end());
      for (std::size_t t = 0; t < top; ++t) {
        for (int f : table.members(coarse[t].second)) {
          const double v = score(f);
          if (v < best) best = v, out[i] = table.normal(f);
        }
      }
    }
  });
  return out;
}

// Reports a level's progress as the fraction of the whole run's budget spent.
class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(const std::function<void(double)>& report, double start, double span, int budget)
      : report_(report), start_(start), span_(span), budget_(std::max(budget, 1)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    report_(start_ + span_ * std::min(1.0, (summary.iteration + 1.0) / budget_));
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::function<void(double)>& report_;
  double start_, span_;
  int budget_;
};

}  // namespace

FewImageResult EstimateNormalsFewImages(const PhotometricData& data,
                                        const FewImageOptions& options) {
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (data.images < 1 || data.images > 2) {
    throw std::invalid_argument("the global few-image solver takes 1 or 2 images, got " +
                                std::to_string(data.images));
  }
  const auto start = Clock::now();
  const std::vector<PhotometricData> levels = ObservationPyramid(data, kCoarsestPixels, kMaxLevels);
  const int coarsest = static_cast<int>(levels.size()) - 1;

  // Progress: each stage's share of the run is its pixel count (the priors' stage is on the
  // coarsest level), spent over the iterations a level typically takes.
  double total_pixels = static_cast<double>(levels.back().pixel_count());
  for (const PhotometricData& l : levels) total_pixels += static_cast<double>(l.pixel_count());
  double progress_start = 0;
  int iterations = 0;
  ceres::Solver::Summary summary;
  const auto solve = [&](ceres::Problem& problem, const PhotometricData& level) {
    ceres::Solver::Options solver;
    // Exact Cholesky steps where they are cheap; on a large level conjugate gradients (Jacobi
    // preconditioned, inexact Newton steps): the start the coarser levels give is close, and
    // each step costs a third of a sparse factorization.
    solver.linear_solver_type =
        level.pixel_count() <= kCholeskyPixels ? ceres::SPARSE_NORMAL_CHOLESKY : ceres::CGNR;
    solver.preconditioner_type = ceres::JACOBI;
    solver.max_num_iterations = options.max_iterations;
    solver.function_tolerance = &level == &levels.back() ? kCoarsestTolerance : kRefineTolerance;
    solver.num_threads = ResolveThreads(options.threads);
    const double span = static_cast<double>(level.pixel_count()) / total_pixels;
    ProgressCallback callback(options.progress, progress_start, span, kTypicalIterations);
    if (options.progress) solver.callbacks.push_back(&callback);
    ceres::Solve(solver, &problem, &summary);
    progress_start += span;
    iterations += static_cast<int>(summary.iterations.size());
  };
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;

  reflectance::ModelOptions model;
  model.lobe = options.model;
  const CandidateTable table(data.light_directions, model, options.material.shininess,
                             kStartCandidates);
  const double spacing = std::sqrt(2 * M_PI / kStartCandidates);

  std::vector<Vec3d> prior;
  for (int l = coarsest; l >= 0; --l) {
    const PhotometricData& level = levels[l];
    const LevelScale scale = ScaleOf(l);
    const Grid grid = GridOf(level);
    NormalBlocks normals(level.pixel_count(), {0.0, 0.0, 1.0});
    if (l == coarsest) {
      // The priors alone inflate the silhouette into a smooth balloon: the first prior.
      ceres::Problem balloon(problem_options);
      AddPriors(balloon, level, grid, normals, options, scale);
      solve(balloon, level);
      prior.resize(normals.size());
      for (std::size_t i = 0; i < normals.size(); ++i)
        prior[i] = Vec3d(normals[i][0], normals[i][1], normals[i][2]).normalized();
    } else {
      prior = UpsampleNormals(levels[l + 1], prior, level);
      // On the outline the upsampled normal is the coarse interior's: start it where the
      // boundary prior holds it instead (the coarse solution's outline lies elsewhere).
      for (std::size_t i = 0; i < prior.size(); ++i) {
        if (!grid.outward[i].isZero()) prior[i] = grid.outward[i];
      }
    }
    const std::vector<Vec3d> begin =
        NearestConsistentNormals(level, prior, options, table, spacing);
    for (std::size_t i = 0; i < normals.size(); ++i)
      normals[i] = {begin[i][0], begin[i][1], begin[i][2]};
    ceres::Problem full(problem_options);
    AddPriors(full, level, grid, normals, options, scale);
    AddData(full, level, normals, options, scale);
    solve(full, level);
    for (std::size_t i = 0; i < normals.size(); ++i)
      prior[i] = Vec3d(normals[i][0], normals[i][1], normals[i][2]).normalized();
  }
  if (options.progress) options.progress(1.0);

  FewImageResult result;
  const int w = data.width, h = data.height;
  result.normals = ImageF(w, h, 3);
  result.ambiguity_deg = ImageF(w, h, 1);
  result.residual = ImageF(w, h, 1);
  for (std::size_t i = 0; i < data.pixel_count(); ++i) {
    const Vec3d& n = prior[i];
    const float* obs = data.pixel(i);
    double sq = 0;
    for (int j = 0; j < data.images; ++j) {
      const DataCost cost{Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]),
                          data.light_directions[j],
                          data.light_intensities[j],
                          options.ambient_term,
                          options.material,
                          model,
                          1.0};
      double r[3];
      cost(n.data(), r);
      sq += r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    }
    result.residual.pixels[data.pixels[i]] = static_cast<float>(std::sqrt(sq / (3 * data.images)));
    for (int c = 0; c < 3; ++c)
      result.normals.pixels[3 * data.pixels[i] + c] = static_cast<float>(n[c]);
    result.ambiguity_deg.pixels[data.pixels[i]] = static_cast<float>(Ambiguity(data, i, options));
  }
  result.iterations = iterations;
  result.final_cost = summary.final_cost;
  result.solve_seconds = SecondsSince(start);
  result.message = summary.BriefReport();
  return result;
}

}  // namespace iphong::solve
