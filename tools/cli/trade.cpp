// stipple trade — the speed–accuracy trade, measured: every client knob
// swept alone from the defaults, each setting timed and compared with the
// reference picture (`stipple truth` of the scan, or without a scan the
// double-precision reference renderer's picture of the leaves), as CSV and
// a plot of error against time with the Pareto front and the defaults.
#include <linux/perf_event.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "platform/file_io.h"
#include "platform/png_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/embedded/model_file.h"
#include "tools/embedded/render_options.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/image_metrics.h"
#include "tools/reference/plot.h"
#include "tools/reference/render.h"
#include "tools/reference/spg_model.h"
#include "tools/reference/truth.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

const char kTradeHelp[] =
    "usage: stipple trade MODEL.spg [--scan SCAN.ply] [--views N] [--repeat R] [render options] -o DIR\n"
    "\n"
    "Sweeps each knob of the fixed-point client alone from the defaults — the cut's\n"
    "pixel threshold (--max-size), the points-per-node scale (--quality), quasi- vs\n"
    "pseudo-random samples, the projection, the point size, supersampling, the\n"
    "shading mode, the screen-space resolve, the point cap, the tile size, colour\n"
    "on/off — and for\n"
    "each setting measures,\n"
    "over N orbit views (default 3): the frame time (median of R frames, default\n"
    "5), the instructions a frame takes (the CPU's counter through perf_event_open:\n"
    "R frames less one frame, over R - 1, so the cut and set-up cancel; empty where\n"
    "the kernel refuses the counter or R is 1), points, nodes, the bytes that stream the\n"
    "cut cold, and the picture against the reference: object PSNR, SSIM, dark where\n"
    "lit, outside the silhouette, missing (stipple image-diff's measures). The\n"
    "reference is SCAN.ply drawn by `stipple truth` (the scan the model was encoded\n"
    "from), or without --scan the reference renderer's picture of every leaf.\n"
    "Render's view and client options set the defaults swept from (--size: 640x480\n"
    "unless given; frames are RGB888). Writes DIR/trade.csv and DIR/trade.png (object PSNR against frame time, one\n"
    "colour per knob, the Pareto front in black, the defaults marked). A progress\n"
    "bar on a terminal.\n";

// Instructions retired by this thread between start() and stop(); -1 when
// the kernel offers no counter (containers, perf_event_paranoid).
class InstructionCounter {
 public:
  InstructionCounter() {
    perf_event_attr a;
    std::memset(&a, 0, sizeof a);
    a.type = PERF_TYPE_HARDWARE;
    a.size = sizeof a;
    a.config = PERF_COUNT_HW_INSTRUCTIONS;
    a.disabled = 1;
    a.exclude_kernel = 1;
    a.exclude_hv = 1;
    fd_ = static_cast<int>(syscall(SYS_perf_event_open, &a, 0, -1, -1, 0));
  }
  ~InstructionCounter() {
    if (fd_ >= 0) close(fd_);
  }
  void start() {
    if (fd_ < 0) return;
    ioctl(fd_, PERF_EVENT_IOC_RESET, 0);
    ioctl(fd_, PERF_EVENT_IOC_ENABLE, 0);
  }
  long long stop() {
    if (fd_ < 0) return -1;
    ioctl(fd_, PERF_EVENT_IOC_DISABLE, 0);
    long long v = 0;
    return read(fd_, &v, sizeof v) == sizeof v ? v : -1;
  }

 private:
  int fd_ = -1;
};

struct Setting {
  std::string knob, value;
  bool is_default = false;
  std::function<void(RenderOptions&)> apply;
};

std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

std::vector<Setting> settings(bool color) {
  std::vector<Setting> s;
  const auto add = [&](const std::string& knob, const std::string& value, bool def, std::function<void(RenderOptions&)> f) {
    s.push_back({knob, value, def, std::move(f)});
  };
  for (double px : {1.0, 1.5, 2.0, 3.0, 4.0, 6.0})
    add("max-size", number(px), px == 2.0,
        [px](RenderOptions& o) { o.rule.max_size_q4 = static_cast<int32_t>(std::lround(px * 16)); });
  for (double q : {0.5, 1.0, 2.0, 4.0})
    add("quality", number(q), q == 1.0,
        [q](RenderOptions& o) { o.config.quality_q8 = static_cast<uint16_t>(std::lround(q * 256)); });
  add("samples", "sobol", true, [](RenderOptions&) {});
  add("samples", "pseudo", false, [](RenderOptions& o) { o.config.source = GaussianSource::kPseudo; });
  add("projection", "affine", true, [](RenderOptions&) {});
  add("projection", "reciprocal", false, [](RenderOptions& o) { o.config.projection = Projection::kReciprocal; });
  add("projection", "exact", false, [](RenderOptions& o) { o.config.projection = Projection::kExact; });
  for (int p : {1, 2, 3})
    add("point-size", std::to_string(p), p == 2, [p](RenderOptions& o) { o.config.point_size = static_cast<uint8_t>(p); });
  for (int n : {1, 2, 4})
    add("supersample", std::to_string(n), n == 1, [n](RenderOptions& o) {
      o.config.supersample = static_cast<uint8_t>(n);
      o.config.raster.max_points <<= n / 2;  // room for the points the larger frame takes
    });
  // Supersampling once more without the resolve, which takes most of its gain.
  for (int n : {1, 2, 4})
    add("supersample-resolve-off", std::to_string(n), false, [n](RenderOptions& o) {
      o.config.supersample = static_cast<uint8_t>(n);
      o.config.raster.max_points <<= n / 2;
      o.config.resolve = false;
    });
  add("shading", "surface", true, [](RenderOptions&) {});
  add("shading", "node", false, [](RenderOptions& o) { o.config.shading = ShadingMode::kPerNode; });
  add("shading", "point", false, [](RenderOptions& o) { o.config.shading = ShadingMode::kPerPoint; });
  add("shading", "none", false, [](RenderOptions& o) { o.config.shading = ShadingMode::kNone; });
  for (int k : {0, 2, 4, 8})
    add("point-cap", std::to_string(k), k == 0, [k](RenderOptions& o) { o.config.point_cap = static_cast<uint8_t>(k); });
  add("splat", "points", true, [](RenderOptions&) {});
  add("splat", "ewa", false, [](RenderOptions& o) { o.config.ewa = true; });
  add("resolve", "on", true, [](RenderOptions&) {});
  add("resolve", "off", false, [](RenderOptions& o) { o.config.resolve = false; });
  for (int t : {4, 5, 6})
    add("tile", std::to_string(1 << t), t == 5, [t](RenderOptions& o) { o.config.raster.tile_log2 = static_cast<uint8_t>(t); });
  if (color) add("colour", "off", false, [](RenderOptions& o) { o.config.grey = true; });
  return s;
}

struct Row {
  double time_ms = 0, instructions = -1, points = 0, nodes = 0, bytes = 0;
  ImageComparison m;
};

}  // namespace

int cmd_trade(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kTradeHelp, stdout);
    std::fputs(cli::kScanOptionsHelp, stdout);
    return 0;
  }
  std::string scan_path, output, v, error;
  args.value("--scan", scan_path);
  if (!args.value("-o", output)) args.value("--output", output);
  unsigned long long views = 3, repeat = 5;
  if (args.value("--views", v) && (!cli::parse_uint(v, 64, views) || views < 1))
    return cli::fail("trade: --views: expected 1..64, got '" + v + "'");
  if (args.value("--repeat", v) && (!cli::parse_uint(v, 1000, repeat) || repeat < 1))
    return cli::fail("trade: --repeat: expected 1..1000, got '" + v + "'");
  RenderOptions base;  // render's options as the defaults the sweep starts from
  if (!parse_render_options(args, base, error)) return cli::fail("trade: " + error);
  if (!base.sized) {
    base.config.raster.width = 640;
    base.config.raster.height = 480;
  }
  base.config.raster.format = PixelFormat::kRgb888;
  base.config.raster.max_points = 1u << 20;
  ScanOptions scan_options;
  if (std::string e; !cli::parse_scan_options(args, scan_options, e)) return cli::fail("trade: " + e);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("trade: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("trade: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("trade: expected one .spg file (see stipple trade --help)");
  if (output.empty()) return cli::fail("trade: -o DIR is required");
  std::vector<uint8_t> file;
  if (!read_spg_file(files[0], file, error)) return cli::fail(error);
  SpgView view;
  const SpgResult r = spg_parse(file.data(), file.size(), &view);
  if (!r.ok()) return cli::fail(spg_error_message(files[0], r, file.data(), file.size()));
  base.config.node_capacity = std::max<uint32_t>(view.header.node_count, 1);  // the cut is never held back by the cache
  DecodedModel model;
  if (!decode_spg(files[0], file.data(), file.size(), model, error)) return cli::fail(error);
  PointCloud scan;
  if (!scan_path.empty()) {
    if (!read_point_cloud(scan_path, scan, error, scan_options)) return cli::fail(error);
    prepare_scan(scan, EncodeOptions{});
  }
  std::error_code ec;
  std::filesystem::create_directories(output, ec);
  if (ec) return cli::fail("trade: " + output + ": " + ec.message());

  // The references, one per view.
  std::vector<ViewSpec> specs;
  std::vector<Image> references;
  std::vector<uint8_t> decoder_storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size()) != DecodeStatus::kOk)
    return cli::fail(files[0] + ": the angle fields are wider than the decoder supports");
  const ViewSpec resolved = resolve_view(base.view, view.header, decoder.extent_mu());
  for (unsigned long long k = 0; k < views; ++k) {
    ViewSpec s = resolved;
    s.yaw = resolved.yaw + 360.0 * static_cast<double>(k) / static_cast<double>(views);
    s.orbit_given = true;
    specs.push_back(s);
    references.push_back(scan_path.empty() ? render_reference(model, leaf_cut(model), base.config, s)
                                           : render_truth(scan, model.bbox_min, model.bbox_max, view.header, base.config, s));
  }
  const std::vector<Setting> all = settings(view.header.has_color());
  InstructionCounter counter;
  ProgressBar progress("trade");
  std::vector<Row> rows;
  for (size_t i = 0; i < all.size(); ++i) {
    progress.update(static_cast<double>(i) / static_cast<double>(all.size()), all[i].knob + " " + all[i].value);
    RenderOptions o = base;
    all[i].apply(o);
    Row row;
    row.m = ImageComparison{0, 0, 0, 0, 0, 0};  // sums over the views
    std::vector<double> times;
    double instructions = 0;
    bool counted = true;
    for (const ViewSpec& s : specs) {
      // One frame and R frames, each with the cut and the set-up: their
      // difference over R - 1 is what a frame takes.
      FixedRender f;
      counter.start();
      if (!render_fixed(view, file.data(), o.config, o.rule, s, f, error, 1)) return cli::fail(files[0] + ": " + error);
      const long long one = counter.stop();
      FixedRender timed;
      counter.start();
      if (!render_fixed(view, file.data(), o.config, o.rule, s, timed, error, static_cast<int>(repeat)))
        return cli::fail(files[0] + ": " + error);
      const long long all_frames = counter.stop();
      counted = counted && repeat > 1 && one >= 0 && all_frames >= one;
      if (counted) instructions += static_cast<double>(all_frames - one) / static_cast<double>(repeat - 1);
      times.insert(times.end(), timed.frame_seconds.begin(), timed.frame_seconds.end());
      const ImageComparison m = compare_images(references[&s - specs.data()], f.image);
      row.m.object_psnr += m.object_psnr / static_cast<double>(specs.size());
      row.m.ssim += m.ssim / static_cast<double>(specs.size());
      row.m.dark_where_lit += m.dark_where_lit / static_cast<double>(specs.size());
      row.m.outside += m.outside / static_cast<double>(specs.size());
      row.m.missing += m.missing / static_cast<double>(specs.size());
      row.points += f.stats.points / static_cast<double>(specs.size());
      row.nodes += static_cast<double>(f.cut.size()) / static_cast<double>(specs.size());
    }
    std::sort(times.begin(), times.end());
    row.time_ms = 1e3 * times[times.size() / 2];
    row.instructions = counted ? instructions / static_cast<double>(specs.size()) : -1;
    row.bytes = row.nodes * static_cast<double>(4 + view.record_bytes);
    rows.push_back(row);
  }
  progress.finish();

  std::string csv =
      "knob,value,default,frame_ms,instructions,points,nodes,bytes_cold,object_psnr_db,ssim,dark_where_lit,outside,missing\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& w = rows[i];
    char line[512];
    std::snprintf(line, sizeof line, "%s,%s,%d,%.4f,%s,%.0f,%.0f,%.0f,%.4f,%.5f,%.5f,%.5f,%.5f\n", all[i].knob.c_str(),
                  all[i].value.c_str(), all[i].is_default ? 1 : 0, w.time_ms,
                  w.instructions < 0 ? "" : std::to_string(static_cast<long long>(w.instructions)).c_str(), w.points,
                  w.nodes, w.bytes, w.m.object_psnr, w.m.ssim, w.m.dark_where_lit, w.m.outside, w.m.missing);
    csv += line;
  }
  if (!write_file_atomic(output + "/trade.csv", std::vector<uint8_t>(csv.begin(), csv.end()), error)) return cli::fail(error);

  // The plot: one series per knob, the Pareto front (no setting both faster
  // and better), the defaults.
  PlotSpec spec;
  const std::string name = std::filesystem::path(files[0]).filename().string();
  spec.title = name + ": object PSNR against frame time (" + std::to_string(base.config.raster.width) + "x" +
               std::to_string(base.config.raster.height) + ", " + std::to_string(views) + " views)";
  spec.x_label = "frame time (ms, median, log scale)";
  spec.log_x = true;  // the knobs span 0.1 ms to tens of ms: a linear axis crushes most of them into its first tick
  spec.y_label = "object PSNR against the reference (dB)";
  static const uint32_t colors[] = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22, 0x7f7f7f};
  for (size_t i = 0; i < rows.size(); ++i) {
    auto it = std::find_if(spec.series.begin(), spec.series.end(), [&](const PlotSeries& p) { return p.label == all[i].knob; });
    if (it == spec.series.end()) {
      spec.series.push_back(PlotSeries{all[i].knob, {}, {}, colors[spec.series.size() % 10], {}});
      it = spec.series.end() - 1;
    }
    it->x.push_back(rows[i].time_ms);
    it->y.push_back(rows[i].m.object_psnr);
    it->point_labels.push_back(all[i].value);
  }
  std::vector<size_t> order(rows.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return rows[a].time_ms < rows[b].time_ms; });
  PlotSeries front{"Pareto front", {}, {}, 0x000000, {}};
  std::vector<size_t> on_front;
  double best = -1e300;
  for (size_t i : order)
    if (rows[i].m.object_psnr > best) {
      best = rows[i].m.object_psnr;
      front.x.push_back(rows[i].time_ms);
      front.y.push_back(rows[i].m.object_psnr);
      on_front.push_back(i);
    }
  spec.series.push_back(front);
  // The knee: the front's point farthest above the chord between its ends,
  // in the plot's own terms (log time, PSNR), each axis scaled to its span.
  size_t knee = on_front.empty() ? 0 : on_front.front();
  if (on_front.size() >= 3) {
    const auto lx = [&](size_t i) { return std::log10(std::max(rows[i].time_ms, 1e-6)); };
    const size_t a = on_front.front(), b = on_front.back();
    const double sx = std::max(lx(b) - lx(a), 1e-9), sy = std::max(rows[b].m.object_psnr - rows[a].m.object_psnr, 1e-9);
    double farthest = -1;
    for (size_t i : on_front) {
      const double across = (lx(i) - lx(a)) / sx, up = (rows[i].m.object_psnr - rows[a].m.object_psnr) / sy;
      if (up - across > farthest) farthest = up - across, knee = i;
    }
  }
  if (!on_front.empty())
    spec.series.push_back(PlotSeries{"knee: " + all[knee].knob + " " + all[knee].value, {rows[knee].time_ms},
                                     {rows[knee].m.object_psnr}, 0x00a000, {}});
  for (size_t i = 0; i < rows.size(); ++i)
    if (all[i].is_default && all[i].knob == "max-size") {
      spec.series.push_back(PlotSeries{"defaults", {rows[i].time_ms}, {rows[i].m.object_psnr}, 0xff0000, {"default"}});
      break;
    }
  size_t left_out = 0;
  if (!write_png(output + "/trade.png", render_plot(spec, &left_out), error)) return cli::fail(error);
  if (!on_front.empty())
    std::printf("knee of the Pareto front: %s %s (%.3f ms, %.2f dB); on the front: ", all[knee].knob.c_str(),
                all[knee].value.c_str(), rows[knee].time_ms, rows[knee].m.object_psnr);
  for (size_t k = 0; k < on_front.size(); ++k)
    std::printf("%s%s %s", k ? ", " : "", all[on_front[k]].knob.c_str(), all[on_front[k]].value.c_str());
  std::printf("\n");
  if (left_out) std::printf("plot: %zu point labels left out where they would overlap (trade.csv has every point)\n", left_out);
  std::printf("%s: %zu settings over %llu views against %s -> %s/trade.csv, %s/trade.png\n", files[0].c_str(), rows.size(),
              views, scan_path.empty() ? "the reference renderer's leaves" : scan_path.c_str(), output.c_str(), output.c_str());
  return 0;
}

}  // namespace stipple
