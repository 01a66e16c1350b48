// stipple core — the simple cut. See cut.h.
#include "core/cut.h"

#include "core/gaussian_table.h"

namespace stipple {

size_t cut_scratch_bytes(const SpgHeader& header) { return (size_t{header.node_count} + 7) / 8; }

int32_t node_radius_mu(const FixedNode& node) {
  uint64_t best = 0;
  for (int k = 0; k < 3; ++k) {
    uint64_t sq = 0;
    for (int c = 0; c < 3; ++c) sq += static_cast<uint64_t>(int64_t{node.axis[k][c]} * node.axis[k][c]);
    if (sq > best) best = sq;
  }
  // |axis| <= 2^30 (sigma saturates there), so 3.5 |axis| < 2^32: clamp to int32.
  const uint64_t r = (isqrt64(best) * static_cast<uint64_t>(kGaussianClip)) >> 12;
  return r > 0x7FFFFFFFu ? 0x7FFFFFFF : static_cast<int32_t>(r);
}

namespace {

// Does the node's projected gamma-extent exceed the threshold? Visible nodes
// only; a node that reaches behind the near plane is always split.
enum class Verdict { kKeep, kSplit, kDrop };

Verdict judge(const SpgView& view, uint32_t id, const CutRule& rule, const NodeDecoder& decoder,
              const Camera& camera) {
  FixedNode node;
  if (decoder.decode(view.records + static_cast<size_t>(id) * view.record_bytes, &node) != DecodeStatus::kOk)
    return Verdict::kDrop;  // unreachable for a validated view
  int32_t c[3];
  camera_space(camera, node.mean, c);
  const int64_t radius = node_radius_mu(node);
  if (c[2] + radius < camera.near_mu) return Verdict::kDrop;
  if (c[2] - radius < camera.near_mu) return Verdict::kSplit;
  // radius * f / Z > max  <=>  radius * f > max * Z (products below 2^52).
  return radius * camera.focal_q4 > int64_t{rule.max_size_q4} * c[2] ? Verdict::kSplit : Verdict::kKeep;
}

}  // namespace

uint32_t simple_cut(const SpgView& view, const CutRule& rule, const NodeDecoder* decoder, const Camera* camera,
                    void* scratch, uint32_t* out, uint32_t capacity) {
  const uint32_t n = view.header.node_count;
  uint8_t* reached = static_cast<uint8_t*>(scratch);
  for (size_t i = 0; i < cut_scratch_bytes(view.header); ++i) reached[i] = 0;
  reached[0] = 1;
  const bool by_size = rule.kind == CutRule::kProjectedSize && decoder != nullptr && camera != nullptr;
  uint32_t count = 0, next_child = 1;
  uint32_t level = 0, level_end = 1, next_level_end = 1;
  for (uint32_t i = 0; i < n; ++i) {
    if (i == level_end) {
      ++level;
      level_end = next_level_end;
    }
    const uint32_t children = spg_child_count(view, i);
    const uint32_t first = next_child;
    next_child += children;
    next_level_end += children;
    if (!((reached[i >> 3] >> (i & 7)) & 1u)) continue;
    Verdict v = Verdict::kKeep;
    if (children > 0) {
      if (by_size) v = judge(view, i, rule, *decoder, *camera);
      else v = level < rule.level ? Verdict::kSplit : Verdict::kKeep;
    } else if (by_size && judge(view, i, rule, *decoder, *camera) == Verdict::kDrop) {
      v = Verdict::kDrop;
    }
    if (v == Verdict::kKeep) {
      if (count < capacity) out[count] = i;
      ++count;
    } else if (v == Verdict::kSplit) {
      for (uint32_t c = first; c < first + children; ++c) reached[c >> 3] = static_cast<uint8_t>(reached[c >> 3] | (1u << (c & 7)));
    }
  }
  return count;
}

}  // namespace stipple
