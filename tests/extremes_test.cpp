// Scans at the numerical extremes, end to end: encode, parse, draw with the
// fixed-point client and with the double reference. Each case: no crash, no
// NaN in what is decoded, the picture sane by a property (the object on
// screen, framed, not a speck), and the fixed client's error against the
// double reference printed (docs/robustness.md lists the figures).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>

#include "core/node_decoder.h"
#include "core/spg_writer.h"
#include "tests/portable/test_files.h"
#include "test_util.h"
#include "tools/embedded/embedded.h"
#include "tools/reference/metrics.h"
#include "tools/reference/render.h"
#include "tools/reference/sampler.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

struct Case {
  std::string name;
  std::function<PointCloud()> make;
  double min_coverage;  // share of the 240x320 frame the object must cover (a speck: 0)
  double min_psnr;      // fixed against double
};

PointCloud transformed(double scale, const Vec3& offset, size_t n = 3000) {
  PointCloud c = test::sphere_cloud(n);
  for (Vec3& p : c.positions) p = p * scale + offset;
  return c;
}

PointCloud from_points(std::vector<Vec3> points) {
  PointCloud c;
  c.positions = std::move(points);
  return c;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"sphere", [] { return transformed(1, Vec3::Zero()); }, 0.15, 28});
  out.push_back({"scaled 1e-6", [] { return transformed(1e-6, Vec3::Zero()); }, 0.15, 28});
  out.push_back({"scaled 1e6", [] { return transformed(1e6, Vec3::Zero()); }, 0.15, 28});
  out.push_back({"scaled 1e12", [] { return transformed(1e12, Vec3::Zero()); }, 0.15, 28});
  out.push_back({"1 unit at 1e7 from the origin", [] { return transformed(1, Vec3(1e7, -1e7, 1e7)); }, 0.15, 28});
  // The stored box is float32 relative to a float64 origin (format version
  // 2): 1 cm at 1e7 is drawn as the unit sphere is (in version 1 it was a
  // speck of two points inside a box rounded out to whole units).
  out.push_back({"1 cm at 1e7 from the origin", [] { return transformed(0.01, Vec3(1e7, -1e7, 1e7)); }, 0.15, 28});
  out.push_back({"all points identical", [] { return from_points(std::vector<Vec3>(500, Vec3(3, -2, 1))); }, 0, 0});
  out.push_back({"two points", [] { return from_points({Vec3(0, 0, 0), Vec3(1, 2, 3)}); }, 0, 0});
  out.push_back({"collinear", [] {
                   std::vector<Vec3> p;
                   for (int i = 0; i < 2000; ++i) p.push_back(Vec3(1, 2, 3) * (i / 100.0));
                   return from_points(p);
                 }, 0, 0});
  out.push_back({"coplanar", [] {
                   std::mt19937 rng(9);
                   std::uniform_real_distribution<double> u(-1, 1);
                   std::vector<Vec3> p;
                   for (int i = 0; i < 3000; ++i) p.push_back(Vec3(u(rng), u(rng), 0));
                   return from_points(p);
                 }, 0.02, 20});
  out.push_back({"every point twice", [] {
                   PointCloud c = test::sphere_cloud(1500);
                   const size_t n = c.size();
                   for (size_t i = 0; i < n; ++i) {
                     c.positions.push_back(c.positions[i]);
                     c.normals.push_back(c.normals[i]);
                   }
                   return c;
                 }, 0.15, 28});
  out.push_back({"sigma ratio 1e12 (a 1e6-long needle 1e-6 thick)", [] {
                   std::mt19937 rng(9);
                   std::uniform_real_distribution<double> u(-1, 1);
                   std::vector<Vec3> p;
                   for (int i = 0; i < 3000; ++i) p.push_back(Vec3(1e6 * u(rng), 1e-6 * u(rng), 1e-6 * u(rng)));
                   return from_points(p);
                 }, 0, 0});
  return out;
}

TEST(Extremes, EveryCaseEncodesDrawsAndStaysFinite) {
  for (const Case& k : cases()) {
    SCOPED_TRACE(k.name);
    PointCloud cloud = k.make();
    std::vector<uint8_t> spg;
    EncodeReport report;
    std::string error;
    ASSERT_TRUE(encode_cloud(cloud, EncodeOptions{}, spg, report, error)) << error;
    SpgView view;
    ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
    const DecodedModel model = test::decode(spg);
    for (const DecodedNode& n : model.nodes) {
      ASSERT_TRUE(n.position.mean.allFinite());
      ASSERT_TRUE(n.position.sigma.allFinite());
    }
    for (const Vec3& s : model.sigma_p) ASSERT_TRUE(s.allFinite());
    ClientConfig config;
    config.resolve = false;  // the points as drawn, as the reference draws them
    config.raster.max_points = 1u << 20;  // none dropped (the reference draws every point)
    FixedRender fixed;
    ASSERT_TRUE(render_fixed(view, spg.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, ViewSpec{}, fixed, error))
        << error;
    size_t covered = 0;
    for (size_t i = 0; i < fixed.image.rgb.size(); i += 3)
      covered += (fixed.image.rgb[i] | fixed.image.rgb[i + 1] | fixed.image.rgb[i + 2]) != 0;
    const double share = static_cast<double>(covered) / (240.0 * 320.0);
    const Image ref = render_reference(model, fixed.cut, config, ViewSpec{});
    const double psnr = image_psnr(fixed.image, ref);
    std::printf("%-48s %6zu nodes, %6u points, covers %5.1f %% of the frame, fixed vs double %6.2f dB\n", k.name.c_str(),
                model.nodes.size(), fixed.stats.points, 100 * share, psnr);
    std::fflush(stdout);
    EXPECT_GT(covered, 0u);  // something is drawn
    EXPECT_GE(share, k.min_coverage);
    EXPECT_LT(share, 0.9);  // framed, not filling the screen
    if (k.min_psnr > 0) {
      EXPECT_GE(psnr, k.min_psnr);
    }
  }
}

// Coordinates at float32's edge: a cloud filling ±3e38 on every axis encodes
// and decodes finite; one coordinate beyond it is refused by the encoder,
// naming the point, the axis and the value — never an infinite box.
TEST(Extremes, CoordinatesAtFloat32sEdgeEncodeAndBeyondItAreRefusedByName) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3e38, 3e38);
  PointCloud cloud;
  for (int i = 0; i < 2000; ++i) cloud.positions.emplace_back(u(rng), u(rng), u(rng));
  std::vector<uint8_t> spg;
  EncodeReport report;
  std::string error;
  ASSERT_TRUE(encode_cloud(cloud, EncodeOptions{}, spg, report, error)) << error;
  const DecodedModel model = test::decode(spg);
  for (const DecodedNode& n : model.nodes) ASSERT_TRUE(n.position.mean.allFinite());
  cloud.positions[1234].z() = -1e39;
  cloud.normals.clear();
  EXPECT_FALSE(encode_cloud(cloud, EncodeOptions{}, spg, report, error));
  EXPECT_EQ(error, "the scan's point 1234 (counting from 0): z = -1e+39 is beyond float32's range (3.403e+38), in which "
                   "a .spg stores positions");
}

// Cameras at the extremes, on the unit sphere: inside the model, close to its
// surface, a million model sizes away, straight down the up axis, the
// narrowest and widest fields of view. Each either draws (no crash; zoomed
// past the leaves it draws their points as dots — the resolve once trimmed
// them all away, a blank screen — a far one a speck) or is refused with a
// message naming --camera — never anything else.
TEST(Extremes, CamerasAtTheExtremesDrawOrAreRefusedByName) {
  const std::vector<uint8_t> spg = test::encode(test::sphere_cloud(3000));
  SpgView view;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  const struct {
    const char* name;
    double yaw, pitch, distance, fov;
  } cameras[] = {
      {"inside the model", 30, 20, 0.001, 35},   {"close to the surface", 30, 20, 0.7, 35},  {"a million sizes away", 30, 20, 1e6, 35},
      {"along the up axis", 0, 90, 3, 35},       {"along -up", 0, -90, 3, 35},         {"fov 1", 30, 20, 3, 1},
      {"fov 170", 30, 20, 3, 170},               {"fov 179.9", 30, 20, 3, 179.9},      {"a yaw of 1e9 degrees", 1e9, 20, 3, 35},
  };
  for (const auto& k : cameras) {
    ViewSpec spec;
    spec.yaw = k.yaw, spec.pitch = k.pitch, spec.distance = k.distance, spec.fov = k.fov;
    spec.orbit_given = true;
    ClientConfig config;
    FixedRender r;
    std::string error;
    if (!render_fixed(view, spg.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, spec, r, error)) {
      std::printf("%-22s refused: %s\n", k.name, error.c_str());
      EXPECT_EQ(error.rfind("--camera: ", 0), 0u) << k.name << ": " << error;
      continue;
    }
    size_t covered = 0;
    for (size_t i = 0; i < r.image.rgb.size(); i += 3) covered += (r.image.rgb[i] | r.image.rgb[i + 1] | r.image.rgb[i + 2]) != 0;
    std::printf("%-22s %6u nodes, %7u points, covers %5.1f %%\n", k.name, r.stats.nodes, r.stats.points,
                100.0 * static_cast<double>(covered) / (240 * 320));
    if (k.distance >= 1e6) {
      EXPECT_LT(covered, 20u) << k.name;  // a speck
    }
    if (k.distance == 0.7 || k.fov == 1) {
      // Closer than the leaves' points cover: dots (the resolve keeps
      // isolated specks), never a blank screen.
      EXPECT_GT(covered, 240u * 320u / 400) << k.name;
    }
  }
}

// Angle fields as wide as the format allows (13 to 16 bits, docs/format.md
// §5): the same model with every frame angle widened, values scaled to the
// same angles, draws as the original does.
TEST(Extremes, WideAngleFieldsDrawAsTheNarrowOnes) {
  const std::vector<uint8_t> file = test::fixture("tests/data/sphere600_normals.spg");
  SpgView view;
  ASSERT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
  const std::vector<uint8_t> out = test::widen_angles(file);
  SpgView wide_view;
  ASSERT_TRUE(spg_parse(out.data(), out.size(), &wide_view).ok());
  const size_t rb = wide_view.record_bytes;
  ASSERT_LE(rb, 32u);
  ClientConfig config;
  FixedRender a, b;
  std::string error;
  ASSERT_TRUE(render_fixed(view, file.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, ViewSpec{}, a, error)) << error;
  ASSERT_TRUE(render_fixed(wide_view, out.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, ViewSpec{}, b, error)) << error;
  const double psnr = image_psnr(a.image, b.image);
  std::printf("13-16-bit angle fields: %zu-byte records, %.2f dB against the %zu-byte original\n", rb, psnr,
              static_cast<size_t>(view.record_bytes));
  EXPECT_GT(psnr, 30.0);
  EXPECT_GT(b.stats.points, a.stats.points / 2);
}

// A sampled model written and read back keeps its precision far from the
// origin: positions are written as doubles (float32 rounded 1 cm at 1e7 to
// whole units: 17 dB instead of 52).
TEST(Extremes, SampledPointsFarFromTheOriginKeepTheirPrecision) {
  const PointCloud original = transformed(0.01, Vec3(1e7, -1e7, 1e7), 20000);
  const DecodedModel m = test::decode(test::encode(original));
  const PointCloud leaves = sample_cut(m, leaf_cut(m), 0);
  const std::string path = "extremes_sample.ply";
  std::string error;
  ASSERT_TRUE(write_ply(path, leaves, error)) << error;
  PointCloud back;
  ASSERT_TRUE(read_point_cloud(path, back, error)) << error;
  std::remove(path.c_str());
  const CloudMetrics before = compare_clouds(original, leaves), after = compare_clouds(original, back);
  std::printf("1 cm at 1e7: sampled leaves %.2f dB, written and read back %.2f dB\n", before.psnr_one_sided, after.psnr_one_sided);
  EXPECT_GT(before.psnr_one_sided, 49.5);
  EXPECT_NEAR(after.psnr_one_sided, before.psnr_one_sided, 0.01);
  // A non-finite point is refused, nothing written.
  PointCloud bad = back;
  bad.positions[5].x() = INFINITY;
  EXPECT_FALSE(write_ply(path, bad, error));
  EXPECT_NE(error.find("point 5 is not finite"), std::string::npos) << error;
  EXPECT_FALSE(std::filesystem::exists(path));
}

// Normals at theta = 0 and pi (the sphere's caps, set to exactly +-z) and
// across the phi seam (the +x meridian), colours at exactly 0 and 255: the
// fixed decoder's normal frames stay unit and point where the reference's
// do (within a few Q14 LSB), leaves of pure white or black decode to 255 or
// 0 exactly, and a white model drawn unlit is pure white wherever it covers
// (per-point colours saturate at 255, never wrap to dark).
TEST(Extremes, NormalsAtThePolesAndTheSeamAndColoursAtTheirEnds) {
  PointCloud c = test::sphere_cloud(4000);
  for (size_t i = 0; i < c.size(); ++i) {
    Vec3& n = c.normals[i];
    if (n.z() > 0.95) n = Vec3(0, 0, 1);
    if (n.z() < -0.95) n = Vec3(0, 0, -1);
    if (std::abs(n.y()) < 0.05 && n.x() > 0) n = Vec3(n.x(), 0, n.z()).normalized();  // on the seam
    c.colors.push_back(c.positions[i].x() > 0 ? Vec3(1, 1, 1) : Vec3(0, 0, 0));
  }
  const std::vector<uint8_t> spg = test::encode(c);
  const DecodedModel model = test::decode(spg);
  SpgView view;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4 + 1);
  NodeDecoder decoder;
  ASSERT_EQ(decoder.init(view, storage.data(), storage.size() * 4), DecodeStatus::kOk);
  int poles = 0, seam = 0, white = 0, black = 0, worst = 0;
  for (uint32_t i = 0; i < view.header.node_count; ++i) {
    FixedNode f;
    ASSERT_EQ(decoder.decode(view.records + size_t{i} * view.record_bytes, &f), DecodeStatus::kOk);
    const DecodedNode& r = model.nodes[i];
    const Vec3 normal = r.normal_frame.col(2);
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(f.normal_frame[2][k] - static_cast<int>(std::lround(normal[k] * 16384))));
    int64_t len2 = 0;
    for (int k = 0; k < 3; ++k) len2 += int64_t{f.normal_frame[2][k]} * f.normal_frame[2][k];
    EXPECT_NEAR(std::sqrt(static_cast<double>(len2)), 16384, 8) << "node " << i;
    poles += std::abs(normal.z()) > 1 - 1e-9;
    seam += std::abs(normal.y()) < 1e-9 && normal.x() > 0;
    if (!r.leaf()) continue;
    const Vec3 mean = r.color.mean;
    if (mean.minCoeff() > 0.999) {
      ++white;
      EXPECT_EQ(f.color[0] + f.color[1] + f.color[2], 3 * 255) << "node " << i;
    }
    if (mean.maxCoeff() < 0.001) {
      ++black;
      EXPECT_EQ(f.color[0] + f.color[1] + f.color[2], 0) << "node " << i;
    }
  }
  std::printf("poles %d, seam %d, white leaves %d, black leaves %d, worst normal %d Q14 LSB\n", poles, seam, white, black, worst);
  EXPECT_GT(poles, 0);
  EXPECT_GT(white, 10);
  EXPECT_GT(black, 10);
  EXPECT_LE(worst, 8);
  // All white, unlit: every covered pixel is exactly white.
  for (Vec3& col : c.colors) col = Vec3(1, 1, 1);
  const std::vector<uint8_t> all_white = test::encode(c);
  ASSERT_TRUE(spg_parse(all_white.data(), all_white.size(), &view).ok());
  ClientConfig config;
  config.shading = ShadingMode::kNone;
  config.resolve = false;
  config.raster.format = PixelFormat::kRgb888;
  FixedRender fixed;
  std::string error;
  ASSERT_TRUE(render_fixed(view, all_white.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, ViewSpec{}, fixed, error))
      << error;
  size_t covered = 0, off_white = 0;
  for (size_t i = 0; i < fixed.image.rgb.size(); i += 3) {
    const int sum = fixed.image.rgb[i] + fixed.image.rgb[i + 1] + fixed.image.rgb[i + 2];
    covered += sum != 0;
    off_white += sum != 0 && sum != 3 * 255;
  }
  EXPECT_GT(covered, 10000u);
  EXPECT_EQ(off_white, 0u);
}

}  // namespace
}  // namespace stipple
