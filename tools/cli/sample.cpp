// stipple sample — points regenerated from a cut by the double-precision reference decoder.
#include <cstdio>
#include <string>
#include <vector>

#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/reference/sampler.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

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

}  // namespace

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
  if (!args.unknown_option().empty()) return cli::fail("sample: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("sample: expected one .spg file (see stipple sample --help)");
  if (has_level == leaves) return cli::fail("sample: give exactly one of --level L and --leaves");
  if (output.empty()) return cli::fail("sample: -o POINTS.ply is required");
  std::string error;
  if (!cli::check_output_name(output, ".ply", "PLY", error)) return cli::fail("sample: " + error);
  if (cli::output_is_input(files[0], output, error)) return cli::fail("sample: " + error);
  unsigned long long level = 0, per_node = 0;
  if (has_level && !cli::parse_uint(level_text, 65535, level))
    return cli::fail("sample: --level: expected a non-negative integer, got '" + level_text + "'");
  if (per_node_text != "original" && (!cli::parse_uint(per_node_text, 1u << 20, per_node) || per_node == 0))
    return cli::fail("sample: --per-node: expected 'original' or a positive integer, got '" + per_node_text + "'");
  unsigned long long max_points = default_max_samples(physical_memory_bytes());
  if (has_max && !cli::parse_uint(max_text, ~0ull, max_points))
    return cli::fail("sample: --max-points: expected a non-negative integer, got '" + max_text + "'");
  DecodedModel model;
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

}  // namespace stipple
