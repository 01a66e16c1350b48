// stipple metrics — nearest-neighbour error and PSNR between two point sets.
#include <cstdio>
#include <string>
#include <vector>

#include "tools/cli/cli.h"
#include "tools/reference/metrics.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kMetricsHelp[] =
    "usage: stipple metrics ORIGINAL GENERATED [--spg MODEL.spg] [--json]\n"
    "\n"
    "Nearest-neighbour distances both ways (kd-tree, exact): RMS, mean, maximum;\n"
    "PSNR = 20 log10(original bbox diagonal / RMS), one-sided (generated ->\n"
    "original, the paper's) and symmetric (the worse direction); Hausdorff\n"
    "distance; normal angle error and RGB colour error when both clouds carry\n"
    "them (generated -> nearest original); with --spg,\n"
    "the model's bits per original point.\n";

}  // namespace

int cmd_metrics(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kMetricsHelp, stdout);
    std::fputs("(--columns applies to ORIGINAL)\n", stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
    return 0;
  }
  std::string spg_path;
  const bool has_spg = args.value("--spg", spg_path);
  const bool json = args.flag("--json");
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("metrics: " + e);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("metrics: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("metrics: " + args.unknown_option_message());
  if (files.size() != 2) return cli::fail("metrics: expected ORIGINAL and GENERATED (see stipple metrics --help)");
  PointCloud original, generated;
  std::string error;
  if (!read_point_cloud(files[0], original, error, scan_options) || !read_point_cloud(files[1], generated, error))
    return cli::fail(error);
  cli::warn(original.warnings);
  cli::warn(generated.warnings);
  double bpp = -1;
  if (has_spg) {
    DecodedModel model;
    if (!load_spg(spg_path, model, error)) return cli::fail(error);
    bpp = 8.0 * static_cast<double>(model.file_bytes) / static_cast<double>(original.size());
  }
  const CloudMetrics m = compare_clouds(original, generated);
  const DirectedDistance& g2o = m.generated_to_original;
  const DirectedDistance& o2g = m.original_to_generated;
  if (json) {
    cli::Json j;
    j.integer("original_points", static_cast<long long>(original.size()))
        .integer("generated_points", static_cast<long long>(generated.size()))
        .num("diagonal", m.diagonal)
        .num("rms_generated_to_original", g2o.rms)
        .num("rms_original_to_generated", o2g.rms)
        .num("mean_generated_to_original", g2o.mean)
        .num("mean_original_to_generated", o2g.mean)
        .num("max_generated_to_original", g2o.max)
        .num("max_original_to_generated", o2g.max)
        .num("hausdorff", m.hausdorff)
        .num("psnr_one_sided_db", m.psnr_one_sided)
        .num("psnr_symmetric_db", m.psnr_symmetric);
    if (g2o.normal_rms_deg >= 0) j.num("normal_rms_deg", g2o.normal_rms_deg).num("normal_mean_deg", g2o.normal_mean_deg);
    if (g2o.color_rms >= 0) j.num("color_rms", g2o.color_rms);
    if (bpp >= 0) j.num("bits_per_point", bpp);
    std::printf("%s\n", j.done().c_str());
    return 0;
  }
  std::printf("original %s points, generated %s points, bbox diagonal %.6g\n",
              cli::with_commas(original.size()).c_str(), cli::with_commas(generated.size()).c_str(), m.diagonal);
  std::printf("  generated -> original   RMS %.4g  mean %.4g  max %.4g\n", g2o.rms, g2o.mean, g2o.max);
  std::printf("  original -> generated   RMS %.4g  mean %.4g  max %.4g\n", o2g.rms, o2g.mean, o2g.max);
  std::printf("  PSNR  %.2f dB one-sided (paper), %.2f dB symmetric\n", m.psnr_one_sided, m.psnr_symmetric);
  std::printf("  Hausdorff %.4g (%.4f%% of the diagonal)\n", m.hausdorff, 100 * m.hausdorff / m.diagonal);
  if (g2o.normal_rms_deg >= 0)
    std::printf("  normals  %.2f deg RMS, %.2f deg mean (generated vs nearest original)\n", g2o.normal_rms_deg,
                g2o.normal_mean_deg);
  if (g2o.color_rms >= 0)
    std::printf("  colour   %.4f RMS RGB distance (0..1 units; %.1f in 8-bit steps)\n", g2o.color_rms,
                g2o.color_rms * 255);
  if (bpp >= 0) std::printf("  %.3f bits per original point (%s)\n", bpp, spg_path.c_str());
  return 0;
}

}  // namespace stipple
