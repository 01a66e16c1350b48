// stipple core — the simple cut: which nodes of a tree to draw.
//
// Until the server's view-dependent cut (TOG05 Fig. 10) exists, a cut is
// chosen by one of two rules over a validated `.spg` tree, walked once in
// breadth-first order (children follow their parents, siblings adjacent):
//   kLevel          the nodes at `level`, plus the leaves above it;
//   kProjectedSize  a node whose projected extent gamma * sigma1 * f / Z is at
//                   most `max_size_q4` (1/16 px) is kept, a larger one is
//                   replaced by its children; leaves are always kept. Nodes
//                   entirely behind the near plane are dropped with their
//                   subtrees.
// The walk needs one bit per node of caller storage (`cut_scratch_bytes`)
// and, for kProjectedSize, decodes each visited node. The server's cut will
// replace this file's rules; its callers keep the same shape.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "core/view_cut.h"

namespace stipple {

struct CutRule {
  enum Kind : uint8_t { kLevel, kProjectedSize } kind = kLevel;
  uint16_t level = 0;
  int32_t max_size_q4 = 32;  // 2 px, the paper's split threshold
  // For kProjectedSize through the view-dependent cut (core/view_cut.h, which
  // the programs use; simple_cut ignores these): cull by frustum and normal
  // cone, and refine only inside a window (px, empty: everywhere).
  bool cull = true;
  uint16_t leaf_cone_q8 = ConeRule{}.leaf_gamma_q8;  // a leaf's normal cone in sigma_n1 (ConeRule)
  int32_t window[4] = {0, 0, 0, 0};
};

size_t cut_scratch_bytes(const SpgHeader& header);

// Writes the cut's node ids, in breadth-first order, to out[0 .. capacity)
// and returns how many the cut has (which may exceed `capacity`: then only
// the first `capacity` were written). `decoder` and `camera` are used by
// kProjectedSize only. `scratch` holds cut_scratch_bytes(view.header) bytes.
uint32_t simple_cut(const SpgView& view, const CutRule& rule, const NodeDecoder* decoder, const Camera* camera,
                    void* scratch, uint32_t* out, uint32_t capacity);

// gamma * sigma1 of a decoded node, in MU (the largest axis length, times 3.5).
int32_t node_radius_mu(const FixedNode& node);

}  // namespace stipple
