// Shared by the integration methods; not part of the public header.
#pragma once

#include <vector>

#include "integrate/integrate.h"

namespace iphong::integrate::internal {

// IntegrateNormals' refusals (std::invalid_argument, one line): channels, sizes, an empty mask,
// non-finite or non-unit normals inside it, more back-facing ones than allowed. Returns the
// number of back-facing normals.
std::size_t CheckInputs(const ImageF& normals, const Mask& mask, const IntegrateOptions& options);

// Least-squares solution f (row-major, full grid, zero mean) of the edge equations
// f_b − f_a = (g_a + g_b)/2 over every pair of 4-neighbours of the rectangle, unit weights
// (gradients outside the mask are 0). Natural boundary conditions (DCT-II; odd sizes through
// the DFT of the mirrored field, as OpenCV's DCT takes even sizes only).
std::vector<double> SolveRectangleNeumann(const GridGradients& g);
// The same on the torus (Frankot–Chellappa): the last column pairs with the first, the last
// row with the first.
std::vector<double> SolveRectanglePeriodic(const GridGradients& g);

struct SparseOutcome {
  std::vector<double> f;  // per masked pixel, in mask order
  ImageF continuity;      // see IntegrateResult
  int components = 0;
  int rounds = 0;
  long long iterations = 0;
  double rms_residual = 0;
  std::size_t cut_edges = 0, separated_pixels = 0;  // bilateral only
  std::size_t memory_bytes = 0;
  std::string solver;
};

// The masked least-squares problem (kQuadratic), or its reweighted version (bilateral). The
// prior, if any, is per masked pixel (NaN = none), already in the integrated unit.
SparseOutcome SolveMasked(const GridGradients& g, const Mask& mask,
                          const std::vector<double>& prior, const IntegrateOptions& options,
                          bool bilateral);

}  // namespace iphong::integrate::internal
