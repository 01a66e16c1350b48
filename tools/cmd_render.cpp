// stipple — `render` (the fixed-point client in process, or the double
// reference) and `ppn-table` (measures the points-per-node table).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <string>

#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli.h"
#include "tools/cmd_render.h"
#include "tools/host/ppn_measure.h"

namespace stipple {
namespace {

const char kRenderHelp[] =
    "usage: stipple render MODEL.spg -o IMAGE.png [options]\n"
    "\n"
    "Renders a .spg file with the handheld client — fixed point, one arena, the\n"
    "same bytes on every platform — in this process: a simple cut of the tree is\n"
    "chosen for the camera, its records are handed to the client, one frame is\n"
    "drawn and written as PNG (RGB565 frames expanded by bit replication).\n"
    "\n";
const char kRenderHelpOutput[] =
    "output:\n"
    "  --reference            draw with the double-precision reference renderer instead\n"
    "  --psnr                 also render the reference and report PSNR against it\n"
    "  --frames N             draw the frame N times and report the median time\n"
    "  --json                 one JSON line of statistics\n";

const char kPpnHelp[] =
    "usage: stipple ppn-table [--coverage C] [--trials N] [--write FILE] [--quiet]\n"
    "\n"
    "Measures the points-per-node table (TOG05 Table 1) with the client's own\n"
    "rasterizer and Gaussian tables: for each screen size and elongation of a\n"
    "node, the fewest points whose squares cover the fraction C (default 0.95)\n"
    "of the pixels inside its 2-sigma ellipse, for Sobol and pseudo-random\n"
    "samples and point sizes 1-3. Prints the paper's examples side by side;\n"
    "--write FILE writes the C++ table (raster/ppn_table.inc).\n";

const char kDiffHelp[] =
    "usage: stipple image-diff EXPECTED.png ACTUAL.png [-o DIFF.png]\n"
    "\n"
    "Compares two RGB images of the same size byte for byte. Prints the number of\n"
    "differing pixels, the largest channel difference and the PSNR; -o writes a\n"
    "diff image (the expected image darkened, differing pixels in red, brighter\n"
    "for larger differences). Exit status 0 when identical, 1 when not.\n";

}  // namespace

int render_to_png(const std::string& name, const std::vector<uint8_t>& file, const RenderOptions& o,
                  const std::string& output, bool reference, bool psnr, bool json, int frames) {
  SpgView view;
  const SpgResult r = spg_parse(file.data(), file.size(), &view);
  if (!r.ok()) return cli::fail(name + ": byte " + std::to_string(r.offset) + ": " + spg_error_text(r.error));
  const double start = monotonic_seconds();
  FixedRender fixed;
  std::string error;
  if (!render_fixed(view, file.data(), o.config, o.rule, o.view, fixed, error, frames))
    return cli::fail(name + ": " + error);
  const double fixed_seconds = monotonic_seconds() - start;
  std::vector<double> sorted = fixed.frame_seconds;
  std::sort(sorted.begin(), sorted.end());
  const double frame_median = sorted.empty() ? 0 : sorted[sorted.size() / 2];
  Image ref;
  if (reference || psnr) {
    DecodedModel model;
    if (!decode_spg(name, file.data(), file.size(), model, error)) return cli::fail(error);
    ref = render_reference(model, fixed.cut, o.config, o.view);
  }
  const Image& image = reference ? ref : fixed.image;
  if (!output.empty() && !write_png(output, image, error)) return cli::fail(error);
  const double db = psnr ? image_psnr(fixed.image, ref) : 0;
  if (json) {
    cli::Json j;
    j.str("model", name).integer("width", o.config.raster.width).integer("height", o.config.raster.height);
    j.integer("cut_nodes", static_cast<long long>(fixed.cut.size()))
        .integer("nodes_drawn", fixed.stats.nodes_drawn)
        .integer("nodes_culled", fixed.stats.nodes_culled)
        .integer("points", fixed.stats.points)
        .integer("points_dropped", fixed.stats.points_dropped)
        .integer("arena_bytes", static_cast<long long>(fixed.arena_bytes))
        .num("seconds", fixed_seconds)
        .num("frame_seconds_median", frame_median)
        .num("points_per_second", frame_median > 0 ? fixed.stats.points / frame_median : 0);
    if (psnr) j.num("psnr_vs_reference", std::isinf(db) ? 999.0 : db);
    if (!output.empty()) j.str("output", output);
    std::printf("%s\n", j.done().c_str());
  } else {
    std::printf("%s: %s nodes in the cut, %s drawn, %s points%s, arena %s bytes%s%s\n", name.c_str(),
                cli::with_commas(fixed.cut.size()).c_str(), cli::with_commas(fixed.stats.nodes_drawn).c_str(),
                cli::with_commas(fixed.stats.points).c_str(),
                fixed.stats.points_dropped ? (" (" + cli::with_commas(fixed.stats.points_dropped) + " over budget)").c_str() : "",
                cli::with_commas(fixed.arena_bytes).c_str(), output.empty() ? "" : (" -> " + output).c_str(),
                reference ? " (reference renderer)" : "");
    if (psnr) std::printf("fixed point vs double reference: PSNR %.2f dB\n", db);
    if (frames > 1)
      std::printf("frame: median %.3f ms of %d, %.1f M points/s\n", 1e3 * frame_median, frames,
                  fixed.stats.points / frame_median / 1e6);
  }
  return 0;
}

int cmd_render(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kRenderHelp, stdout);
    std::fputs(kRenderOptionsHelp, stdout);
    std::fputs(kRenderHelpOutput, stdout);
    return 0;
  }
  RenderOptions o;
  std::string error, output;
  if (!args.value("-o", output)) args.value("--output", output);
  const bool reference = args.flag("--reference"), psnr = args.flag("--psnr"), json = args.flag("--json");
  std::string frames_text;
  unsigned long long frames = 1;
  if (args.value("--frames", frames_text) && (!cli::parse_uint(frames_text, 100000, frames) || frames < 1))
    return cli::fail("render: --frames: expected 1..100000, got '" + frames_text + "'");
  if (!parse_render_options(args, o, error)) return cli::fail("render: " + error);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("render: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("render: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 1) return cli::fail("render: expected one .spg file (see stipple render --help)");
  if (output.empty() && !psnr && frames == 1) return cli::fail("render: -o IMAGE.png is required");
  std::vector<uint8_t> file;
  if (!read_file(files[0], file, error)) return cli::fail(error);
  return render_to_png(files[0], file, o, output, reference, psnr, json, static_cast<int>(frames));
}

int cmd_image_diff(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kDiffHelp, stdout);
    return 0;
  }
  std::string output, error;
  if (!args.value("-o", output)) args.value("--output", output);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("image-diff: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("image-diff: unknown option '" + args.unknown_option() + "'");
  if (files.size() != 2) return cli::fail("image-diff: expected EXPECTED.png and ACTUAL.png");
  Image a, b;
  if (!read_png(files[0], a, error) || !read_png(files[1], b, error))
    return cli::fail(error);
  if (a.width != b.width || a.height != b.height)
    return cli::fail("image-diff: " + files[0] + " is " + std::to_string(a.width) + "x" + std::to_string(a.height) + ", " +
                     files[1] + " is " + std::to_string(b.width) + "x" + std::to_string(b.height));
  long differing = 0;
  int largest = 0;
  std::vector<uint8_t> diff(a.rgb.size());
  for (size_t i = 0; i < a.rgb.size(); i += 3) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.rgb[i + c] - b.rgb[i + c]));
    largest = std::max(largest, d);
    if (d > 0) {
      ++differing;
      diff[i] = static_cast<uint8_t>(std::min(255, 128 + 2 * d));
      diff[i + 1] = diff[i + 2] = 0;
    } else {
      for (int c = 0; c < 3; ++c) diff[i + c] = static_cast<uint8_t>(a.rgb[i + c] / 4);
    }
  }
  if (!output.empty() && !write_png(output, Image{a.width, a.height, diff}, error)) return cli::fail(error);
  if (differing == 0) {
    std::printf("%s and %s are identical (%dx%d)\n", files[0].c_str(), files[1].c_str(), a.width, a.height);
    return 0;
  }
  std::printf("%s and %s differ: %ld of %ld pixels, largest channel difference %d, PSNR %.2f dB%s\n", files[0].c_str(),
              files[1].c_str(), differing, static_cast<long>(a.width) * a.height, largest, image_psnr(a, b),
              output.empty() ? "" : (" -> " + output).c_str());
  return 1;
}

int cmd_image_crc(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs("usage: stipple image-crc IMAGE.png...\n"
               "\n"
               "Prints the CRC-32 of each image's RGB888 pixel bytes (rows top to bottom, no\n"
               "header) — what `stipple-handheld --crc` prints for a frame, so a target without\n"
               "libpng can be checked against the golden PNGs (tests/golden/images.crc).\n",
               stdout);
    return 0;
  }
  const std::vector<std::string> files = args.positionals();
  if (!args.unknown_option().empty()) return cli::fail("image-crc: unknown option '" + args.unknown_option() + "'");
  if (files.empty()) return cli::fail("image-crc: expected one or more PNG files");
  for (const std::string& f : files) {
    Image img;
    std::string error;
    if (!read_png(f, img, error)) return cli::fail(error);
    std::printf("crc32 %08x  %s\n", crc32(img.rgb.data(), img.rgb.size()), f.c_str());
  }
  return 0;
}

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
  if (!args.unknown_option().empty()) return cli::fail("ppn-table: unknown option '" + args.unknown_option() + "'");
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
