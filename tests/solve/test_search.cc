// The global search over candidate normals (solve/search.h): no pixel left in a wrong basin, and
// the table's shortcuts equal the direct computation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "solve/heldout_internal.h"
#include "solve/internal.h"
#include "solve/metrics.h"
#include "solve/model_choice.h"
#include "solve/normals.h"
#include "solve/search.h"
#include "solve/search_lanes.h"
#include "synthetic_spheres.h"

namespace iphong::solve {
namespace {

using test_data::Known;
using test_data::MakeSphereData;
using test_data::Plastic;
using test_data::Synthetic;

// Red albedo under a broad white lobe, 12 lights: highlights pull Woodham's start into a wrong
// basin for a few percent of the pixels (4% ended more than 10° off when the fit started there).
// The global search starts every pixel in the right one: no pixel is off by more than 0.1°.
TEST(Normals, GlobalSearchLeavesNoPixelInAWrongBasin) {
  reflectance::Material red;
  red.kd = Vec3d(0.9, 0.2, 0.1);
  red.ks = Vec3d(0.5, 0.5, 0.4);
  red.shininess = 10;
  const Synthetic s = MakeSphereData(red, 12, 0.0, Vec3d::Zero(), 128);
  const AngularErrorMetrics e = CompareNormals(
      EstimateNormals(s.data, Known(red, Vec3d::Zero())).normals, s.out.normal_cam, s.out.mask);
  double worst = 0;
  for (std::size_t p = 0; p < s.out.mask.inside.size(); ++p) {
    if (s.out.mask.inside[p]) worst = std::max<double>(worst, e.error_deg.pixels[p]);
  }
  RecordProperty("mean_deg", std::to_string(e.mean_deg));
  RecordProperty("worst_deg", std::to_string(worst));
  EXPECT_LT(e.mean_deg, 0.01);
  EXPECT_LT(worst, 0.1);
}

// A search takes its sums from the table (over every light, or a fold's training lights) less
// the few lights it leaves out; it must choose what summing over its usable lights directly does.
// Pixels of a Phong sphere with a fold held out, some lights saturated, or both.
TEST(Normals, SearchSumsFromFoldTablesEqualDirectSums) {
  const Synthetic s = MakeSphereData(Plastic(), 48, 0.002);
  std::vector<int> fold(48);
  for (int j = 0; j < 48; ++j) fold[j] = (j * 7) % 3;
  reflectance::ModelOptions model;
  const CandidateTable with_folds(s.data.light_directions, model, 20, 1000, fold);
  const CandidateTable plain(s.data.light_directions, model, 20, 1000);
  ASSERT_EQ(with_folds.folds(), 3);
  ASSERT_EQ(plain.folds(), 0);
  NormalSearch a(with_folds), b(plain);
  std::vector<double> y(48), usable(48);
  int compared = 0;
  for (std::size_t p = 0; p < s.data.pixel_count(); p += 37) {
    const float* obs = s.data.pixel(p);
    for (int j = 0; j < 48; ++j) {
      y[j] = internal::Luminance(Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]));
    }
    for (int held_out = -1; held_out < 3; ++held_out) {
      for (const bool saturated : {false, true}) {
        for (int j = 0; j < 48; ++j) {
          usable[j] = fold[j] == held_out || (saturated && (j + p) % 11 == 0) ? 0.0 : 1.0;
        }
        const SearchResult x = a.Search(y.data(), usable.data(), 0.01, nullptr);
        const SearchResult z = b.Search(y.data(), usable.data(), 0.01, nullptr);
        ASSERT_EQ(x.candidate, z.candidate) << "pixel " << p << " fold " << held_out;
        ASSERT_NEAR(x.cost, z.cost, 1e-9 + 1e-6 * z.cost);
        ASSERT_NEAR(x.kd, z.kd, 1e-6 * (1 + z.kd));
        ASSERT_NEAR(x.ks, z.ks, 1e-6 * (1 + z.ks));
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 1000);
}

// The search's lane kernels (search_lanes.h) against a plain loop over lanes and lights doing the
// same float operations in the same order: bitwise equal, for the baseline build and, where the
// processor has it, the AVX2 one (which the search then runs).
TEST(Normals, LaneKernelsEqualAPlainLoopBitwise) {
  constexpr int W = internal::kLanes, K = 23;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> d(K * W), s(K * W), y(K), kd(W), ks(W);
  std::vector<int> lit;
  for (int j = 0; j < K; ++j) {
    if (j % 5 != 3) lit.push_back(j);  // some lights unusable
    y[j] = j % 7 == 0 ? 0.0f : u(rng);
    for (int i = 0; i < W; ++i) {
      d[j * W + i] = (i + j) % 4 == 0 ? 0.0f : u(rng);
      s[j * W + i] = (i * j) % 3 == 0 ? 0.0f : u(rng) * u(rng);
    }
  }
  for (int i = 0; i < W; ++i) kd[i] = u(rng), ks[i] = u(rng) * 0.5f;
  const float floor = -0.1f;
  const int n = static_cast<int>(lit.size());
  // The reference, lane by lane.
  float a_ref[W] = {}, b_ref[W] = {}, cost_ref[W] = {}, clipped_ref[W] = {}, sums_ref[5 * W] = {};
  std::vector<float> weights_ref(K * W, 0.5f);  // "before": every weight changes
  float changed_ref[W] = {};
  for (int i = 0; i < W; ++i) {
    for (const int j : lit) {
      a_ref[i] += y[j] * d[j * W + i];
      b_ref[i] += y[j] * s[j * W + i];
      const float r = y[j] - kd[i] * d[j * W + i] - ks[i] * s[j * W + i];
      clipped_ref[i] += floor - r > 0 ? floor - r : 0.0f;
      const float kept = r > floor ? r : floor;
      cost_ref[i] += kept * kept;
      const float w = r >= floor ? 1.0f : 0.0f;
      const float change = w - weights_ref[j * W + i];
      changed_ref[i] += change > 0 ? change : -change;
      weights_ref[j * W + i] = w;
      const float wd = w * d[j * W + i], ws = w * s[j * W + i];
      sums_ref[i] += wd * d[j * W + i];
      sums_ref[W + i] += wd * s[j * W + i];
      sums_ref[2 * W + i] += ws * s[j * W + i];
      sums_ref[3 * W + i] += wd * y[j];
      sums_ref[4 * W + i] += ws * y[j];
    }
  }
  std::vector<const internal::LaneKernels*> variants = {&internal::BaselineLaneKernels()};
  if (internal::Avx2LaneKernels()) variants.push_back(internal::Avx2LaneKernels());
  const auto same = [](const float* x, const float* y, int count) {
    return std::memcmp(x, y, count * sizeof(float)) == 0;
  };
  for (const internal::LaneKernels* v : variants) {
    float a[W], b[W], cost[W], clipped[W], sums[5 * W], changed[W];
    v->product(d.data(), s.data(), true, lit.data(), n, y.data(), a, b);
    EXPECT_TRUE(same(a, a_ref, W) && same(b, b_ref, W)) << v->name;
    v->cost(d.data(), s.data(), true, lit.data(), n, y.data(), kd.data(), ks.data(), floor, cost,
            clipped);
    EXPECT_TRUE(same(cost, cost_ref, W) && same(clipped, clipped_ref, W)) << v->name;
    std::vector<float> weights(K * W, 0.5f);
    v->weighted_sums(d.data(), s.data(), lit.data(), n, y.data(), kd.data(), ks.data(), floor,
                     weights.data(), sums, cost, changed);
    EXPECT_TRUE(same(sums, sums_ref, 5 * W)) << v->name;
    EXPECT_TRUE(same(cost, cost_ref, W) && same(changed, changed_ref, W)) << v->name;
    EXPECT_TRUE(same(weights.data(), weights_ref.data(), K * W)) << v->name;
  }
  RecordProperty("variants", static_cast<int>(variants.size()));
}

// The packing kernel (LaneKernels::pack) is a transpose: out[j·W + i] = rows[i][j], for light
// counts with and without a whole number of 8-light steps, rows apart in memory.
TEST(Normals, PackedBlocksAreTheRowsTransposed) {
  constexpr int W = internal::kLanes;
  std::vector<const internal::LaneKernels*> variants = {&internal::BaselineLaneKernels()};
  if (internal::Avx2LaneKernels()) variants.push_back(internal::Avx2LaneKernels());
  for (const int k : {3, 8, 19, 96}) {
    std::vector<float> table(W * (k + 5));
    for (std::size_t e = 0; e < table.size(); ++e) table[e] = 0.25f * e + 1;
    const float* rows[W];
    for (int i = 0; i < W; ++i) rows[i] = table.data() + ((5 * i) % W) * (k + 5) + i % 3;
    for (const internal::LaneKernels* v : variants) {
      std::vector<float> out(k * W, -1.0f);
      v->pack(rows, k, out.data());
      int wrong = 0;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < W; ++i) wrong += out[j * W + i] != rows[i][j];
      EXPECT_EQ(wrong, 0) << v->name << ", " << k << " lights";
    }
  }
}

// The fused screening kernel (LaneKernels::score) against the search's steps done one by one
// with scalar code: Σ y d and Σ y s in float, Σ d², Σ d s, Σ s² in double — from a base less the
// excluded lights' terms, or over the lit lights — internal::NonNegativePair, then the censored
// cost at the pair rounded to float. Bitwise, with and without a lobe, a prior and a fixed ks.
TEST(Normals, FusedScreeningEqualsItsStepsBitwise) {
  constexpr int W = internal::kLanes, K = 19;
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> d(K * W), s(K * W), y(K);
  std::vector<int> lit, excluded;
  for (int j = 0; j < K; ++j) {
    (j % 6 == 2 ? excluded : lit).push_back(j);
    y[j] = j % 5 == 0 ? 0.02f * u(rng) : u(rng);
    for (int i = 0; i < W; ++i) {
      d[j * W + i] = (i + 2 * j) % 5 == 0 ? 0.0f : u(rng);
      s[j * W + i] = (i * j) % 4 == 1 ? 0.0f : std::pow(u(rng), 6.0f);
    }
  }
  // A base over every light, as the table keeps it (double sums of the float factors).
  double base[3 * W] = {};
  for (int i = 0; i < W; ++i) {
    for (int j = 0; j < K; ++j) {
      const double di = d[j * W + i], si = s[j * W + i];
      base[i] += di * di, base[W + i] += di * si, base[2 * W + i] += si * si;
    }
  }
  const auto bits = [](const void* p, const void* q, std::size_t n) {
    return std::memcmp(p, q, n) == 0;
  };
  std::vector<const internal::LaneKernels*> variants = {&internal::BaselineLaneKernels()};
  if (internal::Avx2LaneKernels()) variants.push_back(internal::Avx2LaneKernels());
  const double fixed = 0.3;
  for (const bool lobe : {true, false}) {
    for (const bool from_base : {true, false}) {
      for (const int settings : {0, 1, 2}) {  // no prior, a prior, a fixed ks
        internal::PairSettings pair;
        pair.ridge = internal::kKsRidge;
        if (settings == 1) pair.prior_weight = 0.7, pair.prior_ks = 0.2;
        if (settings == 2) pair.fixed_ks = &fixed;
        const float floor = -0.05f;
        internal::BlockScore ref;
        for (int i = 0; i < W; ++i) {
          float a = 0, b = 0;
          for (const int j : lit) a += y[j] * d[j * W + i];
          if (lobe)
            for (const int j : lit) b += y[j] * s[j * W + i];
          double dd = 0, dx = 0, ss = 0;
          if (from_base) dd = base[i], dx = base[W + i], ss = base[2 * W + i];
          for (const int j : from_base ? excluded : lit) {
            const double sign = from_base ? -1.0 : 1.0, di = d[j * W + i], si = s[j * W + i];
            dd += sign * di * di, dx += sign * di * si, ss += sign * si * si;
          }
          if (pair.fixed_ks) {
            ref.kd[i] = dd > 1e-12 ? std::max(0.0, (a - fixed * dx) / dd) : 0.0;
            ref.ks[i] = fixed;
          } else {
            const internal::CoefficientPair<double> c = internal::NonNegativePair<double>(
                dd, dx, ss, a, b, pair.prior_weight, pair.prior_ks, pair.ridge);
            ref.kd[i] = c.kd, ref.ks[i] = c.ks;
          }
          const float kd = static_cast<float>(ref.kd[i]), ks = static_cast<float>(ref.ks[i]);
          float cost = 0, clipped = 0;
          for (const int j : lit) {
            float r = y[j] - kd * d[j * W + i];
            if (lobe) r -= ks * s[j * W + i];
            clipped += floor - r > 0 ? floor - r : 0.0f;
            const float kept = r > floor ? r : floor;
            cost += kept * kept;
          }
          ref.cost[i] = cost, ref.clipped[i] = clipped;
        }
        for (const internal::LaneKernels* v : variants) {
          internal::BlockScore out;
          v->score(d.data(), s.data(), lobe, lit.data(), static_cast<int>(lit.size()), y.data(),
                   from_base ? base : nullptr, excluded.data(), static_cast<int>(excluded.size()),
                   pair, floor, &out);
          EXPECT_TRUE(bits(out.kd, ref.kd, sizeof ref.kd) && bits(out.ks, ref.ks, sizeof ref.ks))
              << v->name << " lobe " << lobe << " base " << from_base << " settings " << settings;
          EXPECT_TRUE(bits(out.cost, ref.cost, sizeof ref.cost) &&
                      bits(out.clipped, ref.clipped, sizeof ref.clipped))
              << v->name << " lobe " << lobe << " base " << from_base << " settings " << settings;
        }
      }
    }
  }
}

// score2 and score4 compute blocks side by side: each block's result must be score's on it alone,
// bit for bit, whatever the others hold (distinct factors, one block with a base and one without,
// with and without a lobe, a prior and a fixed ks).
TEST(Normals, ScreeningBlocksSideBySideEqualOneAtATime) {
  constexpr int W = internal::kLanes, K = 13, B = 4;
  std::mt19937 rng(41);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> d(B * K * W), s(B * K * W), y(K);
  std::vector<int> lit, excluded;
  for (int j = 0; j < K; ++j) {
    (j % 5 == 3 ? excluded : lit).push_back(j);
    y[j] = j % 4 == 0 ? 0.02f * u(rng) : u(rng);
  }
  for (std::size_t v = 0; v < d.size(); ++v) {
    d[v] = v % 7 == 0 ? 0.0f : u(rng);
    s[v] = v % 3 == 1 ? 0.0f : std::pow(u(rng), 5.0f);
  }
  std::vector<double> base(B * 3 * W, 0.0);
  for (int q = 0; q < B; ++q) {
    for (int i = 0; i < W; ++i) {
      for (int j = 0; j < K; ++j) {
        const double di = d[(q * K + j) * W + i], si = s[(q * K + j) * W + i];
        base[q * 3 * W + i] += di * di, base[q * 3 * W + W + i] += di * si;
        base[q * 3 * W + 2 * W + i] += si * si;
      }
    }
  }
  std::vector<const internal::LaneKernels*> variants = {&internal::BaselineLaneKernels()};
  if (internal::Avx2LaneKernels()) variants.push_back(internal::Avx2LaneKernels());
  const double fixed = 0.4;
  int compared = 0;
  for (const internal::LaneKernels* v : variants) {
    for (const bool lobe : {true, false}) {
      for (const int settings : {0, 1, 2}) {
        internal::PairSettings pair;
        pair.ridge = internal::kKsRidge;
        if (settings == 1) pair.prior_weight = 0.5, pair.prior_ks = 0.3;
        if (settings == 2) pair.fixed_ks = &fixed;
        const float *dp[B], *sp[B];
        const double* bp[B];
        for (int q = 0; q < B; ++q) {
          dp[q] = d.data() + q * K * W, sp[q] = s.data() + q * K * W;
          bp[q] = q % 2 == 0 ? base.data() + q * 3 * W : nullptr;
        }
        internal::BlockScore one[B], many[B];
        for (int q = 0; q < B; ++q) {
          v->score(dp[q], sp[q], lobe, lit.data(), static_cast<int>(lit.size()), y.data(), bp[q],
                   excluded.data(), static_cast<int>(excluded.size()), pair, -0.05f, &one[q]);
        }
        for (const int blocks : {2, 4}) {
          (blocks == 2 ? v->score2 : v->score4)(
              dp, sp, lobe, lit.data(), static_cast<int>(lit.size()), y.data(), bp, excluded.data(),
              static_cast<int>(excluded.size()), pair, -0.05f, many);
          for (int q = 0; q < blocks; ++q) {
            EXPECT_EQ(std::memcmp(&one[q], &many[q], sizeof one[q]), 0)
                << v->name << " blocks " << blocks << " block " << q << " lobe " << lobe
                << " settings " << settings;
            ++compared;
          }
          // The blocks differ, so a mix-up of their pointers would show.
          EXPECT_NE(std::memcmp(one[0].cost, one[1].cost, sizeof one[0].cost), 0);
        }
      }
    }
  }
  EXPECT_EQ(compared, static_cast<int>(variants.size()) * 2 * 3 * 6);
}

// The lane kernels' 2 × 2 non-negative solve against internal::NonNegativePair, the scalar
// function every other fit calls: bitwise equal in every lane, with and without a prior and with
// a fixed ks, over systems that take each branch (the free solution, either coefficient alone,
// none, a singular or a nearly collinear system).
TEST(Normals, LanePairEqualsNonNegativePairBitwise) {
  constexpr int W = internal::kLanes;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<const internal::LaneKernels*> variants = {&internal::BaselineLaneKernels()};
  if (internal::Avx2LaneKernels()) variants.push_back(internal::Avx2LaneKernels());
  const auto bits_equal = [](double p, double q) { return std::memcmp(&p, &q, sizeof p) == 0; };
  int branches[4] = {0, 0, 0, 0};  // free, kd alone, ks alone, neither
  for (int trial = 0; trial < 4000; ++trial) {
    double sums[5 * W];
    for (int i = 0; i < W; ++i) {
      // Factors of a few lights, so D, X, S are a real Gram matrix; then the kind of system.
      double d = 0, x = 0, s = 0, a = 0, b = 0;
      const int kind = (trial * W + i) % 7;
      for (int j = 0; j < 5; ++j) {
        const double dj = kind == 6 ? 0.0 : u(rng);
        const double sj = kind == 2 ? 0.0 : kind == 3 ? 0.7 * dj : u(rng) * u(rng);
        const double yj = kind == 4 ? -u(rng) : u(rng);
        d += dj * dj, x += dj * sj, s += sj * sj, a += dj * yj, b += sj * yj;
      }
      if (kind == 5) b = -b;  // the lobe's correlation negative: kd alone
      sums[i] = d, sums[W + i] = x, sums[2 * W + i] = s, sums[3 * W + i] = a, sums[4 * W + i] = b;
    }
    const double prior_weight = trial % 3 == 0 ? 0.0 : u(rng), prior_ks = u(rng);
    const double fixed = u(rng);
    for (const internal::LaneKernels* v : variants) {
      for (const bool with_fixed : {false, true}) {
        double kd[W], ks[W];
        v->pair(sums, prior_weight, prior_ks, internal::kKsRidge, with_fixed ? &fixed : nullptr, kd,
                ks);
        for (int i = 0; i < W; ++i) {
          const double d = sums[i], x = sums[W + i], a = sums[3 * W + i];
          double kd_ref = 0, ks_ref = fixed;
          if (with_fixed) {
            kd_ref = d > 1e-12 ? std::max(0.0, (a - fixed * x) / d) : 0.0;
          } else {
            const internal::CoefficientPair<double> c = internal::NonNegativePair(
                d, x, sums[2 * W + i], a, sums[4 * W + i], prior_weight, prior_ks);
            kd_ref = c.kd, ks_ref = c.ks;
            ++branches[(c.kd > 0 && c.ks > 0) ? 0 : c.kd > 0 ? 1 : c.ks > 0 ? 2 : 3];
          }
          ASSERT_TRUE(bits_equal(kd[i], kd_ref) && bits_equal(ks[i], ks_ref))
              << v->name << " trial " << trial << " lane " << i << ": " << kd[i] << " " << ks[i]
              << " against " << kd_ref << " " << ks_ref;
        }
      }
    }
  }
  for (int branch = 0; branch < 4; ++branch) EXPECT_GT(branches[branch], 100) << branch;
}

// Each fine candidate of the search's table belongs to its nearest coarse direction, exactly as
// comparing it with every coarse direction finds (the table compares only a band of z).
TEST(Normals, CandidateTableGroupsEachDirectionWithItsNearestCoarseOne) {
  const std::vector<Vec3d> lights = {Vec3d(0, 0, 1), Vec3d(0.6, 0, 0.8), Vec3d(0, 0.6, 0.8)};
  for (int count : {16, 100, 1000, 4097, 16384}) {
    const CandidateTable table(lights, reflectance::ModelOptions{}, 10, count);
    const std::vector<Vec3d> coarse = HemisphereDirections(std::max(4, count / 4));
    ASSERT_EQ(table.size(), count + static_cast<int>(coarse.size()));
    std::vector<int> owner(count, -1);
    for (int c = table.fine_count(); c < table.size(); ++c) {
      for (int f : table.members(c)) owner[f] = c - table.fine_count();
    }
    for (int f = 0; f < count; ++f) {
      const Vec3d& n = table.normal(f);
      int nearest = 0;
      for (int c = 1; c < static_cast<int>(coarse.size()); ++c)
        if (coarse[c].dot(n) > coarse[nearest].dot(n)) nearest = c;
      ASSERT_EQ(owner[f], nearest) << "count " << count << ", fine direction " << f;
    }
  }
}

// The per-pixel test's fold searches run near the pixel's all-lights answer
// (internal::PreparePixelTestSearch). Under leave-one-out a fold keeps all lights but one, and
// its search scores only the best few coarse directions' members and refits the best few of
// them. On noisy spheres under 12 lights, glossy and matte, nearly every fold's winner is the
// one the wide search finds (93 % and 97 %), and the test gives 97 % of the pixels it tests the
// model it gave before, Lambert about as many (17 → 18 glossy, 17 → 20 matte). With two folds
// (48 lights) nothing is narrowed: the same winners, decisions and costs.
TEST(Normals, PixelTestFoldSearchesStayNearTheAllLightsAnswer) {
  reflectance::Material matte = Plastic();
  matte.ks.setZero();
  for (const int lights : {12, 48}) {
    for (const reflectance::Material& material : {Plastic(), matte}) {
      const Synthetic s = MakeSphereData(material, lights, 0.005);
      const std::vector<int> fold = LightFolds(lights);
      reflectance::ModelOptions model, lambert;
      lambert.lobe = reflectance::Lobe::kLambert;
      const CandidateTable table(s.data.light_directions, model, 20, 1000, fold);
      const CandidateTable lambert_table(s.data.light_directions, lambert, 1, 1000, fold);
      NormalSearch wide(table), narrow(table), wide_lambert(lambert_table),
          narrow_lambert(lambert_table);
      internal::PreparePixelTestSearch(narrow, table);
      internal::PreparePixelTestSearch(narrow_lambert, lambert_table);
      std::vector<double> y(lights), usable(lights, 1.0), training(lights), buffer,
          lambert_cost(lights), model_cost(lights);
      int folds = 0, same = 0, tested = 0, agree = 0, lambert_wide = 0, lambert_narrow = 0;
      double mean_wide = 0, mean_narrow = 0;
      const double t = 0.01;
      for (std::size_t p = 0; p < s.data.pixel_count(); p += 5) {
        const float* obs = s.data.pixel(p);
        for (int j = 0; j < lights; ++j) {
          y[j] = internal::Luminance(Vec3d(obs[3 * j], obs[3 * j + 1], obs[3 * j + 2]));
        }
        const SearchResult a = wide.Search(y.data(), usable.data(), t, nullptr);
        const SearchResult b = narrow.Search(y.data(), usable.data(), t, nullptr);
        ASSERT_EQ(a.candidate, b.candidate);  // the full search is not narrowed
        if (a.candidate < 0) continue;
        for (int f = 0; f < table.folds(); ++f) {
          for (int j = 0; j < lights; ++j) training[j] = fold[j] == f ? 0.0 : 1.0;
          same += wide.Search(y.data(), training.data(), t, nullptr, true).candidate ==
                  narrow.Search(y.data(), training.data(), t, nullptr, true).candidate;
          ++folds;
        }
        const double brightness = *std::max_element(y.begin(), y.end());
        const auto test = [&](NormalSearch& search, NormalSearch& lambert_search) {
          const SearchResult r = search.Search(y.data(), usable.data(), t, nullptr);
          return internal::TestPixelModel(search, table, r, lambert_search, lambert_table, y.data(),
                                          usable.data(), t, brightness, fold.data(), buffer,
                                          lambert_cost.data(), model_cost.data());
        };
        const internal::PixelModelTest x = test(wide, wide_lambert);
        const internal::PixelModelTest z = test(narrow, narrow_lambert);
        if (!x.tested) continue;
        ++tested;
        agree += x.lambert == z.lambert;
        lambert_wide += x.lambert;
        lambert_narrow += z.lambert;
        mean_wide += x.mean, mean_narrow += z.mean;
      }
      std::printf(
          "%d lights, %s: %d of %d fold winners the same; %d of %d tested pixels keep "
          "their model (Lambert %d, narrowed %d); Lambert's excess held-out cost %.4f wide, %.4f "
          "narrowed\n",
          lights, material.ks.isZero() ? "matte" : "glossy", same, folds, agree, tested,
          lambert_wide, lambert_narrow, mean_wide / std::max(tested, 1),
          mean_narrow / std::max(tested, 1));
      ASSERT_GT(tested, 150);
      if (lights == 48) {
        EXPECT_EQ(same, folds);
        EXPECT_EQ(agree, tested);
        EXPECT_EQ(mean_narrow, mean_wide);
      } else {
        EXPECT_LT(same, folds);  // narrowed: a few winners lie farther out
        EXPECT_GT(same, 0.9 * folds);
        EXPECT_GT(agree, 0.97 * tested);
      }
    }
  }
}

}  // namespace
}  // namespace iphong::solve
