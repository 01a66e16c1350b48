// stipple-gl — the desktop client on the GPU: the node stream the handheld
// gets (a local .spg through an in-process server, `stipple serve` over
// TCP, or a serial line) into core's node cache, drawn by platform/gl's
// renderer: records decoded and points generated in the vertex shader.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <epoxy/gl.h>

#include "platform/gl/gl_renderer.h"
#include "platform/png_io.h"
#include "platform/text.h"
#include "platform/sdl2/sdl_gl_window.h"
#include "tools/embedded/options.h"
#include "tools/embedded/render_options.h"
#include "tools/viewer/viewer.h"

namespace stipple {
namespace {

const char kUsage[] =
    "usage: stipple-gl MODEL.spg|SCAN [options]   (a scan is encoded in memory first)\n"
    "       stipple-gl --connect HOST:PORT | --serial DEV [--baud N] [options]\n"
    "\n"
    "The GL desktop client: the same node stream as the handheld, decoded and\n"
    "sampled on the GPU (OpenGL 3.3 core; platform/gl/gl_renderer.h). The window\n"
    "takes the emulator's controls: a left drag orbits, a right drag (or shift\n"
    "and the left button) draws the refinement window, the wheel dollies, arrow\n"
    "keys orbit and tilt (with Enter or Space held, dolly), C L Q colour, lighting\n"
    "and quality, R resets the view, S or F12 writes stipple-gl-NNNN.png here, H\n"
    "or F1 shows the keys, Escape quits. A band at the bottom shows the frame\n"
    "rate, nodes, points, kilobytes received and the view's progress.\n"
    "\n"
    "program:\n"
    "  --connect HOST:PORT  nodes from `stipple serve` (no MODEL.spg)\n"
    "  --serial DEV         the same over a serial line; --baud N its rate (115200)\n"
    "  --decode gpu|cpu     records unpacked in the vertex shader (default) or by\n"
    "                       core's decoder on the CPU, for comparison\n"
    "  --splat points|ewa   the nodes' Gaussian samples as points (default; the\n"
    "                       software client's picture: surface normals, the\n"
    "                       resolve) or one elliptical splat a node, blended (EWA)\n"
    "  --msaa N             multisampling, 0 (default), 2, 4 or 8 (the paper: 8);\n"
    "                       with --resolve off (the resolve draws offscreen)\n"
    "  --headless -o F.png  no window (EGL, surfaceless or a pbuffer): draw the\n"
    "                       view once it has converged and write it\n"
    "  --frames N           with --headless: draw N frames and print the median\n"
    "                       time, nodes/s and points/s\n"
    "  --script FILE        scripted input, as stipple-emulator's\n"
    "  --version            the version\n"
    "(--size defaults to 640x480 and --cache to 200000 nodes here.)\n"
    "\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple-gl: %s\n", message.c_str());
  return 1;
}

// `up`: the view's up axis, colour by elevation's.
GlRenderOptions gl_options(const RenderOptions& o, bool gpu, GlSplat splat, const ViewerControls* c, SpgAxis up = SpgAxis::kPosY) {
  GlRenderOptions g;
  g.elevation = (c ? c->elevation() : o.config.elevation != SpgAxis::kNone) ? up : SpgAxis::kNone;
  g.gpu_decode = gpu;
  g.splat = splat;
  g.surface_normals = o.config.shading != ShadingMode::kPerNode;
  g.resolve = o.config.resolve;
  g.point_cap = o.config.point_cap;
  g.close_ups = o.config.close_ups;
  g.specular = static_cast<float>(o.config.lighting.specular_q8) / 256.f;
  g.shininess = o.config.lighting.shininess;
  g.point_size = o.config.point_size;
  g.samples = o.config.samples;
  g.quality_q8 = c ? c->quality_q8() : o.config.quality_q8;
  g.grey = c ? c->grey() : o.config.grey;
  g.lighting = c ? c->lighting() : o.config.shading != ShadingMode::kNone;
  for (int k = 0; k < 3; ++k) g.light[k] = static_cast<float>(o.config.lighting.light_q14[k]) / 16384.f;
  g.ambient = static_cast<float>(o.config.lighting.ambient_q8) / 256.f;
  g.grey_rgb = o.config.grey_rgb;
  g.clear_rgb = o.config.clear_rgb;
  return g;
}

// The refinement window's outline, in the bound framebuffer (rows from the top).
void outline(int height, const int32_t r[4]) {
  glEnable(GL_SCISSOR_TEST);
  glClearColor(1.f, 1.f, 0.f, 1.f);
  const auto bar = [&](int x0, int y0, int x1, int y1) {
    glScissor(x0, height - y1, std::max(x1 - x0, 1), std::max(y1 - y0, 1));
    glClear(GL_COLOR_BUFFER_BIT);
  };
  bar(r[0], r[1], r[2], r[1] + 1);
  bar(r[0], r[3] - 1, r[2], r[3]);
  bar(r[0], r[1], r[0] + 1, r[3]);
  bar(r[2] - 1, r[1], r[2], r[3]);
  glDisable(GL_SCISSOR_TEST);
}

// Lines of text drawn over the bound framebuffer (rows from the top, GL's
// from the bottom): a dark band, the font at twice its size. Through a
// texture blitted into place (GL 3.3 core has no raster text), drawn anew
// only when the lines or the window's width change.
class Overlay {
 public:
  ~Overlay() {
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (texture_) glDeleteTextures(1, &texture_);
  }
  // `y` the band's top row; -1: at the bottom, -2: in the middle.
  void draw(const std::vector<std::string>& lines, int window_w, int window_h, int y, GLint target) {
    if (lines.empty()) return;
    const int scale = 2, line_h = 9 * scale, h = static_cast<int>(lines.size()) * line_h + 3 * scale;
    const int w = window_w;
    if (!texture_) {
      glGenTextures(1, &texture_);
      glGenFramebuffers(1, &fbo_);
    }
    if (lines != lines_ || w != width_) {
      upload(lines, w, h, scale, line_h);
      lines_ = lines;
      width_ = w;
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(target));
    const int top = y == -1 ? window_h - h : y == -2 ? (window_h - h) / 2 : y;
    glBlitFramebuffer(0, 0, w, h, 0, window_h - top - h, w, window_h - top, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(target));
  }

 private:
  void upload(const std::vector<std::string>& lines, int w, int h, int scale, int line_h) {
    std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
    fill_rect(rgb.data(), w, h, 0, 0, w, h, 0x101418);
    for (size_t i = 0; i < lines.size(); ++i)
      draw_text(rgb.data(), w, h, 4 * scale, 2 * scale + static_cast<int>(i) * line_h, lines[i], 0x9FE0A0, scale);
    // GL's rows run bottom to top.
    std::vector<uint8_t> rows(rgb.size());
    for (int r = 0; r < h; ++r)
      std::copy_n(&rgb[static_cast<size_t>(h - 1 - r) * w * 3], static_cast<size_t>(w) * 3, &rows[static_cast<size_t>(r) * w * 3]);
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, w, h, 0, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture_, 0);
  }

  GLuint texture_ = 0, fbo_ = 0;
  std::vector<std::string> lines_;  // what the texture holds
  int width_ = 0;
};

int run(int argc, char** argv) {
  cli::Args args(argc, argv, 1);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kUsage, stdout);
    std::fputs(kRenderOptionsHelp, stdout);
    return 0;
  }
  if (args.flag("--version")) {
    std::printf("stipple-gl %s\n", STIPPLE_VERSION);
    return 0;
  }
  bool cache_given = false;
  for (int i = 1; i < argc; ++i) cache_given = cache_given || std::strcmp(argv[i], "--cache") == 0;
  std::string error, decode = "gpu", v;
  args.value("--decode", decode);
  unsigned long long msaa = 0;
  if (args.value("--msaa", v) && (!cli::parse_uint(v, 8, msaa) || (msaa != 0 && msaa != 2 && msaa != 4 && msaa != 8)))
    return fail("--msaa: expected 0, 2, 4 or 8, got '" + v + "'");
  if (decode != "gpu" && decode != "cpu") return fail("--decode: expected gpu or cpu, got '" + decode + "'");
  std::string splat_name = "points";
  args.value("--splat", splat_name);
  if (splat_name != "points" && splat_name != "ewa") return fail("--splat: expected points or ewa, got '" + splat_name + "'");
  const GlSplat splat = splat_name == "ewa" ? GlSplat::kEwa : GlSplat::kPoints;
  ViewerOptions vo;
  if (!parse_viewer_options(args, vo, error)) return fail(error);
  RenderOptions& o = vo.render;
  const std::string &model = vo.model, &connect = vo.connect, &serial = vo.serial, &output = vo.output,
                    &script_path = vo.script;
  const bool headless = vo.headless;
  const unsigned long long baud = vo.baud, frames = vo.frames;
  if (headless && output.empty()) return fail("--headless needs -o FRAME.png");
  if (!o.sized) o.config.raster.width = 640, o.config.raster.height = 480;
  if (!cache_given) o.config.node_capacity = 200000;
  o.config.raster.max_points = 1u << 16;  // the software renderer's budget (unused here): keep its arena small
  std::vector<ScriptStep> script;
  if (!script_path.empty() && !read_script(script_path, script, error)) return fail(error);
  const int w = o.config.raster.width, h = o.config.raster.height;
  const bool gpu = decode == "gpu";

  EglContext egl;
  SdlGlWindow window;
  if (headless ? !egl.open(error) : !window.open(w, h, static_cast<int>(msaa), "stipple-gl", error)) return fail(error);
  ViewerSource source;
  if (!source.open(model, connect, serial, static_cast<uint32_t>(baud), o, error)) return fail(error);
  RemoteModel& m = source.model();
  const NodeCache& cache = m.client().cache();
  GlRenderer renderer;
  ViewerControls controls(o, m.header(), cache.decoder().extent_mu());
  const SpgAxis up = controls.view().up;  // colour by elevation's
  if (!renderer.init(cache, gl_options(o, gpu, splat, nullptr, up), error)) return fail(error);
  Camera camera;
  if (!controls.camera(static_cast<uint16_t>(w), static_cast<uint16_t>(h), &camera))
    return fail("--camera: the view is out of the camera's range");
  Image image;
  GlFrameStats stats;

  if (headless) {
    GlOffscreen target;
    if (!target.init(w, h, static_cast<int>(msaa), error)) return fail(error);
    if (!m.view(camera, o.rule.max_size_q4, controls.window(), error)) return fail(source.name() + ": " + error);
    std::vector<double> times;
    for (unsigned long long f = 0; f < std::max<unsigned long long>(frames, 1); ++f) {
      target.bind();
      const auto t = std::chrono::steady_clock::now();
      if (!renderer.draw(cache, camera, w, h, gl_options(o, gpu, splat, nullptr, up), &stats, error)) return fail(error);
      glFinish();
      times.push_back(seconds_since(t));
    }
    image.width = w;
    image.height = h;
    if (!target.read(image.rgb, error)) return fail(error);
    if (!write_png(output, image, error)) return fail(error);
    std::sort(times.begin(), times.end());
    std::printf("%s: %s; %u nodes, %llu points, %llu bytes received -> %s", source.name().c_str(),
                GlRenderer::describe().c_str(), stats.nodes, static_cast<unsigned long long>(stats.points),
                static_cast<unsigned long long>(m.bytes_received()), output.c_str());
    if (frames > 0) {
      const double t = times[times.size() / 2];
      std::printf("; frame: median %.3f ms of %llu, %.2f M nodes/s, %.1f M points/s", 1e3 * t, frames, stats.nodes / t / 1e6,
                  static_cast<double>(stats.points) / t / 1e6);
    }
    std::printf("\n");
    return 0;
  }

  if (!m.request(camera, o.rule.max_size_q4, controls.window(), error)) return fail(error);
  size_t next_step = 0;
  uint32_t frame_number = 0;
  RateMeter rates;
  std::vector<std::string> shots;  // this frame's screenshots
  auto last_tick = std::chrono::steady_clock::now();
  Overlay status, help;
  std::string status_text[2];
  while (!controls.quit()) {
    const auto frame_start = std::chrono::steady_clock::now();
    shots.clear();
    for (; next_step < script.size() && script[next_step].frame <= frame_number; ++next_step) {
      const ScriptStep& s = script[next_step];
      if (s.kind == ScriptStep::kInput) window.inject(s.event);
      else if (s.kind == ScriptStep::kQuit) window.inject(InputEvent{InputKind::kQuit, Button::kNone, 0, 0});
      else shots.push_back(s.path);
    }
    bool changed = false;
    InputEvent e;
    while (window.poll(&e)) changed = controls.apply(e) || changed;
    changed = controls.tick(seconds_since(last_tick)) || changed;
    last_tick = std::chrono::steady_clock::now();
    if (changed) {
      if (!controls.camera(static_cast<uint16_t>(w), static_cast<uint16_t>(h), &camera)) return fail("the camera left its range");
      if (!m.request(camera, o.rule.max_size_q4, controls.window(), error)) return fail(source.name() + ": " + error);
    }
    // What the link has, for at most 10 ms of this frame.
    if (!service_for(m, 0.010, error)) return fail(source.name() + ": " + error);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!renderer.draw(cache, camera, window.width(), window.height(), gl_options(o, gpu, splat, &controls, up), &stats, error))
      return fail(error);
    int32_t rect[4];
    if (controls.dragging(rect)) outline(window.height(), rect);
    else if (controls.window()[0] < controls.window()[2]) outline(window.height(), controls.window());
    // The window as it is now, into `image` and a PNG.
    const auto shoot = [&](const std::string& path) {
      image.width = window.width();
      image.height = window.height();
      return gl_read_pixels(window.width(), window.height(), image.rgb, error) && write_png(path, image, error);
    };
    // Script screenshots see this frame as drawn, without the bands (whose
    // numbers change).
    for (const std::string& path : shots) {
      if (!shoot(path)) return fail(error);
      std::printf("frame %u: screenshot %s %dx%d, crc32 %08x\n", frame_number, path.c_str(), image.width, image.height,
                  crc32(image.rgb.data(), image.rgb.size()));
    }
    if (rates.frame(m.bytes_received())) {
      RemoteModel::Progress progress = m.progress();
      FrameStats fs;
      fs.nodes = stats.nodes;
      fs.points = static_cast<uint32_t>(std::min<uint64_t>(stats.points, 0xFFFFFFFFu));
      status_lines(rates.fps(), fs, m.bytes_received(), rates.bytes_per_s(), controls, progress, status_text[0],
                   status_text[1]);
      char title[160];
      std::snprintf(title, sizeof title, "stipple-gl  %s  %s", status_text[0].c_str(), status_text[1].c_str());
      window.set_title(title);
    }
    status.draw({status_text[0] + "   " + status_text[1]}, window.width(), window.height(), -1, 0);
    if (controls.help()) help.draw(help_lines(), window.width(), window.height(), -2, 0);
    // The S key: the window as shown.
    if (controls.take_screenshot()) {
      const std::string path = screenshot_path("stipple-gl");
      if (!shoot(path)) return fail(error);
      std::printf("screenshot %s (%dx%d)\n", path.c_str(), image.width, image.height);
      std::fflush(stdout);
    }
    window.swap();
    ++frame_number;
    pace_frame(frame_start, 60);
  }
  std::printf("%s: %u frames, last %u nodes, %llu points, %llu bytes received\n", source.name().c_str(), frame_number,
              stats.nodes, static_cast<unsigned long long>(stats.points), static_cast<unsigned long long>(m.bytes_received()));
  return 0;
}

}  // namespace
}  // namespace stipple

int main(int argc, char** argv) { return stipple::run(argc, argv); }
