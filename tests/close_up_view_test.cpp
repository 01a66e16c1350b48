// Close-ups through the whole fixed-point client (raster/close_up.h): a
// scanned plane seen from a tenth of its points' spacing stays a closed
// surface — it was dots over black, or nothing, before the discs.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "tools/embedded/embedded.h"
#include "tools/encoder/encoder.h"

namespace stipple {
namespace {

// The grid plane of 64 x 64 points (tools/scan/point_cloud.h), encoded.
std::vector<uint8_t> grid_plane() {
  std::vector<uint8_t> spg;
  EncodeReport report;
  std::string error;
  PointCloud plane = stipple::grid_plane(64);
  EXPECT_TRUE(encode_cloud(plane, EncodeOptions{}, spg, report, error)) << error;
  return spg;
}

struct Shot {
  double covered = 0;  // share of the screen's pixels
  FrameStats stats;
};

Shot shoot(const std::vector<uint8_t>& spg, const std::string& camera, bool close_ups, uint8_t point_cap = 0) {
  SpgView view;
  EXPECT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  ClientConfig c;
  c.raster = RasterConfig{640, 480, kDefaultTileLog2, PixelFormat::kRgb888, 1u << 22};
  c.close_ups = close_ups;
  c.point_cap = point_cap;
  ViewSpec spec;
  std::string error;
  EXPECT_TRUE(parse_view(camera, spec, error)) << error;
  FixedRender out;
  EXPECT_TRUE(render_fixed(view, spg.data(), c, CutRule{CutRule::kProjectedSize, 0, 32}, spec, out, error)) << error;
  Shot s;
  size_t covered = 0;
  for (size_t i = 0; i + 2 < out.image.rgb.size(); i += 3)
    covered += (out.image.rgb[i] | out.image.rgb[i + 1] | out.image.rgb[i + 2]) != 0;
  s.covered = static_cast<double>(covered) / (640.0 * 480.0);
  s.stats = out.stats;
  return s;
}

// Face on from a tenth of the spacing (0.1 / 63 of the extent) and from
// 0.05 of the model, and at 30 degrees from 0.3: every pixel covered with
// the discs, few without.
TEST(CloseUpView, APlaneSeenFromATenthOfItsSpacingStaysClosed) {
  const std::vector<uint8_t> spg = grid_plane();
  for (const char* camera : {"0,90,0.0016", "0,90,0.05", "20,30,0.3"}) {
    const Shot on = shoot(spg, camera, true), off = shoot(spg, camera, false);
    std::printf("camera %s: %.4f of the screen covered with close-ups (%u discs), %.4f without\n", camera, on.covered,
                on.stats.nodes_close_up, off.covered);
    EXPECT_GE(on.covered, 0.99) << camera;
    EXPECT_GT(on.stats.nodes_close_up, 0u) << camera;
    EXPECT_LT(off.covered, 0.6) << camera;
    EXPECT_EQ(off.stats.nodes_close_up, 0u);
  }
}

// From afar the plane is points, as before: no node is a disc, and the
// point cap (sparse scans kept sparse) turns the discs off.
TEST(CloseUpView, FarViewsAndThePointCapDrawNoDiscs) {
  const std::vector<uint8_t> spg = grid_plane();
  const Shot far = shoot(spg, "20,50,2.5", true);
  EXPECT_EQ(far.stats.nodes_close_up, 0u);
  EXPECT_GT(far.stats.points, 10000u);
  const Shot capped = shoot(spg, "0,90,0.05", true, 2);
  EXPECT_EQ(capped.stats.nodes_close_up, 0u);
}

}  // namespace
}  // namespace stipple
