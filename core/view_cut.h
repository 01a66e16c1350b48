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
// exceptions; storage comes from the caller.
//
// Storage is in three parts, so that a server's cost per client follows
// what the client sees, never the model's size:
//   CutBounds   per node, built once per model, shared read-only (36 B/node);
//   the state   per cut: its sent set, ids as LEB128 differences (1-2
//               bytes a sent node for a screen's cut) — all that
//               persists from one update to the next;
//   CutScratch  what one update works in (the whole cut, the new sent set
//               and sizes, the change, the queue: 32 bytes a cut node);
//               cuts updated one at a time (one thread) may share one, and
//               what a cut reports from it (cut(), sent_size_q4(),
//               entered(), left()) holds until the next update through it.
//   the front  per cut, only for incremental updates (use_front): the cut
//              and the nodes above it with when each must be looked at
//              again (16 bytes a node of the front).
// A cut or a sent set larger than its storage makes update() refuse with
// kStorageTooSmall, leaving the cut as it was; the caller grows the storage
// (relocate, a larger scratch) and updates again. view_cut_bytes(header)
// sizes all three for a whole tree in one block: that never refuses.
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
  // With a window, on-demand accumulation (TOG05 §8.1): a node above a node
  // the previous update sent stays split (where the rule splits it), inside
  // the window or not — the refinements of earlier windows are kept, and the
  // change is only what the new window adds.
  bool accumulate = false;
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
  kStorageTooSmall,  // init: fewer bytes than asked for; update: the cut or the sent set outgrew its storage
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
  bool normals() const { return normals_; }
  // The table init built (bytes(header) of it: 36 bytes a node, the host's
  // little-endian layout) — what a cut table file holds (core/cut_table.h).
  const void* table() const { return bounds_; }
  // Takes a table made by init for `view` (from a cut table file: mapped,
  // not copied) after checking what a cut's safety rests on: each node's
  // children and first child against the view's topology, its points
  // against the leaf counts, its radii (0 <= radius <= subtree radius <=
  // 2^30) and cone (0 .. 0x7FFF), and padding zero. Its other numbers
  // (centres, normals) are trusted: wrong ones give a wrong cut, never a
  // fault. kBadView: the first bad node in *bad_node, the field's name in
  // *bad_field.
  [[nodiscard]] CutStatus attach(const SpgView& view, const void* table, size_t bytes, uint32_t* bad_node,
                                 const char** bad_field);

 private:
  friend class ViewCut;
  const void* bounds_ = nullptr;
  uint32_t node_count_ = 0;
  bool normals_ = false;
};

// Scratch for updates of cuts of up to `capacity` nodes (culled ones
// included): 32 bytes a node. Shared by cuts updated one at a time.
struct CutScratch {
  static size_t bytes(uint32_t capacity);
  // The capacity `bytes` of storage gives (at most 2^31 - 1).
  void init(void* storage, size_t bytes);
  void* storage = nullptr;
  uint32_t capacity = 0;
};

// Storage a cut keeps between updates for up to `sent` sent nodes, at the
// most (the ids are kept as LEB128 differences: one or two bytes each for a
// screen's cut, five at worst); sent_set_bytes: what `ids` (ascending) take.
size_t view_cut_state_bytes(uint32_t sent);
size_t sent_set_bytes(const NodeId* ids, uint32_t count);
// One block for a cut of any camera over a whole tree of `header.node_count`
// nodes with its own bounds, state and scratch (73 bytes a node).
size_t view_cut_bytes(const SpgHeader& header);

class ViewCut {
 public:
  // `view` from spg_parse, `decoder` initialised on it; both are read during
  // init only. One block (view_cut_bytes): its own bounds, state and scratch
  // for the whole tree. The cut starts empty.
  [[nodiscard]] CutStatus init(const SpgView& view, const NodeDecoder& decoder, void* storage, size_t bytes,
                               const ConeRule& cones = {});
  // Over shared bounds and scratch, which must outlive the cut (the scratch
  // may be replaced with use_scratch); `state` holds view_cut_state_bytes(n)
  // for a sent set of up to n nodes (zero bytes is allowed: grow it later).
  [[nodiscard]] CutStatus init(const CutBounds& bounds, void* state, size_t state_bytes, const CutScratch* scratch);
  void use_scratch(const CutScratch* scratch) { scratch_ = scratch; }

  // Incremental updates (TOG05 Fig. 10): with a front, an update starts from
  // the previous cut and looks again only at the nodes whose decision the
  // camera's motion since they were last evaluated may have changed (each
  // has a deadline from its margins and a bound on how fast the camera
  // moves them), splitting and merging there — work in proportion to the
  // change, not the cut. The cut is the from-the-root cut of the same
  // camera, node for node; where that one is bounded by the budget (or
  // refines in a window) update() derives it from the root instead. Without
  // sizes: sent_size_q4() and cut() are not kept (null) in this mode.
  static size_t front_bytes(uint32_t nodes) { return 16 * size_t{nodes}; }
  // `storage` for a front of up to bytes / 16 nodes (null: incremental off);
  // the next update derives the front from the root.
  void use_front(void* storage, size_t bytes);
  // Moves the front to larger storage; false (nothing moved) when it does not fit.
  [[nodiscard]] bool relocate_front(void* storage, size_t bytes);
  uint32_t front_count() const { return front_count_; }
  uint32_t front_capacity() const { return front_capacity_; }
  // Evaluations of nodes by the last update (from the root: every node visited).
  uint32_t evaluated() const { return evaluated_; }
  bool last_was_incremental() const { return last_incremental_; }
  // Moves the sent set into new state storage (larger, to follow a growing
  // cut); false, and nothing moved, when it does not hold the present set.
  [[nodiscard]] bool relocate(void* state, size_t state_bytes);
  size_t state_bytes() const { return state_bytes_; }  // the state storage's size
  size_t state_used() const { return state_used_; }    // what the sent set takes of it

  // Forgets the sent set (the next update reports every sent node as entered).
  void reset();
  // Takes `ids` (ascending, each below the node count) as the sent set a
  // client already holds (a resumed stream): the next update reports the
  // change from them. False, and the cut reset, when they are not ascending
  // or in range, or more than the state holds.
  [[nodiscard]] bool adopt_sent(const NodeId* ids, uint32_t count);

  // Re-derives the cut for `camera`; entered() and left() are the change of
  // the sent set since the previous update (everything, the first time).
  // kStorageTooSmall: the cut outgrew the scratch or the sent set the
  // state; nothing changed (needed_capacity() says how far it got).
  [[nodiscard]] CutStatus update(const Camera& camera, const CutParams& params);

  // The sent nodes, in id (breadth-first) order, and each one's projected
  // radius (1/16 px; what the client's points-per-node table is indexed by).
  uint32_t sent_count() const { return sent_count_; }
  // The original points under a node (its leaves' counts from the file),
  // saturated at 255; 0 when the view had no leaf counts. `id` below the
  // node count.
  uint8_t points(NodeId id) const;
  // The id of the node's first child (a leaf's: where its children would
  // start; node_count() for id == node_count()). A node's descendants at
  // each level below it are one id range: from first_child(lo) to
  // first_child(hi) for the range [lo, hi) above, starting from [id, id + 1).
  uint32_t first_child(uint32_t id) const;
  // The sent set decoded, in the scratch: valid until the next update
  // through it (null before the first update, and after adopt_sent).
  const NodeId* sent() const { return sent_; }
  const uint32_t* sent_size_q4() const { return sent_size_; }
  // Every node of the cut, culled ones included (update's order).
  uint32_t cut_count() const { return cut_count_; }
  const NodeId* cut() const { return cut_; }
  uint32_t culled_count() const { return cut_count_ - sent_count_; }
  // The change since the previous update (in id order when the update came
  // from the root: whenever sent_size_q4() is kept).
  uint32_t entered_count() const { return entered_count_; }
  const NodeId* entered() const { return entered_; }
  uint32_t left_count() const { return left_count_; }
  const NodeId* left() const { return left_; }
  bool is_sent(NodeId id) const;  // a binary search of sent()
  // Nodes visited by the last update (the cost: the cut and the nodes above it).
  uint32_t visited() const { return visited_; }
  uint32_t node_count() const { return node_count_; }
  // After kStorageTooSmall: the cut nodes or sent nodes it reached, a lower
  // bound on the capacity the refused update needs (needed_front(): the
  // front's).
  uint32_t needed_capacity() const { return needed_; }
  uint32_t needed_front() const { return needed_front_; }
  size_t needed_state_bytes() const { return needed_state_; }  // the state's, in bytes

  struct Bound;
  struct FrontNode;

 private:
  struct Eval;
  struct Frame;  // one update's camera, parameters and what follows from them
  struct Due;
  Eval evaluate(const Frame& f, uint32_t node, bool inside) const;
  bool above_previous(uint32_t node) const;  // a node the previous update sent lies below it (accumulation)
  CutStatus derive(Frame& frame, const CutParams& params);  // from the root
  CutStatus keep_sent(const NodeId* fresh, uint32_t fresh_count);
  Due evaluate_due(const Frame& f, uint32_t node) const;
  CutStatus update_incremental(Frame& frame, const CutParams& params, bool rebuild);
  bool same_setting(const Camera& camera, const CutParams& params) const;
  void heap_push(uint32_t size, uint32_t node);
  uint64_t heap_pop();

  CutBounds own_;        // when init built the bounds itself
  CutScratch own_scratch_;  // and its scratch
  const Bound* bounds_ = nullptr;
  const CutScratch* scratch_ = nullptr;
  uint32_t node_count_ = 0;
  bool normals_ = false;
  uint8_t* state_ = nullptr;  // the state: the sent set of the last update (LEB128 differences)
  size_t state_bytes_ = 0, state_used_ = 0, needed_state_ = 0;
  const NodeId* sent_ = nullptr;  // the same, decoded, in the scratch
  // In the scratch, valid until the next update through it.
  NodeId* cut_ = nullptr;
  uint32_t* sent_size_ = nullptr;
  NodeId* entered_ = nullptr;
  NodeId* left_ = nullptr;
  uint64_t* heap_ = nullptr;  // (size << 32 | ~id): the largest size first, then the smallest id
  const uint32_t* previous_ = nullptr;  // accumulation: the previous sent set, decoded (the scratch's last 4 bytes a node)
  uint32_t previous_count_ = 0;
  uint32_t heap_count_ = 0;
  uint32_t unheaped_ = 0;  // the budget's pass: nodes larger than this split without the heap (0: none)
  uint32_t cut_count_ = 0, sent_count_ = 0, entered_count_ = 0, left_count_ = 0, visited_ = 0, needed_ = 0;
  // Incremental mode: the front (ids ascending), the clock its deadlines
  // are on, and the camera and parameters it was made for.
  FrontNode* front_ = nullptr;
  uint32_t front_count_ = 0, front_capacity_ = 0, needed_front_ = 0, evaluated_ = 0;
  bool front_valid_ = false, budget_bound_ = false, last_incremental_ = false, has_previous_ = false;
  uint32_t clock_ = 0;  // motion since the front was derived, in 1/1024 paces
  int64_t pace_turn_ = 1, pace_shift_ = 1, pace_eye_ = 1;        // what a pace stands for (Q14; MU; MU)
  int64_t motion_turn_ = 0, motion_shift_ = 0, motion_eye_ = 0;  // the last step's, to set the paces by
  Camera previous_camera_{};
  CutParams previous_params_{};
  bool ready_ = false;
};

}  // namespace stipple
