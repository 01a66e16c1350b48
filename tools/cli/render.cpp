// stipple render — the fixed-point client in process (or the double reference) -> PNG.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/cli/render_output.h"

namespace stipple {
namespace {

const char kRenderHelp[] =
    "usage: stipple render MODEL.spg -o IMAGE.png [options]\n"
    "\n"
    "Renders a .spg file with the handheld client — fixed point, one arena, the\n"
    "same bytes on every platform — in this process: the view-dependent cut of the\n"
    "tree (core/view_cut.h: split above 2 px, largest first within the cache,\n"
    "culled by frustum and normal cone) is taken for the camera, its records are\n"
    "handed to the client, one frame is\n"
    "drawn and written as PNG (RGB565 frames expanded by bit replication).\n"
    "\n";

const char kRenderHelpOutput[] =
    "output:\n"
    "  --reference            draw with the double-precision reference renderer instead\n"
    "  --psnr                 also render the reference and report PSNR against it\n"
    "  --frames N             draw the frame N times and report the median time\n"
    "  --json                 one JSON line of statistics\n";

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
        .integer("cut_nodes_culled", fixed.culled_nodes)
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
    std::printf("%s: %s nodes sent (%s culled in the cut), %s drawn, %s points%s, arena %s bytes%s%s\n", name.c_str(),
                cli::with_commas(fixed.cut.size()).c_str(), cli::with_commas(fixed.culled_nodes).c_str(),
                cli::with_commas(fixed.stats.nodes_drawn).c_str(),
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

}  // namespace stipple
