// Is the per-pixel model test's standard error right? (tests/solve/pixel_test_probe.h: many
// captures of one pixel, each with its own random lights and noise, through the test's own calls.)
// For each case: the spread of the mean paired difference over the captures against the root
// mean square of the standard error each capture stated, as PairedDifference gives it and as the
// test scales it (LeaveOneOutErrorScale under leave-one-out). A calibrated error has ratio ≈ 1;
// above 1 the error is too small and the test overrules the object's model on noise.
//
//   pixel_test_calibration [DRAWS [LIGHTS...]]     (default 1000 draws; 12 24 48 96 lights)
#include <cstdio>
#include <string>
#include <vector>

#include "solve/pixel_test_probe.h"

using namespace iphong;
using solve::test_data::ProbeCase;

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
          const auto r = solve::test_data::Probe(c, draws, rng);
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
