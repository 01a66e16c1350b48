// The client and its parts against the host's reference code: the fixed-point
// frame against the double-precision renderer (PSNR per projection and
// shading mode), the level cut against the reference decoder's, and the
// committed points-per-node table against a fresh measurement.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "core/cut.h"
#include "raster/client.h"
#include "raster/points_per_node.h"
#include "test_util.h"
#include "tools/reference/ppn_measure.h"
#include "tools/reference/render.h"
#include "tools/reference/spg_model.h"

namespace stipple {
namespace {

struct Bunny {
  std::vector<uint8_t> file;
  SpgView view;
  DecodedModel model;
};

const Bunny& bunny() {
  static const Bunny* b = [] {
    auto* out = new Bunny;
    out->file = test::fixture("tests/golden/bunny_v1.spg");
    EXPECT_TRUE(spg_parse(out->file.data(), out->file.size(), &out->view).ok());
    std::string error;
    EXPECT_TRUE(decode_spg("bunny", out->file.data(), out->file.size(), out->model, error)) << error;
    return out;
  }();
  return *b;
}

// Fixed point against the double reference: same cut, same samples. Ties in
// the z-buffer flip wherever two points land within rounding of each other,
// so the bound is on PSNR, per projection mode (docs/fixed_point.md).
TEST(Client, FixedPointAgainstDoubleReference) {
  const DecodedModel& model = bunny().model;
  std::string error;
  const struct {
    Projection p;
    ShadingMode s;
    double bound;
  } cases[] = {{Projection::kExact, ShadingMode::kNone, 33},         {Projection::kExact, ShadingMode::kPerPoint, 32.5},
               {Projection::kReciprocal, ShadingMode::kPerPoint, 32.5}, {Projection::kAffine, ShadingMode::kNone, 32},
               {Projection::kAffine, ShadingMode::kPerPoint, 30},     {Projection::kAffine, ShadingMode::kSurface, 30}};
  for (const auto& k : cases) {
    for (const char* size : {"240x320", "640x480"}) {
      ClientConfig c;
      const bool big = size[0] == '6';
      c.raster = RasterConfig{static_cast<uint16_t>(big ? 640 : 240), static_cast<uint16_t>(big ? 480 : 320), 5,
                              big ? PixelFormat::kRgb888 : PixelFormat::kRgb565, 1u << 20};
      c.projection = k.p;
      c.shading = k.s;
      c.resolve = false;  // the points as drawn: the reference renderer has no resolve
      CutRule rule{CutRule::kProjectedSize, 0, 32};
      rule.cull = false;  // the projection's precision over the whole model, as the bounds were measured
      const ViewSpec spec;
      FixedRender fixed;
      ASSERT_TRUE(render_fixed(bunny().view, bunny().file.data(), c, rule, spec, fixed, error)) << error;
      const Image ref = render_reference(model, fixed.cut, c, spec);
      const double db = image_psnr(fixed.image, ref);
      const char* projections[] = {"affine", "reciprocal", "exact"};
      const char* shadings[] = {"point", "node", "none", "surface"};
      std::printf("%s projection %-10s shading %-5s: %.2f dB (%u points)\n", size, projections[static_cast<int>(k.p)],
                  shadings[static_cast<int>(k.s)], db, fixed.stats.points);
      EXPECT_GE(db, k.bound);
    }
  }
}

TEST(Cut, LevelCutMatchesTheReferenceDecoder) {
  const Bunny& t = bunny();
  std::vector<uint8_t> scratch(cut_scratch_bytes(t.view.header));
  std::vector<uint32_t> out(t.view.header.node_count);
  for (int level = 0; level <= t.view.header.depth + 1; ++level) {
    const uint32_t n = simple_cut(t.view, CutRule{CutRule::kLevel, static_cast<uint16_t>(level), 0}, nullptr, nullptr,
                                  scratch.data(), out.data(), static_cast<uint32_t>(out.size()));
    out.resize(n);
    EXPECT_EQ(out, level_cut(t.model, level)) << level;
    out.resize(t.view.header.node_count);
  }
  // A short output buffer: the count is still the whole cut's.
  uint32_t two[2];
  EXPECT_EQ(simple_cut(t.view, CutRule{CutRule::kLevel, 5, 0}, nullptr, nullptr, scratch.data(), two, 2),
            level_cut(t.model, 5).size());
}

// Nodes whose sigma is huge relative to the box (a hostile or degenerate
// file): the screen covariance passes 2^63 in 1/256 px^2. The points-per-node
// index must saturate (it overflowed a signed add before, seen by UBSan) and
// the frame still be drawn: such nodes get the most points the table allows.
TEST(Reference, HugeSigmaSaturatesThePointsPerNodeIndex) {
  DecodedModel model = bunny().model;
  ClientConfig c;
  c.raster = RasterConfig{64, 48, 5, PixelFormat::kRgb888, 1u << 20};
  c.samples = 64;
  const std::vector<uint32_t> cut = level_cut(model, 4);
  for (uint32_t id : cut) model.nodes[id].position.sigma *= 1e12;
  const Image huge = render_reference(model, cut, c, ViewSpec{});
  ASSERT_EQ(huge.rgb.size(), 64u * 48 * 3);
  size_t lit = 0;
  for (uint8_t v : huge.rgb) lit += v != 0;
  EXPECT_GT(lit, 0u);
  EXPECT_EQ(ppn_index(INT64_MAX, 0, INT64_MAX).size, kPpnSizes - 1);
  EXPECT_EQ(ppn_index(1, INT64_MAX, 1).aspect, kPpnAspects - 1);
}

// The committed table is what the tool measures (Sobol, 2 px points: the
// default; the other five tables come from the same code).
TEST(PointsPerNode, CommittedTableIsTheMeasuredOne) {
  PpnMeasureOptions o;
  o.point_size = 2;
  PpnTable measured;
  measure_ppn_table(o, measured);
  const PpnTable& committed = ppn_table(GaussianSource::kSobol, 2);
  for (int t = 0; t < kPpnSizes; ++t)
    for (int d = 0; d < kPpnAspects; ++d) EXPECT_EQ(committed[t][d], measured[t][d]) << t << "," << d;
  // Counts grow with size and quasi-random needs fewer points than pseudo-random for large nodes.
  const PpnIndex big = ppn_index(256 * 16, 0, 256 * 16);  // sigma = 4 px
  EXPECT_LT(ppn_table(GaussianSource::kSobol, 2)[big.size][big.aspect], ppn_table(GaussianSource::kPseudo, 2)[big.size][big.aspect]);
}

}  // namespace
}  // namespace stipple
