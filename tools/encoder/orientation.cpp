// stipple host — normal orientation and view hints from the data. See
// orientation.h; the rules and their measurements are in docs/encoder.md.
#include "tools/encoder/orientation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tools/scan/kdtree.h"

namespace stipple {
namespace {

SpgAxis axis_code(int axis, bool negative) {
  return static_cast<SpgAxis>(1 + 2 * axis + (negative ? 1 : 0));
}

// The axis of the largest |component|, signed.
SpgAxis dominant_axis(const Vec3& v) {
  int a = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(v[k]) > std::abs(v[a])) a = k;
  return axis_code(a, v[a] < 0);
}

}  // namespace

const char* scan_kind_name(ScanKind k) {
  switch (k) {
    case ScanKind::kObject: return "object";
    case ScanKind::kViewpoint: return "viewpoint";
    case ScanKind::kCameraFrame: return "camera frame";
    case ScanKind::kSensorInside: return "sensor inside";
    case ScanKind::kTerrain: return "terrain";
  }
  return "?";
}

const char* orient_mode_name(OrientMode m) {
  switch (m) {
    case OrientMode::kAuto: return "auto";
    case OrientMode::kSensor: return "sensor";
    case OrientMode::kUp: return "up";
    case OrientMode::kOutward: return "outward";
  }
  return "?";
}


Vec3 axis_vector(SpgAxis a) {
  if (a == SpgAxis::kNone) return Vec3::Zero();
  const int code = static_cast<int>(a) - 1;
  Vec3 v = Vec3::Zero();
  v[code / 2] = code % 2 ? -1.0 : 1.0;
  return v;
}

double visible_share(const std::vector<Vec3>& points, const Vec3& eye) {
  if (points.empty()) return 0;
  // Cube map: face = dominant axis and sign, (u, v) the other two / |dominant|.
  const int g = static_cast<int>(std::clamp(std::sqrt(static_cast<double>(points.size()) / 24.0), 8.0, 1024.0));
  std::vector<double> nearest(6 * static_cast<size_t>(g) * g, INFINITY);
  std::vector<uint32_t> cell(points.size());
  std::vector<double> dist(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3 d = points[i] - eye;
    const double r = d.norm();
    dist[i] = r;
    if (!(r > 0)) {
      cell[i] = UINT32_MAX;
      continue;
    }
    int a = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(d[k]) > std::abs(d[a])) a = k;
    const double m = std::abs(d[a]);
    const int face = 2 * a + (d[a] < 0);
    const double u = d[(a + 1) % 3] / m, v = d[(a + 2) % 3] / m;  // [-1, 1]
    const int cu = std::clamp(static_cast<int>((u + 1) / 2 * g), 0, g - 1), cv = std::clamp(static_cast<int>((v + 1) / 2 * g), 0, g - 1);
    cell[i] = static_cast<uint32_t>((face * g + cu) * g + cv);
    nearest[cell[i]] = std::min(nearest[cell[i]], r);
  }
  size_t visible = 0;
  for (size_t i = 0; i < points.size(); ++i) visible += cell[i] == UINT32_MAX || dist[i] <= 1.2 * nearest[cell[i]];
  return static_cast<double>(visible) / static_cast<double>(points.size());
}

double spacing_slope(const std::vector<Vec3>& points, const Vec3& eye) {
  if (points.size() < 16) return NAN;
  // A subsample spaces every point alike by one factor: the slope is unchanged.
  const size_t tree_stride = std::max<size_t>(1, points.size() / 20000);
  std::vector<Vec3> sample;
  for (size_t i = 0; i < points.size(); i += tree_stride) sample.push_back(points[i]);
  const KdTree tree(sample);
  const size_t query_stride = std::max<size_t>(1, sample.size() / 2000);
  std::vector<uint32_t> near;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  size_t n = 0;
  for (size_t i = 0; i < sample.size(); i += query_stride) {
    const double r = (sample[i] - eye).norm();
    tree.knearest(sample[i], 7, near);  // itself, then six neighbours
    if (near.size() < 7 || !(r > 0)) continue;
    const double d = (sample[near.back()] - sample[i]).norm();
    if (!(d > 0)) continue;
    const double x = std::log(r), y = std::log(d);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
    ++n;
  }
  if (n < 16) return NAN;
  const double mean_x = sx / static_cast<double>(n);
  const double var_x = sxx / static_cast<double>(n) - mean_x * mean_x;
  if (!(var_x >= 0.01)) return NAN;
  return (sxy / static_cast<double>(n) - mean_x * sy / static_cast<double>(n)) / var_x;
}

ScanFrame analyse_scan(const std::vector<Vec3>& points, const OrientOptions& o, const std::vector<Vec3>* normals) {
  ScanFrame f;
  const Box3 box = bounding_box(points);
  const Vec3 extent = box.max - box.min;
  int thin = 0;
  for (int a = 1; a < 3; ++a)
    if (extent[a] < extent[thin]) thin = a;
  const bool flat = extent[thin] < 0.5 * extent[(thin + 1) % 3] && extent[thin] < 0.5 * extent[(thin + 2) % 3];
  const Vec3 up = o.up != SpgAxis::kNone ? axis_vector(o.up) : axis_vector(axis_code(thin, false));
  f.up = up;
  char text[256];

  // Camera frame: in front of the origin, inside a cone about +z.
  // The frame fills a field of view: its tangents span at least 0.35 (20
  // degrees) both ways, so an object that merely lies ahead is not one.
  size_t in_cone = 0;
  double tx[2] = {INFINITY, -INFINITY}, ty[2] = {INFINITY, -INFINITY};
  for (const Vec3& p : points) {
    if (!(p.z() > 0 && std::abs(p.x()) <= 2 * p.z() && std::abs(p.y()) <= 2 * p.z())) continue;
    ++in_cone;
    tx[0] = std::min(tx[0], p.x() / p.z()), tx[1] = std::max(tx[1], p.x() / p.z());
    ty[0] = std::min(ty[0], p.y() / p.z()), ty[1] = std::max(ty[1], p.y() / p.z());
  }
  const bool camera = !points.empty() && static_cast<double>(in_cone) >= 0.99 * static_cast<double>(points.size()) &&
                      tx[1] - tx[0] >= 0.35 && ty[1] - ty[0] >= 0.35;
  bool inside = true;
  for (int a = 0; a < 3; ++a) inside = inside && extent[a] > 0 && -box.min[a] >= 0.05 * extent[a] && box.max[a] >= 0.05 * extent[a];

  // With normals in the file (or from faces) the data shows which way its
  // surfaces face: a rule that contradicts them (most facing away from the
  // sensor or the sky) does not apply.
  const bool has_normals = normals != nullptr && normals->size() == points.size();
  const auto facing_share = [&](const Vec3& sensor, const Vec3* sky) {
    if (!has_normals) return 1.0;
    size_t toward = 0;
    for (size_t i = 0; i < points.size(); ++i)
      toward += sky ? (*normals)[i].dot(*sky) > 0 : (*normals)[i].dot(sensor - points[i]) > 0;
    return static_cast<double>(toward) / static_cast<double>(points.size());
  };
  const double facing_origin = facing_share(Vec3::Zero(), nullptr);  // rules 2 and 3 both ask
  // Rule 3's evidence of a scanner at the origin, beyond seeing every point
  // from it: spacing growing with distance, or the scan's own normals facing it.
  const auto scanner_inside = [&]() {
    f.spacing_slope = spacing_slope(points, Vec3::Zero());
    return f.spacing_slope >= 0.5 || (has_normals && facing_origin >= 0.9);
  };
  if (o.has_viewpoint) {
    f.kind = ScanKind::kViewpoint;
    f.viewpoint = o.viewpoint;
    f.hint.sensor_side = dominant_axis(o.viewpoint - (box.min + box.max) / 2);
    std::snprintf(text, sizeof text, "viewpoint (%g, %g, %g) given", o.viewpoint.x(), o.viewpoint.y(), o.viewpoint.z());
  } else if (camera && facing_origin >= 0.5) {
    f.kind = ScanKind::kCameraFrame;
    f.hint = SpgViewHint{SpgAxis::kNegY, SpgAxis::kNegZ};
    std::snprintf(text, sizeof text, "camera frame: %.1f %% of the points in front of the origin (+z forward, +y down)",
                  100.0 * static_cast<double>(in_cone) / static_cast<double>(points.size()));
  } else if (inside && facing_origin >= 0.5 && (f.visible_share = visible_share(points, Vec3::Zero())) >= 0.95 &&
             scanner_inside()) {
    f.kind = ScanKind::kSensorInside;
    // Seen from the scanner: from outside, the room shows the backs of its walls and ceiling.
    f.hint.sensor_at_origin = true;
    if (flat) f.hint.up = axis_code(thin, false);
    std::snprintf(text, sizeof text,
                  "sensor at the origin, inside the scan: %.1f %% of the points visible from it, spacing growing with "
                  "distance from it (slope %.2f)",
                  100.0 * f.visible_share, f.spacing_slope);
  } else if (flat && facing_share(Vec3::Zero(), &up) >= 0.5) {
    f.kind = ScanKind::kTerrain;
    f.hint = SpgViewHint{axis_code(thin, false), axis_code(thin, false)};
    std::snprintf(text, sizeof text, "terrain: the %c extent (%g) is under half the others", "xyz"[thin], extent[thin]);
  } else if (f.visible_share >= 0.95) {
    // Around the origin and all in view from it, but not sampled from there:
    // an object stored centred, seen from outside.
    f.kind = ScanKind::kObject;
    if (std::isnan(f.spacing_slope))
      std::snprintf(text, sizeof text, "object: around the origin, its points all at about one distance from it");
    else
      std::snprintf(text, sizeof text,
                    "object: centred on the origin, but its spacing does not grow with the distance from it as a "
                    "scanner's there would (slope %.2f)",
                    f.spacing_slope);
  } else {
    f.kind = ScanKind::kObject;
    std::snprintf(text, sizeof text, "object: no sensor position or up axis in the data");
  }
  f.reason = text;
  switch (f.kind) {
    case ScanKind::kViewpoint:
    case ScanKind::kCameraFrame:
    case ScanKind::kSensorInside: f.orient = OrientMode::kSensor; break;
    case ScanKind::kTerrain: f.orient = OrientMode::kUp; break;
    case ScanKind::kObject: f.orient = OrientMode::kOutward; break;
  }
  // --orient outward or up says what the scan is not: seen from inside.
  if (f.kind == ScanKind::kSensorInside && (o.mode == OrientMode::kOutward || o.mode == OrientMode::kUp)) {
    f.kind = ScanKind::kObject;
    f.hint = SpgViewHint{};
  }
  if (o.up != SpgAxis::kNone) f.hint.up = o.up;
  if (o.mode != OrientMode::kAuto) {
    f.orient = o.mode;
    f.reason += std::string("; --orient ") + orient_mode_name(o.mode);
  }
  return f;
}

}  // namespace stipple
