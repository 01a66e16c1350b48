// The view a user gets for a model (tools/embedded/embedded.h, resolve_view):
// the bunny's and dragon's golden views stay; a camera-frame scan is seen
// upright from the camera; terrain from above about its up axis; a scan made
// from inside from its scanner; options override the file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/elevation_ramp.h"
#include "tests/portable/test_files.h"
#include "tools/embedded/embedded.h"

namespace stipple {
namespace {

SpgHeader box(float lo0, float lo1, float lo2, float hi0, float hi1, float hi2, SpgViewHint hint = {}) {
  SpgHeader h;
  const float v[6] = {lo0, lo1, lo2, hi0, hi1, hi2};
  for (int i = 0; i < 6; ++i) std::memcpy(&h.bbox_bits[i], &v[i], 4);
  h.view_hint = hint;
  return h;
}

void extent_mu(const SpgHeader& h, int32_t out[3]) {
  float v[6];
  for (int i = 0; i < 6; ++i) std::memcpy(&v[i], &h.bbox_bits[i], 4);
  double largest = 0;
  for (int a = 0; a < 3; ++a) largest = std::max(largest, double(v[3 + a]) - v[a]);
  for (int a = 0; a < 3; ++a) out[a] = static_cast<int32_t>((double(v[3 + a]) - v[a]) / largest * (1 << 24));
}

Camera camera_for(const SpgHeader& h, const ViewSpec& spec, ViewSpec* resolved = nullptr) {
  int32_t e[3];
  extent_mu(h, e);
  const ViewSpec v = resolve_view(spec, h, e);
  if (resolved) *resolved = v;
  Camera c;
  EXPECT_TRUE(orbit_camera(orbit_view(e, v), 240, 320, &c));
  return c;
}

// Row k of the camera's rotation (right, down, forward) as a unit vector.
double row(const Camera& c, int k, int axis) { return c.rotation[k][axis] / 16384.0; }

TEST(View, ObjectsKeepTheGoldenView) {
  // The bunny's box: no hint, not flat.
  const SpgHeader bunny = box(-0.0947f, 0.0330f, -0.0619f, 0.0610f, 0.1873f, 0.0588f);
  ViewSpec v;
  const Camera c = camera_for(bunny, ViewSpec{}, &v);
  EXPECT_EQ(v.up, SpgAxis::kPosY);
  EXPECT_EQ(v.yaw, 30);
  EXPECT_EQ(v.pitch, 20);
  EXPECT_EQ(v.distance, 3);
  EXPECT_FALSE(v.has_target);
  EXPECT_LT(row(c, 1, 1), -0.9);  // +y is up on screen
}

TEST(View, CameraFrameIsSeenUprightFromTheCamera) {
  const SpgHeader rgbd = box(-1.07f, -1.58f, 0.84f, 1.81f, 0.41f, 3.82f, SpgViewHint{SpgAxis::kNegY, SpgAxis::kNegZ});
  ViewSpec v;
  const Camera c = camera_for(rgbd, ViewSpec{}, &v);
  EXPECT_EQ(v.up, SpgAxis::kNegY);
  EXPECT_NEAR(std::abs(v.yaw), 180, 1e-9);
  EXPECT_EQ(v.pitch, 0);
  EXPECT_EQ(v.distance, 2);
  // Looking along +z (as the camera did), +y down on screen, +x right: the
  // picture the sensor took, not mirrored, not upside down.
  EXPECT_GT(row(c, 2, 2), 0.999);
  EXPECT_GT(row(c, 1, 1), 0.999);
  EXPECT_GT(row(c, 0, 0), 0.999);
}

TEST(View, TerrainIsSeenFromAboveAboutItsUpAxis) {
  const SpgHeader autzen = box(0.76f, 0.2f, 0.26f, 1178.2f, 562.9f, 114.5f, SpgViewHint{SpgAxis::kPosZ, SpgAxis::kPosZ});
  ViewSpec v;
  const Camera c = camera_for(autzen, ViewSpec{}, &v);
  EXPECT_EQ(v.up, SpgAxis::kPosZ);
  EXPECT_EQ(v.pitch, 50);
  EXPECT_LT(row(c, 2, 2), -0.7);  // looking down
  EXPECT_LT(row(c, 1, 2), -0.5);  // +z is up on screen
  // A file without a hint: the thinnest axis of a flat box, from above too.
  const SpgHeader old = box(0.76f, 0.2f, 0.26f, 1178.2f, 562.9f, 114.5f);
  camera_for(old, ViewSpec{}, &v);
  EXPECT_EQ(v.up, SpgAxis::kPosZ);
  EXPECT_EQ(v.pitch, 50);
}

TEST(View, ScanFromInsideIsSeenFromTheScanner) {
  SpgViewHint hint;
  hint.up = SpgAxis::kPosZ;
  hint.sensor_at_origin = true;
  const SpgHeader room = box(-13.8f, -6.49f, -1.35f, 15.45f, 7.98f, 1.71f, hint);
  ViewSpec v;
  const Camera c = camera_for(room, ViewSpec{}, &v);
  EXPECT_TRUE(v.has_target);
  EXPECT_EQ(v.fov, 90);
  // The eye at the origin, in model units: (0 - min) / largest extent * 2^24.
  const double largest = 15.45 + 13.8;
  const double origin[3] = {13.8 / largest * (1 << 24), 6.49 / largest * (1 << 24), 1.35 / largest * (1 << 24)};
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(c.eye[a], origin[a], 2e-4 * (1 << 24)) << a;
  EXPECT_NEAR(row(c, 2, 2), 0, 1e-3);  // level
}

TEST(View, OptionsOverrideTheFile) {
  const SpgHeader rgbd = box(-1.07f, -1.58f, 0.84f, 1.81f, 0.41f, 3.82f, SpgViewHint{SpgAxis::kNegY, SpgAxis::kNegZ});
  ViewSpec spec;
  std::string error;
  ASSERT_TRUE(parse_view("10,5,4,40", spec, error)) << error;
  ViewSpec v;
  camera_for(rgbd, spec, &v);
  EXPECT_EQ(v.yaw, 10);
  EXPECT_EQ(v.pitch, 5);
  EXPECT_EQ(v.distance, 4);
  EXPECT_EQ(v.up, SpgAxis::kNegY);  // --camera does not change the up axis
  spec.up = SpgAxis::kPosX;
  camera_for(rgbd, spec, &v);
  EXPECT_EQ(v.up, SpgAxis::kPosX);
}

// Colour by elevation (--color elevation, no re-encode): the bunny, up +y,
// drawn unlit — its top rows red, its bottom rows blue, along the ramp; the
// ramp's ends and middle are its colours; down the axis reversed.
TEST(View, ColourByElevationRampsAlongTheUpAxis) {
  EXPECT_EQ(elevation_rgb(0), kElevationRamp[0]);
  EXPECT_EQ(elevation_rgb(128), kElevationRamp[2]);
  EXPECT_EQ(elevation_rgb(255), 0xD81B1Cu);  // a 64th short of the last colour, 0xD7191C
  const std::vector<uint8_t> file = test::fixture("tests/golden/bunny_v1.spg");
  SpgView view;
  ASSERT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
  ClientConfig c;
  c.raster = RasterConfig{240, 320, 5, PixelFormat::kRgb888, 1u << 20};
  c.shading = ShadingMode::kNone;
  c.resolve = false;
  c.elevation = SpgAxis::kPosZ;  // "on": render_fixed takes the view's up (+y here)
  std::string error;
  for (SpgAxis up : {SpgAxis::kPosY, SpgAxis::kNegY}) {
    ViewSpec spec;
    spec.up = up;
    spec.pitch = up == SpgAxis::kPosY ? 20 : -20;
    FixedRender r;
    ASSERT_TRUE(render_fixed(view, file.data(), c, CutRule{CutRule::kProjectedSize, 0, 32}, spec, r, error)) << error;
    // The first and last covered rows' mean red and blue.
    int first = -1, last = -1;
    for (int y = 0; y < 320; ++y)
      for (int x = 0; x < 240; ++x) {
        const uint8_t* p = &r.image.rgb[(static_cast<size_t>(y) * 240 + x) * 3];
        if (p[0] | p[1] | p[2]) (first < 0 ? first : last) = y, last = y;
      }
    ASSERT_GE(first, 0);
    const auto mean = [&](int y, int k) {
      double sum = 0;
      int n = 0;
      for (int x = 0; x < 240; ++x) {
        const uint8_t* p = &r.image.rgb[(static_cast<size_t>(y) * 240 + x) * 3];
        if (p[0] | p[1] | p[2]) sum += p[k], ++n;
      }
      return sum / n;
    };
    // The view turns with its up axis, so the top of the screen is always
    // the high end: red above, blue below.
    EXPECT_GT(mean(first + 2, 0), 150) << spg_axis_name(up);
    EXPECT_LT(mean(first + 2, 2), 100) << spg_axis_name(up);
    EXPECT_GT(mean(last - 2, 2), 150) << spg_axis_name(up);
    EXPECT_LT(mean(last - 2, 0), 100) << spg_axis_name(up);
  }
}

}  // namespace
}  // namespace stipple
