// Fuzz harness: text scans with the layouts users name or the file names —
// the input's first line is a `--columns` list (parse_text_columns), the
// rest a text scan read with it when it parses, and read again with no list
// (a header line, Leica PTS, OBJ or the guess from the column count).
// Checked: no crash; an accepted scan has as many normals and colours as
// points or none, finite coordinates within float32's range, colours in
// [0, 1] and normals of unit length or zero.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "tools/scan/ply_io.h"

namespace {

void check(const stipple::PointCloud& c) {
  if (c.size() == 0) __builtin_trap();
  if ((c.has_normals() && c.normals.size() != c.size()) || (c.has_colors() && c.colors.size() != c.size())) __builtin_trap();
  for (const stipple::Vec3& p : c.positions)
    if (!p.allFinite() || p.cwiseAbs().maxCoeff() > stipple::kMaxCoordinate) __builtin_trap();
  for (const stipple::Vec3& col : c.colors)
    if (!(col.minCoeff() >= 0 && col.maxCoeff() <= 1)) __builtin_trap();
  for (const stipple::Vec3& n : c.normals)
    if (!n.allFinite() || (n.squaredNorm() != 0 && std::abs(n.norm() - 1) > 1e-6)) __builtin_trap();
  for (const auto& t : c.triangles)
    for (uint32_t v : t)
      if (v >= c.size()) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  size_t eol = 0;
  while (eol < size && data[eol] != '\n') ++eol;
  const std::string spec(reinterpret_cast<const char*>(data), eol);
  const uint8_t* body = data + std::min(size, eol + 1);
  const size_t body_size = size - std::min(size, eol + 1);
  PointCloud cloud;
  std::string error;
  ScanOptions named;
  if (parse_text_columns(spec, named.columns, error) &&
      parse_point_cloud("fuzz.txt", body, body_size, cloud, error, named))
    check(cloud);
  if (parse_point_cloud("fuzz.txt", body, body_size, cloud, error)) check(cloud);
  return 0;
}
