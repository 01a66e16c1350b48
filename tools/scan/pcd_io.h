// stipple host — reading PCL's PCD files (Point Cloud Library, v0.5-0.7).
//
// Header lines VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT,
// POINTS, DATA (`#` starts a comment); DATA ascii, binary (records packed
// field after field) or binary_compressed (two u32 sizes, then LZF — liblzf —
// of the fields one after another, each for every point). Fields: x y z
// (required, count 1, any type), normal_x normal_y normal_z, rgb or rgba
// (4 bytes: PCL's packed float or an unsigned 0x00RRGGBB / 0xAARRGGBB);
// others are skipped. Organized clouds (HEIGHT > 1) mark missing points with
// NaN coordinates: those points are dropped and counted in a warning; NaN
// normals (PCL's where a normal is undefined) become zero normals, counted.
// VIEWPOINT's translation, when not the origin, is kept as the sensor
// position estimated normals face (PointCloud::viewpoint).
//
// Errors name the file and the header line, or the point and field, or the
// byte; counts are checked against the bytes that remain before anything is
// sized from them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "tools/scan/point_cloud.h"

namespace stipple {

// True when the bytes look like a PCD file (a "# .PCD" comment or a VERSION
// line first).
bool looks_like_pcd(const uint8_t* data, size_t size);

// `stream`: the points go there a chunk at a time (tools/scan/point_cloud.h).
bool parse_pcd(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error,
               ScanStream* stream = nullptr);

}  // namespace stipple
