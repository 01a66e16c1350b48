// Fuzz harness: the PLY / text scan reader.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "tools/scan/ply_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  stipple::PointCloud cloud;
  std::string error;
  if (stipple::parse_point_cloud("fuzz.ply", data, size, cloud, error)) {
    for (const stipple::Vec3& p : cloud.positions)
      if (!p.allFinite()) __builtin_trap();  // accepted points are always finite
    for (const auto& t : cloud.triangles)
      for (uint32_t v : t)
        if (v >= cloud.size()) __builtin_trap();  // face indices always in range
  } else if (error.rfind("fuzz.ply: ", 0) != 0) {
    __builtin_trap();  // every error names the file
  }
  return 0;
}
