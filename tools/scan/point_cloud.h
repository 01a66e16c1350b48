// stipple host — an in-memory scan: positions, optional normals and colours,
// optional triangles (used only to derive normals).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace stipple {

using Vec3 = Eigen::Vector3d;

// What a LAS scan's points are coloured by (ScanOptions::color_by).
enum class LasColor : uint8_t { kRgb, kIntensity, kClassification };

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

// A scan read a chunk at a time (the encoder in partitions reads a scan of
// any size so): the reader hands `deliver` its points whenever it holds
// kScanChunk of them, and the rest at the end, with the index of the chunk's
// first point and the bytes of the file read so far. The callee may take
// the chunk's vectors; the reader clears them after. What only the whole
// file tells comes at the end, in the fields below.
inline constexpr size_t kScanChunk = size_t{1} << 16;
struct ScanStream {
  std::function<bool(PointCloud& chunk, uint64_t first, uint64_t bytes_read, std::string& error)> deliver;
  uint64_t delivered = 0;     // points handed over so far
  uint64_t triangles = 0;     // faces the file has (not kept: a mesh's normals need the whole mesh)
  // Colours the reader delivers unscaled, to be divided by this once the
  // whole file is read (LAS: 255 for an 8-bit writer's, else 65535); 1 for
  // colours already in [0, 1]. 0: the file's colours are all zero, read
  // without colour.
  double color_divisor = 1;
  // A text scan whose columns 4-6 only the whole file tells apart (normals
  // or r g b): delivered without them, and this names the columns
  // ("x,y,z,r,g,b", as --columns takes them) to read it again with.
  std::string text_columns;
  // Hands over what `cloud` holds (when it holds kScanChunk, or `last`).
  bool flush(PointCloud& cloud, uint64_t bytes_read, bool last, std::string& error);
};

// Axis-aligned bounding box of a set of points.
struct Box3 {
  Vec3 min = Vec3::Constant(0.0);
  Vec3 max = Vec3::Constant(0.0);
  double diagonal() const { return (max - min).norm(); }
};
Box3 bounding_box(const std::vector<Vec3>& points);

// A flat square of side x side points one unit apart in z = 0, with
// normals +z: a scan whose leaves a close-up sees closer than their
// spacing (the close-ups' tests and benchmark).
inline PointCloud grid_plane(int side) {
  PointCloud plane;
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      plane.positions.push_back(Vec3(x, y, 0));
      plane.normals.push_back(Vec3(0, 0, 1));
    }
  return plane;
}

// A patch of side x side points over [-1, 1]^2 on z = (kx x^2 + ky y^2) / 2,
// with its normals on the +z side: seen from above (from its normals' side)
// a dome for kx, ky < 0, a bowl for kx, ky > 0, a saddle for opposite signs.
// The curvature sign's tests and figures (docs/encoder.md "Curvature sign").
inline PointCloud quadric_patch(int side, double kx, double ky) {
  PointCloud patch;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const double x = -1.0 + 2.0 * i / (side - 1), y = -1.0 + 2.0 * j / (side - 1);
      patch.positions.push_back(Vec3(x, y, 0.5 * (kx * x * x + ky * y * y)));
      patch.normals.push_back(Vec3(-kx * x, -ky * y, 1.0).normalized());
    }
  return patch;
}

}  // namespace stipple
