// Projection modes of the client (raster/projection.h) against the exact
// double-precision projection of the same camera-space points, over every
// node of the bunny's tree seen from three views at 640 x 480. The bounds
// asserted here are the errors docs/fixed_point.md reports.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "raster/projection.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

struct ModeError {
  double max_px = 0, sum_sq = 0;
  long n = 0;
  double rms_px() const { return n ? std::sqrt(sum_sq / static_cast<double>(n)) : 0; }
};

template <Projection P>
void accumulate(const NodeProjection& proj, const Gaussian3Q12& g, int32_t near, const uint16_t* recip, ModeError& e) {
  ScreenSample s;
  if (!proj.point<P>(g, near, recip, &s)) return;
  // The same camera-space point (the client's integer arithmetic), projected exactly.
  const int64_t g0 = g.v[0], g1 = g.v[1], g2 = g.v[2];
  const double xp = static_cast<double>(proj.X + ((proj.A[0][0] * g0 + proj.A[1][0] * g1 + proj.A[2][0] * g2) >> 12));
  const double yp = static_cast<double>(proj.Y + ((proj.A[0][1] * g0 + proj.A[1][1] * g1 + proj.A[2][1] * g2) >> 12));
  const double zp = static_cast<double>(s.z);
  const double ex = proj.cx_q4 + proj.focal_q4 * xp / zp, ey = proj.cy_q4 + proj.focal_q4 * yp / zp;
  // Positions are floored to 1/16 px: compare the cell centres.
  const double d = std::hypot((s.x_q4 + 0.5 - ex) / 16, (s.y_q4 + 0.5 - ey) / 16);
  e.max_px = std::max(e.max_px, d);
  e.sum_sq += d * d;
  ++e.n;
}

struct Measured {
  ModeError affine, reciprocal, exact;
  ModeError affine_small;  // nodes whose 3.5-sigma extent is at most 8 px (the bunny's leaves here)
};

Measured measure() {
  const std::vector<uint8_t> file = test::fixture("tests/golden/bunny_v1.spg");
  SpgView view;
  EXPECT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
  std::vector<uint8_t> storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  EXPECT_EQ(decoder.init(view, storage.data(), storage.size()), DecodeStatus::kOk);
  uint16_t recip[1 << kReciprocalBits];
  build_reciprocal_table(recip);
  std::vector<Gaussian3Q12> g(256);
  build_gaussian3_table(GaussianSource::kSobol, g.data(), g.size());
  Measured m;
  const uint32_t yaws[3] = {0, 0x40000000u, 0x95555555u}, pitches[3] = {0, 0x0E38E38Eu, 0x1C71C71Cu};
  for (int v = 0; v < 3; ++v) {
    OrbitView o;
    for (int a = 0; a < 3; ++a) o.target_mu[a] = decoder.extent_mu()[a] / 2;
    o.distance_mu = 37 << 20;  // 2.2 extents
    o.yaw = yaws[v];
    o.pitch = pitches[v];
    o.fov = 0x18E38E39u;  // 35 degrees
    Camera cam;
    EXPECT_TRUE(orbit_camera(o, 640, 480, &cam));
    for (uint32_t i = 0; i < view.header.node_count; ++i) {
      FixedNode node;
      EXPECT_EQ(decoder.decode(view.records + i * view.record_bytes, &node), DecodeStatus::kOk);
      NodeProjection proj;
      if (!proj.setup(cam, node)) continue;
      int64_t extent = 0;
      for (int k = 0; k < 3; ++k) extent = std::max(extent, std::abs(int64_t{proj.mx[k]}) + std::abs(int64_t{proj.my[k]}));
      const bool small = extent * 7 / 2 <= 8 * 256;
      for (const Gaussian3Q12& s : g) {
        accumulate<Projection::kAffine>(proj, s, cam.near_mu, recip, m.affine);
        if (small) accumulate<Projection::kAffine>(proj, s, cam.near_mu, recip, m.affine_small);
        accumulate<Projection::kReciprocal>(proj, s, cam.near_mu, recip, m.reciprocal);
        accumulate<Projection::kExact>(proj, s, cam.near_mu, recip, m.exact);
      }
    }
  }
  return m;
}

TEST(Projection, ErrorOfEachModeAgainstExactDoubleProjection) {
  const Measured m = measure();
  std::printf("projection error, px (max / rms over %ld points):\n", m.exact.n);
  std::printf("  exact       %.4f / %.4f\n", m.exact.max_px, m.exact.rms_px());
  std::printf("  reciprocal  %.4f / %.4f\n", m.reciprocal.max_px, m.reciprocal.rms_px());
  std::printf("  affine      %.4f / %.4f (all nodes)\n", m.affine.max_px, m.affine.rms_px());
  std::printf("  affine      %.4f / %.4f (%ld points of nodes <= 8 px)\n", m.affine_small.max_px, m.affine_small.rms_px(),
              m.affine_small.n);
  ASSERT_GT(m.exact.n, 1000000);
  ASSERT_GT(m.affine_small.n, 100000);
  // Exact division, floored to 1/16 px: within the cell (the centre is 1/32 px
  // from its edges) plus the 1/16 px floor.
  EXPECT_LE(m.exact.max_px, 0.045);
  EXPECT_LE(m.reciprocal.max_px, 0.25);
  EXPECT_LE(m.reciprocal.rms_px(), 0.06);
  EXPECT_LE(m.affine_small.max_px, 0.25);
  EXPECT_LE(m.affine_small.rms_px(), 0.08);
}

TEST(Projection, ReciprocalTableIsRoundedInverse) {
  uint16_t recip[1 << kReciprocalBits];
  build_reciprocal_table(recip);
  for (int i = 0; i < (1 << kReciprocalBits); ++i) {
    const double exact = 67108864.0 / (1024 + i + 0.5);
    EXPECT_LE(std::abs(recip[i] - exact), 0.5) << i;
  }
}

// The slope bound as one unsigned compare (slope_beyond) is |v| >= 2^28
// exactly: at the bound, either side of it and far beyond.
TEST(Projection, SlopeBoundIsTheAbsoluteValueBound) {
  std::vector<int64_t> vs;
  for (const int64_t edge : {int64_t{0}, kMaxScreenSlope, -kMaxScreenSlope})
    for (int64_t d = -3; d <= 3; ++d) vs.push_back(edge + d);
  for (int s = 29; s < 62; s += 4) vs.push_back(int64_t{1} << s), vs.push_back(-(int64_t{1} << s));
  vs.push_back((int64_t{1} << 62) - 1);
  vs.push_back(-(int64_t{1} << 62) + 1);
  for (const int64_t v : vs) EXPECT_EQ(slope_beyond(v), abs64(v) >= kMaxScreenSlope) << v;
}

// The affine set-up (setup<false>: the camera-space mean and axes not
// kept) places and refuses every node as the full set-up does: the
// bunny's nodes from three views, then means from 2^12 MU to 2^30 deep
// with axes up to 2^25, whose slopes pass the bound near the eye.
TEST(Projection, AffineSetupPlacesAndRefusesAsTheFullOne) {
  const std::vector<uint8_t> file = test::fixture("tests/golden/bunny_v1.spg");
  SpgView view;
  ASSERT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
  std::vector<uint8_t> storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  ASSERT_EQ(decoder.init(view, storage.data(), storage.size()), DecodeStatus::kOk);
  long placed = 0, refused = 0;
  const auto same = [&](const Camera& cam, const int32_t c[3], const int32_t a[3][3]) {
    NodeProjection full, affine;
    const bool ok = full.setup(cam, c, a);
    EXPECT_EQ(affine.setup<false>(cam, c, a), ok);
    if (!ok) return void(++refused);
    ++placed;
    EXPECT_EQ(affine.x0_q4, full.x0_q4);
    EXPECT_EQ(affine.y0_q4, full.y0_q4);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(affine.mx[k], full.mx[k]);
      EXPECT_EQ(affine.my[k], full.my[k]);
    }
  };
  const uint32_t yaws[3] = {0, 0x40000000u, 0x95555555u}, pitches[3] = {0, 0x0E38E38Eu, 0x1C71C71Cu};
  Camera cam;
  for (int v = 0; v < 3; ++v) {
    OrbitView o;
    for (int a = 0; a < 3; ++a) o.target_mu[a] = decoder.extent_mu()[a] / 2;
    o.distance_mu = 37 << 20;
    o.yaw = yaws[v];
    o.pitch = pitches[v];
    o.fov = 0x18E38E39u;
    ASSERT_TRUE(orbit_camera(o, 640, 480, &cam));
    for (uint32_t i = 0; i < view.header.node_count; ++i) {
      FixedNode node;
      ASSERT_EQ(decoder.decode(view.records + i * view.record_bytes, &node), DecodeStatus::kOk);
      int32_t c[3], a[3][3];
      camera_space(cam, node.mean, c);
      if (!NodeProjection::in_view(cam, c)) continue;
      for (int k = 0; k < 3; ++k) camera_rotate(cam, node.axis[k], a[k]);
      same(cam, c, a);
    }
  }
  const long bunny = placed;
  cam.near_mu = 1 << 12;  // means from 2^12 MU: slopes up to 2^30 px a sigma
  uint32_t state = 12345;
  const auto next = [&state](int32_t bound) {  // in [-bound, bound]
    state = state * 1664525u + 1013904223u;
    return static_cast<int32_t>(static_cast<int64_t>(state) % (2 * int64_t{bound} + 1) - bound);
  };
  for (int64_t z = cam.near_mu + 1; z < (int64_t{1} << 30); z += z / 3 + 1)
    for (int n = 0; n < 16; ++n) {
      const int32_t c[3] = {next(static_cast<int32_t>(std::min<int64_t>(8 * z, INT32_MAX))),
                            next(static_cast<int32_t>(std::min<int64_t>(8 * z, INT32_MAX))), static_cast<int32_t>(z)};
      int32_t a[3][3];
      for (auto& axis : a)
        for (int32_t& e : axis) e = next(1 << 25);
      same(cam, c, a);
    }
  EXPECT_GT(bunny, 10000);
  EXPECT_GT(placed, bunny + 100);
  EXPECT_GT(refused, 100) << "no slope passed the bound";
}

}  // namespace
}  // namespace stipple
