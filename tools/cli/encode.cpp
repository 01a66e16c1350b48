// stipple encode — scan -> .spg.
#include <cmath>
#include <cstdio>
#include <string>

#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/cli/encode_options.h"
#include "tools/cli/render_output.h"
#include "tools/encoder/encoder.h"
#include "tools/encoder/normals.h"
#include "tools/reference/metrics.h"
#include "tools/reference/sampler.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kEncodeHelp[] =
    "usage: stipple encode SCAN -o MODEL.spg [options]\n"
    "\n"
    "Builds the hierarchy of Gaussians of a scan (PLY, PCD, LAS 1.0-1.4, Leica\n"
    "PTS, OBJ vertices, or x y z [nx ny nz] [r g b] text with or without a line\n"
    "of column names; E57 is refused with how to convert it; docs/robustness.md)\n"
    "and writes it as a .spg file (docs/format.md).\n"
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
    "  --format-version V    2 (default: 16-bit class tables) or 1 (float32 tables,\n"
    "                        for readers older than version 2)\n"
    "  --shrink ETA0,ETA1    curvature shrink of the thin axis (default 0.25,2)\n"
    "  --no-shrink           no curvature shrink\n"
    "  --neighbours K        k for normals of bare point clouds (default 12)\n"
    "  --orient MODE         which way estimated normals face: auto (default: from\n"
    "                        the data, docs/encoder.md), sensor (toward --viewpoint,\n"
    "                        the origin by default), up (toward --up), outward (away\n"
    "                        from the centroid, propagated over neighbours)\n"
    "  --viewpoint X,Y,Z     where the sensor stood (implies --orient sensor unless\n"
    "                        --orient says otherwise)\n"
    "  --up AXIS             the scan's up axis: +x -x +y -y +z -z (stored for\n"
    "                        viewers; --orient up faces it)\n"
    "  --threads N           worker threads (default: one per core); the .spg is\n"
    "                        the same bytes for any count\n"
    "  --every K             keep every K-th point (after normals are derived from\n"
    "                        the full mesh): quick previews and scaling studies\n"
    "  --json                print the summary as JSON (with each stage's seconds:\n"
    "                        read, normals, hierarchy, classes, write)\n"
    "  -q, --quiet           no progress bar\n";

}  // namespace

int cmd_encode(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kEncodeHelp, stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
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
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("encode: " + e);
  const std::vector<std::string> inputs = args.positionals();
  if (!args.unknown_option().empty()) return cli::fail("encode: " + args.unknown_option_message());
  if (inputs.size() != 1) return cli::fail("encode: expected one scan file (see stipple encode --help)");
  if (!cli::check_output_name(output, ".spg", "a .spg model", error)) return cli::fail("encode: " + error);
  if (output.empty()) return cli::fail("encode: -o MODEL.spg is required");
  if (cli::output_is_input(inputs[0], output, error)) return cli::fail("encode: " + error);

  const double start = monotonic_seconds();
  ProgressBar progress("encode", !quiet);
  progress.update(0.0, "reading");
  PointCloud cloud;
  if (!read_point_cloud(inputs[0], cloud, error, scan_options)) return cli::fail(error);
  if (!cloud.warnings.empty()) progress.finish();  // the warnings get lines of their own
  cli::warn(cloud.warnings);
  if (every > 1) keep_every(cloud, every, options);
  const double read_seconds = monotonic_seconds() - start;
  options.consume_scan = true;  // nothing here reads the scan after
  std::vector<uint8_t> spg;
  EncodeReport report;
  if (!encode_cloud(cloud, options, spg, report, error, &progress)) return cli::fail(error);
  report.seconds.read = read_seconds;
  const double write_start = monotonic_seconds();
  if (!write_file_atomic(output, spg, error)) return cli::fail(error);
  report.seconds.write += monotonic_seconds() - write_start;
  progress.finish();
  const double seconds = monotonic_seconds() - start;
  const double peak_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  if (json) std::printf("%s\n", summary_json(inputs[0], report, seconds, peak_mb).c_str());
  else print_summary(inputs[0], report, seconds, peak_mb);
  return 0;
}

}  // namespace stipple
