// stipple info / stipple sample / stipple metrics.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli.h"
#include "tools/host/hierarchy.h"
#include "tools/host/kdtree.h"
#include "tools/host/metrics.h"
#include "tools/host/orientation.h"
#include "tools/host/plot.h"
#include "tools/host/ply_io.h"
#include "tools/host/sampler.h"
#include "tools/host/spg_model.h"

namespace stipple {
namespace {

const char kInfoHelp[] =
    "usage: stipple info MODEL.spg [--json] [--facing-point X,Y,Z | --facing-up AXIS]\n"
    "\n"
    "Validates a .spg file (every check of docs/format.md) and prints its nodes,\n"
    "leaves, depth, record size, bytes, bits per original point, class counts and\n"
    "the partition ratios of TOG05 Table II: APR (average over internal nodes of\n"
    "the largest / smallest child point count) and cAPR (the same for sigma1),\n"
    "and the view hint (up axis, sensor side).\n"
    "\n"
    "  --facing-point X,Y,Z  the share of leaves whose mean normal faces the point\n"
    "                        (n . (X - mean) > 0): normals toward a sensor\n"
    "  --facing-up AXIS      the share whose mean normal has a positive AXIS\n"
    "                        component (+x -x +y -y +z -z): normals toward the sky\n";

const char kSampleHelp[] =
    "usage: stipple sample MODEL.spg (--level L | --leaves) [--per-node original|N] -o POINTS.ply\n"
    "\n"
    "Double-precision reference decoder: generates points from each node of a cut\n"
    "by quasi-random sampling of its Gaussian (docs/sampling.md) and writes them,\n"
    "with normals and colours when the model has them, as binary PLY.\n"
    "\n"
    "  --level L             nodes at depth L, and leaves above it\n"
    "  --leaves              all leaves\n"
    "  --per-node original   as many points per node as it held originals (default;\n"
    "                        the paper's PSNR experiment)\n"
    "  --per-node N          N points per node\n"
    "  --max-points M        refuse cuts that would generate more than M points\n"
    "                        (default: what a quarter of this host's memory holds at\n"
    "                        100 bytes a point, at most 268,435,456: a file's point\n"
    "                        counts are only claims)\n";

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

int cmd_info(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kInfoHelp, stdout);
    return 0;
  }
  const bool json = args.flag("--json");
  std::string point_text, up_text;
  const bool facing_point = args.value("--facing-point", point_text), facing_up = args.value("--facing-up", up_text);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("info: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("info: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 1) return cli::fail("info: expected one .spg file (see stipple info --help)");
  double target[3] = {0, 0, 0};
  SpgAxis up_axis = SpgAxis::kNone;
  if (facing_point && facing_up) return cli::fail("info: give one of --facing-point and --facing-up");
  if (facing_point && !cli::parse_vec3(point_text, target))
    return cli::fail("info: --facing-point: expected X,Y,Z (three finite numbers), got '" + point_text + "'");
  if (facing_up && !parse_axis(up_text, up_axis))
    return cli::fail("info: --facing-up: expected +x, -x, +y, -y, +z or -z, got '" + up_text + "'");
  // The file and 4 bytes a node: the Gaussians are not decoded (a valid
  // file of 1-byte records would need ~350 bytes a node as a DecodedModel).
  std::vector<uint8_t> file;
  std::string error;
  if (!read_file(files[0], file, error)) return cli::fail(error);
  SpgView view;
  const SpgResult parsed = spg_parse(file.data(), file.size(), &view);
  if (!parsed.ok())
    return cli::fail(files[0] + ": byte " + std::to_string(parsed.offset) + ": " + spg_error_text(parsed.error));
  const SpgHeader& h = view.header;
  const std::vector<uint32_t> point_count = spg_point_counts(view);
  const auto sigma1_of = [&](uint32_t node) {
    const NodeFields f = unpack_record(h.layout, view.records + size_t{node} * view.record_bytes);
    return f32_value(load_u32le(view.sigma_p + 12 * size_t{f[Field::kSigmaP]}));
  };
  PartitionRatioAccumulator acc;
  double counts[8], sigma1[8];
  for (uint32_t i = 0, next_child = 1; i < h.node_count; ++i) {
    const uint32_t children = spg_child_count(view, i);
    for (uint32_t c = 0; c < children; ++c) {
      counts[c] = point_count[next_child + c];
      sigma1[c] = sigma1_of(next_child + c);
    }
    if (children) acc.add_family(sigma1_of(i), counts, sigma1, children);
    next_child += children;
  }
  const PartitionRatios ratios = acc.result();
  const double bpp = 8.0 * static_cast<double>(file.size()) / h.point_count;
  // Leaves whose mean normal faces the point or the axis: decoded one at a time.
  double facing = -1;
  if ((facing_point || facing_up) && h.has_normals()) {
    DecodedModel model;
    if (!decode_spg(files[0], file.data(), file.size(), model, error)) return cli::fail(error);
    const Vec3 p(target[0], target[1], target[2]), up = axis_vector(up_axis);
    uint64_t leaves = 0, toward = 0;
    for (const DecodedNode& node : model.nodes) {
      if (!node.leaf()) continue;
      const Vec3 n = node.normal_frame.col(2);
      ++leaves;
      toward += facing_point ? n.dot(p - node.position.mean) > 0 : n.dot(up) > 0;
    }
    facing = static_cast<double>(toward) / static_cast<double>(leaves);
  } else if (facing_point || facing_up) {
    return cli::fail(files[0] + ": --facing-point/--facing-up: the model has no normals");
  }
  const uint64_t record_total = static_cast<uint64_t>(h.node_count) * static_cast<uint64_t>(h.layout.record_bytes());
  if (json) {
    cli::Json j;
    j.str("file", files[0])
        .integer("version", h.version)
        .str("tree", h.tree_arity == 2 ? "binary" : "octree")
        .boolean("normals", h.has_normals())
        .boolean("colors", h.has_color())
        .integer("points", h.point_count)
        .integer("nodes", h.node_count)
        .integer("leaves", h.leaf_count)
        .integer("depth", h.depth)
        .integer("record_bytes", h.layout.record_bytes())
        .integer("bytes", static_cast<long long>(file.size()))
        .integer("records_total_bytes", static_cast<long long>(record_total))
        .num("bits_per_point", bpp)
        .integer("classes_p", h.class_count[0])
        .integer("classes_n", h.class_count[1])
        .integer("classes_c", h.class_count[2])
        .num("apr", ratios.apr)
        .num("capr", ratios.capr)
        .integer("capr_excluded", static_cast<long long>(ratios.capr_excluded))
        .str("view_up", axis_name(h.view_hint.up))
        .str("view_sensor_side", axis_name(h.view_hint.sensor_side));
    if (facing >= 0) j.num("facing_share", facing);
    std::printf("%s\n", j.done().c_str());
    return 0;
  }
  std::printf("%s: stipple .spg version %u, %s tree, %s%s\n", files[0].c_str(), h.version,
              h.tree_arity == 2 ? "binary 2-means" : "octree", h.has_normals() ? "normals" : "no normals",
              h.has_color() ? ", colour" : ", no colour");
  std::printf("  points       %s (original)\n", cli::with_commas(h.point_count).c_str());
  std::printf("  nodes        %s (%s leaves), depth %u\n", cli::with_commas(h.node_count).c_str(),
              cli::with_commas(h.leaf_count).c_str(), h.depth);
  std::printf("  records      %d bytes each, %s bytes in all\n", h.layout.record_bytes(),
              cli::with_commas(record_total).c_str());
  std::printf("  file         %s bytes, %.2f bits per original point\n", cli::with_commas(file.size()).c_str(), bpp);
  std::printf("  classes      sigma_p %u, sigma_n %u, sigma_c %u\n", h.class_count[0], h.class_count[1],
              h.class_count[2]);
  std::printf("  APR %.3f, cAPR %.3f (TOG05 Table II; cAPR from class-quantized sigma1, %llu of %llu families\n"
              "               with a degenerate child left out)\n",
              ratios.apr, ratios.capr, static_cast<unsigned long long>(ratios.capr_excluded),
              static_cast<unsigned long long>(ratios.families));
  std::printf("  bbox         (%g, %g, %g) - (%g, %g, %g)\n", f32_value(h.bbox_bits[0]), f32_value(h.bbox_bits[1]),
              f32_value(h.bbox_bits[2]), f32_value(h.bbox_bits[3]), f32_value(h.bbox_bits[4]), f32_value(h.bbox_bits[5]));
  std::printf("  view         up %s, sensor side %s\n", axis_name(h.view_hint.up), axis_name(h.view_hint.sensor_side));
  if (facing >= 0)
    std::printf("  facing       %.1f %% of the leaves' mean normals face %s %s\n", 100.0 * facing,
                facing_point ? "the point" : "the axis", facing_point ? point_text.c_str() : up_text.c_str());
  return 0;
}

int cmd_sample(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kSampleHelp, stdout);
    return 0;
  }
  std::string level_text, per_node_text = "original", output;
  const bool has_level = args.value("--level", level_text);
  const bool leaves = args.flag("--leaves");
  args.value("--per-node", per_node_text);
  std::string max_text;
  const bool has_max = args.value("--max-points", max_text);
  if (!args.value("-o", output)) args.value("--output", output);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("sample: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("sample: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 1) return cli::fail("sample: expected one .spg file (see stipple sample --help)");
  if (has_level == leaves) return cli::fail("sample: give exactly one of --level L and --leaves");
  if (output.empty()) return cli::fail("sample: -o POINTS.ply is required");
  unsigned long long level = 0, per_node = 0;
  if (has_level && !cli::parse_uint(level_text, 65535, level))
    return cli::fail("sample: --level: expected a non-negative integer, got '" + level_text + "'");
  if (per_node_text != "original" && (!cli::parse_uint(per_node_text, 1u << 20, per_node) || per_node == 0))
    return cli::fail("sample: --per-node: expected 'original' or a positive integer, got '" + per_node_text + "'");
  unsigned long long max_points = default_max_samples(physical_memory_bytes());
  if (has_max && !cli::parse_uint(max_text, ~0ull, max_points))
    return cli::fail("sample: --max-points: expected a non-negative integer, got '" + max_text + "'");
  DecodedModel model;
  std::string error;
  if (!load_spg(files[0], model, error)) return cli::fail(error);
  const std::vector<uint32_t> cut = leaves ? leaf_cut(model) : level_cut(model, static_cast<int>(level));
  const uint64_t count = cut_sample_count(model, cut, static_cast<uint32_t>(per_node));
  if (count > max_points)
    return cli::fail(files[0] + ": the cut would generate " + cli::with_commas(count) + " points, more than --max-points " +
                     cli::with_commas(max_points) + (has_max ? "" : " (the default for this host's memory)"));
  const PointCloud points = sample_cut(model, cut, static_cast<uint32_t>(per_node));
  if (!write_ply(output, points, error)) return cli::fail(error);
  std::printf("%s: %s nodes in the cut, %s points -> %s\n", files[0].c_str(), cli::with_commas(cut.size()).c_str(),
              cli::with_commas(points.size()).c_str(), output.c_str());
  return 0;
}

int cmd_metrics(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kMetricsHelp, stdout);
    return 0;
  }
  std::string spg_path;
  const bool has_spg = args.value("--spg", spg_path);
  const bool json = args.flag("--json");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("metrics: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("metrics: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 2) return cli::fail("metrics: expected ORIGINAL and GENERATED (see stipple metrics --help)");
  PointCloud original, generated;
  std::string error;
  if (!read_point_cloud(files[0], original, error) || !read_point_cloud(files[1], generated, error))
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
    return 0;
  }
  std::string levels_text, plot_path;
  const bool has_levels = args.value("--levels", levels_text);
  args.value("--plot", plot_path);
  const bool json = args.flag("--json");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("levels: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("levels: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 2) return cli::fail("levels: expected MODEL.spg and ORIGINAL (see stipple levels --help)");
  DecodedModel model;
  PointCloud original;
  std::string error;
  if (!load_spg(files[0], model, error) || !read_point_cloud(files[1], original, error)) return cli::fail(error);
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
  const SpgHeader& h = model.header;
  const double startup_bytes = static_cast<double>(spg_startup_bytes(h.class_count));
  const KdTree original_tree(original.positions);  // built once, shared by every level
  ProgressBar progress("levels");
  std::string rows;
  PlotSeries one_sided{"one-sided (paper)", {}, {}, 0x1f77b4, {}}, symmetric{"symmetric", {}, {}, 0xd62728, {}};
  if (!json) std::printf("%6s %10s %12s %10s %10s\n", "level", "nodes", "bits/point", "PSNR-1", "PSNR-sym");
  for (size_t i = 0; i < levels.size(); ++i) {
    progress.update(static_cast<double>(i) / static_cast<double>(levels.size()), "level " + std::to_string(levels[i]));
    const std::vector<uint32_t> cut = level_cut(model, levels[i]);
    const uint64_t limit = default_max_samples(physical_memory_bytes());
    if (cut_sample_count(model, cut, 0) > limit)
      return cli::fail(files[0] + ": level " + std::to_string(levels[i]) + " would generate more than " +
                       cli::with_commas(limit) + " points (the limit for this host's memory)");
    const CloudMetrics m = compare_clouds(original, original_tree, sample_cut(model, cut, 0));
    const double bits = 8.0 * (startup_bytes + static_cast<double>(cut.size()) * h.layout.record_bytes()) /
                        static_cast<double>(original.size());
    for (PlotSeries* s : {&one_sided, &symmetric}) s->x.push_back(bits);
    one_sided.y.push_back(m.psnr_one_sided);
    symmetric.y.push_back(m.psnr_symmetric);
    one_sided.point_labels.push_back(std::to_string(levels[i]));
    if (json) {
      cli::Json j;
      j.integer("level", levels[i])
          .integer("nodes", static_cast<long long>(cut.size()))
          .num("bits_per_point", bits)
          .num("psnr_one_sided_db", m.psnr_one_sided)
          .num("psnr_symmetric_db", m.psnr_symmetric)
          .num("hausdorff", m.hausdorff);
      rows += (rows.empty() ? "" : ", ") + j.done();
    } else {
      progress.finish();
      std::printf("%6d %10zu %12.3f %10.2f %10.2f\n", levels[i], cut.size(), bits, m.psnr_one_sided, m.psnr_symmetric);
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
