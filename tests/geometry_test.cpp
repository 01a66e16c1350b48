// PCA and degenerate nodes, frame quantization bounds, kd-tree, normals.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <numbers>

#include "core/sobol.h"
#include "test_util.h"
#include "tools/scan/kdtree.h"
#include "tools/encoder/node_stats.h"
#include "tools/encoder/normals.h"
#include "tools/encoder/quantize.h"

namespace stipple {
namespace {

constexpr double kPi = std::numbers::pi;

Mat3 rotation(double a, double b, double c) {
  return (Eigen::AngleAxisd(a, Vec3::UnitZ()) * Eigen::AngleAxisd(b, Vec3::UnitY()) *
          Eigen::AngleAxisd(c, Vec3::UnitX()))
      .toRotationMatrix();
}

double line_angle(const Vec3& a, const Vec3& b) { return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))); }

std::vector<uint32_t> iota_ids(size_t n) {
  std::vector<uint32_t> ids(n);
  for (size_t i = 0; i < n; ++i) ids[i] = static_cast<uint32_t>(i);
  return ids;
}

TEST(Pca, RecoversKnownEllipsoidFarFromOrigin) {
  const Mat3 frame = rotation(0.3, -0.7, 1.1);
  const Vec3 sigma(3.0, 1.0, 0.2);
  const Vec3 mean(1e6, -2e6, 5e5);  // centred sums keep full precision here
  const auto pts = test::gaussian_points(200000, mean, frame, sigma);
  const auto ids = iota_ids(pts.size());
  const Gaussian3 g = pca3(pts.data(), ids.data(), pts.size());
  EXPECT_LT((g.mean - mean).norm(), 0.03);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(g.sigma[k], sigma[k], 0.01 * sigma[k]) << "axis " << k;
    EXPECT_LT(line_angle(g.frame.col(k), frame.col(k)), 0.01) << "axis " << k;
  }
  EXPECT_NEAR(g.frame.determinant(), 1.0, 1e-12);  // right-handed, orthonormal
}

TEST(Pca, NearRepeatedAndVanishingEigenvalues) {
  // Two equal sigmas and a vanishing one: the solver must stay orthonormal and exact.
  const Mat3 frame = rotation(1.0, 0.4, -0.2);
  std::vector<Vec3> pts;
  for (int i = 0; i < 360; ++i) {
    const double a = i * kPi / 180;
    pts.push_back(Vec3(5, 5, 5) + frame * Vec3(std::cos(a), std::sin(a), 0));
  }
  const auto ids = iota_ids(pts.size());
  const Gaussian3 g = pca3(pts.data(), ids.data(), pts.size());
  EXPECT_NEAR(g.sigma[0], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(g.sigma[1], std::sqrt(0.5), 1e-12);
  EXPECT_LT(g.sigma[2], 1e-7);
  EXPECT_LT(line_angle(g.frame.col(2), frame.col(2)), 1e-9);
  EXPECT_NEAR((g.frame.transpose() * g.frame - Mat3::Identity()).norm(), 0, 1e-12);
}

PointCloud cloud_of(const std::vector<Vec3>& pts, const Vec3& normal) {
  PointCloud c;
  c.positions = pts;
  c.normals.assign(pts.size(), normal.normalized());
  return c;
}

TEST(Pca, DegenerateLineTurnsTowardsTheNormal) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 20; ++i) pts.push_back(Vec3(i * 0.1, 0, 0));
  const auto ids = iota_ids(pts.size());
  const PointCloud c = cloud_of(pts, Vec3(0.3, 0, 1));
  const NodeStats s = node_stats(c, ids.data(), ids.size(), StatsOptions{});
  EXPECT_LT(line_angle(s.position.frame.col(0), Vec3::UnitX()), 1e-9);
  // f3 is the normal made perpendicular to the line: +z.
  EXPECT_LT((s.position.frame.col(2) - Vec3::UnitZ()).norm(), 1e-9);
  EXPECT_DOUBLE_EQ(s.position.sigma[1], 1e-15);
  EXPECT_DOUBLE_EQ(s.position.sigma[2], 1e-15);
}

TEST(Pca, DegeneratePlaneOnePointAndCoincidentPoints) {
  std::vector<Vec3> plane;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) plane.push_back(Vec3(i, j, 2));
  auto ids = iota_ids(plane.size());
  NodeStats s = node_stats(cloud_of(plane, Vec3(0, 0, -1)), ids.data(), ids.size(), StatsOptions{});
  EXPECT_LT((s.position.frame.col(2) - Vec3(0, 0, -1)).norm(), 1e-9);  // oriented with the normal
  EXPECT_DOUBLE_EQ(s.position.sigma[2], 1e-15);

  for (size_t n : {size_t{1}, size_t{7}}) {
    const std::vector<Vec3> same(n, Vec3(1, 2, 3));
    ids = iota_ids(n);
    const Vec3 normal = Vec3(1, 1, 0).normalized();
    s = node_stats(cloud_of(same, normal), ids.data(), n, StatsOptions{});
    EXPECT_EQ(s.position.mean, Vec3(1, 2, 3));
    EXPECT_LT((s.position.frame.col(2) - normal).norm(), 1e-12);
    EXPECT_NEAR(s.position.frame.determinant(), 1.0, 1e-12);
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(s.position.sigma[k], 1e-15);
    EXPECT_LT((s.normal_frame.col(2) - normal).norm(), 1e-12);
  }
}

TEST(Pca, NormalSpreadMatchesTheLogMap) {
  // Normals tilted by +-0.2 rad about x: sigma_n1 = 0.2, sigma_n2 = 0.
  PointCloud c;
  for (int i = 0; i < 100; ++i) {
    const double a = (i % 2 ? 0.2 : -0.2);
    c.positions.push_back(Vec3(i, 0, 0));
    c.normals.push_back(Vec3(0, std::sin(a), std::cos(a)));
  }
  const auto ids = iota_ids(100);
  Mat3 frame;
  Vec2 sigma;
  normal_stats(c.normals.data(), ids.data(), 100, Vec3::UnitZ(), frame, sigma);
  EXPECT_NEAR(sigma[0], 0.2, 1e-12);
  EXPECT_LT(sigma[1], 1e-12);
  EXPECT_LT((frame.col(2) - Vec3::UnitZ()).norm(), 1e-12);
  EXPECT_LT(line_angle(frame.col(0), Vec3::UnitY()), 1e-9);
}

// Within 0.1 rad of the mean the log map takes a series instead of atan2:
// the same spread to the last bits that matter, on both sides of the switch.
TEST(Pca, NormalSpreadIsExactEitherSideOfTheSeries) {
  for (const double a : {0.001, 0.05, 0.0999, 0.1001, 0.3}) {
    PointCloud c;
    for (int i = 0; i < 64; ++i) {
      c.positions.push_back(Vec3(i, 0, 0));
      const double t = (i % 2 ? a : -a);
      c.normals.push_back(Vec3(std::sin(t) * 0.6, std::sin(t) * 0.8, std::cos(t)));
    }
    const auto ids = iota_ids(64);
    Mat3 frame;
    Vec2 sigma;
    normal_stats(c.normals.data(), ids.data(), 64, Vec3::UnitZ(), frame, sigma);
    EXPECT_NEAR(sigma[0], a, 4e-16 * std::max(1.0, a / 0.1)) << a;
    EXPECT_LT(sigma[1], 1e-7 * a) << a;  // sqrt of the eigensolver's rounding
  }
}

// The curvature's sign (docs/encoder.md "Curvature sign"): along each
// tangent of the normal frame, positive where the patch is convex seen from
// its normals, negative where concave — a dome, a bowl, and saddles either
// way round; the same 1e7 from the origin, and the turn's size near the
// shallow patch's curvature times the positions' variance (k / 3 on [-1, 1]).
TEST(Curvature, TheTurnsSignIsTheSurfacesSeenFromItsNormals) {
  const struct {
    double kx, ky;
    int sign0, sign1;  // along the major (|kx| > |ky|: x) and minor axes
  } patches[] = {{-0.4, -0.2, 1, 1}, {0.4, 0.2, -1, -1}, {0.4, -0.2, -1, 1}, {-0.4, 0.2, 1, -1}};
  for (const auto& p : patches)
    for (const double offset : {0.0, 1e7}) {
      PointCloud c = quadric_patch(41, p.kx, p.ky);
      for (Vec3& v : c.positions) v += Vec3(offset, -offset, offset);
      const auto ids = iota_ids(c.size());
      const NodeStats s = node_stats(c, ids.data(), ids.size(), StatsOptions{});
      EXPECT_LT(line_angle(s.normal_frame.col(0), Vec3::UnitX()), 1e-6) << p.kx << " " << p.ky;
      EXPECT_EQ(s.turn[0] > 0 ? 1 : -1, p.sign0) << p.kx << " " << p.ky << " " << offset;
      EXPECT_EQ(s.turn[1] > 0 ? 1 : -1, p.sign1) << p.kx << " " << p.ky << " " << offset;
      EXPECT_NEAR(std::abs(s.turn[0]), std::abs(p.kx) / 3, 0.1 * std::abs(p.kx) / 3);
      EXPECT_NEAR(std::abs(s.turn[1]), std::abs(p.ky) / 3, 0.1 * std::abs(p.ky) / 3);
      const Vec2 signed_n = signed_sigma_n(s);
      EXPECT_EQ(signed_n[0], p.sign0 * s.sigma_n[0]);
      EXPECT_EQ(signed_n[1], p.sign1 * s.sigma_n[1]);
    }
}

TEST(Pca, CurvatureShrinkFollowsTheFormula) {
  PointCloud c = test::sphere_cloud(400);
  const auto ids = iota_ids(40);  // a cap near the pole
  StatsOptions off;
  off.shrink_eta0 = 1.0;
  const StatsOptions on;  // the defaults
  const NodeStats a = node_stats(c, ids.data(), ids.size(), off);
  const NodeStats b = node_stats(c, ids.data(), ids.size(), on);
  const double beta =
      on.shrink_eta0 + (1 - on.shrink_eta0) * std::max(0.0, 1 - on.shrink_eta1 * std::sqrt(a.sigma_n[0]));
  EXPECT_LT(beta, 1.0);
  EXPECT_NEAR(b.position.sigma[2], a.position.sigma[2] * beta, 1e-15);
  EXPECT_EQ(b.position.sigma[0], a.position.sigma[0]);
}

TEST(FrameQuantization, ErrorWithinBudgetEverywhereIncludingPolesAndSeam) {
  const AngleBits bits{8, 10, 6, false};
  const double half_theta = kPi / 255 / 2, half_phi = kPi / 1024, half_psi = kPi / 128;
  const double f3_bound = std::hypot(half_theta, half_phi) + 1e-12;
  double worst3 = 0, worst1 = 0;
  std::vector<Mat3> frames;
  for (double theta : {0.0, 1e-9, kPi / 255 / 2, 0.5, kPi / 2, kPi - 1e-9, kPi}) {
    for (double phi : {0.0, 1e-9, kPi, 2 * kPi - 1e-9, -1e-9, 2.0}) {
      for (double psi : {0.0, 1.0, kPi - 1e-9, 2.5}) {
        const Vec3 f3(std::cos(phi) * std::sin(theta), std::sin(phi) * std::sin(theta), std::cos(theta));
        const Vec3 t = any_perpendicular(f3);
        const Vec3 f1 = std::cos(psi) * t + std::sin(psi) * f3.cross(t);
        Mat3 m;
        m << f1, f3.cross(f1), f3;
        frames.push_back(m);
      }
    }
  }
  for (uint32_t i = 1; i < 20000; ++i) {  // quasi-random orientations
    const double u = sobol_u32(i, 0) * 0x1p-32, v = sobol_u32(i, 1) * 0x1p-32, w = sobol_u32(i, 2) * 0x1p-32;
    frames.push_back(rotation(2 * kPi * u, std::acos(2 * v - 1), 2 * kPi * w));
  }
  for (const Mat3& m : frames) {
    const Mat3 d = decode_frame(encode_frame(m, bits), bits);
    const double e3 = std::acos(std::min(1.0, d.col(2).dot(m.col(2))));  // f3's sign is kept
    const double e1 = line_angle(d.col(0), m.col(0));
    worst3 = std::max(worst3, e3);
    worst1 = std::max(worst1, e1);
    ASSERT_LE(e3, f3_bound);
    ASSERT_LE(e1, half_psi + f3_bound);
    ASSERT_NEAR(d.determinant(), 1.0, 1e-12);
  }
  RecordProperty("worst_f3_rad", std::to_string(worst3));
  RecordProperty("worst_f1_rad", std::to_string(worst1));
}

TEST(FrameQuantization, ColourHemisphere) {
  const AngleBits bits{4, 3, 3, true};
  const double half_theta = kPi / 2 / 15 / 2, half_phi = kPi / 8, half_psi = kPi / 16;
  for (uint32_t i = 1; i < 5000; ++i) {
    const Mat3 m = rotation(2 * kPi * sobol_u32(i, 0) * 0x1p-32, std::acos(2 * sobol_u32(i, 1) * 0x1p-32 - 1),
                            2 * kPi * sobol_u32(i, 2) * 0x1p-32);
    const Mat3 d = decode_frame(encode_frame(m, bits), bits);
    const double e3 = line_angle(d.col(2), m.col(2));
    ASSERT_LE(e3, std::hypot(half_theta, half_phi) + 1e-12);
    ASSERT_LE(line_angle(d.col(0), m.col(0)), half_psi + std::hypot(half_theta, half_phi) + 1e-12);
  }
}

TEST(ScalarQuantization, CellsAndUnits) {
  EXPECT_EQ(quantize_cell(0.0, 0.0, 1.0, 10), 0);
  EXPECT_EQ(quantize_cell(1.0, 0.0, 1.0, 10), 1023);  // the maximum lands in the last cell
  EXPECT_EQ(quantize_cell(-5.0, 0.0, 1.0, 10), 0);
  for (double v = 0; v <= 1; v += 0.001) {
    const double back = dequantize_cell(quantize_cell(v, -2.0, 1.0, 11), -2.0, 1.0, 11);
    ASSERT_LE(std::abs(back - v), 3.0 / 2048 / 2 + 1e-15);
  }
  EXPECT_EQ(dequantize_cell(0, 3.0, 3.0, 10), 3.0);  // a flat axis
  EXPECT_EQ(quantize_unit(1.0, 5), 31);
  EXPECT_DOUBLE_EQ(dequantize_unit(63, 6), 1.0);
}

TEST(KdTree, MatchesBruteForce) {
  const auto pts = test::gaussian_points(5000, Vec3::Zero(), Mat3::Identity(), Vec3(1, 2, 0.5), 11);
  const KdTree tree(pts);
  const auto queries = test::gaussian_points(300, Vec3::Zero(), Mat3::Identity(), Vec3(2, 2, 2), 12);
  std::vector<uint32_t> knn;
  for (const Vec3& q : queries) {
    std::vector<std::pair<double, uint32_t>> all;
    for (uint32_t i = 0; i < pts.size(); ++i) all.push_back({(pts[i] - q).squaredNorm(), i});
    std::sort(all.begin(), all.end());
    double d2;
    EXPECT_EQ(tree.nearest(q, &d2), all[0].second);
    EXPECT_EQ(d2, all[0].first);
    // A hint (k-means' previous answer) changes the cost, not the distance.
    const uint32_t hinted = tree.nearest(q, static_cast<uint32_t>((q.x() > 0 ? 7 : 4000)));
    EXPECT_EQ((pts[hinted] - q).squaredNorm(), all[0].first);
    tree.knearest(q, 10, knn);
    ASSERT_EQ(knn.size(), 10u);
    for (size_t k = 0; k < 10; ++k) EXPECT_EQ(knn[k], all[k].second);
  }
}

// Coincident points (a float32 scan far from the origin collapses onto one
// lattice value): every query at the shared value ties with all of them. The
// search must stop once k ties are found instead of visiting each one (it
// visited the whole tree before: quadratic, normal estimation never
// finished). Bounded cost per query, exact distances; the wall time of the
// whole estimate is BM_NormalsCoincident in stipple_bench.
TEST(KdTree, CoincidentPointsCostLogarithmicTime) {
  std::vector<Vec3> pts(200000, Vec3(1e7, 1e7, 5.0));
  for (size_t i = 0; i < 1000; ++i) pts[i * 200] = Vec3(1e7 + static_cast<double>(i), 1e7, 5.0);  // a few others
  const KdTree tree(pts);
  std::vector<uint32_t> knn;
  size_t worst = 0;
  for (size_t i = 1; i < pts.size(); i += 997) {
    if (i % 200 == 0) continue;  // one of the distinct points
    size_t visited = 0;
    tree.knearest(pts[i], 12, knn, &visited);
    ASSERT_EQ(knn.size(), 12u);
    std::vector<uint32_t> sorted = knn;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::unique(sorted.begin(), sorted.end()), sorted.end());
    for (uint32_t j : knn) EXPECT_EQ((pts[j] - pts[i]).squaredNorm(), 0.0);
    worst = std::max(worst, visited);
  }
  std::printf("coincident points: at most %zu of 200000 points compared per 12-NN query\n", worst);
  EXPECT_LE(worst, 400u);
  PointCloud c;
  c.positions = pts;
  estimate_normals(c, 12);
  ASSERT_EQ(c.normals.size(), pts.size());
  for (const Vec3& n : c.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-9);
}

TEST(Normals, KnnNormalsOnASphereAreConsistentlyOriented) {
  PointCloud c = test::sphere_cloud(3000, 2.0, false);
  estimate_normals(c, 12);
  ASSERT_TRUE(c.has_normals());
  int outward = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const double d = c.normals[i].dot(c.positions[i].normalized());
    EXPECT_GT(std::abs(d), 0.98) << i;
    outward += d > 0;
  }
  // All one way: the highest point's normal points up, i.e. outward.
  EXPECT_EQ(outward, static_cast<int>(c.size()));
}

TEST(Normals, FromFacesAreAreaWeighted) {
  PointCloud c;
  c.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 2), Vec3(5, 5, 5)};
  // Area 0.5 in z = 0 (normal +z) and area 1 in y = 0 (normal +y).
  c.triangles = {{0, 1, 2}, {0, 3, 1}};
  estimate_normals(c, 3);
  EXPECT_LT((c.normals[2] - Vec3(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((c.normals[3] - Vec3(0, 1, 0)).norm(), 1e-12);
  EXPECT_LT((c.normals[0] - Vec3(0, 2, 1).normalized()).norm(), 1e-12);  // weighted 2:1 by area
  EXPECT_NEAR(c.normals[4].norm(), 1.0, 1e-12);  // isolated vertex: k-NN fallback
}

TEST(Sobol, FirstPointsMatchTheReference) {
  // Joe–Kuo dimensions 1-3, points 1..4 (0.32 fixed point).
  const double expect[4][3] = {{0.5, 0.5, 0.5}, {0.75, 0.25, 0.25}, {0.25, 0.75, 0.75}, {0.375, 0.375, 0.625}};
  for (uint32_t i = 0; i < 4; ++i)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(sobol_u32(i + 1, d) * 0x1p-32, expect[i][d]) << i << "," << d;
  // Each dimension is a (0, m, 1)-net: the first 2^m points hit every 2^-m cell once.
  for (int d = 0; d < kSobolDimensions; ++d) {
    std::vector<int> hits(256, 0);
    for (uint32_t i = 0; i < 256; ++i) ++hits[sobol_u32(i, d) >> 24];
    for (int h : hits) ASSERT_EQ(h, 1) << "dim " << d;
  }
}

}  // namespace
}  // namespace stipple
