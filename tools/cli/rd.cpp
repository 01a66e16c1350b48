// stipple rd — rate against distortion across encoder settings (TOG05 Fig.
// 19a): each setting's model, level by level, bits per original point
// against the PSNR of points regenerated from the level's cut.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/level_trade.h"
#include "tools/reference/plot.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kRdHelp[] =
    "usage: stipple rd SCAN.ply -o DIR [--settings NAME,...] [--extra CSV]\n"
    "\n"
    "Encodes the scan with each encoder setting and measures every tree level of\n"
    "each model as `stipple levels` does: bits per original point a client\n"
    "receives for the level's cut (records plus the startup: header and class\n"
    "tables) against the PSNR of points regenerated from it, one-sided (the\n"
    "paper's) and symmetric. Writes DIR/rd.csv and DIR/rd.png (one-sided PSNR\n"
    "against bits per point, one line per setting). A progress bar on a terminal.\n"
    "--extra CSV adds another coder's points to the plot: lines of\n"
    "NAME,BITS_PER_POINT,PSNR_ONE_SIDED_DB[,...] after a header line, as\n"
    "tools/draco_rd.sh writes for Draco.\n"
    "\n"
    "settings (default: all):\n"
    "  default        stipple encode's defaults (leaves under 16 points; class\n"
    "                 counts scaled to the scan: stipple encode --help)\n"
    "  leaf-4         leaves under 4 points\n"
    "  leaf-32        leaves under 32 points\n"
    "  classes-1024   1024 sigma_p and sigma_n classes\n"
    "  classes-256    256 of each\n"
    "  no-normals     positions only: no normals, no colour (9-byte records)\n"
    "  float-tables   the defaults in format version 1 (float32 class tables,\n"
    "                 twice the startup of version 2's 16-bit codes)\n"
    "  tolerance-1%   encode --tolerance 1% (the variance stop and position widths\n"
    "                 of an error bound of 1 % of the diagonal)\n"
    "  tolerance-0.5% the same at 0.5 %\n"
    "  tolerance-0.3% the same at 0.3 %\n"
    "  tolerance-0.1% the same at 0.1 %\n";

struct RdSetting {
  const char* name;
  void (*apply)(EncodeOptions&);
};
// What encode --tolerance D% sets.
void tolerance(EncodeOptions& o, double share) {
  o.tolerance = share;
  o.tolerance_relative = true;
  o.tree.leaf_size = 2;
}

const RdSetting kSettings[] = {
    {"default", [](EncodeOptions&) {}},
    {"leaf-4", [](EncodeOptions& o) { o.tree.leaf_size = 4; }},
    {"leaf-32", [](EncodeOptions& o) { o.tree.leaf_size = 32; }},
    {"classes-1024", [](EncodeOptions& o) { o.classes_p = o.classes_n = 1024; }},
    {"classes-256", [](EncodeOptions& o) { o.classes_p = o.classes_n = 256; }},
    {"no-normals", [](EncodeOptions& o) { o.normals = o.colors = false; }},
    {"float-tables", [](EncodeOptions& o) { o.format_version = 1; }},
    {"tolerance-1%", [](EncodeOptions& o) { tolerance(o, 0.01); }},
    {"tolerance-0.5%", [](EncodeOptions& o) { tolerance(o, 0.005); }},
    {"tolerance-0.3%", [](EncodeOptions& o) { tolerance(o, 0.003); }},
    {"tolerance-0.1%", [](EncodeOptions& o) { tolerance(o, 0.001); }},
};

}  // namespace

int cmd_rd(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kRdHelp, stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
    return 0;
  }
  std::string output, chosen, extra, error;
  args.value("--extra", extra);
  if (!args.value("-o", output)) args.value("--output", output);
  args.value("--settings", chosen);
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("rd: " + e);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("rd: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("rd: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("rd: expected one scan (see stipple rd --help)");
  if (output.empty()) return cli::fail("rd: -o DIR is required");
  std::vector<const RdSetting*> settings;
  if (chosen.empty()) {
    for (const RdSetting& s : kSettings) settings.push_back(&s);
  } else {
    for (size_t start = 0; start <= chosen.size();) {
      const size_t comma = chosen.find(',', start);
      const std::string name = chosen.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      const RdSetting* found = nullptr;
      for (const RdSetting& s : kSettings)
        if (name == s.name) found = &s;
      if (!found) return cli::fail("rd: --settings: unknown setting '" + name + "' (see stipple rd --help)");
      settings.push_back(found);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  PointCloud scan;
  if (!read_point_cloud(files[0], scan, error, scan_options)) return cli::fail(error);
  std::error_code ec;
  std::filesystem::create_directories(output, ec);
  if (ec) return cli::fail("rd: " + output + ": " + ec.message());
  const KdTree scan_tree(scan.positions);
  ProgressBar progress("rd");
  std::string csv = "setting,level,nodes,bits_per_point,psnr_one_sided_db,psnr_symmetric_db,hausdorff,coded_bits_per_point\n";
  PlotSpec spec;
  spec.title = std::filesystem::path(files[0]).filename().string() + ": rate against distortion by encoder setting";
  spec.x_label = "bits per original point (cut records + startup tables)";
  spec.y_label = "PSNR one-sided (dB)";
  static const uint32_t colors[] = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2};
  for (size_t i = 0; i < settings.size(); ++i) {
    const double share = 1.0 / static_cast<double>(settings.size());
    progress.update(static_cast<double>(i) * share, std::string("encoding, ") + settings[i]->name);
    EncodeOptions o;
    settings[i]->apply(o);
    PointCloud copy = scan;
    std::vector<uint8_t> spg;
    EncodeReport report;
    if (!encode_cloud(copy, o, spg, report, error)) return cli::fail(files[0] + ": " + settings[i]->name + ": " + error);
    DecodedModel model;
    if (!decode_spg(settings[i]->name, spg.data(), spg.size(), model, error)) return cli::fail(error);
    std::vector<int> levels;
    for (int l = 0; l <= model.header.depth; ++l) levels.push_back(l);
    std::vector<LevelPoint> points;
    if (!measure_levels(
            model, scan, scan_tree, levels, points, error,
            [&](size_t k) {
              progress.update((static_cast<double>(i) + 0.2 + 0.8 * static_cast<double>(k) / static_cast<double>(levels.size())) * share,
                              std::string(settings[i]->name) + ", level " + std::to_string(k));
            },
            &spg))
      return cli::fail(files[0] + ": " + settings[i]->name + ": " + error);
    PlotSeries series{settings[i]->name, {}, {}, colors[i % (sizeof colors / sizeof colors[0])], {}};
    for (const LevelPoint& p : points) {
      char line[256];
      std::snprintf(line, sizeof line, "%s,%d,%zu,%.4f,%.3f,%.3f,%.6g,%.4f\n", settings[i]->name, p.level, p.nodes,
                    p.bits_per_point, p.psnr_one_sided, p.psnr_symmetric, p.hausdorff, p.coded_bits_per_point);
      csv += line;
      series.x.push_back(p.bits_per_point);
      series.y.push_back(p.psnr_one_sided);
    }
    spec.series.push_back(series);
  }
  progress.finish();
  if (!extra.empty()) {
    std::vector<uint8_t> bytes;
    if (!read_file(extra, bytes, error)) return cli::fail(error);
    const std::string text(bytes.begin(), bytes.end());
    size_t line_no = 0;
    for (size_t at = 0; at < text.size();) {
      const size_t end = std::min(text.find('\n', at), text.size());
      const std::string line = text.substr(at, end - at);
      at = end + 1;
      if (line_no++ == 0 || line.empty()) continue;  // the header
      const size_t c1 = line.find(','), c2 = c1 == std::string::npos ? c1 : line.find(',', c1 + 1);
      double bits = 0, psnr = 0;
      if (c2 == std::string::npos || !cli::parse_double(line.substr(c1 + 1, c2 - c1 - 1), bits) ||
          !cli::parse_double(line.substr(c2 + 1, line.find(',', c2 + 1) - c2 - 1), psnr))
        return cli::fail(extra + ":" + std::to_string(line_no) + ": expected NAME,BITS_PER_POINT,PSNR_ONE_SIDED_DB");
      const std::string name = line.substr(0, c1);
      auto it = std::find_if(spec.series.begin(), spec.series.end(), [&](const PlotSeries& p) { return p.label == name; });
      if (it == spec.series.end()) {
        spec.series.push_back(PlotSeries{name, {}, {}, 0x000000, {}});
        it = spec.series.end() - 1;
      }
      it->x.push_back(bits);
      it->y.push_back(psnr);
    }
  }
  if (!write_file_atomic(output + "/rd.csv", std::vector<uint8_t>(csv.begin(), csv.end()), error)) return cli::fail(error);
  if (!write_png(output + "/rd.png", render_plot(spec), error)) return cli::fail(error);
  std::printf("%s: %zu settings -> %s/rd.csv, %s/rd.png\n", files[0].c_str(), settings.size(), output.c_str(), output.c_str());
  return 0;
}

}  // namespace stipple
