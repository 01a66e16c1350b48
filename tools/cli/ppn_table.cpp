// stipple ppn-table — measures the points-per-node table with the client's rasterizer.
#include <cmath>
#include <cstdio>
#include <string>

#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/reference/ppn_measure.h"

namespace stipple {
namespace {

const char kPpnHelp[] =
    "usage: stipple ppn-table [--coverage C] [--trials N] [--write FILE] [--quiet]\n"
    "\n"
    "Measures the points-per-node table (TOG05 Table 1) with the client's own\n"
    "rasterizer and Gaussian tables: for each screen size and elongation of a\n"
    "node, the fewest points whose squares cover the fraction C (default 0.95)\n"
    "of the pixels inside its 2-sigma ellipse, for Sobol and pseudo-random\n"
    "samples and point sizes 1-3. Prints the paper's examples side by side;\n"
    "--write FILE writes the C++ table (raster/ppn_table.inc).\n";

}  // namespace

int cmd_ppn_table(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kPpnHelp, stdout);
    return 0;
  }
  PpnMeasureOptions o;
  std::string v, output;
  unsigned long long u = 0;
  if (args.value("--coverage", v) && (!cli::parse_double(v, o.coverage) || !(o.coverage > 0 && o.coverage <= 1)))
    return cli::fail("ppn-table: --coverage: expected a fraction in (0, 1], got '" + v + "'");
  if (args.value("--trials", v)) {
    if (!cli::parse_uint(v, 1024, u) || u < 1) return cli::fail("ppn-table: --trials: expected 1..1024, got '" + v + "'");
    o.trials = static_cast<int>(u);
  }
  args.value("--write", output);
  const bool quiet = args.flag("--quiet");
  if (args.bad()) return cli::fail("ppn-table: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("ppn-table: " + args.unknown_option_message());
  if (!args.positionals().empty()) return cli::fail("ppn-table: takes no files (see stipple ppn-table --help)");

  static PpnTable tables[2][kPpnPointSizes];
  {
    ProgressBar progress("ppn-table", !quiet);
    for (int src = 0; src < 2; ++src)
      for (int p = 0; p < kPpnPointSizes; ++p) {
        PpnMeasureOptions m = o;
        m.source = src == 0 ? GaussianSource::kSobol : GaussianSource::kPseudo;
        m.point_size = p + 1;
        const int part = src * kPpnPointSizes + p;
        measure_ppn_table(m, tables[src][p], [&](double f) {
          progress.update((part + f) / (2 * kPpnPointSizes), src == 0 ? "sobol" : "pseudo");
        });
      }
  }
  // The paper's Table 1 rows: gamma-sigma extents (px) -> points, here for
  // 1 px points (the paper drew 1.8 px points).
  std::printf("points per node, 95%% of the 2-sigma ellipse covered (sigma = extent / 3.5)\n");
  std::printf("%-22s %8s %8s %8s %8s %8s %8s\n", "3.5 sigma extents (px)", "quasi-1", "pseudo-1", "quasi-2", "pseudo-2",
              "quasi-3", "pseudo-3");
  const double rows[][2] = {{1, 1}, {2, 2}, {4, 4}, {8, 8}, {8, 2}, {16, 16}, {16, 4}, {32, 32}};
  for (const auto& row : rows) {
    const int64_t a = std::llround(256 * std::pow(row[0] / 3.5, 2)), c = std::llround(256 * std::pow(row[1] / 3.5, 2));
    const PpnIndex i = ppn_index(a, 0, c);
    char label[32];
    std::snprintf(label, sizeof label, "(%g, %g)", row[0], row[1]);
    std::printf("%-22s", label);
    for (int p = 0; p < kPpnPointSizes; ++p)
      std::printf(" %8u %8u", static_cast<unsigned>(tables[0][p][i.size][i.aspect]),
                  static_cast<unsigned>(tables[1][p][i.size][i.aspect]));
    std::printf("\n");
  }
  if (!output.empty()) {
    const std::string text = ppn_table_source(tables, o);
    std::string error;
    if (!write_file_atomic(output, std::vector<uint8_t>(text.begin(), text.end()), error)) return cli::fail(error);
    std::printf("-> %s\n", output.c_str());
  }
  return 0;
}

}  // namespace stipple
