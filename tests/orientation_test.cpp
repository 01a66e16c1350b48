// Estimated normals face the way users expect (docs/encoder.md,
// "Orientation"): the sensor of a camera frame or of a scan made from
// inside, the sky for terrain, away from the centroid for an object; the
// file's view hint says up and the sensor's side. Synthetic scenes of each
// kind, then every bare scan in ../shared/data, where the share of leaf
// normals facing the sensor or the sky must be at least 90 % (it was 1-34 %).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <random>

#include "test_util.h"
#include "tools/encoder/normals.h"
#include "tools/encoder/orientation.h"

namespace stipple {
namespace {

// A noisy grid on a plane through `origin` spanned by u and v.
std::vector<Vec3> plane(const Vec3& origin, const Vec3& u, const Vec3& v, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<Vec3> out;
  const Vec3 w = u.cross(v).normalized() * (0.002 * (u.norm() + v.norm()));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      out.push_back(origin + u * ((i + 0.5 + jitter(rng)) / n) + v * ((j + 0.5 + jitter(rng)) / n) + w * jitter(rng));
  return out;
}

double share_facing_point(const PointCloud& c, const Vec3& p) {
  size_t k = 0;
  for (size_t i = 0; i < c.size(); ++i) k += c.normals[i].dot(p - c.positions[i]) > 0;
  return static_cast<double>(k) / static_cast<double>(c.size());
}

double share_facing_dir(const PointCloud& c, const Vec3& d) {
  size_t k = 0;
  for (const Vec3& n : c.normals) k += n.dot(d) > 0;
  return static_cast<double>(k) / static_cast<double>(c.size());
}

PointCloud oriented(std::vector<Vec3> points, const OrientOptions& o, ScanFrame* frame_out = nullptr) {
  PointCloud c;
  c.positions = std::move(points);
  const ScanFrame f = analyse_scan(c.positions, o);
  estimate_normals(c, 12, f);
  if (frame_out) *frame_out = f;
  return c;
}

TEST(Orientation, CameraFrameFacesTheSensorWithYDown) {
  // A wall 3 m ahead and a floor below the camera (+y down), as an RGB-D frame sees them.
  std::vector<Vec3> pts = plane(Vec3(-1.5, -1.2, 3), Vec3(3, 0, 0), Vec3(0, 2.4, 0), 60, 1);
  const std::vector<Vec3> floor = plane(Vec3(-1.5, 1.2, 1), Vec3(3, 0, 0), Vec3(0, 0, 2), 40, 2);
  pts.insert(pts.end(), floor.begin(), floor.end());
  ScanFrame f;
  const PointCloud c = oriented(pts, {}, &f);
  EXPECT_EQ(f.kind, ScanKind::kCameraFrame) << f.reason;
  EXPECT_EQ(f.hint.up, SpgAxis::kNegY);
  EXPECT_EQ(f.hint.sensor_side, SpgAxis::kNegZ);
  EXPECT_EQ(share_facing_point(c, Vec3::Zero()), 1.0);
}

TEST(Orientation, ScanFromInsideFacesTheScanner) {
  // Four walls, floor and ceiling of a 12 x 8 x 3 room around a scanner at the origin.
  std::vector<Vec3> pts;
  const auto add = [&](const std::vector<Vec3>& s) { pts.insert(pts.end(), s.begin(), s.end()); };
  add(plane(Vec3(-6, -4, -1.5), Vec3(12, 0, 0), Vec3(0, 0, 3), 40, 1));
  add(plane(Vec3(-6, 4, -1.5), Vec3(12, 0, 0), Vec3(0, 0, 3), 40, 2));
  add(plane(Vec3(-6, -4, -1.5), Vec3(0, 8, 0), Vec3(0, 0, 3), 30, 3));
  add(plane(Vec3(6, -4, -1.5), Vec3(0, 8, 0), Vec3(0, 0, 3), 30, 4));
  add(plane(Vec3(-6, -4, -1.5), Vec3(12, 0, 0), Vec3(0, 8, 0), 50, 5));
  add(plane(Vec3(-6, -4, 1.5), Vec3(12, 0, 0), Vec3(0, 8, 0), 50, 6));
  ScanFrame f;
  const PointCloud c = oriented(pts, {}, &f);
  EXPECT_EQ(f.kind, ScanKind::kSensorInside) << f.reason;
  EXPECT_GE(f.visible_share, 0.95);
  EXPECT_EQ(f.hint.up, SpgAxis::kPosZ);  // the room is flat: z is its thinnest extent
  EXPECT_TRUE(f.hint.sensor_at_origin);  // seen from the scanner
  EXPECT_GE(share_facing_point(c, Vec3::Zero()), 0.99);
}

TEST(Orientation, TerrainFacesTheSky) {
  // Rolling ground 1,000 units wide, 30 high, far from the origin (an airborne tile after its offset).
  std::vector<Vec3> pts = plane(Vec3(10, 10, 5), Vec3(1000, 0, 0), Vec3(0, 600, 0), 120, 7);
  for (Vec3& p : pts) p.z() += 15 * std::sin(p.x() / 90) * std::cos(p.y() / 70);
  ScanFrame f;
  const PointCloud c = oriented(pts, {}, &f);
  EXPECT_EQ(f.kind, ScanKind::kTerrain) << f.reason;
  EXPECT_EQ(f.hint.up, SpgAxis::kPosZ);
  EXPECT_EQ(f.hint.sensor_side, SpgAxis::kPosZ);
  EXPECT_EQ(share_facing_dir(c, Vec3::UnitZ()), 1.0);
  // The same ground with y up (a file from a y-up tool): the thinnest axis.
  for (Vec3& p : pts) std::swap(p.y(), p.z());
  const PointCloud y = oriented(pts, {}, &f);
  EXPECT_EQ(f.hint.up, SpgAxis::kPosY);
  EXPECT_EQ(share_facing_dir(y, Vec3::UnitY()), 1.0);
}

TEST(Orientation, ObjectAwayFromTheOriginFacesOutward) {
  PointCloud s = test::sphere_cloud(3000, 2.0, false);
  for (Vec3& p : s.positions) p += Vec3(10, 20, 30);
  ScanFrame f;
  const PointCloud c = oriented(s.positions, {}, &f);
  EXPECT_EQ(f.kind, ScanKind::kObject) << f.reason;
  EXPECT_EQ(f.hint.encode(), 0);  // no hint: viewers keep their defaults
  EXPECT_EQ(share_facing_point(c, Vec3(10, 20, 30)), 0.0);  // none faces the centre
}

TEST(Orientation, OptionsOverrideTheData) {
  // A sphere around the origin reads as a scan from inside (PCL's convention:
  // the sensor is the origin); --orient outward says it is an object.
  const PointCloud s = test::sphere_cloud(3000, 2.0, false);
  ScanFrame f;
  EXPECT_EQ(share_facing_point(oriented(s.positions, {}, &f), Vec3::Zero()), 1.0);
  EXPECT_EQ(f.kind, ScanKind::kSensorInside);
  OrientOptions o;
  o.mode = OrientMode::kOutward;
  EXPECT_EQ(share_facing_point(oriented(s.positions, o), Vec3::Zero()), 0.0);
  // A viewpoint: every normal faces it; the hint names its side.
  o = OrientOptions{};
  o.has_viewpoint = true;
  o.viewpoint = Vec3(0, 0, 50);
  const PointCloud v = oriented(s.positions, o, &f);
  EXPECT_EQ(f.kind, ScanKind::kViewpoint);
  EXPECT_EQ(f.hint.sensor_side, SpgAxis::kPosZ);
  EXPECT_EQ(share_facing_point(v, Vec3(0, 0, 50)), 1.0);
  // An up axis: stored, and faced by --orient up.
  o = OrientOptions{};
  o.mode = OrientMode::kUp;
  o.up = SpgAxis::kNegX;
  const PointCloud u = oriented(s.positions, o, &f);
  EXPECT_EQ(f.hint.up, SpgAxis::kNegX);
  EXPECT_EQ(share_facing_dir(u, -Vec3::UnitX()), 1.0);
}

// Normals the scan brings are evidence: a sphere around the origin whose
// file normals face outward is an object, not a room seen from inside (so
// its file gets no view hint: the committed sphere fixtures stay as they are).
TEST(Orientation, GivenNormalsOverruleTheGeometry) {
  const PointCloud s = test::sphere_cloud(3000, 2.0, true);
  EXPECT_EQ(analyse_scan(s.positions, {}).kind, ScanKind::kSensorInside);
  const ScanFrame f = analyse_scan(s.positions, {}, &s.normals);
  EXPECT_EQ(f.kind, ScanKind::kObject) << f.reason;
  EXPECT_EQ(f.hint.encode(), 0);
  std::vector<Vec3> inward = s.normals;
  for (Vec3& n : inward) n = -n;
  EXPECT_EQ(analyse_scan(s.positions, {}, &inward).kind, ScanKind::kSensorInside);
}

TEST(Orientation, AxisNames) {
  SpgAxis a;
  ASSERT_TRUE(spg_parse_axis("-y", &a));
  EXPECT_EQ(a, SpgAxis::kNegY);
  ASSERT_TRUE(spg_parse_axis("z", &a));
  EXPECT_EQ(a, SpgAxis::kPosZ);
  EXPECT_FALSE(spg_parse_axis("up", &a));
  EXPECT_FALSE(spg_parse_axis("", &a));
  EXPECT_FALSE(spg_parse_axis("+zz", &a));
  EXPECT_STREQ(spg_axis_name(SpgAxis::kNegX), "-x");
  EXPECT_EQ(axis_vector(SpgAxis::kNegY), Vec3(0, -1, 0));
}

// The scans users bring: every bare scan of ../shared/data, encoded with
// defaults. Leaf mean normals facing the sensor (camera frame, scan from
// inside: the origin) or the sky (airborne and ground LiDAR: +z).
TEST(Orientation, SharedScansFaceTheirSensorOrTheSky) {
  const struct {
    const char* file;
    ScanKind kind;
    bool toward_origin;
  } scans[] = {{"rgbd_office_rgb.ply", ScanKind::kCameraFrame, true},
               {"room_scan1.ply", ScanKind::kSensorInside, true},
               {"autzen_trim_rgb.ply", ScanKind::kTerrain, false},
               {"lone_star_tls.ply", ScanKind::kTerrain, false}};
  for (const auto& s : scans) {
    const std::string path = std::string(STIPPLE_SHARED_DATA) + "/" + s.file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
    PointCloud cloud;
    std::string error;
    ASSERT_TRUE(read_point_cloud(path, cloud, error)) << error;
    ASSERT_FALSE(cloud.has_normals());
    EncodeReport report;
    const DecodedModel m = test::decode(test::encode(cloud, EncodeOptions{}, &report));
    EXPECT_EQ(report.frame.kind, s.kind) << s.file << ": " << report.frame.reason;
    size_t leaves = 0, facing = 0;
    for (const DecodedNode& n : m.nodes) {
      if (!n.leaf()) continue;
      ++leaves;
      const Vec3 normal = n.normal_frame.col(2);
      facing += s.toward_origin ? normal.dot(-n.position.mean) > 0 : normal.z() > 0;
    }
    const double share = static_cast<double>(facing) / static_cast<double>(leaves);
    std::printf("%s: %s, %.1f %% of %zu leaf normals face the %s\n", s.file, scan_kind_name(report.frame.kind),
                100 * share, leaves, s.toward_origin ? "sensor" : "sky");
    EXPECT_GE(share, 0.9) << s.file;
  }
}

}  // namespace
}  // namespace stipple
