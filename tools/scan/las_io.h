// stipple host — reading ASPRS LAS 1.0-1.4 files, point data formats 0-10.
//
// Written here rather than taken from a library: Debian's LAS libraries are
// PDAL (a large framework with its own plugin system) and libLAS (no longer
// maintained, and it reports errors by exception), and the part we need — the
// public header, the point records' X Y Z and RGB — is a fixed binary layout
// of a few dozen lines (ASPRS LAS 1.4 R15, tables 3-4 and 7-17).
//
// Positions are X * scale + offset in double precision, so a survey's large
// offset costs nothing here. RGB (formats 2, 3, 5, 7, 8, 10) is 16 bits a
// channel, scaled to [0, 1]; a file whose values never exceed 255 (an
// 8-bit writer's) is read as 8-bit, with a warning. LAZ (compressed LAS,
// point format bit 7 or 6 set) is refused with a message that says so: no
// Debian package decompresses it.
//
// Errors name the file and the header field or byte; the point count is
// checked against the file's size before anything is sized from it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "tools/scan/point_cloud.h"

namespace stipple {

bool looks_like_las(const uint8_t* data, size_t size);

// `stream`: the points go there a chunk at a time (tools/scan/point_cloud.h),
// their colours unscaled (its color_divisor says how at the end).
bool parse_las(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error,
               ScanStream* stream = nullptr, LasColor color_by = LasColor::kRgb);

// The ASPRS classes (LAS 1.4 R15, table 17) as colours, 0xRRGGBB, the way
// LiDAR viewers show them: ground brown, vegetation greens, buildings red,
// water blue, noise magenta...; and their names, for a legend ("" for a
// class number the standard leaves to users, drawn teal).
uint32_t las_class_rgb(uint8_t c);
const char* las_class_name(uint8_t c);
inline constexpr uint8_t kLasStandardClasses = 19;  // 0 .. 18

}  // namespace stipple
