#include "solve/few_images.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

#include <cmath>
#include <stdexcept>

#include "core/parallel.h"
#include "core/timing.h"
#include "reflectance/phong.h"
#include "solve/internal.h"

namespace iphong::solve {
namespace {

// Reports the fraction of the iteration budget spent, within [start, start + span].
class ProgressCallback : public ceres::IterationCallback {
 public:
  ProgressCallback(std::function<void(double)> report, double start, double span, int budget)
      : report_(std::move(report)), start_(start), span_(span), budget_(std::max(budget, 1)) {}
  void Stage(double start, double span) {
    start_ = start;
    span_ = span;
  }
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (report_) report_(start_ + span_ * std::min(1.0, (summary.iteration + 1.0) / budget_));
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<void(double)> report_;
  double start_, span_;
  int budget_;
};

using internal::Luminance;

// Image j's shading at one pixel through the shared model, against the observation.
struct DataCost {
  Vec3d observed, light_dir, intensity, ambient;
  reflectance::Material material;
  reflectance::ModelOptions model;

  template <typename T>
  bool operator()(const T* n, T* residual) const {
    const Vec3T<T> normal(n[0], n[1], n[2]);
    const Vec3T<T> predicted =
        ambient.cast<T>() +
        reflectance::LightTerm<T>(normal, internal::ViewCam().cast<T>(), light_dir.cast<T>(),
                                  intensity.cast<T>(), intensity.cast<T>(),
                                  reflectance::CastMaterial<T>(material), model);
    for (int c = 0; c < 3; ++c) residual[c] = predicted[c] - T(observed[c]);
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

FewImageResult EstimateNormalsFewImages(const PhotometricData& data,
                                        const FewImageOptions& options) {
  if (auto m = data.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (auto m = options.Validate(); !m.empty()) throw std::invalid_argument(m);
  if (data.images < 1 || data.images > 2) {
    throw std::invalid_argument("the global few-image solver takes 1 or 2 images, got " +
                                std::to_string(data.images));
  }
  const auto start = Clock::now();
  const int w = data.width, h = data.height;
  const std::size_t pixels = data.pixel_count();
  std::vector<int> index(static_cast<std::size_t>(w) * h, -1);
  for (std::size_t i = 0; i < pixels; ++i) index[data.pixels[i]] = static_cast<int>(i);
  auto at = [&](int col, int row) {
    return col < 0 || row < 0 || col >= w || row >= h ? -2 : index[row * w + col];
  };

  std::vector<std::array<double, 3>> normals(pixels, {0.0, 0.0, 1.0});
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem priors_only(problem_options);
  ceres::Problem full(problem_options);

  auto add_priors = [&](ceres::Problem& problem) {
    for (std::size_t i = 0; i < pixels; ++i) {
      problem.AddParameterBlock(normals[i].data(), 3, new ceres::SphereManifold<3>());
    }
    for (std::size_t i = 0; i < pixels; ++i) {
      const int col = data.pixels[i] % w, row = data.pixels[i] / w;
      double* n = normals[i].data();
      // Occluding boundary: neighbours inside the image but outside the mask.
      Vec3d outward = Vec3d::Zero();
      const int dc[4] = {1, -1, 0, 0}, dr[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        if (at(col + dc[k], row + dr[k]) == -1) outward += Vec3d(dc[k], -dr[k], 0);  // y up
      }
      if (outward.norm() > 0) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 3, 3>(
                                     new PriorCost{outward.normalized(), options.boundary_weight}),
                                 nullptr, n);
      }
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<VisibilityCost, 1, 3>(new VisibilityCost{10.0}), nullptr,
          n);
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
  };

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = ResolveThreads(options.threads);
  ceres::Solver::Summary summary;
  // A run on a camera-sized image takes minutes: its progress is the iteration budget spent.
  ProgressCallback progress(options.progress, 0.0, 0.2, options.max_iterations);
  if (options.progress) solver.callbacks.push_back(&progress);

  // Stage 1: the priors alone inflate the silhouette into a smooth start.
  add_priors(priors_only);
  ceres::Solve(solver, &priors_only, &summary);
  progress.Stage(0.2, 0.8);
  int iterations = static_cast<int>(summary.iterations.size());

  // Stage 2: everything, with the data of the shared model.
  add_priors(full);
  reflectance::ModelOptions model;
  model.lobe = options.model;
  for (std::size_t i = 0; i < pixels; ++i) {
    const float* obs = data.pixel(i);
    for (int j = 0; j < data.images; ++j) {
      full.AddResidualBlock(
          new ceres::AutoDiffCostFunction<DataCost, 3, 3>(new DataCost{
              Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]), data.light_directions[j],
              data.light_intensities[j], options.ambient_term, options.material, model}),
          nullptr, normals[i].data());
    }
  }
  ceres::Solve(solver, &full, &summary);
  iterations += static_cast<int>(summary.iterations.size());
  if (options.progress) options.progress(1.0);

  FewImageResult result;
  result.normals = ImageF(w, h, 3);
  result.ambiguity_deg = ImageF(w, h, 1);
  result.residual = ImageF(w, h, 1);
  for (std::size_t i = 0; i < pixels; ++i) {
    const Vec3d n = Vec3d(normals[i][0], normals[i][1], normals[i][2]).normalized();
    const float* obs = data.pixel(i);
    double sq = 0;
    for (int j = 0; j < data.images; ++j) {
      const DataCost cost{Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]),
                          data.light_directions[j],
                          data.light_intensities[j],
                          options.ambient_term,
                          options.material,
                          model};
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
