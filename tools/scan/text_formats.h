// stipple host — the text scans people export, told apart before reading:
//
//   a header line   CloudCompare's "//X,Y,Z,R,G,B", many tools' "x y z" or
//                   "X;Y;Z;Intensity": a first line of names, read as the
//                   columns (x y z; nx ny nz / normal_x..; r g b / red green
//                   blue as 0..255; anything else skipped, said in a warning);
//   Leica PTS       a count line, then `x y z`, `x y z intensity`,
//                   `x y z r g b` or `x y z intensity r g b` lines; a file
//                   may hold several such sections (one a scan position);
//   Wavefront OBJ   `v x y z [r g b]` vertices and `f` faces (their indices
//                   as `v`, `v/vt`, `v//vn` or `v/vt/vn`, negative counting
//                   back), fan-triangulated for the encoder's normals; `vn`,
//                   `vt`, groups and materials are skipped;
//   E57             ASTM E2807's binary container: refused by name, with
//                   what to convert it with (docs/robustness.md, "Formats").
//
// Intensity, where a format has it, is read past and not kept: the encoder
// carries RGB only. Errors name the file and the line.
#pragma once

#include <cstdint>
#include <string>

#include "tools/scan/ply_io.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

// How the plain-text reader reads a file: the columns (the user's, a header
// line's, or PTS's by count), the line to skip as a header (0: none), and
// whether single-integer lines are PTS section counts.
struct TextPlan {
  TextColumns columns;
  int header_line = 0;
  bool pts = false;
  std::string what;  // "a header line", "Leica PTS" or "": said in a warning
};

// Looks at a text file's first lines. False (with `error` naming the line)
// only for a header line that names no x, y and z.
bool plan_text(const std::string& name, const uint8_t* data, size_t size, const TextColumns& given, TextPlan& plan,
               PointCloud& cloud, std::string& error);

bool looks_like_obj(const uint8_t* data, size_t size);
bool parse_obj(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error);

// E57's file signature, "ASTM-E57" at byte 0.
bool looks_like_e57(const uint8_t* data, size_t size);
// The message that refuses one: what it is, and how to convert it.
std::string e57_refusal(const std::string& name);

}  // namespace stipple
