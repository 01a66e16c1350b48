// stipple render — the fixed-point client in process (or the double reference) -> PNG.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "core/elevation_ramp.h"
#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "platform/text.h"
#include "tools/cli/cli.h"
#include "tools/cli/render_output.h"
#include "tools/encoder/encoder.h"
#include "tools/scan/las_io.h"
#include "tools/viewer/viewer.h"

namespace stipple {
namespace {

const char kRenderHelp[] =
    "usage: stipple render MODEL.spg|SCAN -o IMAGE.png [options]\n"
    "\n"
    "Renders a .spg file with the handheld client — fixed point, one arena, the\n"
    "same bytes on every platform — in this process: the view-dependent cut of the\n"
    "tree (core/view_cut.h: split above 2 px, largest first within the cache,\n"
    "culled by frustum and normal cone) is taken for the camera, its records are\n"
    "handed to the client, one frame is\n"
    "drawn and written as PNG (RGB565 frames expanded by bit replication).\n"
    "A scan (PLY, PCD, LAS, PTS, OBJ, text) is encoded in memory first, with the\n"
    "encoder's defaults (`stipple encode` writes it to a file once instead).\n"
    "\n";

const char kRenderHelpOutput[] =
    "streaming:\n"
    "  --connect HOST:PORT    receive the model from `stipple serve` instead of a file\n"
    "                         (MODEL.spg is then not given)\n"
    "  --token FILE           the pre-shared token of a server started with --token\n"
    "  --serial DEV           the same over a serial line (`stipple serve --serial`);\n"
    "  --baud N               its rate (default 115200)\n"
    "  --path orbit:N         N cameras about the up axis from the view's yaw; -o names\n"
    "                         a folder of frame_NNNN.png and frames.log (nodes, points,\n"
    "                         bytes received per frame). On a local file the frames\n"
    "                         come through an in-process server over loopback, the\n"
    "                         same bytes as over TCP once each view has converged\n"
    "  --at T1,T2,...         with --connect or --serial: -o names a folder of\n"
    "                         at_T.png, the frame the client shows T seconds after\n"
    "                         it began to connect (ascending, e.g. 0.5,1,2,5), and\n"
    "                         at.log (nodes held, bytes received, the view's share);\n"
    "                         a time after the view converged gets the converged frame\n"
    "output:\n"
    "  --reference            draw with the double-precision reference renderer instead\n"
    "  --psnr                 also render the reference and report PSNR against it\n"
    "  --frames N             draw the frame N times and report the median time\n"
    "  --json                 one JSON line of statistics\n"
    "  --legend elevation|intensity|classification\n"
    "                         a panel beside the picture saying what its colours\n"
    "                         mean: the elevation ramp (with --color elevation) and\n"
    "                         its heights, the intensity ramp or the LAS classes (of\n"
    "                         a model encoded with --color-by intensity|classification)\n";

// The box's extent along `up` (kNone: +y, as orbit_basis takes it), its two
// ends in the file's units.
void up_range(const SpgHeader& h, SpgAxis up, double& low, double& high) {
  const int axis = up == SpgAxis::kNone ? 1 : spg_axis_index(up);
  const bool down = spg_axis_negative(up);
  float lo = 0, hi = 0;
  double origin = 0;
  std::memcpy(&lo, &h.bbox_bits[axis], 4);
  std::memcpy(&hi, &h.bbox_bits[3 + axis], 4);
  std::memcpy(&origin, &h.origin_bits[axis], 8);
  low = down ? -(origin + hi) : origin + lo;
  high = down ? -(origin + lo) : origin + hi;
}

// The picture widened by the legend's panel (taller too where the key needs it).
void add_legend(Image& image, Legend legend, const SpgHeader& header, SpgAxis up) {
  if (legend == Legend::kNone) return;
  constexpr int kPanel = 150, kRow = 10;
  constexpr uint32_t kBack = 0x101418, kInk = 0xE0E4EA;
  const int rows = legend == Legend::kClassification ? kLasStandardClasses : 0;
  const int w = image.width + kPanel, h = std::max(image.height, 24 + rows * kRow);
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3, 0);
  for (int y = 0; y < image.height; ++y)
    std::memcpy(&rgb[static_cast<size_t>(y) * w * 3], &image.rgb[static_cast<size_t>(y) * image.width * 3],
                static_cast<size_t>(image.width) * 3);
  const int x0 = image.width;
  fill_rect(rgb.data(), w, h, x0, 0, w, h, kBack);
  const char* title = legend == Legend::kElevation ? "elevation" : legend == Legend::kIntensity ? "intensity" : "LAS class";
  draw_text(rgb.data(), w, h, x0 + 8, 6, title, kInk);
  if (legend == Legend::kClassification) {
    for (int c = 0; c < rows; ++c) {
      const int y = 20 + c * kRow;
      fill_rect(rgb.data(), w, h, x0 + 8, y, x0 + 16, y + 7, las_class_rgb(static_cast<uint8_t>(c)));
      draw_text(rgb.data(), w, h, x0 + 20, y, std::to_string(c) + " " + las_class_name(static_cast<uint8_t>(c)), kInk);
    }
  } else {
    // A bar, high at the top: the ramp (or grey), its ends labelled.
    const int top = 20, bottom = h - 12;
    for (int y = top; y < bottom; ++y) {
      const uint32_t t = static_cast<uint32_t>(255 * (bottom - 1 - y) / std::max(bottom - 1 - top, 1));
      fill_rect(rgb.data(), w, h, x0 + 8, y, x0 + 24, y + 1,
                legend == Legend::kElevation ? elevation_rgb(t) : t << 16 | t << 8 | t);
    }
    std::string high = "high", low = "low";
    if (legend == Legend::kElevation) {
      double a = 0, b = 0;
      up_range(header, up, a, b);
      char text[32];
      std::snprintf(text, sizeof text, "%.6g", b);
      high = text;
      std::snprintf(text, sizeof text, "%.6g", a);
      low = text;
    }
    draw_text(rgb.data(), w, h, x0 + 30, top, high, kInk);
    draw_text(rgb.data(), w, h, x0 + 30, bottom - 7, low, kInk);
  }
  image.width = w;
  image.height = h;
  image.rgb = std::move(rgb);
}

}  // namespace

bool parse_legend(const std::string& text, Legend& out, std::string& error) {
  if (text == "elevation") out = Legend::kElevation;
  else if (text == "intensity") out = Legend::kIntensity;
  else if (text == "classification") out = Legend::kClassification;
  else return error = "--legend: expected elevation, intensity or classification, got '" + text + "'", false;
  return true;
}

int render_to_png(const std::string& name, const std::vector<uint8_t>& file, const RenderOptions& o,
                  const std::string& output, bool reference, bool psnr, bool json, int frames, Legend legend) {
  SpgView view;
  const SpgResult r = spg_parse(file.data(), file.size(), &view);
  if (!r.ok()) return cli::fail(spg_error_message(name, r, file.size()));
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
  Image image = reference ? ref : fixed.image;
  if (legend != Legend::kNone) {
    const SpgHeader& h = view.header;
    add_legend(image, legend, h, fixed.up);
  }
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
        .integer("nodes_close_up", fixed.stats.nodes_close_up)
        .integer("splats", fixed.stats.splats)
        .integer("nodes_in_tiles", fixed.stats.nodes_in_tiles)
        .integer("nodes_in_lanes", fixed.stats.nodes_in_lanes)
        .integer("arena_bytes", static_cast<long long>(fixed.arena_bytes))
        .num("seconds", fixed_seconds)
        .num("frame_seconds_median", frame_median)
        .num("points_per_second", frame_median > 0 ? fixed.stats.points / frame_median : 0);
    if (psnr) j.num("psnr_vs_reference", std::isinf(db) ? 999.0 : db);
    if (!output.empty()) j.str("output", output);
    std::printf("%s\n", j.done().c_str());
  } else {
    std::printf("%s: %s nodes sent (%s culled in the cut), %s drawn%s%s, %s points%s, arena %s bytes%s%s\n", name.c_str(),
                cli::with_commas(fixed.cut.size()).c_str(), cli::with_commas(fixed.culled_nodes).c_str(),
                cli::with_commas(fixed.stats.nodes_drawn).c_str(),
                fixed.stats.nodes_close_up ? (" (" + cli::with_commas(fixed.stats.nodes_close_up) + " as close-up discs)").c_str() : "",
                fixed.stats.splats ? (", " + cli::with_commas(fixed.stats.splats) + " EWA splats").c_str() : "",
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

// Frames through the node stream: from a server over TCP or a serial line,
// or from an in-process server over loopback for a local file (exactly one
// of `model`, `connect`, `serial`).
int render_stream(const std::string& model_path, const std::string& connect, const std::string& serial, uint32_t baud,
                  const RenderOptions& o, uint32_t steps, bool folder, const std::string& output,
                  const std::vector<double>& at) {
  const bool remote = model_path.empty();
  const std::string source =
      !remote ? model_path : !connect.empty() ? connect : "serial:" + serial + "@" + std::to_string(baud);
  std::string error;
  const double began = monotonic_seconds();
  ViewerSource src;
  if (!src.open(model_path, connect, serial, baud, o, error)) return cli::fail("render: " + error);
  RemoteModel& model = src.model();
  if (std::error_code ec; folder && !std::filesystem::create_directories(output, ec) && ec)
    return cli::fail("render: " + output + ": cannot make the folder: " + ec.message());
  // The view as render resolves it, from the header the server sent.
  const SpgHeader& h = model.header();
  const int32_t* extent = model.client().decoder().extent_mu();
  const ViewSpec base = resolve_view(o.view, h, extent);
  if (o.config.elevation != SpgAxis::kNone && !model.client().set_elevation(base.up))
    return cli::fail("render: the client refused colour by elevation");
  std::string log;
  const size_t stride = size_t{o.config.raster.width} * bytes_per_pixel(o.config.raster.format);
  std::vector<uint8_t> frame(stride * o.config.raster.height);
  Image image;
  if (!at.empty()) {
    // The first view as it builds: the frame shown at each time asked for.
    Camera c;
    if (!orbit_camera(orbit_view(extent, base), o.config.raster.width, o.config.raster.height, &c))
      return cli::fail("render: the view is out of the camera's range");
    if (!model.request(c, o.rule.max_size_q4, o.rule.window, error)) return cli::fail(source + ": " + error);
    double converged_at = -1;
    for (size_t next = 0; next < at.size();) {
      const double now = monotonic_seconds() - began;
      if (converged_at < 0 && model.converged()) converged_at = now;
      if (now < at[next] && converged_at < 0) {
        if (!model.service(static_cast<int>(std::clamp((at[next] - now) * 1e3, 1.0, 10.0)), error))
          return cli::fail(source + ": " + error);
        continue;
      }
      FrameStats stats;
      if (!model.render(c, frame.data(), stride, &stats, error)) return cli::fail(source + ": " + error);
      image_from_frame(frame.data(), stride, o.config.raster.width, o.config.raster.height, o.config.raster.format, image);
      char name[48];
      std::snprintf(name, sizeof name, "at_%gs.png", at[next]);
      if (!write_png(output + "/" + name, image, error)) return cli::fail(error);
      const RemoteModel::Progress p = model.progress();
      char state[48] = "waiting";
      if (converged_at >= 0) std::snprintf(state, sizeof state, "converged at %.2f s", converged_at);
      else if (p.known) std::snprintf(state, sizeof state, "%s %d%%", p.coarse ? "coarse part" : "view", static_cast<int>(100 * p.share));
      char line[200];
      std::snprintf(line, sizeof line, "%s at %.2f s: nodes %u points %u bytes_received %llu %s\n", name, at[next], stats.nodes,
                    stats.points, static_cast<unsigned long long>(model.bytes_received()), state);
      std::fputs(line, stdout);
      log += line;
      ++next;
    }
    if (!write_file_atomic(output + "/at.log", std::vector<uint8_t>(log.begin(), log.end()), error)) return cli::fail(error);
    return 0;
  }
  uint64_t received = model.bytes_received();
  for (uint32_t k = 0; k < steps; ++k) {
    ViewSpec s = base;
    s.yaw = base.yaw + 360.0 * k / steps;
    Camera c;
    if (!orbit_camera(orbit_view(extent, s), o.config.raster.width, o.config.raster.height, &c))
      return cli::fail("render: the view is out of the camera's range");
    FrameStats stats;
    if (!model.view(c, o.rule.max_size_q4, o.rule.window, error) || !model.render(c, frame.data(), stride, &stats, error))
      return cli::fail(source + ": " + error);
    image_from_frame(frame.data(), stride, o.config.raster.width, o.config.raster.height, o.config.raster.format, image);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04u.png", k);
    const std::string png = folder ? output + "/" + name : output;
    if (!write_png(png, image, error)) return cli::fail(error);
    char line[160];
    std::snprintf(line, sizeof line, "%s nodes %u points %u bytes_received %llu\n", name, stats.nodes, stats.points,
                  static_cast<unsigned long long>(model.bytes_received() - received));
    received = model.bytes_received();
    log += line;
  }
  if (folder && !write_file_atomic(output + "/frames.log", std::vector<uint8_t>(log.begin(), log.end()), error))
    return cli::fail(error);
  std::printf("%s: %u frame%s through the %s, %llu bytes received -> %s\n", source.c_str(), steps, steps == 1 ? "" : "s",
              remote ? "network" : "loopback", static_cast<unsigned long long>(model.bytes_received()), output.c_str());
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
  std::string error, output, connect, path;
  if (!args.value("-o", output)) args.value("--output", output);
  std::string serial_dev, baud_text;
  const bool over_serial = args.value("--serial", serial_dev);
  unsigned long long baud = 115200;
  const bool has_baud = args.value("--baud", baud_text);
  if (has_baud && !cli::parse_uint(baud_text, 4000000, baud))
    return cli::fail("render: --baud: expected a rate, got '" + baud_text + "'");
  if (has_baud && !over_serial)
    return cli::fail("render: --baud " + baud_text + " sets the serial line's rate, but no --serial DEVICE is given");
  const bool remote = args.value("--connect", connect) || over_serial, has_path = args.value("--path", path);
  const bool reference = args.flag("--reference"), psnr = args.flag("--psnr"), json = args.flag("--json");
  std::string legend_text;
  const bool has_legend = args.value("--legend", legend_text);
  Legend legend = Legend::kNone;
  if (has_legend && !parse_legend(legend_text, legend, error)) return cli::fail("render: " + error);
  std::string frames_text;
  unsigned long long frames = 1;
  if (args.value("--frames", frames_text) && (!cli::parse_uint(frames_text, 100000, frames) || frames < 1))
    return cli::fail("render: --frames: expected 1..100000, got '" + frames_text + "'");
  if (!parse_render_options(args, o, error)) return cli::fail("render: " + error);
  std::string token_file;
  if (args.value("--token", token_file) && !cli::read_token(token_file, o.token, error)) return cli::fail("render: --token " + error);
  std::string at_text;
  std::vector<double> at;
  if (args.value("--at", at_text)) {
    for (size_t start = 0; start <= at_text.size();) {
      const size_t comma = std::min(at_text.find(',', start), at_text.size());
      double t = 0;
      if (!cli::parse_double(at_text.substr(start, comma - start), t) || t < 0 || t > 3600 || (!at.empty() && t <= at.back()))
        return cli::fail("render: --at: expected ascending times in seconds from 0 to 3600, as 0.5,1,2,5, got '" + at_text + "'");
      at.push_back(t);
      start = comma + 1;
    }
    if (!remote) return cli::fail("render: --at times a view coming over a link: give --connect HOST:PORT or --serial DEV");
  }
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("render: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("render: " + args.unknown_option_message());
  if (!has_path && at.empty() && !cli::check_output_name(output, ".png", "PNG", error)) return cli::fail("render: " + error);
  if (has_legend && (remote || has_path))
    return cli::fail("render: --legend draws beside one frame of a local model: give it without --connect, --serial or --path");
  if (remote || has_path) {
    unsigned long long steps = 1;
    if (has_path && (path.rfind("orbit:", 0) != 0 || !cli::parse_uint(path.substr(6), 100000, steps) || steps == 0))
      return cli::fail("render: --path: expected orbit:N with N in 1..100000, got '" + path + "'");
    if (remote != files.empty()) return cli::fail(remote ? "render: --connect takes no MODEL.spg" : "render: expected one model (.spg or a scan)");
    if (output.empty())
      return cli::fail(has_path ? "render: -o FOLDER is required with --path"
                       : !at.empty() ? "render: -o FOLDER is required with --at" : "render: -o IMAGE.png is required");
    std::error_code ec;
    if ((has_path || !at.empty()) && std::filesystem::exists(output, ec) && !std::filesystem::is_directory(output, ec))
      return cli::fail(std::string("render: ") + (has_path ? "--path" : "--at") + " writes a folder of frames, but " + output +
                       " is a file (name a folder with -o)");
    if (has_path && !at.empty()) return cli::fail("render: --at takes the first view only: give it without --path");
    return render_stream(remote ? "" : files[0], over_serial ? "" : connect, serial_dev, static_cast<uint32_t>(baud), o,
                         static_cast<uint32_t>(steps), has_path || !at.empty(), output, at);
  }
  if (files.size() != 1) return cli::fail("render: expected one model, a .spg or a scan (see stipple render --help)");
  if (output.empty() && !psnr && frames == 1) return cli::fail("render: -o IMAGE.png is required");
  std::vector<uint8_t> file;
  if (!read_model(files[0], file, error)) return cli::fail(error);  // a scan is encoded in memory
  return render_to_png(files[0], file, o, output, reference, psnr, json, static_cast<int>(frames), legend);
}

}  // namespace stipple
