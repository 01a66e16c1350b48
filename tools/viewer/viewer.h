// stipple tools — what the two desktop viewers share (stipple-emulator,
// stipple-gl): where the node stream comes from, the device's controls, and
// scripted input.
//
// Source: a local .spg served in this process over loopback (the embedded
// default), `--connect HOST:PORT` (a `stipple serve`), or `--serial DEV`;
// each is a RemoteModel (tools/embedded/remote.h) over the same protocol,
// so both viewers see exactly the node stream the handheld gets.
//
// Controls (platform/display.h's input, as platform/sdl2/sdl_input.h maps a
// desktop's): the D-pad's left/right orbit about the up axis at
// kOrbitDegreesPerSecond, up/down tilt at kTiltDegreesPerSecond; with
// select held, up/down dolly at kDollyExtentsPerSecond (model lengths, the
// model's largest side); a left drag orbits (kDragDegrees a screen width),
// the wheel dollies (each notch a tenth of the way to the centre or back),
// reset returns to the first view; colour, lighting and quality toggle; the
// stylus (a right drag) draws the refinement window (TOG05 §8.1: only nodes
// there are refined), a tap clears it; the screenshot and help keys are the
// program's to act on (take_screenshot, help).
//
// Script (`--script FILE`, for tests and demos): one event per line,
// `FRAME ACTION [ARGS]`, FRAME counting presented frames from 0:
//   FRAME down|up BUTTON        up down left right select colour lighting
//                               quality reset screenshot help
//   FRAME press BUTTON          down at FRAME, up 5 frames later
//   FRAME click BUTTON          the same with the mouse on the emulator's key
//   FRAME stylus-down|stylus-move|stylus-up X Y   (screen pixels; the right button)
//   FRAME orbit-down|orbit-move|orbit-up X Y      (the left button)
//   FRAME wheel N               N notches (negative: towards the user)
//   FRAME screenshot PATH       the window as shown (PNG)
//   FRAME quit
// Blank lines and # comments are ignored.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "platform/display.h"
#include "tools/embedded/remote.h"
#include "tools/embedded/render_options.h"
#include "tools/server/server.h"

namespace stipple {

// The options both viewers take: the source, render's view and client
// options, --headless, -o, --frames, --script.
struct ViewerOptions {
  RenderOptions render;
  std::string model, connect, serial, output, script;
  uint32_t baud = 115200;
  bool headless = false;
  uint32_t frames = 0;  // --frames (0: not given)
};
// Consumes them from `args` (a program takes its own options first) and
// checks what is left: one source, no stray option; false with a message.
bool parse_viewer_options(cli::Args& args, ViewerOptions& o, std::string& error);

// The stream's source and the link under it; owns what it opened.
class ViewerSource {
 public:
  ViewerSource();
  ~ViewerSource();
  // `model` (a .spg path) or `connect` (HOST:PORT) or `serial` (a device);
  // exactly one non-empty. Says hello and waits for the startup.
  bool open(const std::string& model, const std::string& connect, const std::string& serial, uint32_t baud,
            const RenderOptions& options, std::string& error);
  RemoteModel& model() { return model_; }
  // What it is, for the status line and logs: "bunny.spg", "tcp 127.0.0.1:7878", "serial /dev/ttyACM0".
  const std::string& name() const { return name_; }
  // Called with "server gone — reconnecting" when the server went away and
  // is being redialled (which blocks for up to ten seconds): a window shows
  // it on its status line. Null: the message goes to stderr only.
  void on_reconnecting(void (*announce)(void* context, const char* text), void* context);

 private:
  struct Links;
  std::unique_ptr<Links> links_;
  RemoteModel model_;
  std::string name_;
};

inline constexpr double kOrbitDegreesPerSecond = 90, kTiltDegreesPerSecond = 60, kDollyExtentsPerSecond = 1;
inline constexpr double kDragDegrees = 180;  // a drag across the screen's width
inline constexpr double kWheelStep = 0.9;    // the distance times this a notch towards the screen
inline constexpr double kMinDistance = 0.01, kMaxDistance = 50;  // model extents from the orbit's centre

// The view a user steers, and the toggles.
class ViewerControls {
 public:
  ViewerControls(const RenderOptions& options, const SpgHeader& header, const int32_t extent_mu[3]);
  // Applies one input event; true when the camera or the cut changed.
  bool apply(const InputEvent& e);
  // Per presented frame, `seconds` after the last: a held D-pad keeps
  // turning (dolly slows within a model length of the centre, so that it
  // never jumps past it). True when the camera changed.
  bool tick(double seconds);
  // True once after the screenshot key was pressed.
  bool take_screenshot();
  // Whether the help is shown (the help key toggles it).
  bool help() const { return help_; }
  const ViewSpec& view() const { return spec_; }
  bool camera(uint16_t width, uint16_t height, Camera* out) const;
  const int32_t* window() const { return window_; }  // px, x0 >= x1: none
  bool quit() const { return quit_; }
  // The colour key cycles the model's colours, elevation, grey.
  bool grey() const { return color_ == kGrey; }
  bool elevation() const { return color_ == kElevation; }
  bool lighting() const { return lighting_; }
  uint16_t quality_q8() const { return quality_q8_; }
  // The rectangle being drawn with the stylus (for an overlay), if any.
  bool dragging(int32_t rect[4]) const;

 private:
  ViewSpec spec_, first_;
  int32_t extent_[3];
  int screen_width_;
  bool held_[kButtonCount] = {};
  enum ColorMode : uint8_t { kModel, kElevation, kGrey } color_ = kModel;
  bool quit_ = false, lighting_ = true, drag_ = false, screenshot_ = false, help_ = false;
  int32_t orbit_at_[2] = {0, 0};  // the orbit drag's last position
  uint16_t quality_q8_;
  int32_t window_[4] = {0, 0, 0, 0};
  int32_t drag_start_[2] = {0, 0}, drag_now_[2] = {0, 0};
};

struct ScriptStep {
  uint32_t frame = 0;
  enum Kind : uint8_t { kInput, kScreenshot, kQuit } kind = kInput;
  InputEvent event;
  std::string path;
  bool click = false;  // a press of the emulator's on-screen key, with the mouse
};

// Parses a script file; false with "FILE:LINE: why".
bool read_script(const std::string& path, std::vector<ScriptStep>& out, std::string& error);

// The keys, as the help shows them (lines of at most 38 characters).
const std::vector<std::string>& help_lines();

// A free name for a screenshot in the current directory:
// PREFIX-0001.png, -0002, ... (the first that does not exist).
std::string screenshot_path(const std::string& prefix);

// Seconds since `t` (steady clock).
double seconds_since(std::chrono::steady_clock::time_point t);

// Frames a second and bytes received a second, over half-second windows:
// the status line's rates.
class RateMeter {
 public:
  // Counts a presented frame; true when the rates were just renewed.
  bool frame(uint64_t bytes_received);
  double fps() const { return fps_; }
  double bytes_per_s() const { return bytes_per_s_; }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  uint64_t bytes_ = 0;
  bool started_ = false;
  int frames_ = 0;
  double fps_ = 0, bytes_per_s_ = 0;
};

// Sleeps out what is left of a frame begun at `start` at `fps` frames a second.
void pace_frame(std::chrono::steady_clock::time_point start, double fps);

// Takes what the link brings for at most `budget` seconds of a frame (and
// at least one read); false on a link failure.
bool service_for(RemoteModel& model, double budget, std::string& error);

// What a view's progress reads as: "coarse 40%", "62%  12 s left", "..."
// before the server says, "" once converged.
std::string progress_text(const RemoteModel::Progress& progress);
// The status line's two lines (the second shows the progress while a view
// comes, then the view's settings).
void status_lines(double fps, const FrameStats& stats, uint64_t bytes, double bytes_per_s, const ViewerControls& c,
                  const RemoteModel::Progress& progress, std::string& line1, std::string& line2);

}  // namespace stipple
