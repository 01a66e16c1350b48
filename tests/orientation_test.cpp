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

// Four walls, floor and ceiling of a 12 x 8 x 3 room, as a scanner at the
// origin (0.7 m off the room's centre) samples them: one point every half
// degree of azimuth and every degree of elevation from -60 to 85 (the
// tripod's blind cone below), 2 mm of range noise.
std::vector<Vec3> scanned_room() {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> noise(-0.002, 0.002);
  const Vec3 half(6, 4, 1.5), room_centre(-0.7, 0.5, -0.2);
  std::vector<Vec3> out;
  for (int az = 0; az < 720; ++az)
    for (int el = -60; el <= 85; ++el) {
      const double a = az * M_PI / 360, e = el * M_PI / 180;
      const Vec3 d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      double t = INFINITY;
      for (int k = 0; k < 3; ++k)
        if (std::abs(d[k]) > 1e-9) t = std::min(t, (room_centre[k] + (d[k] > 0 ? half[k] : -half[k])) / d[k]);
      out.push_back((t + noise(rng)) * d);
    }
  return out;
}

// A closed head-sized shape (an ellipsoid 15 x 22 x 18 cm with bumps),
// its surface sampled evenly, centred on the origin as object scans are stored.
std::vector<Vec3> centred_head() {
  std::vector<Vec3> out;
  const int n = 20000;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    const Vec3 u(r * std::cos(golden * i), r * std::sin(golden * i), z);
    const double bump = 1 + 0.08 * std::sin(5 * u.x()) * std::cos(4 * u.y()) + 0.05 * std::sin(7 * u.z());
    out.push_back(Vec3(0.075 * u.x(), 0.11 * u.y(), 0.09 * u.z()) * bump);
  }
  return out;
}

TEST(Orientation, ScanFromInsideFacesTheScanner) {
  ScanFrame f;
  const PointCloud c = oriented(scanned_room(), {}, &f);
  EXPECT_EQ(f.kind, ScanKind::kSensorInside) << f.reason;
  EXPECT_GE(f.visible_share, 0.95);
  EXPECT_GE(f.spacing_slope, 1.0);       // a scanner's spacing grows with the range
  EXPECT_EQ(f.hint.up, SpgAxis::kPosZ);  // the room is flat: z is its thinnest extent
  EXPECT_TRUE(f.hint.sensor_at_origin);  // seen from the scanner
  EXPECT_GE(share_facing_point(c, Vec3::Zero()), 0.99);
  // --orient outward says it is not seen from inside: no camera at the origin.
  OrientOptions o;
  o.mode = OrientMode::kOutward;
  EXPECT_EQ(analyse_scan(c.positions, o).kind, ScanKind::kObject);
  EXPECT_FALSE(analyse_scan(c.positions, o).hint.sensor_at_origin);
}

// Closed objects stored centred on the origin, the common case for object
// scans: every point is in view from the origin, as in a room scan, but the
// sampling is even — nothing grew with the distance from a scanner there —
// so they are objects, their normals facing outward and their default view
// from outside. The same shapes with the spacing a scanner at the origin
// gives stay scans from inside.
TEST(Orientation, CentredObjectsAreSeenFromOutside) {
  const struct {
    const char* name;
    std::vector<Vec3> points;
  } shapes[] = {{"sphere", test::sphere_cloud(20000, 0.1, false).positions}, {"head", centred_head()}};
  for (const auto& s : shapes) {
    ScanFrame f;
    const PointCloud c = oriented(s.points, {}, &f);
    EXPECT_EQ(f.kind, ScanKind::kObject) << s.name << ": " << f.reason;
    EXPECT_GE(f.visible_share, 0.95) << s.name;  // what once made them rooms
    EXPECT_FALSE(f.hint.sensor_at_origin) << s.name;
    EXPECT_EQ(share_facing_point(c, Vec3::Zero()), 0.0) << s.name;  // every normal outward
    std::printf("%s: %s; %.1f %% visible from the origin, %.1f %% of the normals outward\n", s.name, f.reason.c_str(),
                100 * f.visible_share, 100 * (1 - share_facing_point(c, Vec3::Zero())));
  }
}

// The Stanford scans moved to be centred (on their box's centre and on their
// centroid) and stripped of their faces, as a bare export of them would be:
// objects, and their k-NN normals agree in sign with the faces' normals.
TEST(Orientation, CentredStanfordScansFaceLikeTheirFaces) {
  for (const char* file : {"bunny.ply", "dragon.ply"}) {
    const std::string path = std::string(STIPPLE_SHARED_DATA) + "/" + file;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
    PointCloud scan;
    std::string error;
    ASSERT_TRUE(read_point_cloud(path, scan, error)) << error;
    const Box3 box = bounding_box(scan.positions);
    Vec3 centroid = Vec3::Zero();
    for (const Vec3& p : scan.positions) centroid += p;
    centroid /= static_cast<double>(scan.size());
    for (const Vec3& centre : {Vec3((box.min + box.max) / 2), centroid}) {
      PointCloud faces = scan, bare;
      for (Vec3& p : faces.positions) p -= centre;
      bare.positions = faces.positions;
      prepare_scan(faces, EncodeOptions{});  // normals from the faces
      const ScanFrame f = prepare_scan(bare, EncodeOptions{});
      EXPECT_EQ(f.kind, ScanKind::kObject) << file << ": " << f.reason;
      EXPECT_FALSE(f.hint.sensor_at_origin) << file;
      size_t agree = 0;
      for (size_t i = 0; i < bare.size(); ++i) agree += bare.normals[i].dot(faces.normals[i]) > 0;
      const double share = static_cast<double>(agree) / static_cast<double>(bare.size());
      std::printf("%s centred on its %s: %s; %.1f %% of the k-NN normals face as the faces do\n", file,
                  centre == centroid ? "centroid" : "box", f.reason.c_str(), 100 * share);
      EXPECT_GE(share, 0.9) << file;
    }
  }
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
  // A sphere around the origin is an object seen from outside; --orient
  // sensor says its sensor stood at the origin (PCL's convention).
  const PointCloud s = test::sphere_cloud(3000, 2.0, false);
  ScanFrame f;
  EXPECT_EQ(share_facing_point(oriented(s.positions, {}, &f), Vec3::Zero()), 0.0);
  EXPECT_EQ(f.kind, ScanKind::kObject);
  OrientOptions o;
  o.mode = OrientMode::kSensor;
  EXPECT_EQ(share_facing_point(oriented(s.positions, o), Vec3::Zero()), 1.0);
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
// its file gets no view hint: the committed sphere fixtures stay as they
// are); with them all facing the origin, its sensor stood there.
TEST(Orientation, GivenNormalsOverruleTheGeometry) {
  const PointCloud s = test::sphere_cloud(3000, 2.0, true);
  EXPECT_EQ(analyse_scan(s.positions, {}).kind, ScanKind::kObject);
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
