// The parts the client is made of: the fixed-point camera, the simple cut,
// the shading tables and the points-per-node index (the reference checks
// are in tests/render_reference_test.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "core/camera.h"
#include "core/cut.h"
#include "raster/node_lanes.h"
#include "raster/point_kernel_avx2.h"
#include "raster/point_renderer.h"
#include "raster/points_per_node.h"
#include "raster/shading.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

TEST(Camera, OrbitIsOrthonormalAndLooksAtTheTarget) {
  for (uint32_t yaw = 0; yaw < 0xF0000000u; yaw += 0x13579BDFu)
    for (int32_t pitch_deg : {-80, -30, 0, 45, 89}) {
      OrbitView o;
      o.target_mu[0] = 1 << 23;
      o.target_mu[1] = 3 << 21;
      o.target_mu[2] = -(1 << 20);
      o.distance_mu = 3 << 24;
      o.yaw = yaw;
      o.pitch = static_cast<uint32_t>(static_cast<int64_t>(pitch_deg) * 11930465);
      Camera c;
      ASSERT_TRUE(orbit_camera(o, 640, 480, &c));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          int64_t dot = 0;
          for (int k = 0; k < 3; ++k) dot += int64_t{c.rotation[i][k]} * c.rotation[j][k];
          EXPECT_NEAR(static_cast<double>(dot) / (1 << 28), i == j ? 1.0 : 0.0, 4e-4) << i << j;
        }
      // The target is straight ahead at the orbit distance, within the Q14
      // rotation's precision (1e-4 of the distance: 0.08 px at f = 760 px).
      int32_t t[3];
      camera_space(c, o.target_mu, t);
      EXPECT_LE(std::abs(t[0]), o.distance_mu >> 13);
      EXPECT_LE(std::abs(t[1]), o.distance_mu >> 13);
      EXPECT_NEAR(t[2], o.distance_mu, o.distance_mu >> 13);
      // +y of the model is up on screen (camera y points down) unless looking straight down.
      const int32_t up[3] = {0, 1 << 14, 0};
      int32_t v[3];
      camera_rotate(c, up, v);
      EXPECT_LT(v[1], 0);
    }
}

// Any up axis: the orbit's frame is a right-handed signed permutation (no
// picture is mirrored), its up axis is up on screen at every yaw, and yaw
// turns about it. +y is the identity, so the golden views are unchanged.
TEST(Camera, OrbitAboutEveryAxis) {
  for (uint8_t code = 1; code < kSpgAxisCount; ++code) {
    const SpgAxis axis = static_cast<SpgAxis>(code);
    int32_t b[3][3];
    orbit_basis(axis, b);
    const int64_t det = int64_t{b[0][0]} * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                        int64_t{b[0][1]} * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                        int64_t{b[0][2]} * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    EXPECT_EQ(det, 1) << static_cast<int>(code);
    int32_t up[3] = {0, 0, 0};
    up[(code - 1) / 2] = (code - 1) % 2 ? -(1 << 14) : 1 << 14;
    for (int a = 0; a < 3; ++a) EXPECT_EQ(b[a][1] << 14, up[a]) << static_cast<int>(code);
    for (uint32_t yaw = 0; yaw < 0xF0000000u; yaw += 0x2468ACE1u) {
      OrbitView o;
      o.up = axis;
      o.yaw = yaw;
      o.pitch = 20 * 11930465u;
      Camera c;
      ASSERT_TRUE(orbit_camera(o, 240, 320, &c));
      int32_t v[3];
      camera_rotate(c, up, v);
      EXPECT_LT(v[1], -(1 << 13)) << "up axis " << static_cast<int>(code) << " is not up on screen";
      // The eye's offset from the target has no up component beyond sin(pitch).
      int64_t along = 0;
      for (int a = 0; a < 3; ++a) along += int64_t{c.eye[a] - o.target_mu[a]} * up[a];
      EXPECT_NEAR(static_cast<double>(along) / (1 << 14) / o.distance_mu, 0.342, 1e-3);
    }
  }
  int32_t id[3][3];
  orbit_basis(SpgAxis::kPosY, id);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(id[i][j], i == j ? 1 : 0);
}

TEST(Camera, FocalLengthAndRefusals) {
  OrbitView o;
  o.fov = 0x40000000u;  // 90 degrees: f = h / 2
  Camera c;
  ASSERT_TRUE(orbit_camera(o, 640, 480, &c));
  EXPECT_NEAR(c.focal_q4, 240 * 16, 1);
  EXPECT_EQ(c.center_q4[0], 320 * 16);
  EXPECT_EQ(c.center_q4[1], 240 * 16);
  Camera untouched = c;
  o.distance_mu = 100;
  EXPECT_FALSE(orbit_camera(o, 640, 480, &untouched));
  o.distance_mu = 1 << 25;
  o.fov = 0;
  EXPECT_FALSE(orbit_camera(o, 640, 480, &untouched));
  o.fov = 0x40000000u;
  o.target_mu[1] = (1 << 26) + 1;
  EXPECT_FALSE(orbit_camera(o, 640, 480, &untouched));
  EXPECT_FALSE(orbit_camera(OrbitView{}, 0, 480, &untouched));
}

struct Tree {
  std::vector<uint8_t> file;
  SpgView view;
  std::vector<uint8_t> storage;
  NodeDecoder decoder;
};

const Tree& tree() {
  static Tree* t = [] {
    auto* out = new Tree;
    out->file = test::fixture("tests/golden/bunny_v1.spg");
    EXPECT_TRUE(spg_parse(out->file.data(), out->file.size(), &out->view).ok());
    out->storage.resize(node_decoder_bytes(out->view.header));
    EXPECT_EQ(out->decoder.init(out->view, out->storage.data(), out->storage.size()), DecodeStatus::kOk);
    return out;
  }();
  return *t;
}

// Every root-to-leaf path crosses a projected-size cut exactly once when
// nothing is behind the camera, and every kept inner node is small enough.
TEST(Cut, ProjectedSizeCutIsACutAndRespectsTheThreshold) {
  const Tree& t = tree();
  std::vector<uint8_t> scratch(cut_scratch_bytes(t.view.header));
  std::vector<uint32_t> out(t.view.header.node_count);
  OrbitView o;
  for (int a = 0; a < 3; ++a) o.target_mu[a] = t.decoder.extent_mu()[a] / 2;
  o.distance_mu = 3 << 24;
  Camera cam;
  ASSERT_TRUE(orbit_camera(o, 640, 480, &cam));
  for (int32_t q4 : {16, 32, 128, 1024}) {
    const uint32_t n = simple_cut(t.view, CutRule{CutRule::kProjectedSize, 0, q4}, &t.decoder, &cam, scratch.data(),
                                  out.data(), static_cast<uint32_t>(out.size()));
    std::vector<int> in_cut(t.view.header.node_count, 0);
    for (uint32_t i = 0; i < n; ++i) in_cut[out[i]] = 1;
    // Count cut nodes on the path from each leaf to the root.
    const uint32_t nodes = t.view.header.node_count;
    std::vector<uint32_t> parent(nodes, 0);
    std::vector<bool> leaf(nodes, false);
    for (uint32_t i = 0, next = 1; i < nodes; ++i) {  // breadth-first: children follow in order
      const uint32_t children = spg_child_count(t.view, i);
      leaf[i] = children == 0;
      for (uint32_t c = 0; c < children; ++c) parent[next++] = i;
    }
    for (uint32_t i = 0; i < nodes; ++i) {
      if (!leaf[i]) continue;
      int crossings = 0;
      for (uint32_t v = i;; v = parent[v]) {
        crossings += in_cut[v];
        if (v == 0) break;
      }
      ASSERT_EQ(crossings, 1) << "leaf " << i << " at " << q4;
    }
    for (uint32_t i = 0; i < n; ++i) {
      if (leaf[out[i]]) continue;
      FixedNode node;
      ASSERT_EQ(t.decoder.decode(t.view.records + out[i] * t.view.record_bytes, &node), DecodeStatus::kOk);
      int32_t c[3];
      camera_space(cam, node.mean, c);
      EXPECT_LE(int64_t{node_radius_mu(node)} * cam.focal_q4, int64_t{q4} * c[2]);
    }
  }
}

TEST(Shading, CosSincTableAgainstLibm) {
  ShadingTables tables;
  ASSERT_TRUE(build_shading_tables(Lighting{}, &tables));
  double worst = 0;
  for (int i = 0; i < kCosSincEntries; ++i) {
    const double theta = std::sqrt((i + 0.5) / 128.0);  // the cell's middle, theta^2 in steps of 2^-7
    worst = std::max(worst, std::abs(tables.cos_sinc[i].cos / 16384.0 - std::cos(theta)));
    worst = std::max(worst, std::abs(tables.cos_sinc[i].sinc / 16384.0 - std::sin(theta) / theta));
  }
  EXPECT_LE(worst, 6.0 / 16384);  // measured 5.3 LSB: theta to a binary angle, sincos_q14, one division
  // Past theta^2 = 16 the cells an angle pair within 4 rad reaches repeat
  // the last entry: the clamp the scalar loops no longer make.
  EXPECT_EQ(kCosSincCells, ((16384 * 16384 * 2) >> kCosSincShift) + 1);
  for (int i = kCosSincEntries; i < kCosSincCells; ++i) {
    EXPECT_EQ(tables.cos_sinc[i].cos, tables.cos_sinc[kCosSincEntries - 1].cos) << i;
    EXPECT_EQ(tables.cos_sinc[i].sinc, tables.cos_sinc[kCosSincEntries - 1].sinc) << i;
  }
  // Light normalized; the half vector between it and the eye.
  const double l = std::hypot(std::hypot(4096.0, 6144.0), 14336.0);
  EXPECT_NEAR(tables.light_q14[2], -14336 / l * 16384, 1);
  EXPECT_LT(tables.half_q14[2], tables.light_q14[2]);
}

// A node of n points takes the first bucket of n samples or more, in half
// octaves, so its reach is at most a third more samples' than its own.
TEST(PointRenderer, SampleReachBuckets) {
  EXPECT_EQ(sample_reach_samples(0), 1u);
  EXPECT_EQ(sample_reach_samples(kSampleReachBuckets - 1), 8192u);
  for (uint32_t n = 1; n <= 8192; ++n) {
    const int b = sample_reach_bucket(n);
    ASSERT_GE(sample_reach_samples(b), n) << n;
    if (b > 0) {
      ASSERT_LT(sample_reach_samples(b - 1), n) << n;
    }
  }
  for (int b = 1; b < kSampleReachBuckets; ++b) EXPECT_LT(sample_reach_samples(b - 1), sample_reach_samples(b));
}

// The AVX2 node lanes form the bucket in lanes (node_lanes_avx2.cpp): the
// same bucket as sample_reach_bucket for every count a node can draw. A
// bucket too small there would let a lane's points leave its tiles.
TEST(PointRenderer, SampleReachBucketsInLanes) {
#if defined(__x86_64__) || defined(__i386__)
  if (!avx2::supported()) GTEST_SKIP() << "no AVX2 on this CPU";
  for (uint32_t first = 1; first <= 8192; first += 8) {
    uint32_t count[8];
    int32_t bucket[8];
    for (uint32_t i = 0; i < 8; ++i) count[i] = first + i;
    avx2::sample_reach_buckets(count, bucket);
    for (uint32_t i = 0; i < 8; ++i) ASSERT_EQ(bucket[i], sample_reach_bucket(count[i])) << count[i] << " points";
  }
#else
  GTEST_SKIP() << "no AVX2 lanes on this target";
#endif
}

TEST(Shading, IntensitiesAreLambertAndPhongPowers) {
  Lighting light;
  light.ambient_q8 = 64;
  light.specular_q8 = 128;
  light.shininess = 8;
  ShadingTables t;
  ASSERT_TRUE(build_shading_tables(light, &t));
  EXPECT_EQ(t.diffuse[intensity_index(-16384)], 64);  // facing away: ambient
  EXPECT_EQ(t.diffuse[intensity_index(0)], 64);
  EXPECT_EQ(t.diffuse[intensity_index(16384)], 256);  // full light
  EXPECT_EQ(t.diffuse[intensity_index(8192)], 64 + 96);
  EXPECT_EQ(t.specular[intensity_index(16384)], 128);  // 255 * 0.5, rounded
  EXPECT_EQ(t.specular[intensity_index(8192)], 0);     // 0.5^8 * 127.5 = 0.498
  EXPECT_EQ(t.specular[intensity_index(0)], 0);
  Lighting bad;
  bad.shininess = 0;
  EXPECT_FALSE(build_shading_tables(bad, &t));
}

// The scalar point loops index the intensity tables without a clamp
// (lit_entry_q26): the pad entries must hold every L.n a sampled normal
// reaches, and shade it as the ends do.
TEST(Shading, IntensityPadCoversSampledNormals) {
  ShadingTables t;
  ASSERT_TRUE(build_shading_tables(Lighting{}, &t));
  for (int i = 0; i < kIntensityPad; ++i) {
    EXPECT_EQ(t.diffuse[i], t.diffuse[intensity_index(-16384)]) << i;
    EXPECT_EQ(t.specular[i], t.specular[intensity_index(-16384)]) << i;
    EXPECT_EQ(t.diffuse[kIntensityEntries - 1 - i], t.diffuse[intensity_index(16384)]) << i;
    EXPECT_EQ(t.specular[kIntensityEntries - 1 - i], t.specular[intensity_index(16384)]) << i;
  }
  // L.n = (cos, sinc al, sinc be) . (L.n0, L.t1, L.t2), so |L.n| <= A |L|
  // with A the norm of the first vector at its largest: per cell, the
  // cell's table entry with theta^2 at the cell's end (at most 32 rad^2,
  // both angles within 4 rad; past 16 the entry is the last one again).
  double a2 = 0;
  for (int k = 0; k < kCosSincCells; ++k) {
    const double c = t.cos_sinc[k].cos / 16384.0, s = t.cos_sinc[k].sinc / 16384.0;
    const double theta2 = std::min((k + 1) / 128.0, 32.0);
    a2 = std::max(a2, c * c + s * s * theta2);
  }
  const double a = std::sqrt(a2);
  EXPECT_NEAR(a, 1.2532, 0.001);  // at theta = 4 sqrt(2): cos^2 4 + 2 sin^2 4 under the root
  // |L| within 2^-11 of 1 (the light normalized, light_terms within 4 Q14
  // LSB a component: FrameAngles.CameraFramesAndLightTermsMatchTheReference-
  // Decoder), l0 rounded to Q12 (2^-13) and the along term floored in Q12
  // (2^-12 times sinc <= 1).
  const double reach = a * (1 + 1.0 / 2048 + 1.0 / 8192) + 1.0 / 4096;
  EXPECT_LT(reach, 1 + kIntensityPad / 128.0);
  // The integer formula at its extremes: every angle pair on the 4 rad
  // square's edge and inside, (L.n0, L.t1, L.t2) of norm 1 + 2^-11 in
  // many directions; the index is in the table, its entries the clamped
  // index's.
  const int32_t edge = 16384;
  const double norm = 16384 * (1 + 1.0 / 2048);
  int worst_low = kIntensityEntries, worst_high = -1;
  for (int d = 0; d < 64; ++d)
    for (int e = 0; e <= 16; ++e) {
      const double phi = d * 0.0982, z = -1 + e / 8.0, r = std::sqrt(1 - z * z);
      const int32_t t1 = static_cast<int32_t>(std::lround(norm * r * std::cos(phi)));
      const int32_t t2 = static_cast<int32_t>(std::lround(norm * r * std::sin(phi)));
      const int32_t n0 = static_cast<int32_t>(std::lround(norm * z / 4));  // Q12
      const uint32_t t12 = int16_pair(t1, t2), n0h0 = int16_pair(n0, -n0);
      for (int32_t al = -edge; al <= edge; al += 1024)
        for (int32_t be = -edge; be <= edge; be += 1024) {
          const uint32_t cell = static_cast<uint32_t>(al * al + be * be) >> kCosSincShift;
          const CosSincQ14& cs = t.cos_sinc[cell];
          for (const int i : {lit_index<false>(cs, al, be, t12, n0h0), lit_index<true>(cs, al, be, t12, n0h0)}) {
            ASSERT_GE(i, 0) << al << " " << be << " " << t1 << " " << t2 << " " << n0;
            ASSERT_LT(i, kIntensityEntries) << al << " " << be << " " << t1 << " " << t2 << " " << n0;
            worst_low = std::min(worst_low, i);
            worst_high = std::max(worst_high, i);
            const int ends = std::clamp(i, kIntensityZero - 128, kIntensityZero + 128);  // l within [-1, 1]
            ASSERT_EQ(t.diffuse[i], t.diffuse[ends]);
            ASSERT_EQ(t.specular[i], t.specular[ends]);
          }
        }
    }
  // The reach measured: about 1.25 either way, within the pad's 1.37.
  EXPECT_LE(worst_high, kIntensityZero + 161) << worst_high;
  EXPECT_GE(worst_low, kIntensityZero - 161) << worst_low;
  EXPECT_GT(worst_high, kIntensityZero + 150) << "the extremes were not reached";
}

TEST(PointsPerNode, IndexIsScaleFreeInAspect) {
  // A circle of any size has aspect 0; thinner ellipses have larger aspect.
  for (int64_t s2 = 64; s2 < (int64_t{1} << 28); s2 *= 3) EXPECT_LE(ppn_index(s2, 0, s2).aspect, 1) << s2;
  EXPECT_GT(ppn_index(1 << 20, 0, 1 << 10).aspect, ppn_index(1 << 20, 0, 1 << 16).aspect);
  EXPECT_EQ(ppn_index(int64_t{1} << 40, 0, 1).size, kPpnSizes - 1);
  EXPECT_EQ(half_octave(1), 0);
  EXPECT_EQ(half_octave(2), 2);
  EXPECT_EQ(half_octave(3), 3);
  EXPECT_EQ(half_octave(4), 4);
  EXPECT_EQ(half_octave(6), 5);
}

TEST(PointsPerNode, QualityScalesAndClamps) {
  const PpnTable& t = ppn_table(GaussianSource::kSobol, 2);
  const PpnIndex i = ppn_index(256 * 4, 0, 256 * 4);
  const uint32_t base = points_per_node(t, i, 256, 1024);
  EXPECT_EQ(base, t[i.size][i.aspect]);
  EXPECT_EQ(points_per_node(t, i, 512, 1024), std::min<uint32_t>(2 * base, 1024));
  EXPECT_EQ(points_per_node(t, i, 1, 1024), 1u);
  EXPECT_EQ(points_per_node(t, ppn_index(int64_t{1} << 40, 0, 1), 256, 100), 100u);
}

}  // namespace
}  // namespace stipple
