// stipple host — reference `.spg` decoder. See spg_model.h.
#include "tools/embedded/model_file.h"
#include "tools/reference/spg_model.h"

#include <algorithm>
#include <cstring>

#include "platform/file_io.h"
#include "tools/embedded/embedded.h"
#include "tools/encoder/quantize.h"

namespace stipple {
namespace {
double f32_of(uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}
}  // namespace

bool decode_spg(const std::string& name, const uint8_t* data, size_t size, DecodedModel& model, std::string& error) {
  SpgView view;
  const SpgResult r = spg_parse(data, size, &view);
  if (!r.ok()) {
    error = spg_error_message(name, r, size);
    return false;
  }
  model = DecodedModel{};
  model.file_bytes = size;
  const SpgHeader& h = view.header;
  model.header = h;
  for (int a = 0; a < 3; ++a) {  // absolute: the origin plus the stored box
    model.bbox_min[a] = spg_origin(h, a) + f32_of(h.bbox_bits[a]);
    model.bbox_max[a] = spg_origin(h, a) + f32_of(h.bbox_bits[3 + a]);
  }
  for (uint32_t c = 0; c < h.class_count[0]; ++c)
    model.sigma_p.emplace_back(spg_class_value(view, 0, 3 * c), spg_class_value(view, 0, 3 * c + 1),
                               spg_class_value(view, 0, 3 * c + 2));
  for (uint32_t c = 0; c < h.class_count[1]; ++c)
    model.sigma_n.emplace_back(spg_class_value(view, 1, 2 * c), spg_class_value(view, 1, 2 * c + 1));
  for (uint32_t c = 0; c < h.class_count[2]; ++c)
    model.sigma_c.emplace_back(spg_class_value(view, 2, 3 * c), spg_class_value(view, 2, 3 * c + 1),
                               spg_class_value(view, 2, 3 * c + 2));

  const RecordLayout& layout = h.layout;
  const AngleBits fp_bits = frame_bits(layout, Field::kFpTheta, false);
  const AngleBits fn_bits = frame_bits(layout, Field::kFnTheta, false);
  const AngleBits fc_bits = frame_bits(layout, Field::kFcTheta, true);
  model.nodes.resize(h.node_count);
  uint32_t next_child = 1;
  const uint8_t* leaf_counts = view.leaf_counts;
  for (uint32_t i = 0; i < h.node_count; ++i) {
    DecodedNode& node = model.nodes[i];
    node.child_count = static_cast<uint8_t>(spg_child_count(view, i));
    if (node.child_count) {
      node.first_child = next_child;
      for (uint32_t c = 0; c < node.child_count; ++c) model.nodes[next_child + c].depth = static_cast<uint16_t>(node.depth + 1);
      next_child += node.child_count;
    } else {
      uint32_t v = 0;
      for (int shift = 0;; shift += 7) {  // validated by spg_parse
        const uint8_t b = *leaf_counts++;
        v |= static_cast<uint32_t>(b & 0x7F) << shift;
        if (!(b & 0x80)) break;
      }
      node.point_count = v;
    }
    const NodeFields f = unpack_record(layout, view.records + static_cast<size_t>(i) * view.record_bytes);
    for (int a = 0; a < 3; ++a)
      node.position.mean[a] = dequantize_cell(f.v[a], model.bbox_min[a], model.bbox_max[a], layout.bits[a]);
    node.position.frame = decode_frame({f[Field::kFpTheta], f[Field::kFpPhi], f[Field::kFpPsi]}, fp_bits);
    node.class_p = ClassId{f[Field::kSigmaP]};
    node.position.sigma = model.sigma_p[index_of(node.class_p)];
    if (h.has_normals()) {
      node.normal_frame = decode_frame({f[Field::kFnTheta], f[Field::kFnPhi], f[Field::kFnPsi]}, fn_bits);
      node.class_n = ClassId{f[Field::kSigmaN]};
      node.sigma_n = model.sigma_n[index_of(node.class_n)];
    }
    if (h.has_color()) {
      node.color.mean = Vec3(dequantize_unit(f[Field::kColorR], layout.width(Field::kColorR)),
                             dequantize_unit(f[Field::kColorG], layout.width(Field::kColorG)),
                             dequantize_unit(f[Field::kColorB], layout.width(Field::kColorB)));
      node.color.frame = decode_frame({f[Field::kFcTheta], f[Field::kFcPhi], f[Field::kFcPsi]}, fc_bits);
      node.class_c = ClassId{f[Field::kSigmaC]};
      node.color.sigma = model.sigma_c[index_of(node.class_c)];
    }
  }
  // Internal point counts, children before parents (reverse BFS).
  for (uint32_t i = h.node_count; i-- > 0;) {
    DecodedNode& node = model.nodes[i];
    for (uint32_t c = 0; c < node.child_count; ++c) node.point_count += model.nodes[node.first_child + c].point_count;
  }
  return true;
}

double f32_value(uint32_t bits) { return f32_of(bits); }

double spg_origin(const SpgHeader& h, int axis) {
  double v;
  std::memcpy(&v, &h.origin_bits[axis], 8);
  return v;
}

double spg_largest_extent(const SpgHeader& h) {
  double largest = 0;
  for (int a = 0; a < 3; ++a) largest = std::max(largest, f32_of(h.bbox_bits[3 + a]) - f32_of(h.bbox_bits[a]));
  return largest > 0 ? largest : 1;  // one point: as the client's decoder takes it
}

double spg_class_value(const SpgView& view, int table, size_t index) {
  const uint8_t* t = table == 0 ? view.sigma_p : table == 1 ? view.sigma_n : view.sigma_c;
  if (spg_class_value_bytes(view.header.version) == 4) return f32_of(load_u32le(t + 4 * index));
  const uint16_t code = load_u16le(t + 2 * index);
  if (table == 0) return sigma_p_of_code(code, spg_largest_extent(view.header));
  return (table == 1 ? spg_sigma_n_q12(code, view.header.has_curvature_sign()) : code) / 4096.0;
}

std::vector<uint32_t> spg_point_counts(const SpgView& view) {
  const uint32_t n = view.header.node_count;
  std::vector<uint32_t> count(n, 0);
  const uint8_t* leb = view.leaf_counts;
  for (uint32_t i = 0; i < n; ++i) {
    if (spg_child_count(view, i) != 0) continue;
    uint32_t v = 0;
    for (int shift = 0;; shift += 7) {  // validated by spg_parse
      const uint8_t b = *leb++;
      v |= static_cast<uint32_t>(b & 0x7F) << shift;
      if (!(b & 0x80)) break;
    }
    count[i] = v;
  }
  // Children come after every node before their parent's level, in the order
  // of their parents: walking back from the end, the last unclaimed nodes are
  // the children of the current internal node. Sums fit: the file's total is u32.
  uint32_t end = n;
  for (uint32_t i = n; i-- > 0;) {
    const uint32_t c = spg_child_count(view, i);
    for (uint32_t k = end - c; k < end; ++k) count[i] += count[k];
    end -= c;
  }
  return count;
}

bool load_spg(const std::string& path, DecodedModel& model, std::string& error) {
  std::vector<uint8_t> bytes;
  if (!read_spg_file(path, bytes, error)) return false;
  return decode_spg(path, bytes.data(), bytes.size(), model, error);
}

std::vector<uint32_t> level_cut(const DecodedModel& model, int level) {
  std::vector<uint32_t> cut;
  for (uint32_t i = 0; i < model.nodes.size(); ++i) {
    const DecodedNode& n = model.nodes[i];
    if (n.depth == level || (n.depth < level && n.leaf())) cut.push_back(i);
  }
  return cut;
}

std::vector<uint32_t> leaf_cut(const DecodedModel& model) {
  std::vector<uint32_t> cut;
  for (uint32_t i = 0; i < model.nodes.size(); ++i)
    if (model.nodes[i].leaf()) cut.push_back(i);
  return cut;
}

}  // namespace stipple
