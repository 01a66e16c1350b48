// Plot rendering and PNG round trip.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace stipple
