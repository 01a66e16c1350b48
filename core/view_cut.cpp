// stipple core — the view-dependent cut. See view_cut.h; the measurements
// are in docs/figures.md.
#include "core/view_cut.h"

#include "core/arena.h"

#include <algorithm>

#include "core/cut.h"
#include "core/fixed_trig.h"
#include "core/gaussian_table.h"

namespace stipple {

struct ViewCut::Bound {
  int32_t center[3];     // MU
  int32_t radius;        // gamma * sigma_p1, MU
  int32_t subtree_radius;  // about the centre, holds this sphere and every descendant's (MU)
  uint32_t first_child;  // id of the first child (children are adjacent)
  int16_t normal[3];     // mean normal, Q14 (zero without normals)
  int16_t cone_sin_q14;  // sin of the normal cone's half-angle (CutBounds::init); 0x7FFF: none
  uint16_t pad0;
  uint8_t children;
  uint8_t points;        // original points under the node, saturated at 255 (0: the file did not say)
};
static_assert(sizeof(ViewCut::Bound) == 36);

struct ViewCut::Eval {
  bool visible;   // to be sent if it stays in the cut
  bool split;     // to be replaced by its children
  bool inside;    // its subtree sphere is wholly in the frustum and before the near plane
  uint32_t size;  // projected radius, 1/16 px (saturated)
};

namespace {

constexpr int32_t kNoCone = 0x7FFF;
constexpr uint32_t kInside = 0x80000000u;  // in the breadth-first queue: the node's subtree is wholly visible

// A normal cone's half-angle below a quarter turn as its sine and cosine
// (Q14); sin == kNoCone: a quarter turn or more (no cone).
struct Cone {
  int32_t sin, cos;
};

// The cone of half-angle gamma * sigma_n1 (sigma_n1 in Q12 radians, gamma
// Q8), as a binary angle: 2^32 / (2 pi) = 683565275.6 per radian.
Cone statistical_cone(int32_t sigma_n1_q12, uint16_t gamma_q8) {
  const int64_t sigma = sigma_n1_q12 < 0 ? 0 : sigma_n1_q12 > 0xFFFF ? 0xFFFF : sigma_n1_q12;
  const int64_t binary = ((sigma * gamma_q8 >> 8) * 683565276) >> 12;
  if (binary >= (int64_t{1} << 30)) return Cone{kNoCone, 0};
  const SinCosQ14 sc = sincos_q14(static_cast<uint32_t>(binary));
  return Cone{sc.sin, sc.cos};
}

// The cone about `axis` that holds the cone `c` about `n` (unit Q14
// vectors): half-angle angle(axis, n) + c's, rounded outwards (sines up,
// cosines down), so it only ever grows.
Cone widened(const int16_t axis[3], const int16_t n[3], Cone c) {
  if (c.sin == kNoCone) return c;
  int64_t dot = (int64_t{axis[0]} * n[0] + int64_t{axis[1]} * n[1] + int64_t{axis[2]} * n[2]) >> 14;  // floor
  if (dot > kQ14One) dot = kQ14One;
  if (dot <= 0) return Cone{kNoCone, 0};
  const int64_t sin_t = static_cast<int64_t>(isqrt64(static_cast<uint64_t>((int64_t{kQ14One} * kQ14One) - dot * dot))) + 1;
  const int64_t cos_sum = (dot * c.cos - sin_t * c.sin) >> 14;  // floor
  if (cos_sum <= 0) return Cone{kNoCone, 0};
  const int64_t sin_sum = ((sin_t * c.cos + dot * c.sin) >> 14) + 1;
  return sin_sum >= kQ14One ? Cone{kNoCone, 0} : Cone{static_cast<int32_t>(sin_sum), static_cast<int32_t>(cos_sum)};
}

}  // namespace

size_t CutBounds::bytes(const SpgHeader& header) { return align8(sizeof(ViewCut::Bound) * header.node_count); }
// The scratch of capacity C: cut, fresh sent set, sizes, entered, left (4 C
// each), then the heap (8 C; the breadth-first queue, a ring of 2 C ids, in
// its place).
size_t CutScratch::bytes(uint32_t capacity) { return 28 * size_t{capacity}; }

void CutScratch::init(void* at, size_t size) {
  storage = at;
  const size_t c = size / 28;
  capacity = c > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(c);
}

size_t view_cut_state_bytes(uint32_t sent) { return align8(4 * size_t{sent}); }
size_t view_cut_bytes(const SpgHeader& header) {
  return CutBounds::bytes(header) + view_cut_state_bytes(header.node_count) + CutScratch::bytes(header.node_count);
}

CutStatus CutBounds::init(const SpgView& view, const NodeDecoder& decoder, void* storage, size_t bytes,
                          const ConeRule& cones) {
  bounds_ = nullptr;
  const uint32_t n = view.header.node_count;
  if (n >= kInside) return CutStatus::kBadView;  // the queue's flag bit (a file holds far fewer)
  if (bytes < CutBounds::bytes(view.header)) return CutStatus::kStorageTooSmall;
  using Bound = ViewCut::Bound;
  Bound* bounds = static_cast<Bound*>(storage);
  normals_ = view.header.has_normals();
  uint32_t next_child = 1;
  for (uint32_t i = 0; i < n; ++i) {
    FixedNode node;
    if (decoder.decode(view.records + size_t{i} * view.record_bytes, &node) != DecodeStatus::kOk)
      return CutStatus::kBadView;
    Bound& b = bounds[i];
    for (int k = 0; k < 3; ++k) {
      b.center[k] = node.mean[k];
      b.normal[k] = node.normal_frame[2][k];
    }
    b.radius = node_radius_mu(node);
    b.children = static_cast<uint8_t>(spg_child_count(view, i));
    b.first_child = next_child;
    next_child += b.children;
    b.pad0 = 0;
    b.points = 0;
    // The statistical cone for now (its sine, and its cosine in pad0's
    // place until the pass below).
    // A node of no extent (coincident points) has no surface to face away:
    // it is never back-face culled (its normal is the estimator's guess).
    const Cone cone = normals_ && b.radius > 0
                          ? statistical_cone(node.sigma_n[0], b.children ? cones.gamma_q8 : cones.leaf_gamma_q8)
                          : Cone{kNoCone, 0};
    b.cone_sin_q14 = static_cast<int16_t>(cone.sin);
    b.pad0 = static_cast<uint16_t>(cone.cos);
  }
  // Original points under each node, saturated (what clients cap by).
  spg_node_points(view, &bounds[0].points, sizeof(Bound));
  // Bottom up (children come after their parents): the sphere about each
  // centre that holds its own and every descendant's, padded for the
  // rounding of the camera transform (its rows' lengths are within 2^-12 of
  // one), so a subtree found wholly visible holds only nodes that are.
  for (uint32_t i = n; i-- > 0;) {
    Bound& b = bounds[i];
    int64_t big = b.radius;
    for (uint32_t k = 0; k < b.children; ++k) {
      const Bound& c = bounds[b.first_child + k];
      uint64_t d2 = 0;
      for (int a = 0; a < 3; ++a) {
        const int64_t d = int64_t{c.center[a]} - b.center[a];
        d2 += static_cast<uint64_t>(d * d);
      }
      const int64_t reach = static_cast<int64_t>(isqrt64(d2)) + 1 + c.subtree_radius;
      if (reach > big) big = reach;
    }
    big += (big >> 10) + 4;
    b.subtree_radius = big > (int64_t{1} << 30) ? (1 << 30) : static_cast<int32_t>(big);
  }
  if (normals_) {
    // Bottom up (children come after their parents): an internal node's
    // cone is the narrower of its statistical one and the cone about its
    // normal that holds every child's.
    for (uint32_t i = n; i-- > 0;) {
      Bound& b = bounds[i];
      if (b.children > 0) {
        Cone hull{0, kQ14One};
        for (uint32_t k = 0; k < b.children && hull.sin != kNoCone; ++k) {
          const Bound& c = bounds[b.first_child + k];
          const Cone w = widened(b.normal, c.normal, Cone{c.cone_sin_q14, c.pad0});
          if (w.sin > hull.sin) hull = w;  // below a quarter turn the sine orders the angles
        }
        if (hull.sin < b.cone_sin_q14) {
          b.cone_sin_q14 = static_cast<int16_t>(hull.sin);
          b.pad0 = static_cast<uint16_t>(hull.cos);
        }
      }
    }
    for (uint32_t i = 0; i < n; ++i) bounds[i].pad0 = 0;
  }
  bounds_ = bounds;
  node_count_ = n;
  return CutStatus::kOk;
}

CutStatus ViewCut::init(const SpgView& view, const NodeDecoder& decoder, void* storage, size_t bytes,
                        const ConeRule& cones) {
  ready_ = false;
  const uint32_t n = view.header.node_count;
  const size_t bound_bytes = CutBounds::bytes(view.header), state_bytes = view_cut_state_bytes(n);
  if (bytes < view_cut_bytes(view.header)) return CutStatus::kStorageTooSmall;
  const CutStatus s = own_.init(view, decoder, storage, bound_bytes, cones);
  if (s != CutStatus::kOk) return s;
  uint8_t* state = static_cast<uint8_t*>(storage) + bound_bytes;
  own_scratch_.init(state + state_bytes, CutScratch::bytes(n));
  return init(own_, state, state_bytes, &own_scratch_);
}

CutStatus ViewCut::init(const CutBounds& shared, void* state, size_t state_bytes, const CutScratch* scratch) {
  ready_ = false;
  if (shared.bounds_ == nullptr) return CutStatus::kNotReady;
  bounds_ = static_cast<const Bound*>(shared.bounds_);
  node_count_ = shared.node_count_;
  normals_ = shared.normals_;
  scratch_ = scratch;
  sent_ = static_cast<NodeId*>(state);
  const size_t c = state_bytes / 4;
  state_capacity_ = c > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(c);
  cut_ = entered_ = left_ = nullptr;
  sent_size_ = nullptr;
  heap_ = nullptr;
  cut_count_ = sent_count_ = entered_count_ = left_count_ = visited_ = needed_ = 0;
  ready_ = true;
  return CutStatus::kOk;
}

bool ViewCut::relocate(void* state, size_t state_bytes) {
  if (state_bytes / 4 < sent_count_) return false;
  NodeId* to = static_cast<NodeId*>(state);
  std::copy(sent_, sent_ + sent_count_, to);
  sent_ = to;
  const size_t c = state_bytes / 4;
  state_capacity_ = c > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(c);
  return true;
}

uint8_t ViewCut::points(NodeId id) const { return bounds_[index_of(id)].points; }

bool ViewCut::is_sent(NodeId id) const {
  uint32_t lo = 0, hi = sent_count_;
  const uint32_t want = index_of(id);
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (index_of(sent_[mid]) < want) lo = mid + 1;
    else hi = mid;
  }
  return lo < sent_count_ && index_of(sent_[lo]) == want;
}

void ViewCut::reset() { cut_count_ = sent_count_ = entered_count_ = left_count_ = visited_ = needed_ = 0; }

struct ViewCut::Frame {
  const Camera& camera;
  const CutParams& params;
  int64_t hyp_x, hyp_y;  // |(f, cx)| and |(f, cy)|: the side planes' normals' lengths, Q4, rounded up
  bool split_sizes;      // a node that splits needs its size too (the budget's pass)
  // camera_space as one affine map: c = (R p + t) >> 14 with t = 2^13 - R eye
  // (the same integers: R (p - eye) is exact in 64 bits).
  int64_t rotation[3][3];
  int64_t offset[3];
  int64_t eye[3], focal, cx, cy, near, max_size;  // the camera's and parameters' values, widened
  bool cull_frustum, cull_backfaces, window;
};

// `inside`: an ancestor's subtree sphere was wholly in the frustum and
// before the near plane, so this node's sphere is too (its tests would pass).
[[gnu::always_inline]] inline ViewCut::Eval ViewCut::evaluate(const Frame& f, uint32_t id, bool inside) const {
  const Bound& b = bounds_[id];
  Eval e{false, false, inside, 0};
  const int64_t p0 = b.center[0], p1 = b.center[1], p2 = b.center[2];
  const int64_t z = (f.rotation[2][0] * p0 + f.rotation[2][1] * p1 + f.rotation[2][2] * p2 + f.offset[2]) >> 14;
  const int64_t r = b.radius;
  bool crosses_near = false;
  int64_t x = 0, y = 0;
  if (!inside) {
    if (z + r < f.near) return e;  // wholly behind the near plane
    crosses_near = z - r < f.near;
    const int64_t big = b.subtree_radius;
    e.inside = z - big >= f.near;
    if (!crosses_near && f.cull_frustum) {
      // Planes through the eye and the screen's edges: f X = +-cx Z, f Y = +-cy Z.
      x = (f.rotation[0][0] * p0 + f.rotation[0][1] * p1 + f.rotation[0][2] * p2 + f.offset[0]) >> 14;
      const int64_t fx = f.focal * x, cxz = f.cx * z;
      if (fx - cxz > r * f.hyp_x || -fx - cxz > r * f.hyp_x) return e;
      y = (f.rotation[1][0] * p0 + f.rotation[1][1] * p1 + f.rotation[1][2] * p2 + f.offset[1]) >> 14;
      const int64_t fy = f.focal * y, cyz = f.cy * z;
      if (fy - cyz > r * f.hyp_y || -fy - cyz > r * f.hyp_y) return e;
      // The same planes for the subtree's sphere, on the inside.
      const int64_t bx = -big * f.hyp_x, by = -big * f.hyp_y;
      e.inside = e.inside && fx - cxz <= bx && -fx - cxz <= bx && fy - cyz <= by && -fy - cyz <= by;
    }
  }
  const int64_t sin_a = b.cone_sin_q14;
  if (f.cull_backfaces && sin_a < kQ14One) {
    // Facing away: the angle between the normal and d = eye - centre exceeds
    // 90 degrees + alpha (the cone's half-angle) + beta (the angle the sphere
    // subtends, sin beta = r / |d|). Conservatively, with sin(alpha + beta)
    // <= sin alpha + sin beta and an upper bound L >= |d|:
    //   cos(n, d) < -(sin alpha + r / L)  <=  n . d < -(sin alpha L + r)
    // (Q14 x MU). No square root or trigonometry per update.
    const int64_t d0 = f.eye[0] - p0, d1 = f.eye[1] - p1, d2 = f.eye[2] - p2;
    const int64_t dot = b.normal[0] * d0 + b.normal[1] * d1 + b.normal[2] * d2;
    if (dot < 0) {
      // |d| <= m + (a + b) / 2 for the largest |component| m and the others a, b.
      const int64_t a0 = d0 < 0 ? -d0 : d0, a1 = d1 < 0 ? -d1 : d1, a2 = d2 < 0 ? -d2 : d2;
      const int64_t m = a0 > a1 ? (a0 > a2 ? a0 : a2) : (a1 > a2 ? a1 : a2);
      const int64_t len = m + (a0 + a1 + a2 - m + 1) / 2;
      if (dot < -(sin_a * len + (r << 14))) return e;
    }
  }
  e.visible = true;
  if (crosses_near) {  // as large as it gets; split whenever it can be
    e.size = 0xFFFFFFFFu;
    e.split = b.children > 0;
    return e;
  }
  // Projected radius r f / Z (1/16 px), saturated; the split compares the
  // products (below 2^52), as the simple cut does, and the division is made
  // only where the size is needed: for a node that settles (its points-per-
  // node index) or, under a binding budget, one that splits (its heap key).
  const int64_t rf = r * f.focal;
  const auto projected = [&] {
    const int64_t size = rf / z;
    return size > 0xFFFFFFFE ? 0xFFFFFFFEu : static_cast<uint32_t>(size);
  };
  e.split = b.children > 0 && rf > f.max_size * z;
  if (e.split && f.window) {
    // Only inside the refinement window: the projected circle must meet it.
    const CutParams& p = f.params;
    if (!f.cull_frustum || inside) {
      x = (f.rotation[0][0] * p0 + f.rotation[0][1] * p1 + f.rotation[0][2] * p2 + f.offset[0]) >> 14;
      y = (f.rotation[1][0] * p0 + f.rotation[1][1] * p1 + f.rotation[1][2] * p2 + f.offset[1]) >> 14;
    }
    const int64_t size = projected();
    const int64_t sx = f.cx + f.focal * x / z, sy = f.cy + f.focal * y / z;
    e.split = sx + size >= int64_t{p.window[0]} * 16 && sx - size < int64_t{p.window[2]} * 16 &&
              sy + size >= int64_t{p.window[1]} * 16 && sy - size < int64_t{p.window[3]} * 16;
  }
  if (!e.split || f.split_sizes) e.size = projected();
  return e;
}

void ViewCut::heap_push(uint32_t size, uint32_t node) {
  uint64_t v = (uint64_t{size} << 32) | (~node & 0xFFFFFFFFu);
  uint32_t i = heap_count_++;
  while (i > 0 && heap_[(i - 1) / 2] < v) {
    heap_[i] = heap_[(i - 1) / 2];
    i = (i - 1) / 2;
  }
  heap_[i] = v;
}

uint64_t ViewCut::heap_pop() {
  const uint64_t top = heap_[0], last = heap_[--heap_count_];
  uint32_t i = 0;
  for (;;) {
    uint32_t c = 2 * i + 1;
    if (c >= heap_count_) break;
    if (c + 1 < heap_count_ && heap_[c + 1] > heap_[c]) ++c;
    if (heap_[c] <= last) break;
    heap_[i] = heap_[c];
    i = c;
  }
  if (heap_count_ > 0) heap_[i] = last;
  return top;
}

CutStatus ViewCut::update(const Camera& camera, const CutParams& params) {
  if (!ready_) return CutStatus::kNotReady;
  const auto hyp = [&](int32_t c) {
    return static_cast<int64_t>(isqrt64(static_cast<uint64_t>(int64_t{camera.focal_q4} * camera.focal_q4 + int64_t{c} * c))) + 1;
  };
  Frame frame{camera,
              params,
              hyp(camera.center_q4[0]),
              hyp(camera.center_q4[1]),
              false,
              {},
              {},
              {camera.eye[0], camera.eye[1], camera.eye[2]},
              camera.focal_q4,
              camera.center_q4[0],
              camera.center_q4[1],
              camera.near_mu,
              params.max_size_q4,
              params.cull_frustum,
              params.cull_backfaces && normals_,
              params.window[0] < params.window[2]};
  for (int k = 0; k < 3; ++k) {
    frame.offset[k] = 1 << 13;
    for (int j = 0; j < 3; ++j) {
      frame.rotation[k][j] = camera.rotation[k][j];
      frame.offset[k] -= int64_t{camera.rotation[k][j]} * camera.eye[j];
    }
  }
  // Everything is made in the scratch; the state (the sent set) changes only
  // once the new cut is whole, so a refusal leaves the cut as it was.
  if (scratch_ == nullptr || scratch_->storage == nullptr) return CutStatus::kNotReady;
  const uint32_t capacity = scratch_->capacity;
  needed_ = 0;
  if (sent_count_ > capacity) {  // the change is listed in the scratch
    needed_ = sent_count_;
    return CutStatus::kStorageTooSmall;
  }
  uint8_t* base = static_cast<uint8_t*>(scratch_->storage);
  cut_ = reinterpret_cast<NodeId*>(base);
  NodeId* fresh = cut_ + capacity;
  sent_size_ = reinterpret_cast<uint32_t*>(fresh + capacity);
  entered_ = reinterpret_cast<NodeId*>(sent_size_ + capacity);
  left_ = entered_ + capacity;
  heap_ = reinterpret_cast<uint64_t*>(left_ + capacity);
  const auto too_large = [&](uint64_t reached) {
    needed_ = reached > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(reached);
    cut_count_ = entered_count_ = left_count_ = 0;
    return CutStatus::kStorageTooSmall;
  };
  uint32_t cut_count = 0, fresh_count = 0;
  heap_count_ = 0;
  visited_ = 0;

  const auto settle = [&](uint32_t id, const Eval& e) {
    cut_[cut_count++] = NodeId{id};
    if (e.visible) {
      fresh[fresh_count] = NodeId{id};
      sent_size_[fresh_count++] = e.size;
    }
  };
  // Without a binding budget every splittable node splits, in any order:
  // breadth first, which settles the nodes in id order (ids are breadth-first,
  // children adjacent in their parents' order), so no sort is needed. The
  // queue is a ring in the heap's place: what waits in it and what settled
  // are never more than the finished cut, so 2 C ids hold it.
  uint32_t* queue = reinterpret_cast<uint32_t*>(heap_);
  const uint64_t ring = 2 * uint64_t{capacity};
  uint64_t head = 0, tail = 0;
  if (capacity == 0) return too_large(1);
  queue[tail++] = 0;
  // A binding budget stops it early (too many sent, or too many visited for
  // the budget: the greedy pass then costs what the budget allows).
  const uint64_t visit_limit = 4 * uint64_t{params.max_nodes} + 8;
  {
    uint32_t visited = 0;
    while (head < tail && fresh_count <= params.max_nodes && visited <= visit_limit) {
      const uint32_t id = queue[head++ % ring];
      ++visited;
      const Eval e = evaluate(frame, id & ~kInside, id & kInside);
      if (!e.split) {
        cut_[cut_count++] = NodeId{id & ~kInside};
        if (e.visible) {
          fresh[fresh_count] = NodeId{id & ~kInside};
          sent_size_[fresh_count++] = e.size;
        }
        continue;
      }
      const Bound& b = bounds_[id & ~kInside];
      if (cut_count + (tail - head) + b.children > capacity) return too_large(cut_count + (tail - head) + b.children);
      const uint32_t flag = e.inside ? kInside : 0;
      for (uint32_t k = 0; k < b.children; ++k) queue[tail++ % ring] = (b.first_child + k) | flag;
    }
    visited_ = visited;
  }
  if (head < tail || fresh_count > params.max_nodes) {
    // The budget binds: refine largest projected size first. The sent nodes
    // so far are the settled visible ones plus every node waiting in the heap
    // (all visible).
    cut_count = fresh_count = 0;
    frame.split_sizes = true;
    const auto place = [&](uint32_t id) {
      ++visited_;
      const Eval e = evaluate(frame, id, false);
      if (e.split) heap_push(e.size, id);
      else settle(id, e);
    };
    place(0);
    bool room = true;
    while (heap_count_ > 0) {
      const uint64_t top = heap_pop();
      const uint32_t id = ~static_cast<uint32_t>(top);
      const Bound& b = bounds_[id];
      if (room && uint64_t{fresh_count} + heap_count_ + b.children > params.max_nodes) {
        // The split's cost: its visible children replace it.
        uint32_t visible = 0;
        for (uint32_t k = 0; k < b.children; ++k) visible += evaluate(frame, b.first_child + k, false).visible;
        room = uint64_t{fresh_count} + heap_count_ + visible <= params.max_nodes;
      }
      if (!room) {  // the budget is spent: this node and all still waiting stay whole
        settle(id, Eval{true, false, false, static_cast<uint32_t>(top >> 32)});
        continue;
      }
      if (uint64_t{cut_count} + heap_count_ + b.children > capacity)
        return too_large(uint64_t{cut_count} + heap_count_ + b.children);
      for (uint32_t k = 0; k < b.children; ++k) place(b.first_child + k);
    }
    // Sent nodes in id order (the order a client's cache is filled in), with
    // their sizes: sorted as (id, size) pairs in the heap's storage.
    for (uint32_t i = 0; i < fresh_count; ++i) heap_[i] = (uint64_t{index_of(fresh[i])} << 32) | sent_size_[i];
    std::sort(heap_, heap_ + fresh_count);
    for (uint32_t i = 0; i < fresh_count; ++i) {
      fresh[i] = NodeId{static_cast<uint32_t>(heap_[i] >> 32)};
      sent_size_[i] = static_cast<uint32_t>(heap_[i]);
    }
  }
  if (fresh_count > state_capacity_) return too_large(fresh_count);

  // The change: both sent sets are in id order, so one merge lists it.
  entered_count_ = left_count_ = 0;
  uint32_t i = 0, j = 0;
  while (i < fresh_count || j < sent_count_) {
    const uint32_t a = i < fresh_count ? index_of(fresh[i]) : 0xFFFFFFFFu;
    const uint32_t b = j < sent_count_ ? index_of(sent_[j]) : 0xFFFFFFFFu;
    if (a == b) {
      ++i, ++j;
    } else if (a < b) {
      entered_[entered_count_++] = fresh[i++];
    } else {
      left_[left_count_++] = sent_[j++];
    }
  }
  std::copy(fresh, fresh + fresh_count, sent_);
  sent_count_ = fresh_count;
  cut_count_ = cut_count;
  return CutStatus::kOk;
}

}  // namespace stipple
