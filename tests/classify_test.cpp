// Log-space k-means of sigma tuples.
#include <gtest/gtest.h>

#include <random>

#include "tools/encoder/classify.h"

namespace stipple {
namespace {

TEST(Classify, FewDistinctTuplesAreExact) {
  std::vector<Vec3> t = {Vec3(3, 2, 1), Vec3(1e-15, 1e-15, 1e-15), Vec3(3, 2, 1), Vec3(0.5, 0.25, 0.1)};
  const Classification c = classify_sigmas(t, 3, 16);
  ASSERT_EQ(c.centers.size(), 3u);
  for (size_t i = 0; i < t.size(); ++i)
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(c.centers[c.index[i]][d], t[i][d], 1e-12 * t[i][d]);
  EXPECT_EQ(c.index[0], c.index[2]);
  EXPECT_LT(c.rms_log_error, 1e-12);
}

TEST(Classify, RecoversSeparatedClustersInLogSpace) {
  // Five clusters, each spread by 1 % around a centre; centres decades apart.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.01);
  const Vec3 centers[5] = {Vec3(1, 0.5, 0.1), Vec3(1e-2, 5e-3, 1e-3), Vec3(1e-4, 1e-4, 1e-6), Vec3(10, 1, 0.01),
                           Vec3(1e-3, 1e-3, 1e-3)};
  std::vector<Vec3> t;
  std::vector<int> truth;
  for (int i = 0; i < 20000; ++i) {
    const int k = i % 5;
    t.push_back(centers[k].cwiseProduct(Vec3(std::exp(jitter(rng)), std::exp(jitter(rng)), std::exp(jitter(rng)))));
    truth.push_back(k);
  }
  const Classification c = classify_sigmas(t, 3, 5);
  ASSERT_EQ(c.centers.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    const Vec3& got = c.centers[c.index[static_cast<size_t>(k)]];
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(std::log(got[d]), std::log(centers[k][d]), 0.01) << k;
  }
  for (size_t i = 0; i < t.size(); ++i) ASSERT_EQ(c.index[i], c.index[static_cast<size_t>(truth[i])]);
  EXPECT_NEAR(c.rms_log_error, 0.01 * std::sqrt(3.0), 0.002);
}

// sigma_n with the curvature's sign: a class never crosses a sign, each
// pattern's classes are its magnitudes' (positive tuples alone: exactly
// SigmaClasses'), the budget is shared by the patterns' counts, and a tuple
// of a pattern the sample lacked takes the nearest pattern's class.
TEST(Classify, SignedClassesNeverCrossASign) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> mag(-6.0, 0.0), coin(0.0, 1.0);
  std::vector<Vec3> t, positive;
  for (int i = 0; i < 20000; ++i) {
    Vec3 v(std::exp(mag(rng)), std::exp(mag(rng)), 0);
    positive.push_back(v);
    const double c = coin(rng);  // patterns ++ 50 %, -+ 25 %, +- 15 %, -- 10 %
    if ((c >= 0.5 && c < 0.75) || c >= 0.9) v[0] = -v[0];
    if (c >= 0.75) v[1] = -v[1];
    t.push_back(v);
  }
  const SignedSigmaClasses classes(t, 2, 100);
  ASSERT_EQ(classes.centers().size(), 100u);
  int per[4] = {};
  for (const Vec3& c : classes.centers()) ++per[(c[0] < 0 ? 1 : 0) | (c[1] < 0 ? 2 : 0)];
  EXPECT_EQ(per[0], 50);
  EXPECT_EQ(per[1], 25);
  EXPECT_EQ(per[2], 15);
  EXPECT_EQ(per[3], 10);
  for (const Vec3& v : t) {
    const Vec3& c = classes.centers()[classes.assign(v)];
    ASSERT_EQ(c[0] < 0, v[0] < 0);
    ASSERT_EQ(c[1] < 0, v[1] < 0);
  }
  const SignedSigmaClasses plain(positive, 2, 64);
  const SigmaClasses unsigned_classes(positive, 2, 64);
  ASSERT_EQ(plain.centers(), unsigned_classes.centers());
  for (size_t i = 0; i < 1000; ++i) ASSERT_EQ(plain.assign(positive[i]), unsigned_classes.assign(positive[i]));
  // Positive classes only: a concave tuple keeps its magnitude's class.
  EXPECT_EQ(plain.assign(Vec3(-0.1, 0.05, 0)), plain.assign(Vec3(0.1, 0.05, 0)));
  // No sample (a scan without normals): no class, every tuple class 0.
  const SignedSigmaClasses none(std::vector<Vec3>{}, 2, 64);
  EXPECT_TRUE(none.centers().empty());
  EXPECT_EQ(none.assign(Vec3(-0.1, 0.05, 0)), 0);
}

TEST(Classify, ScalesAndIsDeterministic) {
  // 300 K two-dimensional tuples into 4096 classes: the kd-tree keeps this fast
  // (n x k brute force would be 1.2e9 distance evaluations per iteration).
  std::mt19937_64 rng(9);
  std::lognormal_distribution<double> spread(-5.0, 1.0);
  std::vector<Vec3> t(300000);
  for (Vec3& v : t) {
    const double a = spread(rng), b = spread(rng);
    v = Vec3(std::max(a, b), std::min(a, b), 0);
  }
  const Classification c1 = classify_sigmas(t, 2, 4096, 5, 2);
  const Classification c2 = classify_sigmas(t, 2, 4096, 5, 1);
  EXPECT_EQ(c1.centers.size(), 4096u);
  EXPECT_EQ(c1.index, c2.index);  // thread count does not matter
  EXPECT_LT(c1.rms_log_error, 0.1);  // 4096 classes over a 2-D log-normal: a few percent
  for (const Vec3& center : c1.centers) EXPECT_EQ(center[2], 0.0);
}

}  // namespace
}  // namespace stipple
