// platform/: the one image type from native frames, and the null display
// every screen-less test uses — frames kept and written (PPM), a scripted
// input queue, a simulated clock, errors that name the file.
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "platform/file_io.h"
#include "platform/image.h"
#include "platform/null/null_display.h"

namespace stipple {
namespace {

// A 5 x 3 RGB565 frame with 4 bytes of padding after each row.
std::vector<uint8_t> frame565(size_t stride) {
  std::vector<uint8_t> f(stride * 3, 0xEE);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 5; ++x) {
      const uint16_t v = rgb565(static_cast<uint32_t>((x * 50) << 16 | (y * 100) << 8 | (x + y) * 30));
      f[y * stride + 2 * x] = static_cast<uint8_t>(v);
      f[y * stride + 2 * x + 1] = static_cast<uint8_t>(v >> 8);
    }
  return f;
}

TEST(Image, FromNativeFramesWithStride) {
  const std::vector<uint8_t> f = frame565(14);
  Image img;
  image_from_frame(f.data(), 14, 5, 3, PixelFormat::kRgb565, img);
  ASSERT_EQ(img.rgb.size(), 45u);
  EXPECT_EQ(pixel_at(img, 2, 1), rgb888_from_565(rgb565(100u << 16 | 100u << 8 | 90u)));
  // RGB888 frames are copied as they are.
  std::vector<uint8_t> f888(20 * 3, 0);
  for (size_t i = 0; i < f888.size(); ++i) f888[i] = static_cast<uint8_t>(i);
  image_from_frame(f888.data(), 20, 5, 3, PixelFormat::kRgb888, img);
  EXPECT_EQ(pixel_at(img, 1, 2), (43u << 16) | (44u << 8) | 45u);
  EXPECT_EQ(image_psnr(img, img), INFINITY);
}

TEST(NullDisplay, KeepsWritesAndTimesFrames) {
  const std::string dir = testing::TempDir();
  NullDisplay d(4, 3, PixelFormat::kRgb565, dir + "null_%03d.ppm", 20000);
  EXPECT_EQ(d.now_us(), 0u);
  const std::vector<uint8_t> f = frame565(14);
  std::string error;
  ASSERT_TRUE(d.present(f.data(), 14, 5, 3, PixelFormat::kRgb565, error)) << error;  // cropped to 4 x 3
  ASSERT_TRUE(d.present(f.data(), 14, 5, 3, PixelFormat::kRgb565, error)) << error;
  EXPECT_EQ(d.frames(), 2u);
  EXPECT_EQ(d.now_us(), 40000u);
  Image full;
  image_from_frame(f.data(), 14, 5, 3, PixelFormat::kRgb565, full);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(pixel_at(d.last_frame(), x, y), pixel_at(full, x, y));
  std::vector<uint8_t> written;
  ASSERT_TRUE(read_file(dir + "null_001.ppm", written, error)) << error;
  const std::string header = "P6\n4 3\n255\n";
  ASSERT_EQ(written.size(), header.size() + 36);
  EXPECT_EQ(std::string(written.begin(), written.begin() + static_cast<long>(header.size())), header);
  EXPECT_TRUE(std::equal(d.last_frame().rgb.begin(), d.last_frame().rgb.end(), written.begin() + static_cast<long>(header.size())));
  // A file that cannot be written: false, and the message names it.
  NullDisplay bad(4, 3, PixelFormat::kRgb565, dir + "no_such_dir/frame.ppm");
  EXPECT_FALSE(bad.present(f.data(), 14, 5, 3, PixelFormat::kRgb565, error));
  EXPECT_NE(error.find("no_such_dir/frame.ppm"), std::string::npos) << error;
  // A disk that fills up mid-frame (a file-size limit of 20 bytes here):
  // the reason is said. It said "cannot write the frame" and nothing more.
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead of a signal
  rlimit tiny = old;
  tiny.rlim_cur = 20;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &tiny), 0);
  NullDisplay limited(4, 3, PixelFormat::kRgb565, dir + "limited.ppm");
  const bool presented = limited.present(f.data(), 14, 5, 3, PixelFormat::kRgb565, error);
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, previous);
  EXPECT_FALSE(presented);
  EXPECT_EQ(error, dir + "limited.ppm: cannot write the frame: File too large");
}

TEST(NullDisplay, ReplaysQueuedInputInOrder) {
  NullDisplay d(4, 3, PixelFormat::kRgb888);
  InputEvent e;
  EXPECT_FALSE(d.poll(&e));
  for (int i = 0; i < NullDisplay::kMaxQueued; ++i)
    ASSERT_TRUE(d.push_input(InputEvent{InputKind::kStylusMove, Button::kNone, i, 2 * i}));
  EXPECT_FALSE(d.push_input(InputEvent{InputKind::kQuit, Button::kNone, 0, 0}));  // full
  for (int i = 0; i < NullDisplay::kMaxQueued; ++i) {
    ASSERT_TRUE(d.poll(&e));
    EXPECT_EQ(e.kind, InputKind::kStylusMove);
    EXPECT_EQ(e.x, i);
    EXPECT_EQ(e.y, 2 * i);
  }
  EXPECT_FALSE(d.poll(&e));
}

// A writer killed mid-write (SIGKILL) leaves PATH.partial.PID: the next
// write of PATH removes it, but not a live writer's, and the output is
// whole. The dead writer is a real one: a child killed inside its write.
TEST(FileIo, AKilledWritersPartialFileIsRemovedByTheNextWrite) {
  const std::string folder = testing::TempDir() + "file_io_partial/";
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  const std::string out = folder + "frame.png";
  // A child that starts writing 512 MB and is killed while at it.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::string e;
    const std::vector<uint8_t> big(512u << 20, 7);
    (void)write_file_atomic(out, big, e);
    _exit(0);
  }
  const std::string dead = out + ".partial." + std::to_string(child);
  for (int i = 0; i < 500 && !std::filesystem::exists(dead); ++i) usleep(10000);
  ASSERT_TRUE(std::filesystem::exists(dead)) << "the child never began its write";
  kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_TRUE(std::filesystem::exists(dead));  // what a SIGKILL leaves
  // A live writer's temporary file (this process's parent is alive) stays.
  const std::string live = out + ".partial." + std::to_string(getppid());
  std::string error;
  ASSERT_TRUE(write_file_atomic(live, {1}, error)) << error;  // a file of that name, written by us
  ASSERT_TRUE(write_file_atomic(out, {1, 2, 3}, error)) << error;
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(live));
  std::vector<uint8_t> back;
  ASSERT_TRUE(read_file(out, back, error)) << error;
  EXPECT_EQ(back, (std::vector<uint8_t>{1, 2, 3}));
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace stipple
