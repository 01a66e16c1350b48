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
  uint32_t first_child;  // id of the first child (children are adjacent)
  int16_t normal[3];     // mean normal, Q14 (zero without normals)
  int16_t cone_sin_q14;  // sin of the normal cone's half-angle (CutBounds::init); 0x7FFF: none
  uint16_t pad0;
  uint8_t children;
  uint8_t pad1;
};
static_assert(sizeof(ViewCut::Bound) == 32);

struct ViewCut::Eval {
  bool visible;   // to be sent if it stays in the cut
  bool split;     // to be replaced by its children
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
    b.pad1 = 0;
    // The statistical cone for now (its sine, and its cosine in pad0's
    // place until the pass below).
    const Cone cone = normals_ ? statistical_cone(node.sigma_n[0], b.children ? cones.gamma_q8 : cones.leaf_gamma_q8)
                               : Cone{kNoCone, 0};
    b.cone_sin_q14 = static_cast<int16_t>(cone.sin);
    b.pad0 = static_cast<uint16_t>(cone.cos);
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
};

ViewCut::Eval ViewCut::evaluate(const Frame& f, uint32_t id) const {
  const Bound& b = bounds_[id];
  const Camera& cam = f.camera;
  const CutParams& p = f.params;
  Eval e{false, false, 0};
  int32_t c[3];
  camera_space(cam, b.center, c);
  const int64_t r = b.radius, z = c[2];
  if (z + r < cam.near_mu) return e;  // wholly behind the near plane
  const bool crosses_near = z - r < cam.near_mu;
  if (!crosses_near && p.cull_frustum) {
    // Planes through the eye and the screen's edges: f X = +-cx Z, f Y = +-cy Z.
    const int64_t fx = int64_t{cam.focal_q4} * c[0], fy = int64_t{cam.focal_q4} * c[1];
    const int64_t cxz = int64_t{cam.center_q4[0]} * z, cyz = int64_t{cam.center_q4[1]} * z;
    if (fx - cxz > r * f.hyp_x || -fx - cxz > r * f.hyp_x || fy - cyz > r * f.hyp_y || -fy - cyz > r * f.hyp_y) return e;
  }
  if (p.cull_backfaces && normals_) {
    // Facing away: the angle between the normal and d = eye - centre exceeds
    // 90 degrees + alpha (the cone's half-angle) + beta (the angle the sphere
    // subtends, sin beta = r / |d|). Conservatively, with sin(alpha + beta)
    // <= sin alpha + sin beta and an upper bound L >= |d|:
    //   cos(n, d) < -(sin alpha + r / L)  <=  n . d < -(sin alpha L + r)
    // (Q14 x MU). No square root or trigonometry per update.
    const int64_t sin_a = b.cone_sin_q14;
    if (sin_a < kQ14One) {
      const int64_t d[3] = {int64_t{cam.eye[0]} - b.center[0], int64_t{cam.eye[1]} - b.center[1],
                            int64_t{cam.eye[2]} - b.center[2]};
      const int64_t dot = b.normal[0] * d[0] + b.normal[1] * d[1] + b.normal[2] * d[2];
      if (dot < 0) {
        // |d| <= m + (a + b) / 2 for the largest |component| m and the others a, b.
        const int64_t a0 = d[0] < 0 ? -d[0] : d[0], a1 = d[1] < 0 ? -d[1] : d[1], a2 = d[2] < 0 ? -d[2] : d[2];
        const int64_t m = a0 > a1 ? (a0 > a2 ? a0 : a2) : (a1 > a2 ? a1 : a2);
        const int64_t len = m + (a0 + a1 + a2 - m + 1) / 2;
        if (dot < -(sin_a * len + (r << 14))) return e;
      }
    }
  }
  e.visible = true;
  if (crosses_near) {  // as large as it gets; split whenever it can be
    e.size = 0xFFFFFFFFu;
    e.split = b.children > 0;
    return e;
  }
  // Projected radius r f / Z (1/16 px), saturated; the split compares the
  // products (below 2^52), as the simple cut does.
  const int64_t size = r * cam.focal_q4 / z;
  e.size = size > 0xFFFFFFFE ? 0xFFFFFFFEu : static_cast<uint32_t>(size);
  if (b.children == 0) return e;
  e.split = r * cam.focal_q4 > int64_t{p.max_size_q4} * z;
  if (e.split && p.window[0] < p.window[2]) {
    // Only inside the refinement window: the projected circle must meet it.
    const int64_t x = cam.center_q4[0] + int64_t{cam.focal_q4} * c[0] / z;
    const int64_t y = cam.center_q4[1] + int64_t{cam.focal_q4} * c[1] / z;
    e.split = x + size >= int64_t{p.window[0]} * 16 && x - size < int64_t{p.window[2]} * 16 &&
              y + size >= int64_t{p.window[1]} * 16 && y - size < int64_t{p.window[3]} * 16;
  }
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
  const Frame frame{camera, params, hyp(camera.center_q4[0]), hyp(camera.center_q4[1])};
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
  while (head < tail && sent_count_ <= params.max_nodes && visited_ <= visit_limit) {
    const uint32_t id = queue[head++];
    ++visited_;
    const Eval e = evaluate(frame, id);
    if (!e.split) {
      settle(id, e);
      continue;
    }
    const Bound& b = bounds_[id];
    for (uint32_t k = 0; k < b.children; ++k) queue[tail++] = b.first_child + k;
  }
  if (head < tail || sent_count_ > params.max_nodes) {
    // The budget binds: refine largest projected size first. The sent nodes
    // so far are the settled visible ones plus every node waiting in the heap
    // (all visible).
    cut_count_ = sent_count_ = 0;
    const auto place = [&](uint32_t id) {
      ++visited_;
      const Eval e = evaluate(frame, id);
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
        for (uint32_t k = 0; k < b.children; ++k) visible += evaluate(frame, b.first_child + k).visible;
        room = uint64_t{sent_count_} + heap_count_ + visible <= params.max_nodes;
      }
      if (!room) {  // the budget is spent: this node and all still waiting stay whole
        settle(id, Eval{true, false, static_cast<uint32_t>(top >> 32)});
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
