// stipple host — which way a scan's estimated normals point, and how it
// wants to be seen.
//
// Normals estimated from neighbourhoods (k-NN PCA) have no sign; the sign
// decides what is lit. Users expect normals to face the sensor that saw the
// surface (PCL's convention: toward a viewpoint, the origin by default), or
// the sky for airborne and terrain data. `analyse_scan` reads that from the
// data when no option says it, by these rules in order (docs/encoder.md,
// "Orientation"):
//   1. a viewpoint given (`--viewpoint`, a file's VIEWPOINT): toward it;
//   2. a camera frame: at least 99 % of the points in front of the origin
//      (z > 0) inside a 127-degree cone about +z, filling at least 20
//      degrees of it both ways — an RGB-D or ToF frame; the sensor is the
//      origin, +y points down;
//   3. a sensor inside: the origin inside the bounding box (5-95 % of each
//      axis), at least 95 % of the points visible from it (no other point
//      nearer along the same ray), and sampled as a scanner there samples:
//      at equal angles, so the spacing between points grows with their
//      distance from it (log spacing against log distance has a slope of at
//      least 0.5; a scanner's is about 1) — or, in a scan with normals, at
//      least 90 % of them facing it. A terrestrial or 360-degree scan in its
//      scanner's frame, seen from the scanner. A closed object stored centred
//      on the origin passes the first two tests but not the third: its
//      spacing does not depend on the distance from its centre (slope near
//      0), so it is an object (rule 5), seen from outside;
//   4. terrain: the thinnest extent below half of each other — airborne
//      LiDAR, ground scans: up is the thinnest axis, normals face +up;
//   5. otherwise an object: orientation propagates over the k-NN graph from
//      the point farthest from the centroid, whose normal faces away from it.
// The result also gives the view hint stored in the file: the up axis and
// the side the sensor saw, so viewers orbit the right way and start where
// the sensor stood.
#pragma once

#include <string>
#include <vector>

#include "core/spg_format.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

enum class OrientMode : uint8_t {
  kAuto,     // decide from the data (rules above)
  kSensor,   // each normal faces the viewpoint (the origin unless given)
  kUp,       // each normal faces +up (the thinnest axis unless given)
  kOutward,  // propagate over the k-NN graph, seeded facing away from the centroid
};

struct OrientOptions {
  OrientMode mode = OrientMode::kAuto;
  bool has_viewpoint = false;
  Vec3 viewpoint = Vec3::Zero();
  SpgAxis up = SpgAxis::kNone;  // kNone: the thinnest axis, positive
};

enum class ScanKind : uint8_t { kObject, kViewpoint, kCameraFrame, kSensorInside, kTerrain };

struct ScanFrame {
  ScanKind kind = ScanKind::kObject;
  OrientMode orient = OrientMode::kOutward;  // never kAuto
  Vec3 viewpoint = Vec3::Zero();             // kSensor: where the normals face
  Vec3 up = Vec3::UnitZ();                   // kUp: the direction they face
  // kOutward: each component's seed faces away from this point instead of
  // the points' own centroid (a partition's job: the whole scan's centroid).
  bool has_centre = false;
  Vec3 centre = Vec3::Zero();
  SpgViewHint hint;                          // for the file's header
  double visible_share = 0;                  // rule 3's measure (0 when not measured)
  double spacing_slope = 0;                  // rule 3's sampling measure (0 when not measured; NaN: no spread)
  std::string reason;                        // one line for the user
};

// Decides how to orient normals and the view hint. Options override the
// data: a mode other than kAuto, a viewpoint, an up axis. `normals`, when
// the scan has them (a file's, or from faces), are evidence: rules 2-4 apply
// only when at least half of them face the sensor or the sky.
ScanFrame analyse_scan(const std::vector<Vec3>& points, const OrientOptions& options,
                       const std::vector<Vec3>* normals = nullptr);

// Share of points that nothing nearer hides from `eye`: directions are
// binned in a cube map of about 4 points a cell, and a point counts as
// visible when it lies within 20 % of its cell's nearest distance.
double visible_share(const std::vector<Vec3>& points, const Vec3& eye);

// How the spacing between points grows with their distance from `eye`: the
// least-squares slope of log(distance to the 6th nearest neighbour) against
// log(distance from eye), over up to 2,000 points of a deterministic sample.
// About 1 for a scanner at `eye` (equal angular steps), about 0 for a
// surface sampled evenly (a mesh's vertices, merged scans). NaN where the
// distances from `eye` barely vary (standard deviation of their log under
// 0.1: a sphere about its centre), which says nothing either way.
double spacing_slope(const std::vector<Vec3>& points, const Vec3& eye);

const char* scan_kind_name(ScanKind k);
const char* orient_mode_name(OrientMode m);
Vec3 axis_vector(SpgAxis a);  // unit vector; zero for kNone

}  // namespace stipple
