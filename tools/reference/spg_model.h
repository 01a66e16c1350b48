// stipple host — the double-precision reference decoder of `.spg` files.
//
// Validates the file with core's `spg_parse` (every check of docs/format.md)
// and dequantizes every node to doubles. It is the yardstick the fixed-point
// client is measured against.
#pragma once

#include <string>
#include <vector>

#include "core/spg_format.h"
#include "tools/encoder/node_stats.h"

namespace stipple {

struct DecodedNode {
  Gaussian3 position;
  Mat3 normal_frame = Mat3::Identity();
  Vec2 sigma_n = Vec2::Zero();
  Gaussian3 color;
  uint32_t point_count = 0;  // original points under this node
  uint32_t first_child = 0;
  uint8_t child_count = 0;
  uint16_t depth = 0;
  ClassId class_p{}, class_n{}, class_c{};  // indices into the model's class tables
  bool leaf() const { return child_count == 0; }
};

struct DecodedModel {
  SpgHeader header;
  Vec3 bbox_min = Vec3::Zero(), bbox_max = Vec3::Zero();
  std::vector<Vec3> sigma_p, sigma_c;  // class tables
  std::vector<Vec2> sigma_n;
  std::vector<DecodedNode> nodes;  // breadth-first, as stored
  uint64_t file_bytes = 0;
};

// Decodes `data`; on failure `error` is "<name>: byte <offset>: <what>".
bool decode_spg(const std::string& name, const uint8_t* data, size_t size, DecodedModel& model, std::string& error);
bool load_spg(const std::string& path, DecodedModel& model, std::string& error);

// Original point count of every node of a validated view (leaves from the
// file, internal nodes as the sum of their children), breadth-first: 4 bytes
// a node, where a DecodedModel takes about 350. For tools that need the
// tree's shape but not its Gaussians (`stipple info`).
std::vector<uint32_t> spg_point_counts(const SpgView& view);

// A float32 bit pattern as a double.
double f32_value(uint32_t bits);

// The origin the stored box is relative to (version 2; 0 in version 1).
double spg_origin(const SpgHeader& header, int axis);

// The stored bounding box's largest side (1 for a single point, as the
// client takes it): what version-2 sigma_p codes are relative to.
double spg_largest_extent(const SpgHeader& header);

// Value `index` of a class table of a validated view (table 0 sigma_p in
// model units, 1 sigma_n in radians, 2 sigma_c in colour units), from
// either version's encoding.
double spg_class_value(const SpgView& view, int table, size_t index);

// The cut made of the nodes at `level`, plus the leaves above it.
std::vector<uint32_t> level_cut(const DecodedModel& model, int level);
// All leaves.
std::vector<uint32_t> leaf_cut(const DecodedModel& model);

}  // namespace stipple
