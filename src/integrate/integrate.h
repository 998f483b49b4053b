// Heights from normals: integration of the gradient field a normal map implies.
//
// Frame and pixels (SPEC.md): camera frame x right, y up, z toward the viewer; row 0 is the top
// row. For the orthographic camera a unit normal n gives the slopes
//     p = ∂z/∂x = −nx/nz,   q = ∂z/∂y = −ny/nz,
// and the height z is in pixel units (times `pixel_size` when one is given). Because rows grow
// downward, ∂z/∂row = −q. For a perspective camera (intrinsics fx, fy, cx, cy in pixels, pixel
// centres at col + 0.5, row + 0.5) the integrated quantity is log depth, depth being the
// distance along the optical axis: with ũ = u − cx, ṽ = v − cy and D = nx·ũ/fx − ny·ṽ/fy − nz,
//     ∂log d/∂u = −(nx/fx)/D,   ∂log d/∂v = (ny/fy)/D.
// Near occluding boundaries nz (or −D/|ray|) → 0 and the slopes blow up: the cosine between the
// normal and the viewing ray is clamped to `min_cos`, and edges are weighted by it.
//
// Every method solves the same discrete problem: for each pair of 4-neighbours a, b inside the
// mask, f_b − f_a should equal the mean of their one-sided slopes (forward difference from a,
// backward from b). Least squares over the mask gives a weighted graph Laplacian system:
//  - kQuadratic: on the masked pixels only (any mask shape, holes, several parts), solved with
//    Eigen's sparse solvers;
//  - kDct: on the full rectangle with natural boundary conditions (Simchony et al.), diagonalised
//    by the DCT-II: the exact least-squares solution in O(N log N); gradients outside the mask
//    are taken as 0;
//  - kFft: Frankot–Chellappa, the same on a periodic domain through the DFT;
//  - kBilateral: discontinuity-preserving, in the spirit of bilateral normal integration (Cao et
//    al. 2022): each one-sided equation gets a weight σ(k·(r_other² − r_own²)) from the current
//    residuals, so an edge whose both sides disagree with the surface (a depth step) is cut;
//    iteratively reweighted until the energy settles. Creases are not cut: an edge whose rise
//    f_b − f_a lies between its two one-sided slopes (where any continuous surface puts it)
//    keeps the quadratic weights, unless a side falls away toward it as at an occluding
//    contour (its cosine to the view dropping by √2 or more over that pixel, or clamped).
// The offset is fixed so the masked mean height (each connected part separately) is 0, or the
// depth prior fixes it. Outside the mask the height is NaN.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/types.h"

namespace iphong::integrate {

enum class Method { kAuto, kQuadratic, kDct, kFft, kBilateral };
// For the sparse methods. kAuto = kConjugateGradient: CG preconditioned by an aggregation
// multigrid V-cycle (integrate/multigrid.h); kCholesky: CHOLMOD's (else Eigen's) factorization.
enum class LinearSolver { kAuto, kConjugateGradient, kCholesky };

// "auto", "quadratic", "dct", "fft", "bilateral"; throws std::invalid_argument otherwise.
Method ParseMethod(const std::string& name);
const char* MethodName(Method method);

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
};

struct IntegrateOptions {
  // kAuto: kDct when the mask is the whole image and nothing else asks for the sparse solver,
  // kQuadratic otherwise.
  Method method = Method::kAuto;
  LinearSolver solver = LinearSolver::kAuto;
  double min_cos = 0.05;  // grazing guard (see above)
  // Normals facing away from the camera (nz ≤ 0) are found at the silhouettes of real normal
  // maps (40 of DiLiGenT cat's 45,000 ground-truth normals; recovered normals tip past 90° there
  // too): up to `max_back_facing` of the mask they count as grazing (and are counted in the
  // summary). More means the map is in another frame (z into the scene?) and is an error unless
  // `allow_back_facing`.
  double max_back_facing = 0.02;
  bool allow_back_facing = false;
  double pixel_size = 1.0;   // orthographic: scene units per pixel
  bool perspective = false;  // integrate log depth with `intrinsics`
  Intrinsics intrinsics;
  // Optional prior (1 channel; NaN or infinite = none at that pixel): heights (orthographic,
  // within ±1e12 pixels) or depths (perspective, 0 < depth ≤ 1e12), pulled on with
  // `prior_weight` per pixel against the unit edge weights.
  ImageF depth_prior;
  double prior_weight = 1e-2;
  // Perspective without prior: the masked geometric mean depth.
  double reference_depth = 1.0;
  // kBilateral
  // k of the sigmoid, in 1/pixel²; in perspective the residuals of log depth are taken times the
  // focal length (pixel widths at that depth), so a step cuts alike under either camera.
  double stiffness = 2.0;
  int max_rounds = 50;
  double energy_tolerance = 1e-4;  // relative energy change that stops the reweighting
  // Iterative linear solver
  double cg_tolerance = 1e-6;  // relative residual norm
  int cg_max_iterations = 5000;
  int threads = 0;
  // Called with the fraction done (0..1) from the calling thread, for long runs' progress.
  std::function<void(double)> progress;

  std::string Validate() const;
};

struct IntegrateSummary {
  bool success = false;
  std::string message;
  Method method = Method::kQuadratic;  // the one that ran
  std::string solver;                  // "dct", "fft", "cholesky", "conjugate-gradient"
  std::size_t pixels = 0;
  int components = 0;                  // connected parts of the mask
  std::size_t back_facing_pixels = 0;  // nz ≤ 0, treated as grazing (allow_back_facing)
  int rounds = 1;                      // reweighting rounds (kBilateral)
  long long iterations = 0;            // linear solver iterations (conjugate gradient), summed
  double setup_seconds = 0;            // gradients and assembly
  double solve_seconds = 0;
  double total_seconds = 0;
  double rms_residual = 0;  // of the edge equations, slope units
  // kBilateral: edges cut (continuity < 0.5), and the pixels the cuts separate from the largest
  // joined piece of their part: how high such a piece sits against the rest is not measured by
  // the normals (only the cut edges' residual weight places it).
  std::size_t cut_edges = 0, separated_pixels = 0;
  std::size_t memory_bytes = 0;  // system matrix, factor and work vectors at their peak
};

struct IntegrateResult {
  // 1 channel, NaN outside the mask: height z (orthographic, toward the viewer, in pixel units
  // × pixel_size) or depth along the optical axis (perspective).
  ImageF height;
  // 2 channels: weight in [0, 1] of the edge to the right and of the edge below (1 = continuous,
  // 0 = cut; 0 where the neighbour is outside the mask). All 1 except for kBilateral.
  ImageF continuity;
  IntegrateSummary summary;
};

// Throws std::invalid_argument with a one-line message on bad input: size mismatch, empty mask,
// NaN or non-unit normals inside the mask, normals facing away from the camera.
IntegrateResult IntegrateNormals(const ImageF& normals_cam, const Mask& mask,
                                 const IntegrateOptions& options);

// The surface's shape without its pixel-level detail, at about 1/factor² of the cost: integrates
// the block means of the normals over factor × factor blocks (a block is in the mask if any of
// its pixels is; pixel_size × factor) and returns heights on the original grid, bilinear between
// the blocks' centres, with mean 0 over each part's pixels. It refuses what IntegrateNormals
// refuses, and perspective or a depth prior (std::invalid_argument); factor ≤ 1 is
// IntegrateNormals. The continuity returned is all 1.
IntegrateResult IntegrateNormalsCoarse(const ImageF& normals_cam, const Mask& mask,
                                       const IntegrateOptions& options, int factor);

// Per-pixel slopes ∂f/∂col and ∂f/∂row (f = height in pixels, or log depth) with the grazing
// guard applied, and the cosine used for weighting. Exposed for tests and the profile integral.
struct GridGradients {
  int width = 0, height = 0;
  std::vector<float> d_col, d_row, cos_view;  // row-major, 0 outside the mask
};
GridGradients GradientsFromNormals(const ImageF& normals_cam, const Mask& mask,
                                   const IntegrateOptions& options);

// Seed 003's line integral: heights along a profile from its normals (Nx, Nz), sampled every
// `step` along x, by the trapezoid rule on the slopes −Nx/Nz. The first height is 0.
std::vector<double> IntegrateProfile(const std::vector<Eigen::Vector2d>& normals_xz, double step);

}  // namespace iphong::integrate
