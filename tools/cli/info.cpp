// stipple info — validates a .spg and describes it (nodes, sizes, partition ratios, view hint, normals facing a point).
#include <cstdio>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "tools/embedded/embedded.h"
#include "tools/cli/cli.h"
#include "tools/embedded/model_file.h"
#include "tools/encoder/hierarchy.h"
#include "tools/encoder/orientation.h"
#include "tools/reference/spg_model.h"

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
  if (!args.unknown_option().empty()) return cli::fail("info: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("info: expected one .spg file (see stipple info --help)");
  double target[3] = {0, 0, 0};
  SpgAxis up_axis = SpgAxis::kNone;
  if (facing_point && facing_up) return cli::fail("info: give one of --facing-point and --facing-up");
  if (facing_point && !cli::parse_vec3(point_text, target))
    return cli::fail("info: --facing-point: expected X,Y,Z (three finite numbers), got '" + point_text + "'");
  if (facing_up && !spg_parse_axis(up_text.c_str(), &up_axis))
    return cli::fail("info: --facing-up: expected +x, -x, +y, -y, +z or -z, got '" + up_text + "'");
  // The file and 4 bytes a node: the Gaussians are not decoded (a valid
  // file of 1-byte records would need ~350 bytes a node as a DecodedModel).
  std::vector<uint8_t> file;
  std::string error;
  if (!read_file(files[0], file, error)) return cli::fail(error);
  // A version 3 file is read expanded; its own size and coded section are what it costs.
  const bool coded = spg_is_coded(file.data(), file.size());
  const size_t file_bytes = file.size();
  if (!expand_coded_spg(file, files[0], error)) return cli::fail(error);
  SpgView view;
  const SpgResult parsed = spg_parse(file.data(), file.size(), &view);
  if (!parsed.ok())
    return cli::fail(spg_error_message(files[0], parsed, file.data(), file.size()));
  const SpgHeader& h = view.header;
  const std::vector<uint32_t> point_count = spg_point_counts(view);
  const auto sigma1_of = [&](uint32_t node) {
    const NodeFields f = unpack_record(h.layout, view.records + size_t{node} * view.record_bytes);
    return spg_class_value(view, 0, 3 * size_t{f[Field::kSigmaP]});
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
  const double bpp = 8.0 * static_cast<double>(file_bytes) / h.point_count;
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
  // Version 3's coded section: what its file holds in place of the records.
  const uint64_t coded_bytes = file_bytes - (file.size() - record_total);
  if (json) {
    cli::Json j;
    j.str("file", files[0])
        .integer("version", coded ? kSpgCodedVersion : h.version)
        .str("tree", h.tree_arity == 2 ? "binary" : "octree")
        .boolean("normals", h.has_normals())
        .boolean("curvature_sign", h.has_curvature_sign())
        .boolean("colors", h.has_color())
        .integer("points", h.point_count)
        .integer("nodes", h.node_count)
        .integer("leaves", h.leaf_count)
        .integer("depth", h.depth)
        .integer("record_bytes", h.layout.record_bytes())
        .integer("bytes", static_cast<long long>(file_bytes))
        .integer("records_total_bytes", static_cast<long long>(record_total))
        .integer("records_coded_bytes", static_cast<long long>(coded ? coded_bytes : record_total))
        .num("bits_per_point", bpp)
        .integer("classes_p", h.class_count[0])
        .integer("classes_n", h.class_count[1])
        .integer("classes_c", h.class_count[2])
        .integer("class_table_bytes", static_cast<long long>(spg_startup_bytes(h.version, h.class_count) - spg_fixed_header_bytes(h.version)))
        .num("apr", ratios.apr)
        .num("capr", ratios.capr)
        .integer("capr_excluded", static_cast<long long>(ratios.capr_excluded))
        .str("view_up", spg_axis_name(h.view_hint.up))
        .str("view_sensor_side", spg_axis_name(h.view_hint.sensor_side))
        .boolean("view_sensor_at_origin", h.view_hint.sensor_at_origin);
    if (facing >= 0) j.num("facing_share", facing);
    std::printf("%s\n", j.done().c_str());
    return 0;
  }
  std::printf("%s: stipple .spg version %u%s, %s tree, %s%s\n", files[0].c_str(), coded ? kSpgCodedVersion : h.version,
              coded ? " (coded records)" : "",
              h.tree_arity == 2 ? "binary 2-means" : "octree",
              h.has_curvature_sign() ? "normals with the curvature's sign" : h.has_normals() ? "normals" : "no normals",
              h.has_color() ? ", colour" : ", no colour");
  std::printf("  points       %s (original)\n", cli::with_commas(h.point_count).c_str());
  std::printf("  nodes        %s (%s leaves), depth %u\n", cli::with_commas(h.node_count).c_str(),
              cli::with_commas(h.leaf_count).c_str(), h.depth);
  std::printf("  records      %d bytes each, %s bytes in all\n", h.layout.record_bytes(),
              cli::with_commas(record_total).c_str());
  if (coded)
    std::printf("               coded in %s bytes, %.2f bytes a node (tables included)\n", cli::with_commas(coded_bytes).c_str(),
                static_cast<double>(coded_bytes) / h.node_count);
  std::printf("  file         %s bytes, %.2f bits per original point\n", cli::with_commas(file_bytes).c_str(), bpp);
  std::printf("  classes      sigma_p %u, sigma_n %u, sigma_c %u (tables %s bytes, %s)\n", h.class_count[0],
              h.class_count[1], h.class_count[2],
              cli::with_commas(spg_startup_bytes(h.version, h.class_count) - spg_fixed_header_bytes(h.version)).c_str(),
              h.version == 1 ? "float32" : "16-bit codes");
  std::printf("  APR %.3f, cAPR %.3f (TOG05 Table II; cAPR from class-quantized sigma1, %llu of %llu families\n"
              "               with a degenerate child left out)\n",
              ratios.apr, ratios.capr, static_cast<unsigned long long>(ratios.capr_excluded),
              static_cast<unsigned long long>(ratios.families));
  double o[3];
  for (int a = 0; a < 3; ++a) o[a] = spg_origin(h, a);
  std::printf("  bbox         (%.10g, %.10g, %.10g) - (%.10g, %.10g, %.10g)\n", o[0] + f32_value(h.bbox_bits[0]),
              o[1] + f32_value(h.bbox_bits[1]), o[2] + f32_value(h.bbox_bits[2]), o[0] + f32_value(h.bbox_bits[3]),
              o[1] + f32_value(h.bbox_bits[4]), o[2] + f32_value(h.bbox_bits[5]));
  if (o[0] != 0 || o[1] != 0 || o[2] != 0)
    std::printf("  origin       (%.17g, %.17g, %.17g): the box is stored relative to it\n", o[0], o[1], o[2]);
  std::printf("  view         up %s, sensor side %s%s\n", spg_axis_name(h.view_hint.up), spg_axis_name(h.view_hint.sensor_side),
              h.view_hint.sensor_at_origin ? ", sensor at the origin: viewers start there, inside the scan" : "");
  if (facing >= 0)
    std::printf("  facing       %.1f %% of the leaves' mean normals face %s %s\n", 100.0 * facing,
                facing_point ? "the point" : "the axis", facing_point ? point_text.c_str() : up_text.c_str());
  return 0;
}

}  // namespace stipple
