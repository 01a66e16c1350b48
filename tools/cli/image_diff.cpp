// stipple image-diff — two images compared byte for byte, with a diff image.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "platform/png_io.h"
#include "tools/cli/cli.h"
#include "tools/reference/image_metrics.h"

namespace stipple {
namespace {

const char kDiffHelp[] =
    "usage: stipple image-diff EXPECTED.png ACTUAL.png [-o DIFF.png] [--json]\n"
    "\n"
    "Compares two RGB images of the same size byte for byte. Prints the number of\n"
    "differing pixels, the largest channel difference and the PSNR; -o writes a\n"
    "diff image (the expected image darkened, differing pixels in red, brighter\n"
    "for larger differences). When they differ it also measures ACTUAL against\n"
    "EXPECTED as a reference picture (`stipple truth`; black is background):\n"
    "PSNR over the object (the pixels either covers), SSIM of the luma, the share\n"
    "of lit reference pixels shown at under half their luma (dark where lit), the\n"
    "share of ACTUAL's pixels outside the reference's silhouette and of the\n"
    "reference's pixels ACTUAL leaves empty, the silhouettes' intersection over\n"
    "union, and a line saying which of these dominates: object PSNR is over the\n"
    "pixels either covers, so a nearly empty picture can score well on it — read\n"
    "the IoU first (tools/reference/image_metrics.h).\n"
    "--json prints all of it as one object. Exit status 0 when identical, 1 when not.\n";

}  // namespace

int cmd_image_diff(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kDiffHelp, stdout);
    return 0;
  }
  std::string output, error;
  if (!args.value("-o", output)) args.value("--output", output);
  const bool json = args.flag("--json");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("image-diff: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("image-diff: " + args.unknown_option_message());
  if (files.size() != 2) return cli::fail("image-diff: expected EXPECTED.png and ACTUAL.png");
  if (!cli::check_output_name(output, ".png", "PNG", error)) return cli::fail("image-diff: " + error);
  Image a, b;
  if (!read_png(files[0], a, error) || !read_png(files[1], b, error))
    return cli::fail(error);
  if (a.width != b.width || a.height != b.height)
    return cli::fail("image-diff: " + files[0] + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + ", " +
                     files[1] + " is " + std::to_string(b.width) + "x" + std::to_string(b.height));
  long differing = 0;
  int largest = 0;
  std::vector<uint8_t> diff(a.rgb.size());
  for (size_t i = 0; i < a.rgb.size(); i += 3) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.rgb[i + c] - b.rgb[i + c]));
    largest = std::max(largest, d);
    if (d > 0) {
      ++differing;
      diff[i] = static_cast<uint8_t>(std::min(255, 128 + 2 * d));
      diff[i + 1] = diff[i + 2] = 0;
    } else {
      for (int c = 0; c < 3; ++c) diff[i + c] = static_cast<uint8_t>(a.rgb[i + c] / 4);
    }
  }
  if (!output.empty() && !write_png(output, Image{a.width, a.height, diff}, error)) return cli::fail(error);
  const ImageComparison m = compare_images(a, b);
  if (json) {
    std::printf("%s\n", cli::Json()
                           .str("expected", files[0])
                           .str("actual", files[1])
                           .integer("width", a.width)
                           .integer("height", a.height)
                           .integer("differing_pixels", differing)
                           .integer("largest_difference", largest)
                           .num("psnr_db", differing ? image_psnr(a, b) : 999)
                           .integer("object_pixels", m.object_pixels)
                           .num("object_psnr_db", differing ? m.object_psnr : 999)
                           .num("ssim", m.ssim)
                           .num("dark_where_lit", m.dark_where_lit)
                           .num("outside_silhouette", m.outside)
                           .num("missing", m.missing)
                           .num("silhouette_iou", m.iou)
                           .str("verdict", silhouette_verdict(m))
                           .done()
                           .c_str());
    return differing ? 1 : 0;
  }
  if (differing == 0) {
    std::printf("%s and %s are identical (%dx%d)\n", files[0].c_str(), files[1].c_str(), a.width, a.height);
    return 0;
  }
  std::printf("%s and %s differ: %ld of %ld pixels, largest channel difference %d, PSNR %.2f dB%s\n", files[0].c_str(),
              files[1].c_str(), differing, static_cast<long>(a.width) * a.height, largest, image_psnr(a, b),
              output.empty() ? "" : (" -> " + output).c_str());
  std::printf("against it as the reference: object PSNR %.2f dB over %ld pixels, SSIM %.4f, dark where lit %.2f %%, "
              "outside its silhouette %.2f %%, missing %.2f %%, silhouette IoU %.3f\n",
              m.object_psnr, m.object_pixels, m.ssim, 100 * m.dark_where_lit, 100 * m.outside, 100 * m.missing, m.iou);
  std::printf("%s\n", silhouette_verdict(m).c_str());
  return 1;
}

}  // namespace stipple
