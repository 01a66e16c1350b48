// stipple-emulator — the handheld on a desktop: the very client the device
// runs (core's node cache and stream, raster's fixed-point renderer, one
// arena) in an SDL2 window that looks and reacts like the device
// (platform/sdl2). Its nodes come over the same node stream as the
// device's: from a local .spg through an in-process server, from `stipple
// serve` over TCP, or over a serial line.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "platform/png_io.h"
#include "platform/sdl2/sdl_display.h"
#include "tools/embedded/options.h"
#include "tools/embedded/render_options.h"
#include "tools/viewer/viewer.h"

namespace stipple {
namespace {

const char kUsage[] =
    "usage: stipple-emulator MODEL.spg|SCAN [options]   (a scan is encoded in memory first)\n"
    "       stipple-emulator --connect HOST:PORT | --serial DEV [--baud N] [options]\n"
    "\n"
    "The handheld client in a window that emulates the device: its screen (240x320\n"
    "RGB565 unless --size says 320x240, 480x640, ...) scaled with nearest filtering\n"
    "in a device frame, a status line (frames a second, nodes, points, kilobytes\n"
    "received, the link's rate) and the device's controls, with a desktop's habits:\n"
    "  left drag            orbit the model\n"
    "  right drag           the stylus: draws the refinement window (or shift and\n"
    "                       the left button; only nodes there are refined; another\n"
    "                       window adds to what the earlier ones refined, TOG05's\n"
    "                       on-demand mode, over a protocol 4 server); a click\n"
    "                       clears it\n"
    "  wheel                dolly\n"
    "  arrow keys           the D-pad: left/right orbit (90 degrees a second),\n"
    "                       up/down tilt; with Enter or Space (select) held,\n"
    "                       up/down dolly (a model length a second)\n"
    "  the on-screen keys   clickable; lit while held\n"
    "  C                    colour: the model's, by elevation, grey\n"
    "  L, Q                 lighting, quality (1, 1/2, 1/4, 2)\n"
    "  R                    reset the view\n"
    "  S or F12             a screenshot: stipple-emulator-NNNN.png here (printed)\n"
    "  H or F1              the keys, on the screen\n"
    "  Escape               quit\n"
    "\n"
    "program:\n"
    "  --connect HOST:PORT  nodes from `stipple serve` (no MODEL.spg)\n"
    "  --serial DEV         the same over a serial line; --baud N its rate (115200)\n"
    "  --scale N            window pixels per device pixel, 1..4 (default: 2, or\n"
    "                       the largest that fits the screen's height)\n"
    "  --version            the version\n"
    "  --headless -o F.png  no window (SDL's offscreen driver): draw the view once it\n"
    "                       has converged and write the device's screen, the same\n"
    "                       bytes as `stipple render` of that view\n"
    "  --frames N           with --headless: draw N frames, print the median time\n"
    "  --script FILE        scripted input (tools/viewer/viewer.h: FRAME down|up|press\n"
    "                       BUTTON, stylus-down|move|up X Y, screenshot PATH, quit)\n"
    "\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple-emulator: %s\n", message.c_str());
  return 1;
}

// The stylus's rectangle while it is drawn, as an outline on the screen.
void outline(uint8_t* frame, size_t stride, const RasterConfig& r, const int32_t rect[4]) {
  const auto put = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= r.width || y >= r.height) return;
    uint8_t* p = frame + static_cast<size_t>(y) * stride + static_cast<size_t>(x) * bytes_per_pixel(r.format);
    if (r.format == PixelFormat::kRgb565) p[0] = 0xE0, p[1] = 0xFF;  // yellow, little-endian 5-6-5
    else p[0] = 0xFF, p[1] = 0xFF, p[2] = 0x00;
  };
  for (int x = rect[0]; x < rect[2]; ++x) put(x, rect[1]), put(x, rect[3] - 1);
  for (int y = rect[1]; y < rect[3]; ++y) put(rect[0], y), put(rect[2] - 1, y);
}

int run(int argc, char** argv) {
  cli::Args args(argc, argv, 1);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kUsage, stdout);
    std::fputs(kRenderOptionsHelp, stdout);
    return 0;
  }
  if (args.flag("--version")) {
    std::printf("stipple-emulator %s\n", STIPPLE_VERSION);
    return 0;
  }
  std::string error, v;
  unsigned long long scale = 0;  // 0: the default, fitted to the screen
  if (args.value("--scale", v) && (!cli::parse_uint(v, 4, scale) || scale < 1))
    return fail("--scale: expected 1..4, got '" + v + "'");
  ViewerOptions vo;
  if (!parse_viewer_options(args, vo, error)) return fail(error);
  const RenderOptions& o = vo.render;
  const std::string &model = vo.model, &connect = vo.connect, &serial = vo.serial, &output = vo.output,
                    &script_path = vo.script;
  const bool headless = vo.headless;
  const unsigned long long baud = vo.baud, frames = vo.frames;
  if (headless && output.empty() && script_path.empty()) return fail("--headless needs -o FRAME.png (or a --script)");
  std::vector<ScriptStep> script;
  if (!script_path.empty() && !read_script(script_path, script, error)) return fail(error);

  SdlDisplay display;
  SdlDisplayOptions d;
  d.width = o.config.raster.width;
  d.height = o.config.raster.height;
  d.scale = static_cast<int>(scale);  // 0: SdlDisplay fits it
  d.headless = headless;
  d.title = "stipple-emulator";
  // The window first: without a display the program says so at once,
  // before it loads (or encodes) a model.
  if (!display.open(d, error)) return fail(error);
  ViewerSource source;
  if (!source.open(model, connect, serial, static_cast<uint32_t>(baud), o, error)) return fail(error);
  RemoteModel& m = source.model();
  Client& client = m.client();
  const int32_t* extent = client.decoder().extent_mu();
  ViewerControls controls(o, m.header(), extent);
  // Colour by elevation: along the view's up axis.
  const SpgAxis up = controls.view().up;
  if (!client.set_elevation(controls.elevation() ? up : SpgAxis::kNone)) return fail("the client refused colour by elevation");
  const RasterConfig& r = o.config.raster;
  const size_t stride = size_t{r.width} * bytes_per_pixel(r.format);
  std::vector<uint8_t> frame(stride * r.height);
  Camera camera;
  if (!controls.camera(r.width, r.height, &camera)) return fail("--camera: the view is out of the camera's range");

  if (headless && script.empty()) {
    // Once the view has converged: the device's screen, as `stipple render` draws it.
    if (!m.view(camera, o.rule.max_size_q4, controls.window(), error)) return fail(source.name() + ": " + error);
    std::vector<double> times;
    FrameStats stats;
    for (unsigned long long f = 0; f < std::max<unsigned long long>(frames, 1); ++f) {
      const auto t = std::chrono::steady_clock::now();
      if (!m.render(camera, frame.data(), stride, &stats, error)) return fail(error);
      times.push_back(seconds_since(t));
      if (!display.present(frame.data(), stride, r.width, r.height, r.format, error)) return fail(error);
    }
    Image image;
    image_from_frame(frame.data(), stride, r.width, r.height, r.format, image);
    if (!write_png(output, image, error)) return fail(error);
    std::sort(times.begin(), times.end());
    std::printf("%s: %u nodes, %u points, %llu bytes received -> %s", source.name().c_str(), stats.nodes, stats.points,
                static_cast<unsigned long long>(m.bytes_received()), output.c_str());
    if (frames > 0) std::printf("; frame: median %.3f ms of %llu", 1e3 * times[times.size() / 2], frames);
    std::printf("\n");
    return 0;
  }

  // The interactive loop: input, the latest camera to the server, whatever
  // the link brought, a frame, the status line; about 30 frames a second.
  if (!m.request(camera, o.rule.max_size_q4, controls.window(), error)) return fail(error);
  // While the server is redialled the last frame stays up, saying so.
  struct Shown {
    SdlDisplay* display;
    const std::vector<uint8_t>* frame;
    size_t stride;
    const RasterConfig* raster;
    std::string line1;
  } shown{&display, &frame, stride, &r, source.name()};
  source.on_reconnecting(
      [](void* context, const char* text) {
        auto* s = static_cast<Shown*>(context);
        std::string ignored;
        s->display->set_status(s->line1, text);
        (void)s->display->present(s->frame->data(), s->stride, s->raster->width, s->raster->height, s->raster->format,
                                  ignored);
      },
      &shown);
  size_t next_step = 0;
  uint32_t frame_number = 0;
  FrameStats stats;
  RateMeter rates;
  Image shot;
  bool had_window = false;  // the last camera sent had a refinement window
  auto last_tick = std::chrono::steady_clock::now();
  while (!controls.quit()) {
    const auto frame_start = std::chrono::steady_clock::now();
    for (; next_step < script.size() && script[next_step].frame <= frame_number; ++next_step) {
      const ScriptStep& s = script[next_step];
      if (s.kind == ScriptStep::kInput && s.click) display.click(s.event.button, s.event.kind == InputKind::kButtonDown);
      else if (s.kind == ScriptStep::kInput) display.inject(s.event);
      else if (s.kind == ScriptStep::kQuit) display.inject(InputEvent{InputKind::kQuit, Button::kNone, 0, 0});
      else if (!display.screenshot(shot, error) || !write_png(s.path, shot, error)) return fail(error);
      else {
        // What a script checks: the window's size, and the device screen's
        // pixels (the last frame drawn) as a CRC-32.
        Image screen;
        image_from_frame(frame.data(), stride, r.width, r.height, r.format, screen);
        std::printf("frame %u: screenshot %s %dx%d, screen crc32 %08x\n", frame_number, s.path.c_str(), shot.width,
                    shot.height, crc32(screen.rgb.data(), screen.rgb.size()));
      }
    }
    bool changed = false;
    InputEvent e;
    while (display.poll(&e)) changed = controls.apply(e) || changed;
    changed = controls.tick(seconds_since(last_tick)) || changed;
    last_tick = std::chrono::steady_clock::now();
    display.set_overlay(controls.help() ? &help_lines() : nullptr);
    if (changed) {
      if (!client.set_view(controls.lighting() ? o.config.shading == ShadingMode::kNone ? ShadingMode::kSurface
                                                                                       : o.config.shading
                                               : ShadingMode::kNone,
                           controls.grey(), controls.quality_q8()) ||
          !client.set_elevation(controls.elevation() ? up : SpgAxis::kNone))
        return fail("the view's options were refused");
      if (!controls.camera(r.width, r.height, &camera)) return fail("the camera left its range");
      // A window after a window keeps what the earlier ones refined.
      const bool windowed = controls.window()[0] < controls.window()[2];
      if (!m.request(camera, o.rule.max_size_q4, controls.window(), error, windowed && had_window))
        return fail(source.name() + ": " + error);
      had_window = windowed;
    }
    // What the link has, for at most 10 ms of this frame.
    if (!service_for(m, 0.010, error)) return fail(source.name() + ": " + error);
    if (!m.render(camera, frame.data(), stride, &stats, error)) return fail(error);
    int32_t rect[4];
    if (controls.dragging(rect)) outline(frame.data(), stride, r, rect);
    else if (controls.window()[0] < controls.window()[2]) outline(frame.data(), stride, r, controls.window());
    rates.frame(m.bytes_received());
    std::string line1, line2;
    status_lines(rates.fps(), stats, m.bytes_received(), rates.bytes_per_s(), controls, m.progress(), line1, line2);
    display.set_status(line1, line2);
    if (!display.present(frame.data(), stride, r.width, r.height, r.format, error)) return fail(error);
    if (controls.take_screenshot()) {  // the S key: the window as shown
      const std::string path = screenshot_path("stipple-emulator");
      if (!display.screenshot(shot, error) || !write_png(path, shot, error)) return fail(error);
      std::printf("screenshot %s (%dx%d)\n", path.c_str(), shot.width, shot.height);
      std::fflush(stdout);
    }
    ++frame_number;
    pace_frame(frame_start, 30);
  }
  if (!output.empty()) {
    Image image;
    image_from_frame(frame.data(), stride, r.width, r.height, r.format, image);
    if (!write_png(output, image, error)) return fail(error);
  }
  std::printf("%s: %u frames, last %u nodes, %u points, %llu bytes received\n", source.name().c_str(), frame_number,
              stats.nodes, stats.points, static_cast<unsigned long long>(m.bytes_received()));
  return 0;
}

}  // namespace
}  // namespace stipple

int main(int argc, char** argv) { return stipple::run(argc, argv); }
