// stipple encode / stipple demo.
#include <cstdio>
#include <string>

#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli.h"
#include "tools/host/encoder.h"
#include "tools/host/metrics.h"
#include "tools/host/normals.h"
#include "tools/host/ply_io.h"
#include "tools/host/sampler.h"
#include "tools/host/spg_model.h"

namespace stipple {
namespace {

const char kEncodeHelp[] =
    "usage: stipple encode SCAN -o MODEL.spg [options]\n"
    "\n"
    "Builds the hierarchy of Gaussians of a scan (PLY ascii/binary, or x y z\n"
    "[nx ny nz] [r g b] text) and writes it as a .spg file (docs/format.md).\n"
    "\n"
    "options:\n"
    "  -o, --output FILE     the .spg to write (required)\n"
    "  --leaf-size N         nodes with fewer than N points are leaves (default 16)\n"
    "  --classes P,N,C       sigma classes for positions, normals, colours\n"
    "                        (at most 4096,4096,64; 0 = automatic, the default:\n"
    "                        clamp(nodes/16, 64, 4096) for P and N, 64 for C)\n"
    "  --balance B           2-means balance band [B, 1-B] before the Euclidean\n"
    "                        fallback (default 0.3)\n"
    "  --octree              octree partition (SGP03, TOG05 Table II baseline)\n"
    "  --no-normals          store no normals (13 -> 9 bytes per node)\n"
    "  --no-color            store no colours even if the scan has them\n"
    "  --shrink ETA0,ETA1    curvature shrink of the thin axis (default 0.25,2)\n"
    "  --no-shrink           no curvature shrink\n"
    "  --neighbours K        k for normals of bare point clouds (default 12)\n"
    "  --threads N           worker threads (default 2)\n"
    "  --every K             keep every K-th point (after normals are derived from\n"
    "                        the full mesh): quick previews and scaling studies\n"
    "  --json                print the summary as JSON\n"
    "  -q, --quiet           no progress bar\n";

const char kDemoHelp[] =
    "usage: stipple demo [--scan FILE] [-o MODEL.spg] [encode options]\n"
    "\n"
    "The main job on the embedded default, in one process and without a network:\n"
    "encodes the bundled scan (" STIPPLE_DEFAULT_SCAN "),\n"
    "decodes it again with the reference decoder, regenerates the leaves'\n"
    "points and prints size, time and geometric error.\n";

// Parses the options shared by encode and demo. Returns false on a bad value.
bool parse_encode_options(cli::Args& args, EncodeOptions& o, bool& quiet, bool& json, std::string& error) {
  std::string v;
  unsigned long long u;
  if (args.value("--leaf-size", v)) {
    if (!cli::parse_uint(v, 1u << 20, u) || u < 2) return error = "--leaf-size: expected an integer >= 2, got '" + v + "'", false;
    o.tree.leaf_size = static_cast<uint32_t>(u);
  }
  if (args.value("--classes", v)) {
    unsigned long long c[3];
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t comma = v.find(',', start);
      const std::string part = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (!cli::parse_uint(part, 65535, c[k]) || (k < 2 && comma == std::string::npos))
        return error = "--classes: expected P,N,C (three integers), got '" + v + "'", false;
      start = comma + 1;
    }
    o.classes_p = static_cast<int>(c[0]);
    o.classes_n = static_cast<int>(c[1]);
    o.classes_c = static_cast<int>(c[2]);
  }
  if (args.value("--balance", v)) {
    if (!cli::parse_double(v, o.tree.balance) || o.tree.balance < 0 || o.tree.balance > 0.5)
      return error = "--balance: expected a number in [0, 0.5], got '" + v + "'", false;
  }
  if (args.value("--shrink", v)) {
    const size_t comma = v.find(',');
    if (comma == std::string::npos || !cli::parse_double(v.substr(0, comma), o.tree.stats.shrink_eta0) ||
        !cli::parse_double(v.substr(comma + 1), o.tree.stats.shrink_eta1) || o.tree.stats.shrink_eta0 < 0 ||
        o.tree.stats.shrink_eta0 > 1 || o.tree.stats.shrink_eta1 < 0)
      return error = "--shrink: expected ETA0,ETA1 with ETA0 in [0, 1] and ETA1 >= 0, got '" + v + "'", false;
  }
  if (args.value("--neighbours", v)) {
    if (!cli::parse_uint(v, 64, u) || u < 3) return error = "--neighbours: expected 3..64, got '" + v + "'", false;
    o.normal_neighbours = static_cast<int>(u);
  }
  if (args.value("--threads", v)) {
    if (!cli::parse_uint(v, 256, u) || u < 1) return error = "--threads: expected 1..256, got '" + v + "'", false;
    o.tree.threads = static_cast<int>(u);
  }
  if (args.flag("--no-shrink")) o.tree.stats.shrink_eta0 = 1.0;
  o.tree.octree = args.flag("--octree");
  o.normals = !args.flag("--no-normals");
  o.colors = !args.flag("--no-color");
  quiet = args.flag("--quiet") || args.flag("-q");
  json = args.flag("--json");
  if (args.bad()) return error = args.error(), false;
  return true;
}

std::string summary_json(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb) {
  cli::Json j;
  j.str("scan", scan)
      .integer("points", static_cast<long long>(r.points))
      .integer("nodes", static_cast<long long>(r.nodes))
      .integer("leaves", static_cast<long long>(r.leaves))
      .integer("depth", r.depth)
      .integer("bytes", static_cast<long long>(r.bytes))
      .integer("record_bytes", static_cast<long long>(r.record_bytes))
      .num("bits_per_point", r.bits_per_point)
      .num("seconds", seconds)
      .num("peak_mb", peak_mb)
      .str("normals", r.normals_source)
      .boolean("colors", r.colors)
      .integer("classes_p", r.classes[0])
      .integer("classes_n", r.classes[1])
      .integer("classes_c", r.classes[2])
      .num("apr", r.ratios.apr)
      .num("capr", r.ratios.capr)
      .integer("capr_excluded", static_cast<long long>(r.ratios.capr_excluded))
      .integer("euclidean_fallbacks", static_cast<long long>(r.tree.euclidean_fallbacks))
      .integer("unbalanced_splits", static_cast<long long>(r.tree.unbalanced));
  return j.done();
}

void print_summary(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb) {
  std::printf("%s: %s points, %s nodes, %s leaves, depth %d, %s bytes (%llu-byte records), %.2f bits/point, "
              "%.2f s, peak %.0f MB\n",
              scan.c_str(), cli::with_commas(r.points).c_str(), cli::with_commas(r.nodes).c_str(),
              cli::with_commas(r.leaves).c_str(), r.depth, cli::with_commas(r.bytes).c_str(),
              static_cast<unsigned long long>(r.record_bytes), r.bits_per_point, seconds, peak_mb);
}

// Keeps every k-th point. Normals are derived first, from the full mesh, since
// the subset's triangles would be meaningless.
void keep_every(PointCloud& cloud, unsigned long long k, const EncodeOptions& o) {
  if (o.normals) estimate_normals(cloud, o.normal_neighbours);
  PointCloud out;
  for (size_t i = 0; i < cloud.size(); i += k) {
    out.positions.push_back(cloud.positions[i]);
    if (cloud.has_normals()) out.normals.push_back(cloud.normals[i]);
    if (cloud.has_colors()) out.colors.push_back(cloud.colors[i]);
  }
  cloud = std::move(out);
}

}  // namespace

int cmd_encode(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kEncodeHelp, stdout);
    return 0;
  }
  EncodeOptions options;
  bool quiet = false, json = false;
  std::string output, error;
  if (!args.value("-o", output)) args.value("--output", output);
  if (!parse_encode_options(args, options, quiet, json, error)) return cli::fail(error);
  std::string every_text;
  unsigned long long every = 1;
  if (args.value("--every", every_text) && (!cli::parse_uint(every_text, 1u << 30, every) || every == 0))
    return cli::fail("encode: --every: expected a positive integer, got '" + every_text + "'");
  const std::vector<std::string> inputs = args.positionals();
  if (!args.unknown_option().empty()) return cli::fail("encode: unknown option '" + args.unknown_option() + "'");
  if (inputs.size() != 1) return cli::fail("encode: expected one scan file (see stipple encode --help)");
  if (output.empty()) return cli::fail("encode: -o MODEL.spg is required");

  const double start = monotonic_seconds();
  ProgressBar progress("encode", !quiet);
  progress.update(0.0, "reading");
  PointCloud cloud;
  if (!read_point_cloud(inputs[0], cloud, error)) return cli::fail(error);
  if (every > 1) keep_every(cloud, every, options);
  std::vector<uint8_t> spg;
  EncodeReport report;
  if (!encode_cloud(cloud, options, spg, report, error, &progress)) return cli::fail(error);
  if (!write_file_atomic(output, spg, error)) return cli::fail(error);
  progress.finish();
  const double seconds = monotonic_seconds() - start;
  const double peak_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  if (json) std::printf("%s\n", summary_json(inputs[0], report, seconds, peak_mb).c_str());
  else print_summary(inputs[0], report, seconds, peak_mb);
  return 0;
}

int cmd_demo(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kDemoHelp, stdout);
    return 0;
  }
  EncodeOptions options;
  bool quiet = false, json = false;
  std::string scan = STIPPLE_DEFAULT_SCAN, output, error;
  args.value("--scan", scan);
  if (!args.value("-o", output)) args.value("--output", output);
  if (!parse_encode_options(args, options, quiet, json, error)) return cli::fail(error);
  if (!args.unknown_option().empty()) return cli::fail("demo: unknown option '" + args.unknown_option() + "'");

  const double start = monotonic_seconds();
  ProgressBar progress("encode", !quiet);
  PointCloud cloud;
  if (!read_point_cloud(scan, cloud, error)) return cli::fail(error);
  std::vector<uint8_t> spg;
  EncodeReport report;
  if (!encode_cloud(cloud, options, spg, report, error, &progress)) return cli::fail(error);
  progress.finish();
  const double seconds = monotonic_seconds() - start;
  if (!output.empty() && !write_file_atomic(output, spg, error)) return cli::fail(error);
  print_summary(scan, report, seconds, static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0));

  DecodedModel model;
  if (!decode_spg("(in memory)", spg.data(), spg.size(), model, error)) return cli::fail(error);
  const PointCloud generated = sample_cut(model, leaf_cut(model), 0);
  const CloudMetrics m = compare_clouds(cloud, generated, options.tree.threads);
  std::printf("leaves resampled: %s points; PSNR %.1f dB one-sided (generated -> original), %.1f dB symmetric; "
              "Hausdorff %.3g (%.3f%% of the diagonal)\n",
              cli::with_commas(generated.size()).c_str(), m.psnr_one_sided, m.psnr_symmetric, m.hausdorff,
              100 * m.hausdorff / m.diagonal);
  return 0;
}

}  // namespace stipple
