// stipple host — an in-memory scan: positions, optional normals and colours,
// optional triangles (used only to derive normals).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace stipple {

using Vec3 = Eigen::Vector3d;

struct PointCloud {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // empty, or one unit (or zero) vector per point
  std::vector<Vec3> colors;   // empty, or one RGB per point in [0, 1]
  std::vector<std::array<uint32_t, 3>> triangles;  // faces, fan-triangulated
  std::vector<std::string> warnings;  // what the reader noticed or guessed, "<file>: <what>", for the user
  bool has_viewpoint = false;         // the file says where its sensor stood (PCD's VIEWPOINT)
  Vec3 viewpoint = Vec3::Zero();

  size_t size() const { return positions.size(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }
};

// Axis-aligned bounding box of a set of points.
struct Box3 {
  Vec3 min = Vec3::Constant(0.0);
  Vec3 max = Vec3::Constant(0.0);
  double diagonal() const { return (max - min).norm(); }
};
Box3 bounding_box(const std::vector<Vec3>& points);

}  // namespace stipple
