// stipple encode — scan -> .spg.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/cli/encode_options.h"
#include "tools/cli/render_output.h"
#include "tools/embedded/model_file.h"
#include "core/cut_table.h"
#include "tools/encoder/coded_file.h"
#include "tools/encoder/encoder.h"
#include "tools/encoder/merge.h"
#include "tools/encoder/partition.h"
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
    "  --tolerance D         an error bound: leaves of sigma1 at most D (the variance\n"
    "                        stop; leaves of 2 points or more unless --leaf-size says)\n"
    "                        and position fields with cells of at most D/2; D in the\n"
    "                        scan's units (0.002), with a unit for a scan in metres\n"
    "                        (2mm, 0.5cm, 20um), or a share of the diagonal (0.3%)\n"
    "  --classes P,N,C       sigma classes for positions, normals, colours\n"
    "                        (at most 4096,4096,64; 0 = automatic, the default:\n"
    "                        P clamp(nodes/16, 64, 2048), N clamp(nodes/64, 64,\n"
    "                        1024), C 64)\n"
    "  --balance B           2-means balance band [B, 1-B] before the Euclidean\n"
    "                        fallback (default 0.3)\n"
    "  --octree              octree partition (SGP03, TOG05 Table II baseline)\n"
    "  --no-normals          store no normals (13 -> 9 bytes per node)\n"
    "  --no-color            store no colours even if the scan has them\n"
    "  --format-version V    2 (default: 16-bit class tables), 3 (version 2 with\n"
    "                        its records entropy-coded, each child against its\n"
    "                        parent: about a third smaller, expanded in memory by\n"
    "                        every reader) or 1 (float32 tables, for readers older\n"
    "                        than version 2)\n"
    "  --shrink ETA0,ETA1    curvature shrink of the thin axis (default 0.25,2)\n"
    "  --no-shrink           no curvature shrink\n"
    "  --no-curvature-sign   sigma_n without its sign: concave patches shade as\n"
    "                        convex (the file then reads in clients before the\n"
    "                        sign; version 1 has none)\n"
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
    "  --memory BYTES        the memory the encoder may use (2G, 1500M; default:\n"
    "                        half of this host's): a scan larger than fits is\n"
    "                        encoded in partitions, each its own job\n"
    "  --partition-points N  partitions of at most about N points (instead of\n"
    "                        what --memory allows)\n"
    "  --class-sample N      fit the sigma classes to N nodes' tuples (default\n"
    "                        2097152; every node's in a smaller tree)\n"
    "  --tmp DIR             where partition files go (default: a folder beside\n"
    "                        MODEL.spg; removed after)\n"
    "  --plan-only DIR       plan and partition the scan into DIR, run nothing:\n"
    "                        for a cluster (docs/encoder.md \"On a cluster\")\n"
    "  --merge DIR           assemble MODEL.spg from DIR once every job has run\n"
    "                        (stipple encode-part DIR ID); no SCAN\n"
    "  --every K             keep every K-th point (after normals are derived from\n"
    "                        the full mesh): quick previews and scaling studies\n"
    "  --no-cut-table        write no MODEL.spg.cut beside the model (the per-node\n"
    "                        cut bounds servers and local viewers map instead of\n"
    "                        decoding the tree; stipple cut-table writes it later)\n"
    "  --json                print the summary as JSON (with each stage's seconds:\n"
    "                        read, normals, hierarchy, classes, write; partitions)\n"
    "  -q, --quiet           no progress bar\n";

const char kEncodePartHelp[] =
    "usage: stipple encode-part DIR ID [--threads N]\n"
    "\n"
    "Runs one job of a plan that stipple encode --plan-only DIR wrote: reads\n"
    "DIR/part-ID.pts (and its halo), estimates normals where the scan has\n"
    "none, builds the partition's subtree and writes DIR/part-ID.nodes\n"
    "(atomically, CRC-32 at its end). Jobs are independent: run them in any\n"
    "order, on any machine that sees DIR, then stipple encode --merge DIR.\n"
    "Prints the part's file, nodes and CRC-32.\n"
    "\n"
    "options:\n"
    "  --threads N           worker threads (default: one per core)\n";

// The model's cut table beside it (MODEL.spg.cut: what servers and local
// viewers map instead of decoding the tree), made from the file just
// written. A table that cannot be written is a warning: the model is whole,
// and whatever reads it builds the bounds itself.
void write_cut_table(const std::string& output, EncodeReport& report, ProgressBar& progress) {
  const double start = monotonic_seconds();
  progress.update(1.0, "cut table");
  std::string error;
  if (!make_cut_table(output, ConeRule{}, error)) {
    progress.finish();
    cli::warn({error + "; " + output + " is whole, and servers and viewers build its cut bounds in memory (stipple cut-table " +
               output + " writes the table)"});
    return;
  }
  report.cut_table = cut_table_path(output);
  report.cut_table_bytes = cut_table_bytes(static_cast<uint32_t>(report.nodes));  // a .spg's count is 32-bit
  report.seconds.cut_table = monotonic_seconds() - start;
}

// --format-version 3: the version 2 file just written, its records coded
// (tools/encoder/coded_file.h), written over it.
bool code_file(const std::string& output, EncodeReport& report, ProgressBar& progress, std::string& error) {
  const double start = monotonic_seconds();
  progress.update(0.0, "coding records");
  std::vector<uint8_t> plain, coded;
  if (!read_file(output, plain, error)) return false;
  CodedFileReport coding;
  if (!write_coded_spg(plain.data(), plain.size(), coded, coding, error,
                       [&](double done) { progress.update(done, "coding records"); }))
    return error = output + ": " + error, false;
  if (!write_file_atomic(output, coded, error)) return false;
  report.expanded_bytes = plain.size();
  report.bytes = coded.size();
  report.bits_per_point = 8.0 * static_cast<double>(report.bytes) / static_cast<double>(report.points);
  report.seconds.coding = monotonic_seconds() - start;
  return true;
}

// --merge DIR: the .spg from a plan whose jobs have run.
int merge_plan(const std::string& dir, const std::string& output, int threads, bool quiet, bool json,
               bool cut_table, bool coded) {
  const double start = monotonic_seconds();
  std::string error;
  PartitionPlan plan;
  if (!read_plan(dir, plan, error)) return cli::fail("encode --merge: " + error);
  std::vector<std::unique_ptr<PartNodes>> parts;
  for (uint32_t i = 0; i < plan.partitions(); ++i) {
    std::unique_ptr<PartNodes> part = open_part_file(dir, plan, i, error);
    if (!part) return cli::fail("encode --merge: " + error);
    parts.push_back(std::move(part));
  }
  ProgressBar progress("merge", !quiet);
  AtomicFileWriter file;
  if (!file.open(output, error)) return cli::fail("encode --merge: " + error);
  EncodeReport report;
  if (!merge_parts(plan, parts, threads, sink_into(file), report, error, &progress) || !file.commit(error))
    return cli::fail("encode --merge: " + error);
  report.partitions = plan.partitions();
  if (coded && !code_file(output, report, progress, error)) return cli::fail("encode --merge: " + error);
  if (cut_table) write_cut_table(output, report, progress);
  progress.finish();
  const double peak_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  if (json) std::printf("%s\n", summary_json(dir, report, monotonic_seconds() - start, peak_mb).c_str());
  else print_summary(dir, report, monotonic_seconds() - start, peak_mb);
  return 0;
}

}  // namespace

int cmd_encode_part(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) return std::fputs(kEncodePartHelp, stdout), 0;
  int threads = 1;
  unsigned long long u = 0;
  if (std::string e; !parse_threads(args, threads, e)) return cli::fail("encode-part: " + e);
  const std::vector<std::string> pos = args.positionals();
  if (!args.unknown_option().empty()) return cli::fail("encode-part: " + args.unknown_option_message());
  if (pos.size() != 2) return cli::fail("encode-part: expected DIR and ID (see stipple encode-part --help)");
  if (!cli::parse_uint(pos[1], 0xFFFFFFFFull, u)) return cli::fail("encode-part: ID: expected a job number, got '" + pos[1] + "'");
  std::string error;
  PartitionPlan plan;
  if (!read_plan(pos[0], plan, error)) return cli::fail("encode-part: " + error);
  uint32_t crc = 0;
  const double start = monotonic_seconds();
  if (!run_part_file(pos[0], plan, static_cast<uint32_t>(u), threads, error, &crc)) return cli::fail("encode-part: " + error);
  std::printf("%s: %s points, crc32 %08x, %.2f s\n", part_path(pos[0], static_cast<uint32_t>(u), "nodes").c_str(),
              cli::with_commas(plan.part_points[u]).c_str(), crc, monotonic_seconds() - start);
  return 0;
}

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
  std::string plan_dir, merge_dir;
  args.value("--plan-only", plan_dir);
  args.value("--merge", merge_dir);
  const std::vector<std::string> inputs = args.positionals();
  if (!args.unknown_option().empty()) return cli::fail("encode: " + args.unknown_option_message());
  if (!merge_dir.empty()) {
    if (!inputs.empty()) return cli::fail("encode: --merge DIR takes no scan: the plan in DIR names its partitions");
    if (output.empty()) return cli::fail("encode: -o MODEL.spg is required");
    if (!cli::check_output_name(output, ".spg", "a .spg model", error)) return cli::fail("encode: " + error);
    return merge_plan(merge_dir, output, options.tree.threads, quiet, json, options.cut_table, options.coded_file);
  }
  if (!plan_dir.empty()) {
    if (inputs.size() != 1) return cli::fail("encode: expected one scan file (see stipple encode --help)");
    if (every > 1) return cli::fail("encode: --every previews a scan; --plan-only plans all of it");
    std::error_code ec;
    std::filesystem::create_directories(plan_dir, ec);
    if (ec) return cli::fail("encode: --plan-only: " + plan_dir + ": " + ec.message());
    PartitionPlan plan;
    ProgressBar progress("plan", !quiet);
    const auto warn = [&](const std::vector<std::string>& w) {
      if (!w.empty()) progress.finish();
      cli::warn(w);
    };
    if (!plan_scan_file(inputs[0], scan_options, options, plan_dir, plan, error, &progress, warn)) {
      for (uint32_t i = 0; i < plan.partitions(); ++i)
        for (const char* suffix : {"pts", "halo"}) std::filesystem::remove(part_path(plan_dir, i, suffix), ec);
      return cli::fail("encode: --plan-only: " + error);
    }
    progress.finish();
    std::printf("%s: %s points in %u partitions, planned in %s\n"
                "  run each job: stipple encode-part %s ID   (ID 0..%u; %s/jobs.txt lists them)\n"
                "  then:         stipple encode --merge %s -o MODEL.spg\n",
                inputs[0].c_str(), cli::with_commas(plan.points).c_str(), plan.partitions(), plan_dir.c_str(),
                plan_dir.c_str(), plan.partitions() - 1, plan_dir.c_str(), plan_dir.c_str());
    return 0;
  }
  if (inputs.size() != 1) return cli::fail("encode: expected one scan file (see stipple encode --help)");
  if (!cli::check_output_name(output, ".spg", "a .spg model", error)) return cli::fail("encode: " + error);
  if (output.empty()) return cli::fail("encode: -o MODEL.spg is required");
  if (cli::output_is_input(inputs[0], output, error)) return cli::fail("encode: " + error);

  const double start = monotonic_seconds();
  ProgressBar progress("encode", !quiet);
  progress.update(0.0, "reading");
  const auto warn = [&](const std::vector<std::string>& w) {
    if (!w.empty()) progress.finish();  // the warnings get lines of their own
    cli::warn(w);
  };
  EncodeReport report;
  if (every > 1) {  // a preview: the scan read whole, then thinned
    PointCloud cloud;
    if (!read_point_cloud(inputs[0], cloud, error, scan_options)) return cli::fail(error);
    warn(cloud.warnings);
    keep_every(cloud, every, options);
    const double read_seconds = monotonic_seconds() - start;
    options.consume_scan = true;  // nothing here reads the scan after
    if (!encode_to_file(cloud, options, output, report, error, &progress)) return cli::fail(error);
    report.seconds.read = read_seconds;
  } else if (!encode_scan_file(inputs[0], scan_options, options, output, report, error, &progress, warn)) {
    return cli::fail(error);
  }
  if (options.coded_file && !code_file(output, report, progress, error)) return cli::fail("encode: " + error);
  if (options.cut_table) write_cut_table(output, report, progress);
  progress.finish();
  const double seconds = monotonic_seconds() - start;
  const double peak_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  if (json) std::printf("%s\n", summary_json(inputs[0], report, seconds, peak_mb).c_str());
  else print_summary(inputs[0], report, seconds, peak_mb);
  return 0;
}

}  // namespace stipple
