// The desktop viewers' shared parts (tools/viewer): scripts parse into the
// events they name, in frame order, and a bad line is refused naming the
// file, the line and what is wrong; the controls turn, tilt, dolly, toggle
// and draw the refinement window as the help says.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>

#include "tests/portable/test_files.h"
#include "tools/viewer/viewer.h"

namespace stipple {
namespace {

std::string write_script(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(ViewerScript, ParsesEventsInFrameOrder) {
  const std::string path = write_script("ok.script",
                                        "# a comment\n"
                                        "10 press colour\n"
                                        "3 stylus-down 5 6   # trailing comment\n"
                                        "\n"
                                        "20 screenshot out.png\n"
                                        "30 quit\n");
  std::vector<ScriptStep> s;
  std::string error;
  ASSERT_TRUE(read_script(path, s, error)) << error;
  ASSERT_EQ(s.size(), 5u);  // press = down, then up five frames later
  EXPECT_EQ(s[0].frame, 3u);
  EXPECT_EQ(s[0].event.kind, InputKind::kStylusDown);
  EXPECT_EQ(s[0].event.x, 5);
  EXPECT_EQ(s[1].event.kind, InputKind::kButtonDown);
  EXPECT_EQ(s[1].event.button, Button::kColor);
  EXPECT_EQ(s[2].frame, 15u);
  EXPECT_EQ(s[2].event.kind, InputKind::kButtonUp);
  EXPECT_EQ(s[3].kind, ScriptStep::kScreenshot);
  EXPECT_EQ(s[3].path, "out.png");
  EXPECT_EQ(s[4].kind, ScriptStep::kQuit);
}

TEST(ViewerScript, RefusesBadLinesNamingThem) {
  const struct {
    const char* text;
    const char* message;
  } cases[] = {
      {"x press up\n", ":1: expected a frame number, got 'x'"},
      {"1\n", ":1: expected an action after the frame number"},
      {"\n2 press sideways\n",
       ":2: expected a button (up down left right select colour lighting quality reset screenshot help), got 'sideways'"},
      {"1 wheel 0\n", ":1: expected a number of notches (-100..100, not 0) after wheel"},
      {"1 orbit-move 5\n", ":1: expected X Y in screen pixels after orbit-move"},
      {"1 stylus-move 5\n", ":1: expected X Y in screen pixels after stylus-move"},
      {"1 stylus-up -1 4\n", ":1: expected X Y in screen pixels after stylus-up"},
      {"1 screenshot\n", ":1: expected a path after screenshot"},
      {"1 dance\n", ":1: unknown action 'dance'"},
      {"1 quit now\n", ":1: unexpected 'now'"},
      {"99999999999 quit\n", ":1: expected a frame number, got '99999999999'"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const std::string path = write_script("bad" + std::to_string(k++) + ".script", c.text);
    std::vector<ScriptStep> s;
    std::string error;
    EXPECT_FALSE(read_script(path, s, error)) << c.text;
    EXPECT_EQ(error.rfind(path, 0), 0u) << error;
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
  }
  std::vector<ScriptStep> s;
  std::string error;
  EXPECT_FALSE(read_script(::testing::TempDir() + "no_such.script", s, error));
  EXPECT_NE(error.find("no_such.script"), std::string::npos) << error;
}

TEST(ViewerControls, TurnTiltDollyToggleAndWindow) {
  RenderOptions o;
  SpgHeader header;
  const int32_t extent[3] = {1 << 24, 1 << 24, 1 << 24};
  ViewerControls c(o, header, extent);
  Camera start, turned;
  ASSERT_TRUE(c.camera(240, 320, &start));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kButtonDown, Button::kRight, 0, 0}));
  EXPECT_TRUE(c.tick(0.1));  // held: keeps turning
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kButtonUp, Button::kRight, 0, 0}));
  EXPECT_FALSE(c.tick(0.1));
  ASSERT_TRUE(c.camera(240, 320, &turned));
  EXPECT_NE(std::memcmp(start.eye, turned.eye, sizeof start.eye), 0);
  EXPECT_FALSE(c.grey());
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kButtonDown, Button::kColor, 0, 0}));  // colour -> elevation -> grey
  EXPECT_TRUE(c.elevation());
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kButtonDown, Button::kColor, 0, 0}));
  EXPECT_TRUE(c.grey());
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kButtonDown, Button::kQuality, 0, 0}));
  EXPECT_EQ(c.quality_q8(), 128);
  // A drag draws the window (ends inclusive); a tap clears it.
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kStylusDown, Button::kNone, 50, 60}));
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kStylusMove, Button::kNone, 80, 90}));
  int32_t r[4];
  ASSERT_TRUE(c.dragging(r));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kStylusUp, Button::kNone, 80, 90}));
  EXPECT_EQ(c.window()[0], 50);
  EXPECT_EQ(c.window()[3], 91);
  EXPECT_FALSE(c.dragging(r));
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kStylusDown, Button::kNone, 10, 10}));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kStylusUp, Button::kNone, 11, 10}));
  EXPECT_EQ(c.window()[0], c.window()[2]);
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kQuit, Button::kNone, 0, 0}));
  EXPECT_TRUE(c.quit());
}

TEST(ViewerScript, ParsesTheDesktopsGestures) {
  const std::string path = write_script("gestures.script",
                                        "1 orbit-down 10 20\n"
                                        "2 orbit-move 30 20\n"
                                        "3 orbit-up 30 20\n"
                                        "4 wheel -2\n"
                                        "5 click select\n"
                                        "6 press screenshot\n");
  std::vector<ScriptStep> s;
  std::string error;
  ASSERT_TRUE(read_script(path, s, error)) << error;
  ASSERT_EQ(s.size(), 8u);
  EXPECT_EQ(s[0].event.kind, InputKind::kOrbitDown);
  EXPECT_EQ(s[1].event.kind, InputKind::kOrbitMove);
  EXPECT_EQ(s[1].event.x, 30);
  EXPECT_EQ(s[2].event.kind, InputKind::kOrbitUp);
  EXPECT_EQ(s[3].event.kind, InputKind::kWheel);
  EXPECT_EQ(s[3].event.y, -2);
  EXPECT_EQ(s[4].event.button, Button::kSelect);
  EXPECT_TRUE(s[4].click);
  EXPECT_EQ(s[5].event.button, Button::kScreenshot);
  EXPECT_FALSE(s[5].click);
}

// Speeds are per second, not per frame: a second of a held key turns the
// view by the same angle whatever the frame rate; a drag across the screen
// turns it kDragDegrees; the wheel dollies by kWheelStep a notch; reset
// returns to the first view and clears the window; the screenshot key is
// taken once; the help key toggles the help.
TEST(ViewerControls, DesktopHabits) {
  RenderOptions o;
  o.config.raster.width = 240;
  SpgHeader header;
  const int32_t extent[3] = {1 << 24, 1 << 24, 1 << 24};
  ViewerControls slow(o, header, extent), fast(o, header, extent);
  const double yaw = slow.view().yaw, distance = slow.view().distance, pitch = slow.view().pitch;
  for (ViewerControls* c : {&slow, &fast}) c->apply(InputEvent{InputKind::kButtonDown, Button::kRight, 0, 0});
  const double start = slow.view().yaw;  // the press turned a frame's worth at once
  for (int f = 0; f < 10; ++f) slow.tick(0.1);   // 10 fps for a second
  for (int f = 0; f < 60; ++f) fast.tick(1.0 / 60);  // 60 fps for a second
  EXPECT_NEAR(slow.view().yaw - start, kOrbitDegreesPerSecond, 1e-9);
  EXPECT_NEAR(fast.view().yaw - start, kOrbitDegreesPerSecond, 1e-9);

  ViewerControls c(o, header, extent);
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kOrbitDown, Button::kNone, 0, 100}));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kOrbitMove, Button::kNone, 120, 100}));  // half the width to the right
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kOrbitUp, Button::kNone, 120, 124}));     // then 24 px down
  EXPECT_NEAR(c.view().yaw, yaw - kDragDegrees / 2, 1e-9);
  EXPECT_NEAR(c.view().pitch, pitch + 24 * kDragDegrees / 240, 1e-9);
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kWheel, Button::kNone, 0, 2}));
  EXPECT_NEAR(c.view().distance, distance * kWheelStep * kWheelStep, 1e-9);
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kStylusDown, Button::kNone, 50, 60}));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kStylusUp, Button::kNone, 80, 90}));
  EXPECT_TRUE(c.apply(InputEvent{InputKind::kButtonDown, Button::kReset, 0, 0}));
  EXPECT_EQ(c.view().yaw, yaw);
  EXPECT_EQ(c.view().pitch, pitch);
  EXPECT_EQ(c.view().distance, distance);
  EXPECT_EQ(c.window()[0], c.window()[2]);
  EXPECT_FALSE(c.take_screenshot());
  EXPECT_FALSE(c.apply(InputEvent{InputKind::kButtonDown, Button::kScreenshot, 0, 0}));
  EXPECT_TRUE(c.take_screenshot());
  EXPECT_FALSE(c.take_screenshot());
  EXPECT_FALSE(c.help());
  c.apply(InputEvent{InputKind::kButtonDown, Button::kHelp, 0, 0});
  EXPECT_TRUE(c.help());
  c.apply(InputEvent{InputKind::kButtonDown, Button::kHelp, 0, 0});
  EXPECT_FALSE(c.help());
  for (const std::string& line : help_lines()) EXPECT_LE(line.size(), 38u) << line;
}

}  // namespace
}  // namespace stipple
