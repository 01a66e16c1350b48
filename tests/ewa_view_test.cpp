// EWA splats in the fixed-point client (raster/ewa.h, `--splat ewa`)
// against the scan: the bunny's three orbit views and its close-up, each
// with the software client's defaults and with EWA, compared with `stipple
// truth` of the scan (docs/fixed_point.md "EWA").
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "test_util.h"
#include "tools/embedded/embedded.h"
#include "tools/reference/image_metrics.h"
#include "tools/reference/truth.h"

namespace stipple {
namespace {

TEST(EwaView, TheBunnyAgainstItsScan) {
  const test::BunnyAndScan b("tests/golden/bunny_v2.spg");
  ASSERT_TRUE(b.ok);
  const SpgView& view = b.view;
  std::string error;
  ClientConfig config;  // the software client's defaults
  config.raster = RasterConfig{640, 480, 5, PixelFormat::kRgb888, 1u << 22};
  const struct {
    const char* camera;
    double gain;  // the least EWA must add, dB (measured +1.83, +1.24, +1.39; the close-up +2.13)
  } views[] = {{"30,20", 1.0}, {"150,20", 0.8}, {"260,20", 0.9}, {"30,20,0.8", 1.5}};
  double sum[2] = {};
  for (const auto& v : views) {
    ViewSpec spec;
    ASSERT_TRUE(parse_view(v.camera, spec, error)) << error;
    const Image truth = render_truth(b.scan, b.model.bbox_min, b.model.bbox_max, view.header, config, spec);
    ImageComparison m[2];
    FrameStats stats[2];
    for (int ewa = 0; ewa < 2; ++ewa) {
      ClientConfig c = config;
      c.ewa = ewa == 1;
      FixedRender r;
      ASSERT_TRUE(render_fixed(view, b.file.data(), c, CutRule{CutRule::kProjectedSize, 0, 32}, spec, r, error)) << error;
      m[ewa] = compare_images(truth, r.image);
      stats[ewa] = r.stats;
    }
    std::printf("camera %-9s object PSNR %.2f dB (SSIM %.3f) with points, %.2f (%.3f) with EWA's %u splats\n", v.camera,
                m[0].object_psnr, m[0].ssim, m[1].object_psnr, m[1].ssim, stats[1].splats);
    EXPECT_GT(m[1].object_psnr, m[0].object_psnr + v.gain) << v.camera;
    EXPECT_GT(m[1].ssim, m[0].ssim) << v.camera;
    EXPECT_EQ(m[1].iou, m[0].iou) << v.camera;  // the points' coverage: the same silhouette
    EXPECT_GT(stats[1].splats, stats[1].nodes_drawn / 3) << v.camera;
    if (std::string(v.camera).size() <= 6) sum[0] += m[0].object_psnr, sum[1] += m[1].object_psnr;
  }
  std::printf("mean of the three views: points %.2f dB, EWA %.2f dB\n", sum[0] / 3, sum[1] / 3);
  EXPECT_GT(sum[1], sum[0] + 3 * 1.2);
}

}  // namespace
}  // namespace stipple
