// stipple truth — the reference picture from the scan itself: the original
// scan (its mesh when it has faces, else its points) drawn with the camera,
// size, up axis and lighting `stipple render` uses for the encoded model.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "platform/png_io.h"
#include "tools/cli/cli.h"
#include "tools/cli/encode_options.h"
#include "tools/embedded/render_options.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/truth.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kTruthHelp[] =
    "usage: stipple truth SCAN.ply -o TRUTH.png [view and client options]\n"
    "\n"
    "Draws the original scan with the camera `stipple render` uses for the model\n"
    "`stipple encode SCAN.ply` makes (the same bounding box, up axis and default\n"
    "view) and the client's lighting: the scan's mesh when it has faces (Gouraud\n"
    "shading of the encoder's normals), otherwise its points as z-buffered squares\n"
    "of the point size. Compare a render with it: stipple image-diff TRUTH.png\n"
    "RENDER.png (object PSNR, SSIM, dark-where-lit and outside-silhouette shares).\n"
    "The view, size, format, shading, colour and point-size options are render's;\n"
    "--orient and --viewpoint are encode's (give what the model was encoded with).\n";

}  // namespace

int cmd_truth(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kTruthHelp, stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
    std::fputs(kRenderOptionsHelp, stdout);
    return 0;
  }
  RenderOptions o;
  std::string output, error;
  if (!args.value("-o", output)) args.value("--output", output);
  if (!parse_render_options(args, o, error)) return cli::fail("truth: " + error);
  EncodeOptions encode;  // the encoder's view of the scan: --orient, --viewpoint as encode takes them
  if (!parse_orient_options(args, encode.orient, error)) return cli::fail("truth: " + error);
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("truth: " + e);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("truth: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("truth: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("truth: expected one scan (see stipple truth --help)");
  if (output.empty()) return cli::fail("truth: -o TRUTH.png is required");
  if (!cli::check_output_name(output, ".png", "PNG", error)) return cli::fail("truth: " + error);
  if (cli::output_is_input(files[0], output, error)) return cli::fail("truth: " + error);
  PointCloud cloud;
  if (!read_point_cloud(files[0], cloud, error, scan_options)) return cli::fail(error);
  if (cloud.size() == 0) return cli::fail(files[0] + ": the scan has no points");
  // What the encoder would do: its normals, its frame (view hint), its box.
  const ScanFrame frame = prepare_scan(cloud, encode);
  float bmin[3], bmax[3];  // relative to the origin, as the encoder stores them
  const Vec3 origin = stored_origin(cloud.positions, kSpgVersion);
  stored_bounding_box(cloud.positions, origin, bmin, bmax);
  SpgHeader header;
  header.version = kSpgVersion;
  header.view_hint = frame.hint;
  for (int a = 0; a < 3; ++a) {  // the stored box: the default view of a scan taken from inside is placed by it
    std::memcpy(&header.bbox_bits[a], &bmin[a], 4);
    std::memcpy(&header.bbox_bits[3 + a], &bmax[a], 4);
    std::memcpy(&header.origin_bits[a], &origin[a], 8);
  }
  header.flags = static_cast<uint16_t>((cloud.has_normals() ? kAttrNormals : 0) | (cloud.has_colors() ? kAttrColor : 0));
  TruthStats stats;
  const Image image = render_truth(cloud, origin + Vec3(bmin[0], bmin[1], bmin[2]), origin + Vec3(bmax[0], bmax[1], bmax[2]), header, o.config,
                                   o.view, &stats);
  if (!write_png(output, image, error)) return cli::fail(error);
  std::printf("%s: %s, %zu drawn (%zu behind the near plane) -> %s\n", files[0].c_str(),
              stats.mesh ? (std::to_string(cloud.triangles.size()) + " triangles").c_str()
                         : (std::to_string(cloud.size()) + " points").c_str(),
              stats.drawn, stats.skipped, output.c_str());
  return 0;
}

}  // namespace stipple
