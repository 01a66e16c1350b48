// stipple core — the view-dependent cut (TOG05 §7, Fig. 10): which nodes of
// a tree a client needs for a camera, and what changed since the last camera.
//
// Rule, for one camera: start at the root; a node is *split* (replaced by
// its children) when it is visible, has children, its projected radius
// gamma * sigma_p1 * f / Z exceeds `max_size_q4` (2 px by default, the
// paper's threshold) or it reaches behind the near plane, and — with a
// refinement window — its projected circle meets the window. Splits go
// largest projected size first (ties: smaller id), so under a node budget
// the cut is coarser where nodes are smallest on screen: a split that would
// take the sent nodes past `max_nodes` ends the refinement. The cut is an
// antichain covering the tree; its *sent* nodes are the visible ones. A node
// is culled (in the cut, not sent) when it lies wholly behind the near plane,
// outside the view frustum (its sphere of radius gamma * sigma_p1) or, with
// normals, faces away from the eye (its normal cone, ConeRule, widened by
// the angle its sphere subtends, points away).
//
// The cut is persistent: update() re-derives it from the root through a
// table of per-node bounds built once at init (no node is decoded per
// update), visiting the cut and the nodes above it — time in proportion to
// the cut, never to the tree — and reports the nodes that entered and left
// the sent set since the previous update, which is what a server streams.
// The result depends on the camera and parameters only, never on earlier
// cameras: an updated cut equals a fresh one. Integer only, no heap, no
// exceptions; storage comes from the caller (view_cut_bytes).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "core/node_format.h"
#include "core/spg_format.h"

namespace stipple {

struct CutParams {
  int32_t max_size_q4 = 32;        // split above this projected radius (1/16 px)
  uint32_t max_nodes = 0xFFFFFFFFu;  // most sent nodes (the client's cache capacity)
  bool cull_frustum = true;
  bool cull_backfaces = true;      // needs normals in the file (the cones: ConeRule)
  uint16_t width = 240, height = 320;  // the screen the camera projects to (px)
  // On-demand refinement (TOG05 §8.1): only nodes whose projected circle
  // meets [x0, x1) x [y0, y1) (px) are split; empty (x0 >= x1): everywhere.
  int32_t window[4] = {0, 0, 0, 0};
};

// The normal cones back faces are culled by, fixed per model (CutBounds).
// A leaf's cone has half-angle leaf_gamma * sigma_n1; an internal node's is
// the narrower of gamma * sigma_n1 and the cone about its mean normal that
// holds its children's cones — so it holds every leaf cone below it, and a
// node is culled only when all of them face away. The trade between nodes
// removed and silhouette pixels lost, per leaf gamma, is in docs/cut.md.
struct ConeRule {
  uint16_t gamma_q8 = 896;       // 3.5, the paper's gamma (Q8)
  uint16_t leaf_gamma_q8 = 256;  // 1.0 (Q8)
};

enum class CutStatus : uint8_t {
  kOk = 0,
  kStorageTooSmall,  // init: fewer bytes than view_cut_bytes
  kBadView,          // init: a node fails to decode, or 2^31 nodes or more (never for a view spg_parse accepted)
  kNotReady,         // update before a successful init
};

// The per-node bounds a cut is derived from (36 bytes a node), built once
// per model and shared, read-only, by every client's cut.
class CutBounds {
 public:
  static size_t bytes(const SpgHeader& header);
  // `view` from spg_parse, `decoder` initialised on it; both are read during
  // init only.
  [[nodiscard]] CutStatus init(const SpgView& view, const NodeDecoder& decoder, void* storage, size_t bytes,
                               const ConeRule& cones = {});
  uint32_t node_count() const { return node_count_; }

 private:
  friend class ViewCut;
  const void* bounds_ = nullptr;
  uint32_t node_count_ = 0;
  bool normals_ = false;
};

// Storage for one cut of a tree of `header.node_count` nodes: with its own
// bounds, 68 1/4 bytes a node (view_cut_bytes); over shared bounds, 32 1/4
// (view_cut_state_bytes).
size_t view_cut_bytes(const SpgHeader& header);
size_t view_cut_state_bytes(const SpgHeader& header);

class ViewCut {
 public:
  // `view` from spg_parse, `decoder` initialised on it; both are read during
  // init only. Builds its own bounds table; the cut starts empty.
  [[nodiscard]] CutStatus init(const SpgView& view, const NodeDecoder& decoder, void* storage, size_t bytes,
                               const ConeRule& cones = {});
  // Over shared bounds, which must outlive the cut.
  [[nodiscard]] CutStatus init(const CutBounds& bounds, void* storage, size_t bytes);

  // Forgets the sent set (the next update reports every sent node as entered).
  void reset();

  // Re-derives the cut for `camera`; entered() and left() are the change of
  // the sent set since the previous update (everything, the first time).
  [[nodiscard]] CutStatus update(const Camera& camera, const CutParams& params);

  // The sent nodes, in id (breadth-first) order, and each one's projected
  // radius (1/16 px; what the client's points-per-node table is indexed by).
  uint32_t sent_count() const { return sent_count_; }
  // The original points under a node (its leaves' counts from the file),
  // saturated at 255; 0 when the view had no leaf counts. `id` below the
  // node count.
  uint8_t points(NodeId id) const;
  const NodeId* sent() const { return sent_; }
  const uint32_t* sent_size_q4() const { return sent_size_; }
  // Every node of the cut, culled ones included (update's order).
  uint32_t cut_count() const { return cut_count_; }
  const NodeId* cut() const { return cut_; }
  uint32_t culled_count() const { return cut_count_ - sent_count_; }
  // The change since the previous update.
  uint32_t entered_count() const { return entered_count_; }
  const NodeId* entered() const { return entered_; }
  uint32_t left_count() const { return left_count_; }
  const NodeId* left() const { return left_; }
  bool is_sent(NodeId id) const { return (sent_bits_[index_of(id) >> 3] >> (index_of(id) & 7)) & 1u; }
  // Nodes visited by the last update (the cost: the cut and the nodes above it).
  uint32_t visited() const { return visited_; }
  uint32_t node_count() const { return node_count_; }

  struct Bound;

 private:
  struct Eval;
  struct Frame;  // one update's camera, parameters and what follows from them
  Eval evaluate(const Frame& f, uint32_t node, bool inside) const;
  void heap_push(uint32_t size, uint32_t node);
  uint64_t heap_pop();

  CutBounds own_;  // when init built the bounds itself
  const Bound* bounds_ = nullptr;
  uint32_t node_count_ = 0;
  bool normals_ = false;
  uint8_t* sent_bits_ = nullptr;   // the sent set of the last update
  uint8_t* fresh_bits_ = nullptr;  // scratch: the sent set being made
  NodeId* cut_ = nullptr;
  NodeId* sent_ = nullptr;
  NodeId* previous_ = nullptr;  // the previous update's sent nodes
  uint32_t* sent_size_ = nullptr;
  NodeId* entered_ = nullptr;
  NodeId* left_ = nullptr;
  uint64_t* heap_ = nullptr;  // (size << 32 | ~id): the largest size first, then the smallest id
  uint32_t heap_count_ = 0;
  uint32_t cut_count_ = 0, sent_count_ = 0, previous_count_ = 0, entered_count_ = 0, left_count_ = 0, visited_ = 0;
  bool ready_ = false;
};

}  // namespace stipple
