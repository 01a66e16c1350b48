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

struct Layout {
  size_t sent_bits, fresh_bits, cut, sent, previous, sizes, entered, left, heap, total;
};

// The per-client state (the bounds are separate).
Layout layout_of(uint32_t n) {
  Layout l{};
  ArenaCarver arena;
  const auto take = [&](size_t bytes) { return arena.take(bytes); };
  l.sent_bits = take((size_t{n} + 7) / 8);
  l.fresh_bits = take((size_t{n} + 7) / 8);
  l.cut = take(4 * size_t{n});
  l.sent = take(4 * size_t{n});
  l.previous = take(4 * size_t{n});
  l.sizes = take(4 * size_t{n});
  l.entered = take(4 * size_t{n});
  l.left = take(4 * size_t{n});
  l.heap = take(8 * size_t{n});
  l.total = arena.total();
  return l;
}

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

inline bool bit(const uint8_t* bits, uint32_t i) { return (bits[i >> 3] >> (i & 7)) & 1u; }
inline void set_bit(uint8_t* bits, uint32_t i) { bits[i >> 3] = static_cast<uint8_t>(bits[i >> 3] | (1u << (i & 7))); }
inline void clear_bit(uint8_t* bits, uint32_t i) { bits[i >> 3] = static_cast<uint8_t>(bits[i >> 3] & ~(1u << (i & 7))); }

}  // namespace

size_t CutBounds::bytes(const SpgHeader& header) { return align8(sizeof(ViewCut::Bound) * header.node_count); }
size_t view_cut_state_bytes(const SpgHeader& header) { return layout_of(header.node_count).total; }
size_t view_cut_bytes(const SpgHeader& header) { return CutBounds::bytes(header) + view_cut_state_bytes(header); }

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
  const size_t bound_bytes = CutBounds::bytes(view.header);
  if (bytes < view_cut_bytes(view.header)) return CutStatus::kStorageTooSmall;
  const CutStatus s = own_.init(view, decoder, storage, bound_bytes, cones);
  if (s != CutStatus::kOk) return s;
  return init(own_, static_cast<uint8_t*>(storage) + bound_bytes, bytes - bound_bytes);
}

CutStatus ViewCut::init(const CutBounds& shared, void* storage, size_t bytes) {
  ready_ = false;
  if (shared.bounds_ == nullptr) return CutStatus::kNotReady;
  const uint32_t n = shared.node_count_;
  const Layout l = layout_of(n);
  if (bytes < l.total) return CutStatus::kStorageTooSmall;
  uint8_t* base = static_cast<uint8_t*>(storage);
  bounds_ = static_cast<const Bound*>(shared.bounds_);
  node_count_ = n;
  normals_ = shared.normals_;
  sent_bits_ = base + l.sent_bits;
  fresh_bits_ = base + l.fresh_bits;
  for (size_t i = 0; i < (size_t{n} + 7) / 8; ++i) sent_bits_[i] = fresh_bits_[i] = 0;
  cut_ = reinterpret_cast<NodeId*>(base + l.cut);
  sent_ = reinterpret_cast<NodeId*>(base + l.sent);
  previous_ = reinterpret_cast<NodeId*>(base + l.previous);
  sent_size_ = reinterpret_cast<uint32_t*>(base + l.sizes);
  entered_ = reinterpret_cast<NodeId*>(base + l.entered);
  left_ = reinterpret_cast<NodeId*>(base + l.left);
  heap_ = reinterpret_cast<uint64_t*>(base + l.heap);
  cut_count_ = sent_count_ = previous_count_ = entered_count_ = left_count_ = visited_ = 0;
  ready_ = true;
  return CutStatus::kOk;
}

uint8_t ViewCut::points(NodeId id) const { return bounds_[index_of(id)].points; }

void ViewCut::reset() {
  for (uint32_t i = 0; i < sent_count_; ++i) {
    const uint32_t id = index_of(sent_[i]);
    sent_bits_[id >> 3] = static_cast<uint8_t>(sent_bits_[id >> 3] & ~(1u << (id & 7)));
  }
  cut_count_ = sent_count_ = previous_count_ = entered_count_ = left_count_ = visited_ = 0;
}

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
  // The previous sent set is kept for the delta.
  for (uint32_t i = 0; i < sent_count_; ++i) previous_[i] = sent_[i];
  previous_count_ = sent_count_;
  cut_count_ = sent_count_ = 0;
  heap_count_ = 0;
  visited_ = 0;

  const auto settle = [&](uint32_t id, const Eval& e) {
    cut_[cut_count_++] = NodeId{id};
    if (e.visible) {
      sent_[sent_count_] = NodeId{id};
      sent_size_[sent_count_++] = e.size;
    }
  };
  // Without a binding budget every splittable node splits, in any order:
  // breadth first, which settles the nodes in id order (ids are breadth-first,
  // children adjacent in their parents' order), so no sort is needed.
  uint32_t* queue = reinterpret_cast<uint32_t*>(heap_);
  uint32_t head = 0, tail = 0;
  queue[tail++] = 0;
  // A binding budget stops it early (too many sent, or too many visited for
  // the budget: the greedy pass then costs what the budget allows).
  const uint64_t visit_limit = 4 * uint64_t{params.max_nodes} + 8;
  {
    uint32_t cut_count = 0, sent_count = 0, visited = 0;
    while (head < tail && sent_count <= params.max_nodes && visited <= visit_limit) {
      const uint32_t id = queue[head++];
      ++visited;
      const Eval e = evaluate(frame, id & ~kInside, id & kInside);
      if (!e.split) {
        cut_[cut_count++] = NodeId{id & ~kInside};
        if (e.visible) {
          sent_[sent_count] = NodeId{id & ~kInside};
          sent_size_[sent_count++] = e.size;
        }
        continue;
      }
      const Bound& b = bounds_[id & ~kInside];
      const uint32_t flag = e.inside ? kInside : 0;
      for (uint32_t k = 0; k < b.children; ++k) queue[tail++] = (b.first_child + k) | flag;
    }
    cut_count_ = cut_count;
    sent_count_ = sent_count;
    visited_ = visited;
  }
  if (head < tail || sent_count_ > params.max_nodes) {
    // The budget binds: refine largest projected size first. The sent nodes
    // so far are the settled visible ones plus every node waiting in the heap
    // (all visible).
    cut_count_ = sent_count_ = 0;
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
      if (room && uint64_t{sent_count_} + heap_count_ + b.children > params.max_nodes) {
        // The split's cost: its visible children replace it.
        uint32_t visible = 0;
        for (uint32_t k = 0; k < b.children; ++k) visible += evaluate(frame, b.first_child + k, false).visible;
        room = uint64_t{sent_count_} + heap_count_ + visible <= params.max_nodes;
      }
      if (!room) {  // the budget is spent: this node and all still waiting stay whole
        settle(id, Eval{true, false, false, static_cast<uint32_t>(top >> 32)});
        continue;
      }
      for (uint32_t k = 0; k < b.children; ++k) place(b.first_child + k);
    }
    // Sent nodes in id order (the order a client's cache is filled in), with
    // their sizes: sorted as (id, size) pairs in the heap's storage.
    for (uint32_t i = 0; i < sent_count_; ++i) heap_[i] = (uint64_t{index_of(sent_[i])} << 32) | sent_size_[i];
    std::sort(heap_, heap_ + sent_count_);
    for (uint32_t i = 0; i < sent_count_; ++i) {
      sent_[i] = NodeId{static_cast<uint32_t>(heap_[i] >> 32)};
      sent_size_[i] = static_cast<uint32_t>(heap_[i]);
    }
  }

  // The delta against the previous sent set (bit sets, cleared by the lists).
  entered_count_ = left_count_ = 0;
  for (uint32_t i = 0; i < sent_count_; ++i) {
    const uint32_t id = index_of(sent_[i]);
    if (!bit(sent_bits_, id)) entered_[entered_count_++] = sent_[i];
    set_bit(fresh_bits_, id);
  }
  for (uint32_t i = 0; i < previous_count_; ++i) {
    const uint32_t id = index_of(previous_[i]);
    if (!bit(fresh_bits_, id)) left_[left_count_++] = previous_[i];
    clear_bit(sent_bits_, id);
  }
  for (uint32_t i = 0; i < sent_count_; ++i) {
    const uint32_t id = index_of(sent_[i]);
    set_bit(sent_bits_, id);
    clear_bit(fresh_bits_, id);
  }
  return CutStatus::kOk;
}

}  // namespace stipple
