// stipple core — the view-dependent cut. See view_cut.h; the measurements
// are in docs/figures.md.
#include "core/view_cut.h"

#include "core/arena.h"

#include <algorithm>
#include <utility>

#include "core/cut.h"
#include "core/fixed_trig.h"
#include "core/gaussian_table.h"
#include "core/spg_writer.h"

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

// A depth-first walk's stack of child ranges: (first, count) pairs in the
// caller's storage, `capacity` of them.
struct RangeStack {
  uint32_t* pairs;
  uint32_t capacity;
  uint32_t depth = 0;
  bool push(uint32_t first, uint32_t count) {
    if (depth == capacity) return false;
    pairs[2 * depth] = first;
    pairs[2 * depth + 1] = count;
    ++depth;
    return true;
  }
  // The next node, depth first; false when the walk is done.
  bool next(uint32_t& id) {
    while (depth > 0) {
      uint32_t* top = pairs + 2 * (depth - 1);
      if (top[1] > 0) {
        id = top[0]++;
        --top[1];
        return true;
      }
      --depth;
    }
    return false;
  }
};

constexpr int32_t kNoCone = 0x7FFF;
constexpr uint32_t kInside = 0x80000000u;  // in the breadth-first queue: the node's subtree is wholly visible

// A normal cone's half-angle below a quarter turn as its sine and cosine
// (Q14); sin == kNoCone: a quarter turn or more (no cone).
struct Cone {
  int32_t sin, cos;
};

// The cone of half-angle gamma * |sigma_n1| (sigma_n1 in Q12 radians, its
// sign the curvature's, which the spread does not depend on; gamma
// Q8), as a binary angle: 2^32 / (2 pi) = 683565275.6 per radian.
Cone statistical_cone(int32_t sigma_n1_q12, uint16_t gamma_q8) {
  const int64_t spread = sigma_n1_q12 < 0 ? -int64_t{sigma_n1_q12} : sigma_n1_q12;
  const int64_t sigma = spread > 0xFFFF ? 0xFFFF : spread;
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

// The state's sent set: ids ascending, each the LEB128 of its distance from
// the one before less one (the first: the id itself), so the ids of a
// screen's cut — dense in id order — take one or two bytes each.
size_t encode_ids(const NodeId* ids, uint32_t n, uint8_t* out) {
  size_t at = 0;
  uint32_t next = 0;  // the smallest id the next may be
  for (uint32_t i = 0; i < n; ++i) {
    at += store_leb128(out + at, index_of(ids[i]) - next);
    next = index_of(ids[i]) + 1;
  }
  return at;
}

// A count as the 31 bits every capacity here has (larger: the largest).
uint32_t count31(uint64_t n) { return n > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(n); }

// Reads the ids back in order (the state is ours: well formed).
struct IdReader {
  const uint8_t* at;
  uint32_t next = 0;
  uint32_t read() {
    uint32_t d = 0;
    for (int shift = 0;; shift += 7) {
      const uint8_t b = *at++;
      d |= uint32_t{b & 0x7Fu} << shift;
      if (!(b & 0x80u)) break;
    }
    const uint32_t id = next + d;
    next = id + 1;
    return id;
  }
};

}  // namespace

size_t sent_set_bytes(const NodeId* ids, uint32_t count) {
  size_t n = 0;
  uint32_t next = 0;
  for (uint32_t i = 0; i < count; ++i) {
    n += leb128_bytes(index_of(ids[i]) - next);
    next = index_of(ids[i]) + 1;
  }
  return n;
}

size_t CutBounds::bytes(const SpgHeader& header) { return align8(sizeof(ViewCut::Bound) * header.node_count); }
// The scratch of capacity C: the heap (8 C; the breadth-first queue, a ring
// of 2 C ids, in its place), entered, left, cut, fresh sent set, sizes (4 C
// each), 4 C to spare — in the incremental mode the walk's and the
// expansion's stacks take 14 C from the cut on, then the fresh sent set
// takes the place it has in a derivation.
size_t CutScratch::bytes(uint32_t capacity) { return 32 * size_t{capacity}; }

void CutScratch::init(void* at, size_t size) {
  storage = at;
  capacity = count31(size / 32);
}

size_t view_cut_state_bytes(uint32_t sent) { return align8(5 * size_t{sent}); }
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

CutStatus CutBounds::attach(const SpgView& view, const void* table, size_t bytes, uint32_t* bad_node,
                            const char** bad_field) {
  bounds_ = nullptr;
  *bad_node = 0;
  *bad_field = "";
  const uint32_t n = view.header.node_count;
  if (n >= kInside) return CutStatus::kBadView;
  if (table == nullptr || bytes < sizeof(ViewCut::Bound) * size_t{n}) return CutStatus::kStorageTooSmall;
  const ViewCut::Bound* bounds = static_cast<const ViewCut::Bound*>(table);
  const auto bad = [&](uint32_t i, const char* field) {
    *bad_node = i;
    *bad_field = field;
    return CutStatus::kBadView;
  };
  // One pass front to back: the leaf counts are read in order, and an
  // internal node's points are its children's (further on in the table,
  // checked when reached), summed and saturated as spg_node_points does.
  const uint8_t* counts = view.leaf_counts;
  uint64_t next_child = 1;
  for (uint32_t i = 0; i < n; ++i) {
    const ViewCut::Bound& b = bounds[i];
    const uint32_t children = spg_child_count(view, i);
    if (b.children != children) return bad(i, "children");
    if (b.first_child != next_child) return bad(i, "first_child");
    next_child += children;
    if (b.radius < 0 || b.radius > (1 << 30)) return bad(i, "radius");
    if (b.subtree_radius < b.radius || b.subtree_radius > (1 << 30)) return bad(i, "subtree_radius");
    if (b.cone_sin_q14 < 0) return bad(i, "cone");
    if (b.pad0 != 0) return bad(i, "padding");
    uint32_t points = 0;
    if (counts != nullptr && children == 0) {
      for (int shift = 0;; shift += 7) {  // validated by spg_parse: at most 5 bytes
        const uint8_t byte = *counts++;
        points |= static_cast<uint32_t>(byte & 0x7Fu) << shift;
        if ((byte & 0x80u) == 0) break;
      }
    } else if (counts != nullptr) {
      for (uint32_t k = 0; k < children; ++k) points += bounds[b.first_child + k].points;
    }
    if (b.points != (points < 255 ? points : 255)) return bad(i, "points");
  }
  if (n > 0 && next_child != n) return bad(n - 1, "first_child");
  bounds_ = bounds;
  node_count_ = n;
  normals_ = view.header.has_normals();
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
  state_ = static_cast<uint8_t*>(state);
  state_bytes_ = state == nullptr ? 0 : state_bytes;
  state_used_ = needed_state_ = 0;
  sent_ = nullptr;
  cut_ = entered_ = left_ = nullptr;
  sent_size_ = nullptr;
  heap_ = nullptr;
  cut_count_ = sent_count_ = entered_count_ = left_count_ = visited_ = needed_ = 0;
  front_ = nullptr;
  front_count_ = front_capacity_ = 0;
  front_valid_ = budget_bound_ = has_previous_ = false;
  unheaped_ = 0;
  ready_ = true;
  return CutStatus::kOk;
}

bool ViewCut::relocate(void* state, size_t state_bytes) {
  if (state_bytes < state_used_ || (state == nullptr && state_used_ > 0)) return false;
  uint8_t* to = static_cast<uint8_t*>(state);
  if (state_used_ > 0) std::copy(state_, state_ + state_used_, to);
  state_ = to;
  state_bytes_ = state == nullptr ? 0 : state_bytes;
  return true;
}

bool ViewCut::adopt_sent(const NodeId* ids, uint32_t count) {
  reset();
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t id = index_of(ids[i]);
    if (id >= node_count_ || (i > 0 && id <= index_of(ids[i - 1]))) return false;
  }
  const size_t bytes = sent_set_bytes(ids, count);
  if (bytes > state_bytes_) {
    needed_state_ = bytes;
    return false;
  }
  state_used_ = encode_ids(ids, count, state_);
  sent_count_ = count;
  return true;
}

uint8_t ViewCut::points(NodeId id) const { return bounds_[index_of(id)].points; }

bool ViewCut::is_sent(NodeId id) const {
  IdReader r{state_};
  for (uint32_t i = 0; i < sent_count_; ++i) {
    const uint32_t got = r.read();
    if (got >= index_of(id)) return got == index_of(id);
  }
  return false;
}

void ViewCut::reset() {
  cut_count_ = sent_count_ = entered_count_ = left_count_ = visited_ = needed_ = 0;
  state_used_ = needed_state_ = 0;
  sent_ = nullptr;
  front_count_ = 0;
  front_valid_ = budget_bound_ = has_previous_ = false;
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
  bool cull_frustum, cull_backfaces, window, accumulate;
  // Incremental mode: the clock deadlines are set on, and the motion a clock
  // unit (kClockUnit ticks) stands for.
  uint32_t clock;
  int64_t pace_turn, pace_shift, pace_eye;
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
    if (!e.split && f.accumulate) e.split = above_previous(id);
  }
  if (!e.split || f.split_sizes) e.size = projected();
  return e;
}

uint32_t ViewCut::first_child(uint32_t id) const { return id < node_count_ ? bounds_[id].first_child : node_count_; }

bool ViewCut::above_previous(uint32_t id) const {
  // The node's descendants, level by level, are one id range each.
  uint32_t lo = first_child(id), hi = first_child(id + 1);
  const uint32_t* end = previous_ + previous_count_;
  while (lo < hi) {
    const uint32_t* at = std::lower_bound(previous_, end, lo);  // the first previous id at or above lo
    if (at < end && *at < hi) return true;
    lo = first_child(lo);
    hi = first_child(hi);
  }
  return false;
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
              params.window[0] < params.window[2],
              params.accumulate && params.window[0] < params.window[2],
              0,
              1,
              1,
              1};
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
  needed_ = needed_front_ = 0;
  if (sent_count_ > capacity) {  // the change is listed in the scratch
    needed_ = sent_count_;
    return CutStatus::kStorageTooSmall;
  }
  uint8_t* base = static_cast<uint8_t*>(scratch_->storage);
  // The heap first (8-byte entries on the storage's 8-byte alignment, for
  // any capacity), then the 4-byte lists.
  heap_ = reinterpret_cast<uint64_t*>(base);
  entered_ = reinterpret_cast<NodeId*>(heap_ + capacity);
  left_ = entered_ + capacity;
  cut_ = left_ + capacity;
  sent_size_ = reinterpret_cast<uint32_t*>(cut_ + 2 * size_t{capacity});
  if (frame.accumulate) {
    // The previous sent set, decoded for binary searches, in the scratch's
    // last 4 bytes a node (no other list uses them).
    uint32_t* previous = sent_size_ + capacity;
    IdReader r{state_};
    for (uint32_t i = 0; i < sent_count_; ++i) previous[i] = r.read();
    previous_ = previous;
    previous_count_ = sent_count_;
  }
  evaluated_ = 0;
  last_incremental_ = false;
  CutStatus status;
  const bool setting_kept = has_previous_ && same_setting(camera, params);
  if (front_ == nullptr || frame.window) {
    front_valid_ = false;
    status = derive(frame, params);
  } else if (budget_bound_ && setting_kept) {
    // The budget bound the last cut: from the root again, until it does not.
    front_valid_ = false;
    status = derive(frame, params);
  } else {
    status = update_incremental(frame, params, !front_valid_ || !setting_kept);
  }
  if (status == CutStatus::kOk) {
    previous_camera_ = camera;
    previous_params_ = params;
    has_previous_ = true;
  }
  return status;
}

// The change against the state's sent set (both in id order: one merge),
// then `fresh` (ascending, in the scratch) becomes the state.
CutStatus ViewCut::keep_sent(const NodeId* fresh, uint32_t fresh_count) {
  const size_t bytes = sent_set_bytes(fresh, fresh_count);
  if (bytes > state_bytes_) {
    needed_state_ = bytes;
    entered_count_ = left_count_ = 0;
    return CutStatus::kStorageTooSmall;
  }
  entered_count_ = left_count_ = 0;
  IdReader old{state_};
  uint32_t i = 0, j = 0, b = j < sent_count_ ? old.read() : 0xFFFFFFFFu;
  while (i < fresh_count || j < sent_count_) {
    const uint32_t a = i < fresh_count ? index_of(fresh[i]) : 0xFFFFFFFFu;
    if (a == b) {
      ++i;
      b = ++j < sent_count_ ? old.read() : 0xFFFFFFFFu;
    } else if (a < b) {
      entered_[entered_count_++] = fresh[i++];
    } else {
      left_[left_count_++] = NodeId{b};
      b = ++j < sent_count_ ? old.read() : 0xFFFFFFFFu;
    }
  }
  state_used_ = encode_ids(fresh, fresh_count, state_);
  sent_count_ = fresh_count;
  sent_ = fresh;
  return CutStatus::kOk;
}

CutStatus ViewCut::derive(Frame& frame, const CutParams& params) {
  const uint32_t capacity = scratch_->capacity;
  NodeId* fresh = cut_ + capacity;
  const auto too_large = [&](uint64_t reached) {
    needed_ = count31(reached);
    cut_count_ = entered_count_ = left_count_ = 0;
    return CutStatus::kStorageTooSmall;
  };
  uint32_t cut_count = 0, fresh_count = 0;
  heap_count_ = 0;
  visited_ = 0;
  if (capacity == 0) return too_large(1);
  // The breadth-first pass gives up, and the budget binds, past this many
  // visits (the largest-first pass then costs what the budget allows).
  const uint64_t visit_limit = 4 * uint64_t{params.max_nodes} + 8;

  const auto settle = [&](uint32_t id, const Eval& e) {
    cut_[cut_count++] = NodeId{id};
    if (e.visible) {
      fresh[fresh_count] = NodeId{id};
      sent_size_[fresh_count++] = e.size;
    }
  };
  // The budget's pass: refine the largest projected size first, until a
  // split does not fit the budget (its visible children replace it); that
  // node and every one still waiting stay whole. The sent nodes at any
  // moment are the settled visible ones and every waiting one (all
  // visible). `placed`: the nodes evaluated into the cut or the heap, each
  // one a node of the budget-free cut or above it. When a split is refused,
  // `waited` is where the nodes that waited begin in `fresh` (each one
  // splits without the budget; the ones before it are the budget-free
  // cut's).
  //
  // The heap is the pass's cost; the nodes larger on screen than
  // `unheaped_` split without it, depth first, when that is sure to give
  // the same cut. Before the greedy pass pops a node, every node larger
  // than it has split (it pops largest first) and its sent count is at most
  // the cut's nodes, which a split never lessens: so while the cut that
  // splits every node larger than a size S has at most the budget's nodes
  // (culled ones included), no node larger than S is refused, and those
  // splits are made in any order. S is the last pass's smallest split size
  // with the cut then at 7/8 of the budget (a camera's step moves a few
  // percent of it); the first split past the budget here makes the pass
  // start over with the heap alone.
  const auto largest_first = [&](uint64_t& placed, bool& refused, uint32_t& waited) {
    refused = false;
    frame.split_sizes = true;
    const auto place = [&](uint32_t id) {
      ++placed;
      const Eval e = evaluate(frame, id, false);
      if (e.split) heap_push(e.size, id);
      else settle(id, e);
    };
    // The cut's nodes it may reach without the heap: the budget's (or the
    // scratch's, when smaller: the heap's pass then refuses as it would).
    const uint64_t room = std::min<uint64_t>(params.max_nodes, capacity);
    const uint64_t unheaped_cut = room - room / 8;
    bool whole = false;  // the nodes above unheaped_ split
    if (unheaped_ > 0) {
      cut_count = fresh_count = 0;
      heap_count_ = 0;
      placed = 0;
      // The stack in the change lists (unused until keep_sent): `capacity` pairs.
      RangeStack stack{reinterpret_cast<uint32_t*>(entered_), capacity};
      uint64_t waiting = 1;  // in the stack, not yet evaluated
      stack.push(0, 1);
      whole = true;
      for (uint32_t id = 0; stack.next(id);) {
        --waiting;
        ++placed;
        const Eval e = evaluate(frame, id, false);
        if (!e.split) {
          settle(id, e);
        } else if (e.size <= unheaped_) {
          heap_push(e.size, id);
        } else {
          const Bound& b = bounds_[id];
          waiting += b.children;
          if (uint64_t{cut_count} + heap_count_ + waiting > room || !stack.push(b.first_child, b.children)) {
            whole = false;
            break;
          }
        }
      }
    }
    if (!whole) {
      cut_count = fresh_count = 0;
      heap_count_ = 0;
      placed = 0;
      place(0);
    }
    // The next pass's size: set below; when the cut split without the heap
    // is already past 7/8 of the budget, a little larger than this one's.
    unheaped_ = whole && uint64_t{cut_count} + heap_count_ > unheaped_cut
                    ? static_cast<uint32_t>(std::min<uint64_t>(uint64_t{unheaped_} * 17 / 16 + 1, 0xFFFFFFFEu))
                    : 0;
    while (heap_count_ > 0) {
      const uint64_t top = heap_pop();
      const uint32_t id = ~static_cast<uint32_t>(top);
      const Bound& b = bounds_[id];
      if (uint64_t{fresh_count} + heap_count_ + b.children > params.max_nodes) {
        uint32_t visible = 0;
        for (uint32_t k = 0; k < b.children; ++k) visible += evaluate(frame, b.first_child + k, false).visible;
        if (uint64_t{fresh_count} + heap_count_ + visible > params.max_nodes) {
          // The budget is spent. What waits settles in the heap's order (the
          // sent set is sorted below); the cut and the heap never held more
          // than the capacity together.
          refused = true;
          waited = fresh_count;
          settle(id, Eval{true, false, false, static_cast<uint32_t>(top >> 32)});
          for (uint32_t i = 0; i < heap_count_; ++i)
            settle(~static_cast<uint32_t>(heap_[i]), Eval{true, false, false, static_cast<uint32_t>(heap_[i] >> 32)});
          heap_count_ = 0;
          break;
        }
      }
      if (uint64_t{cut_count} + heap_count_ + b.children > capacity)
        return too_large(uint64_t{cut_count} + heap_count_ + b.children);
      for (uint32_t k = 0; k < b.children; ++k) place(b.first_child + k);
      if (uint64_t{cut_count} + heap_count_ <= unheaped_cut) unheaped_ = static_cast<uint32_t>(top >> 32);
    }
    return CutStatus::kOk;
  };
  // After a refused split: does the budget-free cut fit the budget all the
  // same (its sent nodes within it, and the breadth-first pass's visits
  // within their limit), as when splits below the refused node's children
  // cull more than they add? The nodes below the waiting ones, depth first
  // (a stack of child ranges in the change lists, unused until keep_sent),
  // until either count passes its bound. 1: it fits; 0: it does not; -1:
  // the stack outgrew its room. `visits` counts on from the nodes placed.
  const auto budget_free_fits = [&](uint64_t& visits, uint32_t waited) {
    uint64_t visible = waited;
    frame.split_sizes = false;
    RangeStack stack{reinterpret_cast<uint32_t*>(entered_), capacity};
    for (uint32_t i = waited; i < fresh_count; ++i) {
      const Bound& w = bounds_[index_of(fresh[i])];
      stack.push(w.first_child, w.children);
      for (uint32_t id = 0; stack.next(id);) {
        if (++visits > visit_limit + 1) return 0;
        const Eval e = evaluate(frame, id, false);
        if (e.split) {
          if (!stack.push(bounds_[id].first_child, bounds_[id].children)) return -1;
        } else if (e.visible && ++visible > params.max_nodes) {
          return 0;
        }
      }
    }
    return 1;
  };

  // The last cut was the budget's: most likely this one is too, and the
  // largest-first pass comes first. Its cut is the from-the-root cut unless
  // the budget-free cut fits after all (then that one is made below).
  bool settled = false, by_size = false;  // by_size: the largest-first pass's cut (sorted below)
  if (budget_bound_) {
    uint64_t placed = 0;
    uint32_t waited = 0;
    bool refused = false;
    if (largest_first(placed, refused, waited) != CutStatus::kOk) return CutStatus::kStorageTooSmall;
    visited_ = count31(placed);
    if (!refused) {
      // Nothing refused: every splittable node split, the budget-free cut
      // (the breadth-first pass would have given up past its visits).
      settled = true;
      budget_bound_ = placed > visit_limit + 1;
    } else {
      uint64_t visits = placed;
      const int fits = budget_free_fits(visits, waited);
      visited_ = count31(visits);
      if (fits < 0) return too_large(uint64_t{capacity} + 1);
      settled = fits == 0;
      budget_bound_ = settled;
    }
    by_size = settled;
  }
  if (!settled) {
    // Without a binding budget every splittable node splits, in any order:
    // breadth first, which settles the nodes in id order (ids are
    // breadth-first, children adjacent in their parents' order), so no sort
    // is needed. The queue is a ring in the heap's place: what waits in it
    // and what settled are never more than the finished cut, so 2 C ids
    // hold it. A binding budget stops it early (too many sent, or too many
    // visited).
    cut_count = fresh_count = 0;
    frame.split_sizes = false;
    uint32_t* queue = reinterpret_cast<uint32_t*>(heap_);
    const uint64_t ring = 2 * uint64_t{capacity};
    // head, tail: the nodes taken from the queue (visited) and put in it;
    // taken, put: where in the ring (wrapped by a compare: a 64-bit
    // division there was a fifth of the pass's time).
    uint64_t head = 0, tail = 1, taken = 0, put = 1;
    queue[0] = 0;
    const uint32_t max_nodes = params.max_nodes;
    while (head < tail && fresh_count <= max_nodes && head <= visit_limit) {
      const uint32_t id = queue[taken];
      if (++taken == ring) taken = 0;
      ++head;
      const Eval e = evaluate(frame, id & ~kInside, id & kInside);
      if (!e.split) {
        settle(id & ~kInside, e);
        continue;
      }
      const Bound& b = bounds_[id & ~kInside];
      const uint32_t n = b.children;
      if (cut_count + (tail - head) + n > capacity) return too_large(cut_count + (tail - head) + n);
      // Ids below kInside (init): the flag and the child's index never carry into each other.
      const uint32_t first = b.first_child | (e.inside ? kInside : 0);
      if (n == 2 && put + 2 < ring) {  // the binary tree's case, without a loop
        queue[put] = first;
        queue[put + 1] = first + 1;
        put += 2;
      } else if (put + n < ring) {
        for (uint32_t k = 0; k < n; ++k) queue[put + k] = first + k;
        put += n;
      } else {
        for (uint32_t k = 0; k < n; ++k) {
          queue[put] = first + k;
          if (++put == ring) put = 0;
        }
      }
      tail += n;
    }
    visited_ = count31(uint64_t{visited_} + head);  // after a largest-first pass that found it fits, both
    budget_bound_ = head < tail || fresh_count > params.max_nodes;
    if (budget_bound_) {
      uint64_t placed = 0;
      uint32_t waited = 0;
      bool refused = false;
      if (largest_first(placed, refused, waited) != CutStatus::kOk) return CutStatus::kStorageTooSmall;
      visited_ = count31(uint64_t{visited_} + placed);
      by_size = true;
    }
  }
  if (by_size) {
    // The largest-first pass's sent nodes in id order (the order a client's
    // cache is filled in), with their sizes: (id, size) pairs radix sorted
    // by id, 11 bits a pass, between the heap's storage and the change
    // lists' (unused until keep_sent).
    uint64_t* from = heap_;
    uint64_t* to = reinterpret_cast<uint64_t*>(entered_);
    for (uint32_t i = 0; i < fresh_count; ++i) from[i] = (uint64_t{index_of(fresh[i])} << 32) | sent_size_[i];
    for (int shift = 32; shift < 64 && (uint64_t{node_count_ - 1} >> (shift - 32)) > 0; shift += 11) {
      uint32_t start[2048] = {};
      for (uint32_t i = 0; i < fresh_count; ++i) ++start[(from[i] >> shift) & 2047];
      uint32_t at = 0;
      for (uint32_t& s : start) at += std::exchange(s, at);
      for (uint32_t i = 0; i < fresh_count; ++i) to[start[(from[i] >> shift) & 2047]++] = from[i];
      std::swap(from, to);
    }
    for (uint32_t i = 0; i < fresh_count; ++i) {
      fresh[i] = NodeId{static_cast<uint32_t>(from[i] >> 32)};
      sent_size_[i] = static_cast<uint32_t>(from[i]);
    }
  }
  const CutStatus kept = keep_sent(fresh, fresh_count);
  if (kept != CutStatus::kOk) return kept;
  cut_count_ = cut_count;
  evaluated_ = visited_;
  return CutStatus::kOk;
}

// ---------------------------------------------------------------------------
// Incremental updates.
//
// Every decision a node's evaluation makes — behind the near plane or not,
// crossing it, outside a side plane, facing away, split — compares a
// quantity with a threshold fixed per node: a camera-space functional
// g = w . (p - eye) (|w| <= 1: depth, or a side plane's distance), or for
// facing away n . (eye - p) + sin_a L(eye - p) + r. How far a camera's step
// can move them is bounded for every node at once:
//   g changes by at most |w1 - w0| |p - o| + |w1 . (o - e1) - w0 . (o - e0)|,
//   o the root's centre (the turn and the shift, the largest over the five
//   functionals; the near plane's move counts as a shift in depth);
//   the facing quantity by at most (1 + 1.375 sin_a) |e1 - e0|.
// So each evaluation gives its node a deadline on a clock that runs with the
// camera's motion, kClockUnit ticks per pace (a step's turn, shift and eye
// move, each measured against its own pace, the largest counting): the
// node's smallest margin, less the rounding of the camera transform, over
// its motion bound per pace (turn x |p - o| + shift, or the eye's). Until
// the clock reaches it no decision of the node can differ from a fresh
// evaluation's. An update advances the clock, walks the front (the cut and
// every node above it, ids ascending) into the parts whose earliest deadline
// has come (sub_due), evaluates those nodes again, and splits (a subtree
// evaluated below, as from the root) or merges (the nodes below leave)
// where a decision changed. The paces are set, when the front is derived,
// to half again the last step's motion: a step more than twice that (a
// jump, or a camera that sped up) derives the front again.
namespace {
constexpr int64_t kClockUnit = 1024;            // clock ticks per pace of motion
constexpr int64_t kRoundingMu = 2;              // the camera transform's rounding, and more
constexpr uint32_t kMaxTicks = 0x7FFFFFFFu;     // a deadline's furthest (the clock restarts before)
constexpr int64_t kMaxStepTicks = 2 * kClockUnit;  // a step of twice the pace derives the front again, paced by it
constexpr uint32_t kSplitBit = 0x80000000u;    // above the cut
constexpr uint32_t kVisibleBit = 0x40000000u;  // a sent cut node
constexpr uint32_t kFlagMask = kSplitBit | kVisibleBit;

uint32_t ticks(int64_t margin, int64_t slack, int64_t per_tick_num, int64_t pace) {
  // floor((margin - slack) * kClockUnit / (per_tick_num * pace)), 0 when none
  if (margin <= slack) return 0;
  const int64_t num = (margin - slack) > (int64_t{1} << 50) ? (int64_t{1} << 60) : (margin - slack) * kClockUnit;
  const int64_t t = num / (per_tick_num * pace);
  return t > kMaxTicks ? kMaxTicks : static_cast<uint32_t>(t);
}

uint32_t due_at(uint32_t clock, uint32_t t) {
  const uint64_t d = uint64_t{clock} + t;
  return d > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(d);
}
}  // namespace

// The front is kept depth first: a node, then its part of the front (its
// children's parts, in order), `size` entries in all — so a part whose
// earliest deadline has not come is passed over in one step.
struct ViewCut::FrontNode {
  uint32_t id;
  uint32_t due;      // the clock at which its own decisions must be looked at again
  uint32_t sub_due;  // the earliest due in its part of the front (its own included)
  uint32_t size;     // entries in its part (itself included), and kSplitBit, kVisibleBit
};
static_assert(sizeof(ViewCut::FrontNode) == 16);

struct ViewCut::Due {
  bool visible, split;
  uint32_t due;
};

void ViewCut::use_front(void* storage, size_t bytes) {
  front_ = static_cast<FrontNode*>(storage);
  front_capacity_ = storage == nullptr ? 0 : static_cast<uint32_t>(std::min<size_t>(bytes / 16, 0x3FFFFFFFu));
  front_count_ = 0;
  front_valid_ = false;
}

bool ViewCut::relocate_front(void* storage, size_t bytes) {
  if (bytes / 16 < front_count_ || storage == nullptr) return false;
  FrontNode* to = static_cast<FrontNode*>(storage);
  std::copy(front_, front_ + front_count_, to);
  front_ = to;
  front_capacity_ = static_cast<uint32_t>(std::min<size_t>(bytes / 16, 0x3FFFFFFFu));
  return true;
}

bool ViewCut::same_setting(const Camera& c, const CutParams& p) const {
  const Camera& o = previous_camera_;
  const CutParams& q = previous_params_;
  return c.focal_q4 == o.focal_q4 && c.center_q4[0] == o.center_q4[0] && c.center_q4[1] == o.center_q4[1] &&
         p.max_size_q4 == q.max_size_q4 && p.cull_frustum == q.cull_frustum &&
         p.cull_backfaces == q.cull_backfaces && p.width == q.width && p.height == q.height;
}

// The node's decisions (as evaluate() makes them, without a window) and the
// clock at which they may first differ.
ViewCut::Due ViewCut::evaluate_due(const Frame& f, uint32_t id) const {
  const Bound& b = bounds_[id];
  const int64_t p0 = b.center[0], p1 = b.center[1], p2 = b.center[2];
  const int64_t z = (f.rotation[2][0] * p0 + f.rotation[2][1] * p1 + f.rotation[2][2] * p2 + f.offset[2]) >> 14;
  const int64_t r = b.radius;
  constexpr int64_t kFar = int64_t{1} << 62;
  int64_t keep_cam = kFar, keep_eye = kFar;  // the margins of decisions that must all hold (MU; Q14 MU)
  int64_t cull_cam = -1, cull_eye = -1;      // the margins of culling decisions, any one of which suffices
  const auto abs64 = [](int64_t v) { return v < 0 ? -v : v; };
  const int64_t behind = z + r - f.near;     // < 0: wholly behind the near plane
  const int64_t crossing = z - r - f.near;   // < 0: reaches behind it
  bool culled = behind < 0;
  if (culled) {
    cull_cam = -behind;
  } else {
    keep_cam = std::min(behind, abs64(crossing));
    if (crossing >= 0 && f.cull_frustum) {
      const int64_t x = (f.rotation[0][0] * p0 + f.rotation[0][1] * p1 + f.rotation[0][2] * p2 + f.offset[0]) >> 14;
      const int64_t y = (f.rotation[1][0] * p0 + f.rotation[1][1] * p1 + f.rotation[1][2] * p2 + f.offset[1]) >> 14;
      const int64_t fx = f.focal * x, cxz = f.cx * z, fy = f.focal * y, cyz = f.cy * z;
      const int64_t planes[4] = {fx - cxz - r * f.hyp_x, -fx - cxz - r * f.hyp_x, fy - cyz - r * f.hyp_y,
                                 -fy - cyz - r * f.hyp_y};
      for (int k = 0; k < 4; ++k) {
        const int64_t distance = abs64(planes[k]) / (k < 2 ? f.hyp_x : f.hyp_y);  // MU
        if (planes[k] > 0) {  // outside: culled while it stays outside and the node before the near plane
          culled = true;
          cull_cam = std::max(cull_cam, std::min(distance, crossing));
        } else {
          keep_cam = std::min(keep_cam, distance);
        }
      }
    }
  }
  const int64_t sin_a = b.cone_sin_q14;
  int64_t k_eye = 0;
  if (f.cull_backfaces && sin_a < kQ14One) {
    const int64_t d0 = f.eye[0] - p0, d1 = f.eye[1] - p1, d2 = f.eye[2] - p2;
    const int64_t dot = b.normal[0] * d0 + b.normal[1] * d1 + b.normal[2] * d2;
    const int64_t a0 = d0 < 0 ? -d0 : d0, a1 = d1 < 0 ? -d1 : d1, a2 = d2 < 0 ? -d2 : d2;
    const int64_t m = a0 > a1 ? (a0 > a2 ? a0 : a2) : (a1 > a2 ? a1 : a2);
    const int64_t len = m + (a0 + a1 + a2 - m + 1) / 2;
    const int64_t facing = dot + sin_a * len + (r << 14);  // < 0: faces away (evaluate()'s test)
    k_eye = kQ14One + 8 + ((sin_a * 11) >> 3);           // |n| (Q14, rounded) + 1.375 sin_a (L's slope)
    if (facing < 0) {
      culled = true;
      cull_eye = -facing;
    } else {
      keep_eye = facing;
    }
  }
  const int64_t eye_slack = sin_a + 16;
  // The node's move per pace in camera-space functionals: turn x |p - o| + shift.
  const Bound& root = bounds_[0];
  const int64_t o0 = p0 - root.center[0], o1 = p1 - root.center[1], o2 = p2 - root.center[2];
  const int64_t b0 = o0 < 0 ? -o0 : o0, b1 = o1 < 0 ? -o1 : o1, b2 = o2 < 0 ? -o2 : o2;
  const int64_t bm = b0 > b1 ? (b0 > b2 ? b0 : b2) : (b1 > b2 ? b1 : b2);
  const int64_t rho = bm + (b0 + b1 + b2 - bm + 1) / 2 + 1;  // >= |p - o|
  const int64_t per_pace = ((f.pace_turn * rho) >> 14) + 1 + f.pace_shift;
  if (culled) {
    const uint32_t t = std::max(cull_cam >= 0 ? ticks(cull_cam, kRoundingMu, 1, per_pace) : 0u,
                                cull_eye >= 0 ? ticks(cull_eye, eye_slack, k_eye, f.pace_eye) : 0u);
    return Due{false, false, due_at(f.clock, t)};
  }
  bool split = b.children > 0;
  if (split && crossing >= 0) {
    const int64_t q = r * f.focal - f.max_size * z;  // > 0: larger than the threshold on screen
    split = q > 0;
    keep_cam = std::min(keep_cam, abs64(q) / f.max_size);
  }
  uint32_t t = ticks(keep_cam, kRoundingMu, 1, per_pace);
  if (keep_eye != kFar) t = std::min(t, ticks(keep_eye, eye_slack, k_eye, f.pace_eye));
  return Due{true, split, due_at(f.clock, t)};
}

CutStatus ViewCut::update_incremental(Frame& frame, const CutParams& params, bool rebuild) {
  const uint32_t capacity = scratch_->capacity;
  const Bound& root = bounds_[0];
  // The camera's motion since the last update, bounded (above).
  int64_t turn = 0, shift = 0, eye_move = 0;
  if (has_previous_) {
    const Camera& c0 = previous_camera_;
    const Camera& c1 = frame.camera;
    // The five functionals (depth, the four side planes) as Q14 vectors,
    // for a camera, and each one's value at o.
    const auto functionals = [&](const Camera& c, int64_t w[5][3], int64_t at_o[5]) {
      for (int j = 0; j < 3; ++j) {
        const int64_t r0 = c.rotation[0][j], r1 = c.rotation[1][j], r2 = c.rotation[2][j];
        w[0][j] = r2;
        w[1][j] = (frame.focal * r0 - frame.cx * r2) / frame.hyp_x;
        w[2][j] = (-frame.focal * r0 - frame.cx * r2) / frame.hyp_x;
        w[3][j] = (frame.focal * r1 - frame.cy * r2) / frame.hyp_y;
        w[4][j] = (-frame.focal * r1 - frame.cy * r2) / frame.hyp_y;
      }
      for (int t = 0; t < 5; ++t) {
        at_o[t] = 0;
        for (int j = 0; j < 3; ++j) at_o[t] += w[t][j] * (int64_t{root.center[j]} - c.eye[j]);
      }
      at_o[0] -= int64_t{c.near_mu} << 14;  // the near plane's move is a move in depth
    };
    int64_t w0[5][3], w1[5][3], s0[5], s1[5];
    functionals(c0, w0, s0);
    functionals(c1, w1, s1);
    uint64_t e2 = 0, far = 0;
    for (int j = 0; j < 3; ++j) {
      const int64_t de = int64_t{c1.eye[j]} - c0.eye[j];
      e2 += static_cast<uint64_t>(de * de);
      const int64_t d = int64_t{root.center[j]} - c1.eye[j];
      far += static_cast<uint64_t>(d < 0 ? -d : d) + static_cast<uint64_t>(de < 0 ? -de : de);
    }
    for (int t = 0; t < 5; ++t) {
      uint64_t d2 = 0;
      for (int j = 0; j < 3; ++j) {
        const int64_t d = w1[t][j] - w0[t][j];
        d2 += static_cast<uint64_t>(d * d);
      }
      turn = std::max(turn, static_cast<int64_t>(isqrt64(d2)) + 4);  // + the vectors' rounding
      const int64_t ds = s1[t] - s0[t];
      // + the rounded vectors' error at o (4 Q14 units a component, twice).
      shift = std::max(shift, ((ds < 0 ? -ds : ds) >> 14) + 2 + static_cast<int64_t>((8 * far) >> 14));
    }
    eye_move = static_cast<int64_t>(isqrt64(e2)) + 1;
    motion_turn_ = turn;
    motion_shift_ = shift;
    motion_eye_ = eye_move;
  }
  const bool eye_counts = frame.cull_backfaces;
  if (!rebuild) {
    const auto over = [](int64_t m, int64_t pace) { return (m * kClockUnit + pace - 1) / pace; };
    const int64_t step = std::max({over(turn, pace_turn_), over(shift, pace_shift_), eye_counts ? over(eye_move, pace_eye_) : 0});
    if (step > kMaxStepTicks || int64_t{clock_} + step >= int64_t{1} << 31) rebuild = true;
    else clock_ += static_cast<uint32_t>(step);
  }
  if (rebuild) {
    // The clock restarts, paced by half again the last step's motion (the
    // first time: about a degree, and a 64th of the model's radius).
    clock_ = 0;
    const int64_t radius = root.subtree_radius / 64 + 1;
    pace_turn_ = has_previous_ ? motion_turn_ * 3 / 2 + 1 : 300;
    pace_shift_ = has_previous_ ? motion_shift_ * 3 / 2 + 1 : radius;
    pace_eye_ = has_previous_ ? motion_eye_ * 3 / 2 + 1 : radius;
    front_count_ = 0;
  }
  frame.clock = clock_;
  frame.pace_turn = pace_turn_;
  frame.pace_shift = pace_shift_;
  frame.pace_eye = pace_eye_;
  last_incremental_ = !rebuild;
  front_valid_ = false;  // until this update is whole
  visited_ = 0;

  // The scratch: the walk's and the expansion's stacks (depth first).
  struct Open {        // a node of the front being walked below
    uint32_t at;       // where it is written
    uint32_t end;      // where its part ends in the old front (read side)
    uint32_t min_due;  // the earliest due met below it so far (its own included)
  };
  struct Grow {        // a node being expanded below
    uint32_t at, next, left, min_due;  // where it is written, its next child, children to go, earliest due
  };
  Open* walk = reinterpret_cast<Open*>(cut_);
  Grow* grow = reinterpret_cast<Grow*>(walk + capacity / 2);
  const uint32_t depth_capacity = capacity / 2;
  uint32_t sp = 0;
  int64_t cut_delta = 0;
  entered_count_ = left_count_ = 0;
  const auto refuse = [&](uint64_t reached, uint64_t front) {
    needed_ = count31(reached);
    needed_front_ = count31(front);
    front_valid_ = false;
    front_count_ = 0;
    entered_count_ = left_count_ = 0;
    return CutStatus::kStorageTooSmall;
  };
  // Writes the subtrees of nodes [first, first + count) at `w` in depth-first
  // order, as from the root, never reaching `limit`; their earliest due in
  // *earliest. False when the room or the stack runs out.
  const auto expand = [&](uint32_t first, uint32_t count, uint32_t& w, uint32_t limit, uint32_t& earliest) {
    uint32_t gp = 0;
    grow[gp++] = Grow{0xFFFFFFFFu, first, count, 0xFFFFFFFFu};
    while (gp > 0) {
      Grow& g = grow[gp - 1];
      if (g.left == 0) {
        const Grow done = g;
        --gp;
        if (done.at != 0xFFFFFFFFu) {
          front_[done.at].size = (w - done.at) | (front_[done.at].size & kFlagMask);
          front_[done.at].sub_due = done.min_due;
        }
        if (gp > 0) grow[gp - 1].min_due = std::min(grow[gp - 1].min_due, done.min_due);
        else earliest = done.min_due;
        continue;
      }
      const uint32_t id = g.next++;
      --g.left;
      if (w >= limit) return false;
      const Due d = evaluate_due(frame, id);
      ++evaluated_;
      if (d.split) {
        if (gp >= depth_capacity) return false;
        front_[w] = FrontNode{id, d.due, d.due, kSplitBit | 1};
        const Bound& b = bounds_[id];
        grow[gp++] = Grow{w, b.first_child, b.children, d.due};
      } else {
        front_[w] = FrontNode{id, d.due, d.due, (d.visible ? kVisibleBit : 0) | 1};
        ++cut_delta;
        if (d.visible && entered_count_ >= capacity) return false;
        if (d.visible) entered_[entered_count_++] = NodeId{id};
        g.min_due = std::min(g.min_due, d.due);
      }
      ++w;
    }
    return true;
  };
  if (rebuild) {
    uint32_t w = 0, earliest = 0;
    if (!expand(0, 1, w, front_capacity_, earliest))
      return refuse(uint64_t{capacity} * 2, std::max<uint64_t>(uint64_t{front_capacity_} * 2, 1024));
    front_count_ = w;
    // The sent set: the visible cut nodes in id order, and the change
    // against the old one.
    if (entered_count_ > params.max_nodes || front_count_ > 4 * uint64_t{params.max_nodes} + 9) {
      // The from-the-root cut is bounded by the budget here: that one.
      front_count_ = 0;
      last_incremental_ = false;
      return derive(frame, params);
    }
    NodeId* fresh = cut_ + capacity;  // the stacks are done with
    const uint32_t fresh_count = entered_count_;
    std::copy(entered_, entered_ + fresh_count, fresh);
    std::sort(fresh, fresh + fresh_count, [](NodeId x, NodeId y) { return index_of(x) < index_of(y); });
    const CutStatus kept = keep_sent(fresh, fresh_count);
    if (kept != CutStatus::kOk) return refuse(0, 0), kept;
    cut_count_ = static_cast<uint32_t>(cut_delta);
  } else {
    // One sweep: the old front moved to the end of its storage is read from
    // there and the new one written from the start (a merge frees room, a
    // split takes it: the room left free is the most it may take).
    const uint32_t n = front_count_, gap = front_capacity_ - n;
    if (gap > 0 && n > 0) std::copy_backward(front_, front_ + n, front_ + gap + n);
    uint32_t r = gap, w = 0;
    const uint32_t end = gap + n;
    const auto fold = [&](uint32_t due) {
      if (sp > 0) walk[sp - 1].min_due = std::min(walk[sp - 1].min_due, due);
    };
    for (;;) {
      while (sp > 0 && walk[sp - 1].end == r) {  // a part walked: its size and earliest due
        const Open o = walk[--sp];
        front_[o.at].size = (w - o.at) | (front_[o.at].size & kFlagMask);
        front_[o.at].sub_due = o.min_due;
        fold(o.min_due);
      }
      if (r == end) break;
      FrontNode e = front_[r];
      const uint32_t size = e.size & ~kFlagMask;
      if (e.sub_due > clock_) {  // nothing in this part has come due: it moves as it is
        if (w != r) std::copy(front_ + r, front_ + r + size, front_ + w);
        w += size;
        r += size;
        fold(e.sub_due);
        continue;
      }
      ++visited_;
      const bool was_split = e.size & kSplitBit;
      Due d{true, was_split, e.due};
      if (e.due <= clock_) {
        d = evaluate_due(frame, e.id);
        ++evaluated_;
        e.due = d.due;
      }
      if (was_split && d.split) {  // still above the cut: walk below it
        if (sp >= depth_capacity) return refuse(uint64_t{capacity} * 2, 0);
        front_[w] = e;
        walk[sp++] = Open{w, r + size, e.due};
        ++w;
        ++r;
        continue;
      }
      if (was_split) {  // merge: the part below leaves (its sent nodes, the sent set)
        for (uint32_t q = r + 1; q < r + size; ++q) {
          const FrontNode& gone = front_[q];
          if (gone.size & kSplitBit) continue;
          --cut_delta;
          if (gone.size & kVisibleBit) left_[left_count_++] = NodeId{gone.id};
        }
        ++cut_delta;
        if (d.visible && entered_count_ >= capacity) return refuse(uint64_t{capacity} * 2, 0);
        if (d.visible) entered_[entered_count_++] = NodeId{e.id};
        front_[w++] = FrontNode{e.id, e.due, e.due, (d.visible ? kVisibleBit : 0) | 1};
        r += size;
        fold(e.due);
        continue;
      }
      if (d.split) {  // split: its subtree is made below it, as from the root
        if (e.size & kVisibleBit) left_[left_count_++] = NodeId{e.id};
        --cut_delta;
        const uint32_t at = w++;
        ++r;
        front_[at] = FrontNode{e.id, e.due, e.due, kSplitBit | 1};
        const Bound& b = bounds_[e.id];
        uint32_t earliest = 0;
        if (!expand(b.first_child, b.children, w, r, earliest))
          return refuse(uint64_t{capacity} * 2, uint64_t{front_capacity_} * 2);
        front_[at].size = (w - at) | kSplitBit;
        front_[at].sub_due = std::min(e.due, earliest);
        fold(front_[at].sub_due);
        continue;
      }
      // Stays in the cut: seen now, or not.
      const bool was_visible = e.size & kVisibleBit;
      if (d.visible && !was_visible && entered_count_ >= capacity) return refuse(uint64_t{capacity} * 2, 0);
      if (d.visible && !was_visible) entered_[entered_count_++] = NodeId{e.id};
      if (!d.visible && was_visible) left_[left_count_++] = NodeId{e.id};
      front_[w++] = FrontNode{e.id, e.due, e.due, (d.visible ? kVisibleBit : 0) | 1};
      ++r;
      fold(e.due);
    }
    front_count_ = w;
    const uint64_t sent_after = uint64_t{sent_count_} - left_count_ + entered_count_;
    if (sent_after > capacity) return refuse(sent_after, 0);
    if (sent_after > params.max_nodes || front_count_ > 4 * uint64_t{params.max_nodes} + 9) {
      front_count_ = 0;
      last_incremental_ = false;
      return derive(frame, params);
    }
    // The sent set: the old one (read from the state) less the left, with
    // the entered, in id order; then kept (which lists the same change).
    const auto by_id = [](NodeId x, NodeId y) { return index_of(x) < index_of(y); };
    std::sort(entered_, entered_ + entered_count_, by_id);
    std::sort(left_, left_ + left_count_, by_id);
    NodeId* fresh = cut_ + capacity;
    uint32_t fresh_count = 0, l = 0, k = 0;
    IdReader old{state_};
    for (uint32_t i = 0; i < sent_count_; ++i) {
      const uint32_t id = old.read();
      if (l < left_count_ && index_of(left_[l]) == id) {
        ++l;
        continue;
      }
      while (k < entered_count_ && index_of(entered_[k]) < id) fresh[fresh_count++] = entered_[k++];
      fresh[fresh_count++] = NodeId{id};
    }
    while (k < entered_count_) fresh[fresh_count++] = entered_[k++];
    const CutStatus kept = keep_sent(fresh, fresh_count);
    if (kept != CutStatus::kOk) return refuse(0, 0), kept;
    cut_count_ = static_cast<uint32_t>(int64_t{cut_count_} + cut_delta);
  }
  cut_ = nullptr;
  sent_size_ = nullptr;
  front_valid_ = true;
  budget_bound_ = false;
  return CutStatus::kOk;
}

}  // namespace stipple
