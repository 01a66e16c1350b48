// stipple tools — the desktop viewers' shared parts. See viewer.h.
#include "tools/viewer/viewer.h"

#include <cmath>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

#include "platform/file_io.h"
#include "tools/encoder/encoder.h"
#include "platform/loopback/loopback_transport.h"
#include "platform/serial/serial_transport.h"
#include "platform/tcp/tcp_transport.h"

namespace stipple {

namespace {

// A .spg by its first bytes (a scan is encoded in memory instead).
bool starts_as_spg(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  return in.read(magic, sizeof magic) && std::equal(magic, magic + 4, kSpgMagic, [](char a, uint8_t b) {
           return static_cast<uint8_t>(a) == b;
         });
}

}  // namespace

bool parse_viewer_options(cli::Args& args, ViewerOptions& o, std::string& error) {
  std::string v;
  unsigned long long u = 0;
  args.value("--connect", o.connect);
  args.value("--serial", o.serial);
  if (args.value("--baud", v)) {
    if (!cli::parse_uint(v, 4000000, u)) return error = "--baud: expected a rate, got '" + v + "'", false;
    o.baud = static_cast<uint32_t>(u);
  }
  if (args.value("--frames", v)) {
    if (!cli::parse_uint(v, 100000, u) || u < 1) return error = "--frames: expected 1..100000, got '" + v + "'", false;
    o.frames = static_cast<uint32_t>(u);
  }
  o.headless = args.flag("--headless");
  if (!args.value("-o", o.output)) args.value("--output", o.output);
  args.value("--script", o.script);
  if (!parse_render_options(args, o.render, error)) return false;
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return error = args.error(), false;
  if (!args.unknown_option().empty()) return error = args.unknown_option_message(), false;
  if (files.size() > 1) return error = "expected one .spg file", false;
  o.model = files.empty() ? "" : files[0];
  if (o.model.empty() && o.connect.empty() && o.serial.empty())
    return error = "expected a .spg file, --connect HOST:PORT or --serial DEV (stipple encode data/bunny.ply -o bunny.spg makes one)",
           false;
  return true;
}

struct ViewerSource::Links {
  Server local;
  LoopbackPipe pipe;
  std::unique_ptr<TcpTransport> tcp;
  std::unique_ptr<SerialTransport> serial;
  std::string host;
  uint16_t port = 0;
  void (*announce)(void* context, const char* text) = nullptr;
  void* announce_context = nullptr;
};

ViewerSource::ViewerSource() : links_(std::make_unique<Links>()) {}

void ViewerSource::on_reconnecting(void (*announce)(void* context, const char* text), void* context) {
  links_->announce = announce;
  links_->announce_context = context;
}
ViewerSource::~ViewerSource() { model_.close(); }

bool ViewerSource::open(const std::string& model, const std::string& connect, const std::string& serial, uint32_t baud,
                        const RenderOptions& o, std::string& error) {
  Links& l = *links_;
  RemoteModel::Options ro;
  Transport* link = nullptr;
  if ((!model.empty()) + (!connect.empty()) + (!serial.empty()) != 1)
    return error = "expected one source: a .spg file, --connect HOST:PORT or --serial DEV", false;
  if (!serial.empty()) {
    l.serial = std::make_unique<SerialTransport>();
    if (!l.serial->open(serial, baud, error)) return error = "--serial " + error, false;
    link = l.serial.get();
    ro.fd = l.serial->fd();
    ro.serial = true;
    name_ = "serial " + serial;
  } else if (!connect.empty()) {
    int fd = -1;
    if (!parse_host_port(connect, "127.0.0.1", l.host, l.port, error) || !tcp_connect(l.host, l.port, 5000, &fd, error))
      return error = "--connect " + error, false;
    l.tcp = std::make_unique<TcpTransport>(fd, connect);
    link = l.tcp.get();
    ro.fd = fd;
    // A server that goes away is redialled for ten seconds.
    ro.reconnect = [](void* context, int* new_fd) -> Transport* {
      auto* r = static_cast<Links*>(context);
      std::fprintf(stderr, "stipple: server gone — reconnecting to %s:%u\n", r->host.c_str(), r->port);
      if (r->announce) r->announce(r->announce_context, "server gone \u2014 reconnecting");
      for (int attempt = 0; attempt < 50; ++attempt) {
        std::string ignored;
        if (tcp_connect(r->host, r->port, 1000, new_fd, ignored)) {
          std::fprintf(stderr, "stipple: reconnected to %s:%u\n", r->host.c_str(), r->port);
          r->tcp = std::make_unique<TcpTransport>(*new_fd, r->host);
          return r->tcp.get();
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      }
      return nullptr;
    };
    ro.reconnect_context = &l;
    name_ = "tcp " + connect;
  } else {
    ServerOptions so;
    so.cull = o.rule.cull;
    so.cones = cone_rule(o.rule);
    if (starts_as_spg(model)) {
      // Mapped with its cut table, as stipple serve and stipple-handheld read one.
      auto mapped = std::make_shared<ServedModel>();
      if (!mapped->open(model, so.cones, error)) return false;
      if (mapped->table_refused()) std::fprintf(stderr, "stipple: %s\n", mapped->table_note().c_str());
      if (!l.local.init(std::move(mapped), so, error)) return false;
    } else {
      std::vector<uint8_t> file;
      if (!read_model(model, file, error)) return false;  // a scan is encoded in memory
      if (!l.local.init(std::move(file), model, so, error)) return false;
    }
    l.local.add_client(std::make_unique<TransportRef>(l.pipe.server()), -1, "loopback");
    link = &l.pipe.client();
    ro.pump = [](void* s) {
      static_cast<Server*>(s)->step(0);
      return true;
    };
    ro.pump_context = &l.local;
    const size_t slash = model.find_last_of('/');
    name_ = slash == std::string::npos ? model : model.substr(slash + 1);
  }
  ro.token = o.token;
  ro.coded = o.coded;
  if (!model_.connect(*link, o.config, ro, error)) return error = (model.empty() ? name_ : model) + ": " + error, false;
  return true;
}

ViewerControls::ViewerControls(const RenderOptions& o, const SpgHeader& header, const int32_t extent_mu[3])
    : spec_(resolve_view(o.view, header, extent_mu)),
      first_(spec_),
      screen_width_(std::max<int>(o.config.raster.width, 1)),
      quality_q8_(o.config.quality_q8) {
  for (int k = 0; k < 3; ++k) extent_[k] = extent_mu[k];
  for (int k = 0; k < 4; ++k) window_[k] = o.rule.window[k];
  color_ = o.config.grey ? kGrey : o.config.elevation != SpgAxis::kNone ? kElevation : kModel;
  lighting_ = o.config.shading != ShadingMode::kNone;
}

bool ViewerControls::apply(const InputEvent& e) {
  switch (e.kind) {
    case InputKind::kQuit: quit_ = true; return false;
    case InputKind::kButtonDown:
    case InputKind::kButtonUp: {
      const bool down = e.kind == InputKind::kButtonDown;
      held_[static_cast<int>(e.button)] = down;
      if (!down) return false;
      switch (e.button) {
        case Button::kColor: color_ = color_ == kModel ? kElevation : color_ == kElevation ? kGrey : kModel; return true;
        case Button::kLighting: lighting_ = !lighting_; return true;
        case Button::kQuality: {  // 1 -> 1/2 -> 1/4 -> 2 -> 1
          quality_q8_ = static_cast<uint16_t>(quality_q8_ >= 512 ? 256 : quality_q8_ > 64 ? quality_q8_ / 2 : 512);
          return true;
        }
        case Button::kReset: {  // the first view, refined everywhere
          spec_ = first_;
          window_[0] = window_[1] = window_[2] = window_[3] = 0;
          return true;
        }
        case Button::kScreenshot: screenshot_ = true; return false;
        case Button::kHelp: help_ = !help_; return false;
        default: return tick(1.0 / 30);  // a press turns at once, a frame's worth
      }
    }
    case InputKind::kOrbitDown:
      orbit_at_[0] = e.x;
      orbit_at_[1] = e.y;
      return false;
    case InputKind::kOrbitMove:
    case InputKind::kOrbitUp: {
      // Grabbing the model: a drag to the right turns its front to the
      // right (the camera goes left), a drag down shows its top.
      const double per_px = kDragDegrees / screen_width_;
      const int dx = e.x - orbit_at_[0], dy = e.y - orbit_at_[1];
      orbit_at_[0] = e.x;
      orbit_at_[1] = e.y;
      if (dx == 0 && dy == 0) return false;
      spec_.yaw -= dx * per_px;
      spec_.pitch = std::clamp(spec_.pitch + dy * per_px, -85.0, 85.0);
      return true;
    }
    case InputKind::kWheel: {
      spec_.distance = std::clamp(spec_.distance * std::pow(kWheelStep, e.y), kMinDistance, kMaxDistance);
      return true;
    }
    case InputKind::kStylusDown:
      drag_ = true;
      drag_start_[0] = drag_now_[0] = e.x;
      drag_start_[1] = drag_now_[1] = e.y;
      return false;
    case InputKind::kStylusMove:
      drag_now_[0] = e.x;
      drag_now_[1] = e.y;
      return false;
    case InputKind::kStylusUp: {
      drag_ = false;
      const int32_t x0 = std::min(drag_start_[0], e.x), x1 = std::max(drag_start_[0], e.x) + 1;
      const int32_t y0 = std::min(drag_start_[1], e.y), y1 = std::max(drag_start_[1], e.y) + 1;
      if (x1 - x0 < 4 || y1 - y0 < 4) {  // a tap: refine everywhere again
        const bool had = window_[0] < window_[2];
        window_[0] = window_[1] = window_[2] = window_[3] = 0;
        return had;
      }
      window_[0] = x0;
      window_[1] = y0;
      window_[2] = x1;
      window_[3] = y1;
      return true;
    }
    case InputKind::kNone: return false;
  }
  return false;
}

bool ViewerControls::tick(double seconds) {
  const auto held = [&](Button b) { return held_[static_cast<int>(b)]; };
  seconds = std::clamp(seconds, 0.0, 0.25);  // a stalled frame does not jump the view
  bool changed = false;
  if (held(Button::kLeft) != held(Button::kRight)) {
    spec_.yaw += (held(Button::kLeft) ? -1 : 1) * kOrbitDegreesPerSecond * seconds;
    changed = true;
  }
  if (held(Button::kUp) != held(Button::kDown)) {
    const bool up = held(Button::kUp);
    if (held(Button::kSelect)) {
      const double step = kDollyExtentsPerSecond * seconds * std::min(1.0, spec_.distance);
      spec_.distance = std::clamp(spec_.distance + (up ? -step : step), kMinDistance, kMaxDistance);
    } else {
      spec_.pitch = std::clamp(spec_.pitch + (up ? 1 : -1) * kTiltDegreesPerSecond * seconds, -85.0, 85.0);
    }
    changed = true;
  }
  return changed;
}

bool ViewerControls::take_screenshot() {
  const bool s = screenshot_;
  screenshot_ = false;
  return s;
}

bool ViewerControls::camera(uint16_t width, uint16_t height, Camera* out) const {
  return orbit_camera(orbit_view(extent_, spec_), width, height, out);
}

bool ViewerControls::dragging(int32_t rect[4]) const {
  if (!drag_) return false;
  rect[0] = std::min(drag_start_[0], drag_now_[0]);
  rect[1] = std::min(drag_start_[1], drag_now_[1]);
  rect[2] = std::max(drag_start_[0], drag_now_[0]) + 1;
  rect[3] = std::max(drag_start_[1], drag_now_[1]) + 1;
  return true;
}

namespace {

bool button_named(const std::string& s, Button* out) {
  static const struct {
    const char* name;
    Button button;
  } names[] = {{"up", Button::kUp},           {"down", Button::kDown},         {"left", Button::kLeft},
               {"right", Button::kRight},     {"select", Button::kSelect},     {"colour", Button::kColor},
               {"color", Button::kColor},     {"lighting", Button::kLighting}, {"quality", Button::kQuality},
               {"reset", Button::kReset},     {"screenshot", Button::kScreenshot}, {"help", Button::kHelp}};
  for (const auto& n : names)
    if (s == n.name) return *out = n.button, true;
  return false;
}

}  // namespace

bool read_script(const std::string& path, std::vector<ScriptStep>& out, std::string& error) {
  std::vector<uint8_t> bytes;
  if (!read_file(path, bytes, error)) return false;
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::string frame_text, action;
    if (!(words >> frame_text)) continue;
    const auto bad = [&](const std::string& why) { return error = path + ":" + std::to_string(number) + ": " + why, false; };
    char* end = nullptr;
    const unsigned long frame = std::strtoul(frame_text.c_str(), &end, 10);
    if (*end != '\0' || frame > 1000000) return bad("expected a frame number, got '" + frame_text + "'");
    if (!(words >> action)) return bad("expected an action after the frame number");
    ScriptStep s;
    s.frame = static_cast<uint32_t>(frame);
    std::string arg;
    if (action == "down" || action == "up" || action == "press" || action == "click") {
      if (!(words >> arg) || !button_named(arg, &s.event.button))
        return bad("expected a button (up down left right select colour lighting quality reset screenshot help), got '" +
                   arg + "'");
      s.event.kind = action == "up" ? InputKind::kButtonUp : InputKind::kButtonDown;
      s.click = action == "click";
      if (action == "click") action = "press";
      out.push_back(s);
      if (action == "press") {
        s.frame += 5;
        s.event.kind = InputKind::kButtonUp;
        out.push_back(s);
      }
    } else if (action == "stylus-down" || action == "stylus-move" || action == "stylus-up" || action == "orbit-down" ||
               action == "orbit-move" || action == "orbit-up") {
      if (!(words >> s.event.x >> s.event.y) || s.event.x < 0 || s.event.y < 0 || s.event.x > 4095 || s.event.y > 4095)
        return bad("expected X Y in screen pixels after " + action);
      const bool stylus = action.compare(0, 6, "stylus") == 0;
      const std::string what = action.substr(action.find('-') + 1);
      s.event.kind = what == "down"   ? (stylus ? InputKind::kStylusDown : InputKind::kOrbitDown)
                     : what == "move" ? (stylus ? InputKind::kStylusMove : InputKind::kOrbitMove)
                                      : (stylus ? InputKind::kStylusUp : InputKind::kOrbitUp);
      out.push_back(s);
    } else if (action == "wheel") {
      if (!(words >> s.event.y) || s.event.y == 0 || s.event.y < -100 || s.event.y > 100)
        return bad("expected a number of notches (-100..100, not 0) after wheel");
      s.event.kind = InputKind::kWheel;
      out.push_back(s);
    } else if (action == "screenshot") {
      if (!(words >> s.path)) return bad("expected a path after screenshot");
      s.kind = ScriptStep::kScreenshot;
      out.push_back(s);
    } else if (action == "quit") {
      s.kind = ScriptStep::kQuit;
      out.push_back(s);
    } else {
      return bad("unknown action '" + action +
                 "' (down up press click stylus-down stylus-move stylus-up orbit-down orbit-move orbit-up wheel screenshot quit)");
    }
    if (words >> arg) return bad("unexpected '" + arg + "'");
  }
  std::stable_sort(out.begin(), out.end(), [](const ScriptStep& a, const ScriptStep& b) { return a.frame < b.frame; });
  return true;
}

const std::vector<std::string>& help_lines() {
  static const std::vector<std::string> lines = {
      "LEFT DRAG      orbit",
      "RIGHT DRAG     refinement window",
      "  (or shift + left), a click clears",
      "WHEEL          dolly",
      "ARROWS         orbit and tilt",
      "SPACE + UP/DN  dolly",
      "C              colour, elevation, grey",
      "L  Q           lighting, quality",
      "R              reset the view",
      "S or F12       screenshot (PNG)",
      "H or F1        this help",
      "ESC            quit",
  };
  return lines;
}

std::string screenshot_path(const std::string& prefix) {
  for (int n = 1; n < 100000; ++n) {
    char name[64];
    std::snprintf(name, sizeof name, "-%04d.png", n);
    const std::string path = prefix + name;
    if (!std::ifstream(path).good()) return path;
  }
  return prefix + ".png";
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

bool RateMeter::frame(uint64_t bytes_received) {
  if (!started_) {  // the window starts at the first frame, with what had arrived by then
    started_ = true;
    bytes_ = bytes_received;
    start_ = std::chrono::steady_clock::now();
  }
  ++frames_;
  const double elapsed = seconds_since(start_);
  if (elapsed < 0.5) return false;
  fps_ = frames_ / elapsed;
  bytes_per_s_ = static_cast<double>(bytes_received - bytes_) / elapsed;
  bytes_ = bytes_received;
  start_ = std::chrono::steady_clock::now();
  frames_ = 0;
  return true;
}

void pace_frame(std::chrono::steady_clock::time_point start, double fps) {
  const double spare = 1.0 / fps - seconds_since(start);
  if (spare > 0) std::this_thread::sleep_for(std::chrono::duration<double>(spare));
}

bool service_for(RemoteModel& model, double budget, std::string& error) {
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < 64 && (k == 0 || seconds_since(start) < budget); ++k) {
    const uint64_t before = model.bytes_received();
    if (!model.service(0, error)) return false;
    if (model.bytes_received() == before && k > 0) break;
  }
  return true;
}

std::string progress_text(const RemoteModel::Progress& p) {
  if (!p.known) return "...";
  char t[64];
  if (p.share >= 1) return "";
  if (p.coarse) std::snprintf(t, sizeof t, "coarse %d%%", static_cast<int>(100 * p.share));
  else std::snprintf(t, sizeof t, "%d%%  %.0f s left", static_cast<int>(100 * p.share), std::ceil(p.seconds_left));
  return t;
}

void status_lines(double fps, const FrameStats& stats, uint64_t bytes, double bytes_per_s, const ViewerControls& c,
                  const RemoteModel::Progress& progress, std::string& line1, std::string& line2) {
  char a[128], b[160];
  std::snprintf(a, sizeof a, "%4.1f fps  %u nodes  %u pts", fps, stats.nodes, stats.points);
  // While a view comes: how much of it, and how long the rest will take;
  // then the view's settings.
  const std::string received = progress_text(progress);
  char settings[64];
  std::snprintf(settings, sizeof settings, "%s%s q%.2g", c.grey() ? "grey" : c.elevation() ? "elevation" : "colour",
                c.lighting() ? " lit" : "",
                c.quality_q8() / 256.0);
  std::snprintf(b, sizeof b, "%llu KB  %.1f KB/s  %s", static_cast<unsigned long long>(bytes / 1024), bytes_per_s / 1024,
                received.empty() ? settings : received.c_str());
  line1 = a;
  line2 = b;
}

}  // namespace stipple
