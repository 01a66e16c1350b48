// The curvature's sign through the whole pipeline (docs/encoder.md
// "Curvature sign"): a bowl, a dome and saddles encoded with and without it,
// drawn by the fixed-point client with surface normals at a coarse cut (16 px
// nodes, where a node's own turn shows) and compared with the picture of
// their points (`stipple truth`). Without the sign a concave patch turns its
// normals as a convex one would: each node a bump, the bowl scalloped (SSIM
// 0.81-0.82 against the points); with it the bowl is smooth (0.87-0.91).
// The dome, convex everywhere, draws the very same bytes either way. The
// object PSNR hardly moves (within 0.15 dB): the silhouette's ragged edge
// dominates it, the same with and without.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "tools/embedded/embedded.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/image_metrics.h"
#include "tools/reference/spg_model.h"
#include "tools/reference/truth.h"

namespace stipple {
namespace {

struct Picture {
  double psnr = 0;
  double ssim = 0;
  std::vector<uint8_t> rgb;
};

// The patch encoded (the sign on or off) and drawn against its points from
// `camera`, 640 x 480, surface normals.
Picture draw(const PointCloud& patch, bool sign, const std::string& camera) {
  EncodeOptions o;
  o.curvature_sign = sign;
  std::vector<uint8_t> spg;
  EncodeReport report;
  std::string error;
  PointCloud copy = patch;
  EXPECT_TRUE(encode_cloud(copy, o, spg, report, error)) << error;
  SpgView view;
  EXPECT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  EXPECT_EQ(view.header.has_curvature_sign(), sign);
  ClientConfig c;
  c.raster = RasterConfig{640, 480, kDefaultTileLog2, PixelFormat::kRgb888, 1u << 22};
  c.shading = ShadingMode::kSurface;
  ViewSpec spec;
  EXPECT_TRUE(parse_view(camera, spec, error)) << error;
  FixedRender out;
  EXPECT_TRUE(render_fixed(view, spg.data(), c, CutRule{CutRule::kProjectedSize, 0, 16 * 16}, spec, out, error)) << error;
  DecodedModel model;
  EXPECT_TRUE(decode_spg("patch", spg.data(), spg.size(), model, error)) << error;
  const Image truth = render_truth(patch, model.bbox_min, model.bbox_max, view.header, c, spec);
  const ImageComparison m = compare_images(truth, out.image);
  return Picture{m.object_psnr, m.ssim, out.image.rgb};
}

TEST(CurvatureView, ConcaveAndSaddlePatchesShadeAsTheirPoints) {
  const struct {
    const char* name;
    double kx, ky;
    double gain;  // the least SSIM the sign adds (measured: bowl 0.062-0.090, saddles 0.007-0.034)
  } patches[] = {{"dome", -1.6, -0.8, 0}, {"bowl", 1.6, 0.8, 0.05}, {"saddle", 1.6, -0.8, 0.005}, {"saddle'", -1.6, 0.8, 0.005}};
  for (const auto& p : patches) {
    const PointCloud patch = quadric_patch(400, p.kx, p.ky);
    for (const char* camera : {"30,50", "330,50", "0,30"}) {
      const Picture with = draw(patch, true, camera), without = draw(patch, false, camera);
      std::printf("%-8s camera %-7s SSIM %.3f (object PSNR %.2f dB) with the sign, %.3f (%.2f) without\n", p.name, camera,
                  with.ssim, with.psnr, without.ssim, without.psnr);
      if (p.gain == 0) {
        EXPECT_EQ(with.rgb, without.rgb) << p.name << " " << camera;  // convex: the same frame
      } else {
        EXPECT_GT(with.ssim, without.ssim + p.gain) << p.name << " " << camera;
        EXPECT_GT(with.psnr, without.psnr - 0.15) << p.name << " " << camera;
      }
    }
  }
}

}  // namespace
}  // namespace stipple
