// Is the per-pixel model test's standard error right? The test (solve/normals.cc) gives a pixel
// to Lambert where Lambert's held-out cost is lower than the object's model's by more than
// kPixelModelSignificance standard errors of the per-light paired difference, the K differences
// taken as independent (PairedDifference). Under leave-one-out (24 lights or fewer) they come from
// K fits sharing K − 2 of their K − 1 training lights.
//
// Many captures of one pixel go through the solver's own test (tests/solve/pixel_test_probe.h);
// a calibrated standard error is, in root mean square over the captures, the spread of their mean
// differences: the table gives spread / error as PairedDifference states it and as the test scales
// it under leave-one-out by Nadeau and Bengio's correction for overlapping training sets, √(1 +
// K/(K − 1)) (LeaveOneOutErrorScale).
//
//   pixel_test_calibration [DRAWS [LIGHTS...]]     (default 1000 draws; 12 24 48 96 lights)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "solve/pixel_test_probe.h"

using namespace iphong;
using namespace iphong::solve;
using namespace iphong::solve::test_data;

int main(int argc, char** argv) {
  const int draws = argc > 1 ? std::stoi(argv[1]) : 1000;
  std::vector<int> counts;
  for (int i = 2; i < argc; ++i) counts.push_back(std::stoi(argv[i]));
  if (counts.empty()) counts = {12, 24, 48, 96};
  struct Truth {
    const char* name;
    reflectance::Lobe lobe;
    double shininess, kd, ks;
  };
  const Truth truths[] = {
      {"lambert", reflectance::Lobe::kLambert, 1, 1.0, 0.0},
      {"blinn n20 ks0.3", reflectance::Lobe::kBlinnPhong, 20, 0.7, 0.3},
      {"blinn n80 ks0.5", reflectance::Lobe::kBlinnPhong, 80, 0.5, 0.5},
  };
  std::mt19937_64 rng(20261129);
  std::printf(
      "| pixel | tilt | K | noise | tested | mean diff | spread | stated SE | spread/stated "
      "| spread/scaled | Lambert takes |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k : counts) {
    double ratio_stated = 0, ratio_scaled = 0;
    int cases = 0;
    for (const Truth& truth : truths) {
      for (double tilt : {0.0, 30.0}) {
        for (double noise : {0.01, 0.03}) {
          ProbeCase c;
          c.truth = truth.lobe;
          c.shininess = truth.shininess;
          c.kd = truth.kd;
          c.ks = truth.ks;
          c.tilt_deg = tilt;
          c.lights = k;
          c.noise = noise;
          const auto r = Probe(c, draws, rng);
          if (r.tested < 20 || !(r.stated > 0)) {
            std::printf("| %s | %.0f | %d | %.2f | %d | (too few tested) |||||||\n", truth.name,
                        tilt, k, noise, r.tested);
            continue;
          }
          ratio_stated += r.spread / r.stated;
          ratio_scaled += r.spread / r.scaled;
          ++cases;
          std::printf(
              "| %s | %.0f | %d | %.2f | %d | %+.4f | %.4f | %.4f | %.2f | %.2f | %.1f %% |\n",
              truth.name, tilt, k, noise, r.tested, r.mean, r.spread, r.stated, r.spread / r.stated,
              r.spread / r.scaled, 100 * r.lambert);
        }
      }
    }
    if (cases > 0) {
      std::printf("| **mean of %d cases** | | %d | | | | | | **%.2f** | **%.2f** | |\n", cases, k,
                  ratio_stated / cases, ratio_scaled / cases);
    }
  }
  return 0;
}
