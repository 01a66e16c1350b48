// stipple host — reading scans (PLY and plain text) and writing PLY.
//
// PLY: `ascii`, `binary_little_endian` and `binary_big_endian` 1.0. Vertex
// element: x y z (any scalar type) required; nx ny nz optional; colour as
// red/green/blue or diffuse_red/diffuse_green/diffuse_blue (uchar/ushort scaled
// to [0, 1], float/double taken as [0, 1], other integer types by their
// maximum). Faces (`vertex_indices` or `vertex_index` lists) are
// fan-triangulated and kept for normal estimation. Other elements and
// properties are skipped.
//
// PCD (tools/scan/pcd_io.h) and LAS (tools/scan/las_io.h) are told by their
// signatures and read by their own readers.
//
// Plain text (anything else): one point per line, `x y z`, `x y z nx ny nz`,
// `x y z r g b` (integers 0..255: told from normals by their values, with a
// warning), `x y z r g b a` or `x y z nx ny nz r g b` — or any layout the
// user names (`--columns x,y,z,-,r,g,b`, ScanOptions::columns); separators
// whitespace, ',' or ';', or decimal commas where the first line shows them
// (a warning says so); `#` starts a comment; every line must have the same
// number of columns. A binary file or a .spg given as a scan is refused as
// such, naming the byte.
//
// Errors are returned, never thrown, as "<path>: <where>: <what>", where
// <where> names the header line, element index, property or byte offset.
// Nothing is sized from a header count before the count is checked against
// the bytes that remain, so a hostile header cannot cause a huge allocation.
// Non-finite coordinates, normals or colours are rejected. A scan where at
// least 1 % of the points (and 100 or more) repeat another point's position
// exactly gets a warning in `cloud.warnings` (float32 collapse far from the
// origin is the usual cause).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tools/scan/point_cloud.h"

namespace stipple {

// A text scan's columns as the user names them, instead of the guess from
// the column count and values: x y z (required), nx ny nz and r g b (0..255;
// each group all or none), `-` for a column to skip (intensity, alpha, time).
struct TextColumns {
  enum Field : uint8_t { kSkip, kX, kY, kZ, kNx, kNy, kNz, kR, kG, kB };
  std::vector<Field> fields;  // in file order; empty: told from the file
};
// Parses "x,y,z,-,r,g,b" (commas or spaces). On failure `error` says which name.
bool parse_text_columns(const std::string& spec, TextColumns& columns, std::string& error);

struct ScanOptions {
  TextColumns columns;  // text scans only: a PLY, PCD or LAS file is refused with them
  // What a LAS scan's colour is (encode --color-by): its RGB (the default),
  // its intensity as grey, or its classification through the ASPRS palette
  // (tools/scan/las_io.h). Intensity and classification are LAS's: another
  // format is refused with them.
  LasColor color_by = LasColor::kRgb;
};

bool read_point_cloud(const std::string& path, PointCloud& cloud, std::string& error,
                      const ScanOptions& options = {});
// Parses an in-memory file; `name` is used in error messages.
bool parse_point_cloud(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud,
                       std::string& error, const ScanOptions& options = {});

// The same a chunk at a time, for a scan larger than memory: every format
// but OBJ (scan_streams says which), memory-mapped, each chunk validated
// as read_point_cloud validates the whole (the same messages, the points
// counted from the file's start). `rest` ends with the reader's warnings
// and the file's viewpoint, and no points. The whole-file checks a stream
// cannot make are the caller's: repeated positions (duplicate_warning), a
// mesh's faces (stream.triangles), LAS colours (stream.color_divisor), a
// text scan's columns 4-6 (stream.text_columns).
bool scan_streams(const std::string& path);
bool stream_point_cloud(const std::string& path, ScanStream& stream, PointCloud& rest, std::string& error,
                        const ScanOptions& options = {});

// "<name>: N of M points (P %) repeat another point's position exactly[; far
// from the origin ...]" where N is at least 1 % of M and 100; "" otherwise.
std::string duplicate_warning(const std::string& name, uint64_t duplicates, uint64_t points, const Box3& box);

// The largest coordinate magnitude a scan may have: float32's largest value,
// since a .spg stores its box in float32 (docs/format.md §1). Readers refuse a
// scan with one beyond it, naming the point, the axis and the value.
inline constexpr double kMaxCoordinate = 3.4028234663852886e38;
// "" when every coordinate is within ±kMaxCoordinate; else what is not.
std::string beyond_float_range(const std::vector<Vec3>& points, uint64_t first = 0);  // points counted from `first`

// Points whose position equals an earlier point's (exact comparison).
size_t count_duplicate_positions(const std::vector<Vec3>& points);

// Writes binary little-endian PLY: double x y z (no float32 rounding far
// from the origin), then float nx ny nz and uchar red green blue when
// present. Refuses (writing nothing) a cloud with a non-finite position.
bool write_ply(const std::string& path, const PointCloud& cloud, std::string& error);

}  // namespace stipple
