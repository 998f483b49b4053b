// Ceres's refinement of a model's censored least-squares fit, and the covariance of its shared
// coefficients from one pass of Ceres's Jacobians, scaled by the residual variance.
#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "material/internal.h"
#include "reflectance/material.h"
#include "solve/internal.h"

namespace iphong::material::internal {

using reflectance::Lobe;

namespace {

// One pixel's residuals r_jc = y − a − E_jc (kd_c d_j + ks_c s_j(n)) over its used lights, the
// lobe from the shared model (reflectance::LobePower). kd is a parameter block, or eliminated:
// the least-squares kd_c for the current (a, ks, n), differentiated through.
struct PixelResidual {
  const Sample* s = nullptr;
  std::size_t p = 0;
  std::vector<int> lights;
  reflectance::ModelOptions model;

  template <typename T>
  bool Evaluate(const T* ambient, const T* ks, const T* log_n, const T* kd, T* r) const {
    using std::exp;
    const T n = exp(log_n[0]);
    const std::size_t m = lights.size();
    std::vector<T> lobe(m, T(0));
    if (model.lobe != Lobe::kLambert) {
      for (std::size_t i = 0; i < m; ++i) {
        const double c = s->cosine(model.lobe, p * s->lights + lights[i]);
        if (c > 0) lobe[i] = reflectance::LobePower(T(c), T(0), n, model);
      }
    }
    // kd: the block, or per channel the least-squares value for the current (a, ks, n).
    Vec3T<T> kd_vec;
    for (int c = 0; c < 3; ++c) {
      if (kd) {
        kd_vec[c] = kd[c];
        continue;
      }
      T num(0);
      double den = 0;
      for (std::size_t i = 0; i < m; ++i) {
        const int j = lights[i];
        const double e = s->data->light_intensities[j][c];
        const double ed = e * s->diffuse[p * s->lights + j];
        num += ed * (T(double(s->y(p, j)[c])) - ambient[c] - e * ks[c] * lobe[i]);
        den += ed * ed;
      }
      kd_vec[c] = den > 1e-8 ? num / den : T(0);
    }
    // Each observation against the shared model's combination of the factors.
    const Vec3T<T> a(ambient[0], ambient[1], ambient[2]), k_s(ks[0], ks[1], ks[2]);
    for (std::size_t i = 0; i < m; ++i) {
      const int j = lights[i];
      reflectance::LightFactors<T> f;
      f.diffuse = T(s->diffuse[p * s->lights + j]);
      f.specular = lobe[i];
      const Vec3T<T> e = s->data->light_intensities[j].template cast<T>();
      const Vec3T<T> model_value = a + reflectance::CombineFactors<T>(f, e, e, kd_vec, k_s);
      const float* y = s->y(p, j);
      for (int c = 0; c < 3; ++c) r[3 * i + c] = T(double(y[c])) - model_value[c];
    }
    return true;
  }
};

struct EliminatedResidual : PixelResidual {
  template <typename T>
  bool operator()(const T* ambient, const T* ks, const T* log_n, T* r) const {
    return Evaluate<T>(ambient, ks, log_n, nullptr, r);
  }
};
struct GroupResidual : PixelResidual {
  template <typename T>
  bool operator()(const T* ambient, const T* ks, const T* log_n, const T* kd, T* r) const {
    return Evaluate<T>(ambient, ks, log_n, kd, r);
  }
};

double Rss(const Sample& s, Lobe lobe, const Coefficients& c,
           const std::vector<unsigned char>& used) {
  double rss = 0;
  for (std::size_t p = 0; p < s.size(); ++p) {
    if (!c.kd_known[s.group[p]]) continue;
    for (int j = 0; j < s.lights; ++j) {
      if (!used[p * s.lights + j]) continue;
      const Vec3d r =
          Eigen::Vector3f(s.y(p, j)).cast<double>() - internal::Predict(s, lobe, c, p, j);
      rss += r.squaredNorm();
    }
  }
  return rss;
}

// One pass over the residual blocks with Ceres's Jacobians, over the parameter blocks `blocks`
// (in that order): H = JᵀJ, the gradient Jᵀr, the sandwich's meat Σ_p g_p g_pᵀ with
// g_p = J_p ᵀ r_p per residual block (pixel), and the cost ½ Σ r².
struct JacobianSums {
  Eigen::MatrixXd hessian, meat;
  Eigen::VectorXd gradient;
  std::vector<int> offset;  // each block's first column
  double cost = 0;
};

JacobianSums SumJacobians(ceres::Problem& problem, const std::vector<const double*>& blocks,
                          int threads) {
  JacobianSums sums;
  int size = 0;
  for (const double* b : blocks) sums.offset.push_back(size), size += problem.ParameterBlockSize(b);
  std::vector<ceres::ResidualBlockId> ids;
  problem.GetResidualBlocks(&ids);
  // The cost functions are const and thread-safe: chunks of pixels in parallel, each into its own
  // sums, added in chunk order (so the result does not depend on the threads).
  constexpr std::size_t kChunk = 64;
  const std::size_t chunks = (ids.size() + kChunk - 1) / kChunk;
  std::vector<JacobianSums> partial(chunks);
  // The longest residual block, so one Jacobian buffer per chunk serves every pixel.
  int longest = 0;
  for (ceres::ResidualBlockId id : ids) {
    longest = std::max(longest, problem.GetCostFunctionForResidualBlock(id)->num_residuals());
  }
  ParallelFor(0, ids.size(), kChunk, threads, [&](std::size_t begin, std::size_t end) {
    JacobianSums& part = partial[begin / kChunk];
    part.hessian = Eigen::MatrixXd::Zero(size, size);
    part.meat = Eigen::MatrixXd::Zero(size, size);
    part.gradient = Eigen::VectorXd::Zero(size);
    std::vector<double*> params;
    std::vector<double> residuals(longest);
    Eigen::MatrixXd j_all(longest, size);
    std::vector<std::vector<double>> jac;
    std::vector<double*> jac_ptr;
    std::vector<int> column;
    for (std::size_t r_id = begin; r_id < end; ++r_id) {
      problem.GetParameterBlocksForResidualBlock(ids[r_id], &params);
      const ceres::CostFunction* cost = problem.GetCostFunctionForResidualBlock(ids[r_id]);
      const int m = cost->num_residuals();
      jac.resize(params.size());
      jac_ptr.assign(params.size(), nullptr);
      column.assign(params.size(), -1);
      for (std::size_t b = 0; b < params.size(); ++b) {
        const auto it = std::find(blocks.begin(), blocks.end(), params[b]);
        if (it == blocks.end()) continue;
        column[b] = sums.offset[it - blocks.begin()];
        jac[b].resize(longest * problem.ParameterBlockSize(params[b]));
        jac_ptr[b] = jac[b].data();
      }
      cost->Evaluate(params.data(), residuals.data(), jac_ptr.data());
      auto j_p = j_all.topRows(m);
      j_p.setZero();
      for (std::size_t b = 0; b < params.size(); ++b) {
        if (column[b] < 0) continue;
        const int n = problem.ParameterBlockSize(params[b]);
        for (int r = 0; r < m; ++r)
          for (int k = 0; k < n; ++k) j_p(r, column[b] + k) = jac[b][r * n + k];
      }
      const Eigen::Map<const Eigen::VectorXd> r(residuals.data(), m);
      const Eigen::VectorXd g = j_p.transpose() * r;
      part.cost += 0.5 * r.squaredNorm();
      part.gradient += g;
      part.hessian.noalias() += j_p.transpose() * j_p;
      part.meat.noalias() += g * g.transpose();
    }
  });
  sums.hessian = Eigen::MatrixXd::Zero(size, size);
  sums.meat = Eigen::MatrixXd::Zero(size, size);
  sums.gradient = Eigen::VectorXd::Zero(size);
  for (const JacobianSums& part : partial) {
    sums.hessian += part.hessian;
    sums.meat += part.meat;
    sums.gradient += part.gradient;
    sums.cost += part.cost;
  }
  return sums;
}

}  // namespace

ceres::CostFunction* PixelCost(const Sample& s, std::size_t p, std::vector<int> lights, Lobe lobe,
                               bool eliminate_kd) {
  reflectance::ModelOptions model;
  model.lobe = lobe;
  const int residuals = static_cast<int>(3 * lights.size());
  if (eliminate_kd) {
    auto* f = new EliminatedResidual;
    f->s = &s, f->p = p, f->lights = std::move(lights), f->model = model;
    return new ceres::AutoDiffCostFunction<EliminatedResidual, ceres::DYNAMIC, 3, 3, 1>(f,
                                                                                        residuals);
  }
  auto* f = new GroupResidual;
  f->s = &s, f->p = p, f->lights = std::move(lights), f->model = model;
  return new ceres::AutoDiffCostFunction<GroupResidual, ceres::DYNAMIC, 3, 3, 1, 3>(f, residuals);
}

// Ceres's refinement of the censored fit and the covariance of its shared coefficients.
ModelFit Refine(const Sample& s, Lobe lobe, bool eliminate_kd,
                const std::vector<unsigned char>& used, int threads, Coefficients* c) {
  ModelFit fit;
  fit.lobe = lobe;
  const bool specular = lobe != Lobe::kLambert;
  double ambient[3] = {c->ambient[0], c->ambient[1], c->ambient[2]};
  double ks[3] = {c->ks[0], c->ks[1], c->ks[2]};
  double log_n[1] = {specular ? std::log(c->shininess) : 0.0};
  std::vector<std::array<double, 3>> kd(s.groups);
  for (int g = 0; g < s.groups; ++g) kd[g] = {c->kd[g][0], c->kd[g][1], c->kd[g][2]};

  ceres::Problem problem;
  std::size_t observations = 0;
  std::vector<unsigned char> group_used(s.groups, 0);
  for (std::size_t p = 0; p < s.size(); ++p) {
    const int g = s.group[p];
    if (!c->kd_known[g]) continue;
    std::vector<int> lights;
    for (int j = 0; j < s.lights; ++j) {
      if (used[p * s.lights + j]) lights.push_back(j);
    }
    if (lights.empty()) continue;
    observations += 3 * lights.size();
    ceres::CostFunction* cost = PixelCost(s, p, std::move(lights), lobe, eliminate_kd);
    if (eliminate_kd) {
      problem.AddResidualBlock(cost, nullptr, ambient, ks, log_n);
    } else {
      problem.AddResidualBlock(cost, nullptr, ambient, ks, log_n, kd[g].data());
      group_used[g] = 1;
    }
  }
  if (observations == 0) throw std::invalid_argument("no usable observation lights a pixel");
  for (int i = 0; i < 3; ++i) {
    problem.SetParameterLowerBound(ambient, i, 0);
    if (specular) problem.SetParameterLowerBound(ks, i, 0);
  }
  if (specular) {
    problem.SetParameterLowerBound(log_n, 0, 0);
    problem.SetParameterUpperBound(log_n, 0, std::log(8192.0));
  } else {
    problem.SetParameterBlockConstant(ks);
    problem.SetParameterBlockConstant(log_n);
  }
  // The free blocks. Without a lobe (ks = 0 in every channel) the shininess is not observable:
  // its block is held and left out, and its standard error stays NaN.
  const bool lobe_seen = specular && c->ks.maxCoeff() > 0;
  if (specular && !lobe_seen) problem.SetParameterBlockConstant(log_n);
  std::vector<const double*> blocks = {ambient};
  if (specular) blocks.push_back(ks);
  if (lobe_seen) blocks.push_back(log_n);
  std::vector<int> kd_block_group;
  if (!eliminate_kd) {
    for (int g = 0; g < s.groups; ++g) {
      if (group_used[g]) blocks.push_back(kd[g].data()), kd_block_group.push_back(g);
    }
  }
  // The profile fit is the least-squares optimum already, up to its parabolic step in n: Ceres
  // runs only where the Gauss–Newton step from it (over the coordinates no bound holds) is longer
  // than 0.05 standard errors. Otherwise its trust region shrinks through rejected steps, a full
  // Jacobian each (DiLiGenT pot1's Phong: 7 iterations and 10 s for a step of 0.02 s.e.).
  JacobianSums sums = SumJacobians(problem, blocks, threads);
  {
    const int size = static_cast<int>(sums.gradient.size());
    std::vector<int> free;
    for (int b = 0; b < static_cast<int>(blocks.size()); ++b) {
      const int n = problem.ParameterBlockSize(blocks[b]);
      for (int k = 0; k < n; ++k) {
        const int i = sums.offset[b] + k;
        const double value = blocks[b][k], g = sums.gradient[i];
        const bool at_lower =
            (blocks[b] == ambient || blocks[b] == ks || blocks[b] == log_n) && value <= 0 && g > 0;
        const bool at_upper = blocks[b] == log_n && value >= std::log(8192.0) && g < 0;
        if (!at_lower && !at_upper) free.push_back(i);
      }
    }
    Eigen::MatrixXd h(free.size(), free.size());
    Eigen::VectorXd g(free.size());
    for (std::size_t a = 0; a < free.size(); ++a) {
      g[a] = sums.gradient[free[a]];
      for (std::size_t b = 0; b < free.size(); ++b) h(a, b) = sums.hessian(free[a], free[b]);
    }
    const double decrement =
        size == 0 || free.empty() ? 0.0 : 0.5 * g.dot(h.completeOrthogonalDecomposition().solve(g));
    // The Gauss–Newton step's length in standard errors: δᵀHδ/σ̂² with δ = H⁻¹g, σ̂² = 2·cost/m.
    const double step_se = std::sqrt(2 * decrement / (2 * sums.cost / observations + 1e-300));
    if (step_se > 0.05) {
      ceres::Solver::Options options;
      options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
      options.max_num_iterations = 50;
      options.num_threads = ResolveThreads(threads);
      ceres::Solver::Summary summary;
      ceres::Solve(options, &problem, &summary);
      fit.iterations = static_cast<int>(summary.iterations.size());
      fit.converged = summary.termination_type == ceres::CONVERGENCE;
      sums = SumJacobians(problem, blocks, threads);
    } else {
      fit.converged = true;  // the profile fit's optimum; no Ceres iteration needed
    }
  }

  c->ambient = Vec3d(ambient[0], ambient[1], ambient[2]);
  c->ks = specular ? Vec3d(ks[0], ks[1], ks[2]) : Vec3d::Zero();
  c->shininess = specular ? std::exp(log_n[0]) : 0;
  if (eliminate_kd) {
    const Coefficients albedo = internal::AlbedoFit(s, lobe, c->ambient, c->ks, c->shininess, used);
    c->kd = albedo.kd;
    c->kd_known = albedo.kd_known;
  } else {
    for (int g = 0; g < s.groups; ++g) c->kd[g] = Vec3d(kd[g][0], kd[g][1], kd[g][2]);
  }
  c->rss = Rss(s, lobe, *c, used);

  std::size_t albedos = 0;
  for (int g = 0; g < s.groups; ++g) albedos += c->kd_known[g];
  fit.parameters = 3 * albedos + (specular ? 7 : 3);
  fit.observations = observations;
  fit.rss = c->rss;
  fit.sigma = observations > fit.parameters
                  ? std::sqrt(c->rss / static_cast<double>(observations - fit.parameters))
                  : NAN;
  fit.bic = observations * std::log(std::max(c->rss, 1e-300) / observations) +
            fit.parameters * std::log(static_cast<double>(observations));

  // The covariance of the free blocks: σ̂² H⁻¹ with H = JᵀJ from the Jacobian pass. It is what
  // ceres::Covariance computes, but its dense SVD of the whole m × 7 Jacobian (4.5 million rows
  // on DiLiGenT's ball) took 60 % of the run; H is 7 × 7. Rank deficient (H's reciprocal
  // condition number below 1e-14): no standard errors.
  const int size = static_cast<int>(sums.gradient.size());
  const std::vector<int>& offset = sums.offset;
  const Eigen::MatrixXd& hessian = sums.hessian;
  const Eigen::MatrixXd& meat = sums.meat;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(hessian, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd singular = svd.singularValues();
  fit.covariance_ok = std::isfinite(fit.sigma) && size > 0 && singular[size - 1] > 0 &&
                      singular[size - 1] / singular[0] > 1e-14;
  if (fit.covariance_ok) {
    const Eigen::MatrixXd cov =
        svd.matrixV() * singular.cwiseInverse().asDiagonal() * svd.matrixU().transpose();
    const Eigen::MatrixXd sandwich = cov * meat * cov;
    const double var = fit.sigma * fit.sigma;
    auto se = [&](int i) { return std::sqrt(var * cov(i, i)); };
    auto robust = [&](int i) { return std::sqrt(sandwich(i, i)); };
    for (int i = 0; i < 3; ++i) fit.ambient_se[i] = se(i), fit.ambient_robust_se[i] = robust(i);
    if (specular) {
      for (int i = 0; i < 3; ++i) fit.ks_se[i] = se(3 + i), fit.ks_robust_se[i] = robust(3 + i);
    }
    if (lobe_seen) {
      for (int i = 0; i < 3; ++i) {
        // The correlation is unchanged by n = exp(log n) to first order.
        fit.ks_shininess_correlation[i] = cov(3 + i, 6) / std::sqrt(cov(3 + i, 3 + i) * cov(6, 6));
      }
      fit.shininess_se = c->shininess * se(6);  // the delta method
      fit.shininess_robust_se = c->shininess * robust(6);
    }
    fit.kd_se.assign(s.groups, Vec3d::Constant(NAN));
    for (std::size_t b = 0; b < kd_block_group.size(); ++b) {
      const int at = offset[blocks.size() - kd_block_group.size() + b];
      for (int i = 0; i < 3; ++i) fit.kd_se[kd_block_group[b]][i] = se(at + i);
    }
    if (eliminate_kd) fit.kd_se.clear();
  }
  fit.ambient_term = c->ambient;
  fit.ks = c->ks;
  fit.shininess = c->shininess;
  fit.kd = c->kd;
  return fit;
}

}  // namespace iphong::material::internal
