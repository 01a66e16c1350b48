// stipple levels — bits per point and PSNR of each tree level's cut (the trade), with a plot.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/embedded/model_file.h"
#include "tools/reference/level_trade.h"
#include "tools/reference/plot.h"
#include "tools/reference/sampler.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/kdtree.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kLevelsHelp[] =
    "usage: stipple levels MODEL.spg ORIGINAL [--levels A,B,...] [--json]\n"
    "\n"
    "The size/accuracy trade of a model's tree levels: for each level's cut (the\n"
    "nodes at that depth plus the leaves above it, then all leaves), the nodes\n"
    "in the cut, the bits per original point a client receives for it (its\n"
    "records plus the startup header and class tables), and the PSNR of points\n"
    "regenerated from the cut (as many per node as it held originals) against\n"
    "the original scan, one-sided (the paper's) and symmetric.\n"
    "\n"
    "  --levels A,B,...   the levels to measure (default: every level)\n"
    "  --plot FILE.png    also draw PSNR against bits per point\n"
    "  --json             print the table as a JSON array\n";

}  // namespace

int cmd_levels(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kLevelsHelp, stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
    return 0;
  }
  std::string levels_text, plot_path;
  const bool has_levels = args.value("--levels", levels_text);
  args.value("--plot", plot_path);
  const bool json = args.flag("--json");
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("levels: " + e);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("levels: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("levels: " + args.unknown_option_message());
  if (files.size() != 2) return cli::fail("levels: expected MODEL.spg and ORIGINAL (see stipple levels --help)");
  DecodedModel model;
  PointCloud original;
  std::string error;
  if (!cli::check_output_name(plot_path, ".png", "PNG", error)) return cli::fail("levels: --plot " + error);
  std::vector<uint8_t> file;
  if (!read_spg_file(files[0], file, error) || !decode_spg(files[0], file.data(), file.size(), model, error) ||
      !read_point_cloud(files[1], original, error, scan_options))
    return cli::fail(error);
  std::vector<int> levels;
  if (has_levels) {
    size_t start = 0;
    while (start <= levels_text.size()) {
      const size_t comma = levels_text.find(',', start);
      const std::string part = levels_text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      unsigned long long v;
      if (!cli::parse_uint(part, 65535, v)) return cli::fail("levels: --levels: expected integers, got '" + part + "'");
      levels.push_back(static_cast<int>(v));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  } else {
    for (int l = 0; l <= model.header.depth; ++l) levels.push_back(l);
  }
  const KdTree original_tree(original.positions);  // built once, shared by every level
  ProgressBar progress("levels");
  std::vector<LevelPoint> points;
  if (!measure_levels(
          model, original, original_tree, levels, points, error,
          [&](size_t i) {
            progress.update(static_cast<double>(i) / static_cast<double>(levels.size()), "level " + std::to_string(levels[i]));
          },
          &file))
    return cli::fail(files[0] + ": " + error);
  std::string rows;
  PlotSeries one_sided{"one-sided (paper)", {}, {}, 0x1f77b4, {}}, symmetric{"symmetric", {}, {}, 0xd62728, {}};
  if (!json) {
    progress.finish();
    std::printf("%6s %10s %12s %12s %10s %10s\n", "level", "nodes", "bits/point", "coded", "PSNR-1", "PSNR-sym");
  }
  for (const LevelPoint& p : points) {
    for (PlotSeries* s : {&one_sided, &symmetric}) s->x.push_back(p.bits_per_point);
    one_sided.y.push_back(p.psnr_one_sided);
    symmetric.y.push_back(p.psnr_symmetric);
    one_sided.point_labels.push_back(std::to_string(p.level));
    if (json) {
      cli::Json j;
      j.integer("level", p.level)
          .integer("nodes", static_cast<long long>(p.nodes))
          .num("bits_per_point", p.bits_per_point)
          .num("coded_bits_per_point", p.coded_bits_per_point)
          .num("psnr_one_sided_db", p.psnr_one_sided)
          .num("psnr_symmetric_db", p.psnr_symmetric)
          .num("hausdorff", p.hausdorff);
      rows += (rows.empty() ? "" : ", ") + j.done();
    } else {
      std::printf("%6d %10zu %12.3f %12.3f %10.2f %10.2f\n", p.level, p.nodes, p.bits_per_point, p.coded_bits_per_point,
                  p.psnr_one_sided, p.psnr_symmetric);
    }
  }
  progress.finish();
  if (json) std::printf("[%s]\n", rows.c_str());
  if (!plot_path.empty()) {
    PlotSpec spec;
    const std::string name = std::filesystem::path(files[0]).filename().string();
    spec.title = name + ": PSNR by tree level (labels: level)";
    spec.x_label = "bits per original point (cut records + startup tables)";
    spec.y_label = "PSNR (dB)";
    spec.series = {one_sided, symmetric};
    const Image img = render_plot(spec);
    if (!write_png(plot_path, img, error)) return cli::fail(error);
    if (!json) std::printf("plot: %s\n", plot_path.c_str());
  }
  return 0;
}

}  // namespace stipple
