// Plot rendering and PNG round trip.
#include <gtest/gtest.h>

#include "core/spg_format.h"
#include "platform/file_io.h"
#include "platform/png_io.h"
#include "tools/reference/plot.h"

namespace stipple {
namespace {

PlotSpec spec() {
  PlotSpec s;
  s.title = "PSNR by level";
  s.x_label = "bits per point";
  s.y_label = "PSNR (dB)";
  s.series = {{"one-sided", {1.5, 2.5, 11.3}, {30, 56, 62}, 0x1f77b4, {"8", "12", "19"}},
              {"symmetric", {1.5, 2.5, 11.3}, {30, 56, 61}, 0xd62728, {}}};
  return s;
}

TEST(Plot, MarkersLandWhereTheDataSays) {
  const PlotSpec s = spec();
  const Image img = render_plot(s);
  ASSERT_EQ(img.width, 900);
  ASSERT_EQ(img.height, 560);
  EXPECT_EQ(pixel_at(img, 0, 0), 0xFFFFFFu);  // background
  int px, py;
  plot_position(s, 11.3, 61, px, py);  // drawn last: its colour is on top
  EXPECT_EQ(pixel_at(img, px, py), 0xd62728u);
  plot_position(s, 11.3, 62, px, py);
  EXPECT_EQ(pixel_at(img, px, py), 0x1f77b4u);
  // The title is drawn: dark pixels in the top band.
  int ink = 0;
  for (int y = 10; y < 35; ++y)
    for (int x = 0; x < img.width; ++x) ink += pixel_at(img, x, y) == 0;
  EXPECT_GT(ink, 200);
  EXPECT_EQ(render_plot(s).rgb, img.rgb);  // deterministic
}

TEST(Plot, PngRoundTripIsExact) {
  const Image img = render_plot(spec());
  const std::string path = testing::TempDir() + "plot.png";
  std::string error;
  ASSERT_TRUE(write_png(path, img, error)) << error;
  Image back;
  ASSERT_TRUE(read_png(path, back, error)) << error;
  EXPECT_EQ(back.width, img.width);
  EXPECT_EQ(back.height, img.height);
  EXPECT_EQ(back.rgb, img.rgb);
  back.width = 10;
  back.height = 10;
  EXPECT_FALSE(write_png(path, back, error));  // size mismatch
  EXPECT_NE(error.find("does not match"), std::string::npos);
  EXPECT_FALSE(read_png(testing::TempDir() + "missing.png", back, error));
}

// A PNG whose IHDR claims `width` x `height`: a 1 x 1 image written by
// libpng with its header's size rewritten and the chunk's CRC fixed.
std::vector<uint8_t> png_claiming(uint32_t width, uint32_t height) {
  const std::string path = testing::TempDir() + "tiny.png";
  std::string error;
  EXPECT_TRUE(write_png(path, Image{1, 1, {1, 2, 3}}, error)) << error;
  std::vector<uint8_t> f;
  EXPECT_TRUE(read_file(path, f, error)) << error;
  // Signature (8), IHDR length (4) and type (4), then width and height big-endian.
  const auto put = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) f[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
  };
  put(16, width);
  put(20, height);
  put(29, crc32(f.data() + 12, 17));  // over the type and the 13 data bytes
  return f;
}

TEST(Png, AHeaderClaimingMorePixelsThanTheFileHoldsIsRefusedBeforeAllocating) {
  // 1,000,000 x 1,431 pixels (4.3 GB as RGB) in a file of under 100 bytes.
  const std::vector<uint8_t> f = png_claiming(1000000, 1431);
  ASSERT_LT(f.size(), 100u);
  const std::string path = testing::TempDir() + "hostile.png";
  std::string error;
  ASSERT_TRUE(write_file_atomic(path, f, error)) << error;
  Image img;
  EXPECT_FALSE(read_png(path, img, error));
  EXPECT_EQ(error, path + ": the header claims 1000000 x 1431 pixels, more than its " + std::to_string(f.size()) +
                       " bytes can hold (a damaged or hostile file)");
  EXPECT_TRUE(img.rgb.empty());
  // Past the sane maximum, in a file long enough for it (64 KB after IEND).
  std::vector<uint8_t> padded = png_claiming(16384, 16385);
  padded.resize(padded.size() + 65536, 0);
  ASSERT_TRUE(write_file_atomic(path, padded, error)) << error;
  EXPECT_FALSE(read_png(path, img, error));
  EXPECT_EQ(error, path + ": the header claims 16384 x 16385 pixels, more than the 134217728 this reader takes");
  // Within both bounds, libpng's own error for the missing pixels, still no crash.
  ASSERT_TRUE(write_file_atomic(path, png_claiming(40, 30), error)) << error;
  EXPECT_FALSE(read_png(path, img, error));
  EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
}

}  // namespace
}  // namespace stipple
