// stipple raster — the software point renderer. See point_renderer.h;
// formats and measured errors are in docs/fixed_point.md.
#include "raster/point_renderer.h"

#include <array>
#include <type_traits>
#include <utility>

#include "raster/point_kernel_avx2.h"
#include "raster/resolve.h"

#include "core/arena.h"
#include "core/elevation_ramp.h"
#include "core/fixed_range.h"

namespace stipple {
namespace {

constexpr int32_t kMaxFocalQ4 = 1 << 20;
constexpr int32_t kMaxDepthMu = 1 << 30;
constexpr int32_t kMaxSigmaN = 4 << 12;       // theta table covers theta <= 4 rad
constexpr int32_t kMaxSigmaP = 1 << 25;       // MU: two box extents
constexpr int kMeanTermBits = 11;             // the mean tables: position fields up to 11 bits
// The mean table is built for a frame whose nodes are at least 1 / kMeanCellsPerNode
// of its entries: an entry costs ~30 instructions to build on ARMv5, and
// saves each node ~160 of draw_node's (docs/fixed_point.md, "ARMv5").
constexpr uint32_t kMeanCellsPerNode = 5;
constexpr uint32_t kLaneBatches = 64;         // node lanes: batches of 8 set up in one call
// The fewest points a node drawn in the tile pass has. Where the node lanes
// set nodes up (x86-64 builds) every count: they draw no node through the
// bins, and their tile loop files small nodes' points into shared lanes.
// Elsewhere a tile node costs ~400 instructions beyond its points (its row,
// its links, the scalar loop's set-up in each tile: ARMv5), the bins ~130
// more a point than the tile pass, so nodes of 1-3 points are binned
// (docs/fixed_point.md, "ARMv5"). The picture is the same either way.
constexpr uint32_t kTileMinPoints = avx2::kBuilt ? 1 : 4;

struct Layout {
  size_t raster, internal_frame, coverage, screen_coverage, resolve, g_position, g_normal, g_color, shading, reciprocal,
      lanes, grey, angles, tile_list, mean_terms, ppn, close_ups, splats, ewa_sums, total;
};

// The raster's configuration: the screen, times the supersampling, in
// RGB888 when it is resolved afterwards.
RasterConfig internal_raster(const RendererConfig& c) {
  RasterConfig r = c.raster;
  if (c.supersample > 1) {
    r.width = static_cast<uint16_t>(r.width * c.supersample);
    r.height = static_cast<uint16_t>(r.height * c.supersample);
    r.format = PixelFormat::kRgb888;
  }
  r.max_nodes = c.tile_nodes;
  r.item_words = c.tile_nodes ? kTileFields : 0;
  return r;
}

Layout layout_of(const RendererConfig& c) {
  Layout l{};
  ArenaCarver arena;
  const auto take = [&](size_t bytes) { return arena.take(bytes); };
  const RasterConfig r = internal_raster(c);
  l.raster = take(point_raster_bytes(r));
  l.internal_frame = take(c.supersample > 1 ? size_t{r.width} * r.height * 3 : 0);
  // The resolve works on the screen: the internal frame's coverage, then
  // (supersampling) the screen's, a pixel covered where any of its block is.
  l.coverage = take(c.resolve ? coverage_bytes(r.width, r.height) : 0);
  l.screen_coverage = take(c.resolve && c.supersample > 1 ? coverage_bytes(c.raster.width, c.raster.height) : 0);
  l.resolve = take(c.resolve ? resolve_scratch_bytes(c.raster.width, c.raster.format) : 0);
  l.g_position = take(sizeof(Gaussian3Q12) * c.samples);
  l.g_normal = take(c.normals ? sizeof(Gaussian2Q12) * c.samples : 0);
  l.g_color = take(c.color ? sizeof(Gaussian3Q12) * c.samples : 0);
  l.shading = take(sizeof(ShadingTables));
  l.reciprocal = take(sizeof(uint16_t) << kReciprocalBits);
  l.lanes = take(point_lane_bytes(c.samples));
  l.grey = take(align8(4 * kIntensityEntries) + 2 * 4 * kGreyShades);
  l.angles = take(frame_angles_bytes(c.max_angle_bits));
  // The node lanes' tables (x86-64 builds, lanes kBest): one tile's list
  // of nodes and the points-per-node table with room for the lanes' 32-bit
  // reads; and, for every set-up, each mean field value's camera-space terms.
  const bool node_lanes = avx2::kBuilt && c.lanes == PointLanes::kBest && c.tile_nodes > 0;
  l.tile_list = take(node_lanes ? 4 * size_t{point_raster_items(r)} : 0);
  l.mean_terms = take(sizeof(int32_t) * 3 * 3 * (size_t{1} << kMeanTermBits));
  l.ppn = take(node_lanes ? sizeof(PpnTable) + 4 : 0);
  l.close_ups = take(c.close_ups ? sizeof(CloseUp) * close_up_capacity(r.width, r.height) : 0);
  l.splats = take(sizeof(Splat) * c.splats);
  l.ewa_sums = take(c.splats ? ewa_tile_bytes(r.tile_log2) : 0);
  l.total = arena.total();
  return l;
}

// Where draw_points puts a point: filed in the raster's bins.
struct RasterSink {
  PointRaster& raster;
  int size;
  bool put(int32_t x_q4, int32_t y_q4, uint32_t depth, uint32_t rgb) {
    return raster.add(ScreenPoint{x_q4, y_q4, depth, rgb}, size);
  }
};

// The pixels [lo, hi] a node's point squares can cover along one axis, from
// the mean's screen position p0 (Q4) and the slopes m (1/256 px per sigma):
// every sample is within the table's clip per component, so its offset
// (m . g) >> 16 lies in [-(c sum|m|) / 2^16 - 1, (c sum|m|) / 2^16].
struct Span {
  int32_t lo, hi;
};
// `reach` = sum_k |m_k| G_k, G_k the largest |g_k| of the node's samples
// (Q12): how far its points' offsets m . g (1/2^20 px) reach. For the tile
// pass's nodes |m_k| < 2^15 and G_k <= kGaussianClip < 2^14: int32.
[[gnu::always_inline]] inline Span pixel_span(int32_t p0_q4, int32_t reach, int size) {
  const int32_t d = reach >> 16;
  const int32_t lo = p0_q4 - d - 1 - (size - 1) * 8, hi = p0_q4 + d - (size - 1) * 8;
  return Span{lo >> 4, (hi >> 4) + size - 1};
}

inline int32_t abs32(int32_t v) { return v < 0 ? -v : v; }

// One mean axis's camera-space terms: R's column `axis` (Q14) times d =
// mean_a - eye_a (|d| <= 2^29 + 2^24), each rounded from Q14 (mul_q14_fast:
// 32-bit products on 32-bit targets). A node's camera-space mean is their
// sum over the three axes (every partial sum within int32): formed per node
// (camera_mean) or read from the frame's table over the field's values
// (build_mean_terms) — the same terms either way. The column is taken by
// value: the table's stores cannot alias it, so its loop keeps it in
// registers.
struct RotationColumn {
  int32_t r0, r1, r2;
};
inline RotationColumn rotation_column(const Camera& camera, int axis) {
  return RotationColumn{camera.rotation[0][axis], camera.rotation[1][axis], camera.rotation[2][axis]};
}
inline void mean_axis_terms(RotationColumn column, int32_t d, int32_t out[3]) {
  out[0] = mul_q14_fast(column.r0, d);
  out[1] = mul_q14_fast(column.r1, d);
  out[2] = mul_q14_fast(column.r2, d);
}

inline int bit_length(uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }

// Whether a node's screen sigmas' geometric mean passes 2^log2 px: its
// screen covariance (a, b; b, c in (1/16 px)^2, each below 3 * 2^48) has a
// determinant past (16 2^log2)^4 in (1/16 px)^4 — which needs a + c past
// 2 (16 2^log2)^2 (the node lanes leave every such node to this set-up).
// Huge nodes' terms are shifted to 31 bits first: their determinant's top
// bits decide.
inline bool screen_sigma_beyond(int64_t a, int64_t b, int64_t c, int log2) {
  const int kDet = 4 * (4 + log2);
  const int64_t most = a > c ? a : c;
  if (most < (int64_t{1} << (kDet / 2))) return false;  // a + c below 2 (16 2^log2)^2: the determinant below the bound
  const int s = bit_length(static_cast<uint64_t>(most)) > 31 ? bit_length(static_cast<uint64_t>(most)) - 31 : 0;
  const int64_t as = a >> s, bs = b >> s, cs = c >> s;
  const int64_t det = as * cs - bs * bs;
  return 2 * s >= kDet ? det > 0 : det > (int64_t{1} << (kDet - 2 * s));
}

// A node's camera-space mean formed from its fields (mean_axis_terms), in a
// frame without the mean table.
void camera_mean(const Camera& camera, const NodeDecoder& decoder, const NodeFields& fields, int32_t c[3]) {
  c[0] = c[1] = c[2] = 0;
  for (int a = 0; a < 3; ++a) {
    int32_t t[3];
    mean_axis_terms(rotation_column(camera, a), decoder.mean_axis_mu(a, fields.v[a]) - camera.eye[a], t);
    for (int i = 0; i < 3; ++i) c[i] += t[i];
  }
}

// The frame's mean table: each position field value's camera-space terms
// (mean_axis_terms), [q][3] an axis, q below 2^kMeanTermBits — the terms
// draw_node would form, read by it and by the node lanes.
void build_mean_terms(const Camera& camera, const NodeDecoder& decoder, int32_t* table, const int32_t* out[3]) {
  for (int a = 0; a < 3; ++a) {
    int32_t* t = table + size_t{3} * a * (size_t{1} << kMeanTermBits);
    const uint32_t cells = decoder.mean_axis_cells(a, t, 3);  // the cell centres, then their terms in place
    const RotationColumn column = rotation_column(camera, a);
    const int32_t eye = camera.eye[a];
    for (uint32_t q = 0; q < cells; ++q) mean_axis_terms(column, t[3 * q] - eye, t + 3 * q);
    out[a] = t;
  }
}

}  // namespace

void build_reciprocal_table(uint16_t out[1 << kReciprocalBits]) {
  // 2^26 / (1024 + i + 1/2) = 2^28 / (4 (1024 + i) + 2), rounded half up.
  for (uint32_t i = 0; i < (1u << kReciprocalBits); ++i)
    out[i] = static_cast<uint16_t>(((uint64_t{1} << 29) / (4 * (1024 + i) + 2) + 1) / 2);
}

const char* render_status_text(RenderStatus s) {
  switch (s) {
    case RenderStatus::kOk: return "ok";
    case RenderStatus::kBadConfig: return "invalid renderer configuration";
    case RenderStatus::kStorageTooSmall: return "storage smaller than point_renderer_bytes";
    case RenderStatus::kNoStartup: return "no startup message loaded";
    case RenderStatus::kBadCamera: return "camera out of range";
  }
  return "unknown status";
}

bool renderer_config_valid(const RendererConfig& c) {
  if (c.supersample != 1 && c.supersample != 2 && c.supersample != 4) return false;
  if (uint32_t{c.raster.width} * c.supersample > 8192 || uint32_t{c.raster.height} * c.supersample > 8192) return false;
  return point_raster_bytes(internal_raster(c)) > 0 && point_raster_bytes(c.raster) > 0 && c.samples >= 1 && c.samples <= 8192 && c.splats <= (1u << 24) && c.point_size >= 1 &&
         c.point_size <= 3 && c.max_angle_bits >= 1 && c.max_angle_bits <= kMaxAngleBits && c.quality_q8 >= 1 && c.lighting.shininess >= 1 && c.lighting.shininess <= 64 &&
         (c.lighting.light_q14[0] | c.lighting.light_q14[1] | c.lighting.light_q14[2]) != 0;
}

size_t point_renderer_bytes(const RendererConfig& config) {
  return renderer_config_valid(config) ? layout_of(config).total : 0;
}

bool PointRenderer::set_view(ShadingMode shading, bool grey, uint16_t quality_q8) {
  if (g_position_ == nullptr) return false;
  RendererConfig c = config_;
  c.shading = shading;
  c.grey = grey;
  c.quality_q8 = quality_q8;
  if (!renderer_config_valid(c) || (shading != ShadingMode::kNone && !c.normals)) return false;
  config_ = c;
  return true;
}

bool PointRenderer::set_elevation(SpgAxis up) {
  if (g_position_ == nullptr || static_cast<uint8_t>(up) >= kSpgAxisCount) return false;
  config_.elevation = up;
  return true;
}

RenderStatus PointRenderer::init(const RendererConfig& config, void* storage, size_t bytes) {
  if (!renderer_config_valid(config)) return RenderStatus::kBadConfig;
  const Layout l = layout_of(config);
  if (bytes < l.total) return RenderStatus::kStorageTooSmall;
  uint8_t* base = static_cast<uint8_t*>(storage);
  internal_ = internal_raster(config);
  internal_.avx2 = config.lanes == PointLanes::kBest && avx2::supported();
  if (raster_.init(internal_, base + l.raster, l.internal_frame - l.raster) != RasterStatus::kOk)
    return RenderStatus::kBadConfig;
  internal_frame_ = config.supersample > 1 ? base + l.internal_frame : nullptr;
  coverage_ = config.resolve ? base + l.coverage : nullptr;
  screen_coverage_ = config.resolve ? base + (config.supersample > 1 ? l.screen_coverage : l.coverage) : nullptr;
  resolve_scratch_ = config.resolve ? base + l.resolve : nullptr;
  config_ = config;
  g_position_ = reinterpret_cast<Gaussian3Q12*>(base + l.g_position);
  g_normal_ = config.normals ? reinterpret_cast<Gaussian2Q12*>(base + l.g_normal) : nullptr;
  g_color_ = config.color ? reinterpret_cast<Gaussian3Q12*>(base + l.g_color) : nullptr;
  shading_ = reinterpret_cast<ShadingTables*>(base + l.shading);
  reciprocal_ = reinterpret_cast<uint16_t*>(base + l.reciprocal);
  angles_.init(base + l.angles, config.max_angle_bits);
  static_assert(kTileLinks == PointRaster::kItemLinks, "a tile node's row is the raster's item and its links");
  tile_nodes_.init(raster_.item_words(0), raster_.item_capacity());
  tile_list_ = l.tile_list != l.mean_terms ? reinterpret_cast<uint32_t*>(base + l.tile_list) : nullptr;
  mean_terms_ = reinterpret_cast<int32_t*>(base + l.mean_terms);
  lane_ppn_ = l.ppn != l.close_ups ? reinterpret_cast<uint16_t*>(base + l.ppn) : nullptr;
  close_ups_ = config.close_ups ? reinterpret_cast<CloseUp*>(base + l.close_ups) : nullptr;
  close_up_capacity_ = config.close_ups ? close_up_capacity(internal_.width, internal_.height) : 0;
  splats_ = config.splats ? reinterpret_cast<Splat*>(base + l.splats) : nullptr;
  splat_capacity_ = config.splats;
  ewa_sums_ = config.splats ? reinterpret_cast<uint32_t*>(base + l.ewa_sums) : nullptr;
  lanes_ = config.lanes == PointLanes::kScalar ? PointLanes::kScalar
           : config.lanes == PointLanes::kBest && avx2::supported() ? PointLanes::kBest
                                                                     : PointLanes::kBaseline;
  build_gaussian3_table(config.source, g_position_, config.samples);
  if (g_normal_) build_gaussian2_table(config.source, g_normal_, config.samples);
  if (g_color_) build_gaussian3_table(config.source, g_color_, config.samples, kColorSobolDim);
  if (!build_shading_tables(config.lighting, shading_)) return RenderStatus::kBadConfig;
  build_reciprocal_table(reciprocal_);
  int32_t most[3] = {0, 0, 0};
  for (uint32_t i = 0, j = 0; i < kSampleReachBuckets; ++i) {
    for (; j < sample_reach_samples(static_cast<int>(i)) && j < config.samples; ++j)
      for (int k = 0; k < 3; ++k)
        if (abs32(g_position_[j].v[k]) > most[k]) most[k] = abs32(g_position_[j].v[k]);
    for (int k = 0; k < 3; ++k) sample_reach_[i][k] = most[k];
  }
  tables_ = PointTables{g_position_, g_normal_, g_color_, shading_};
  build_point_lanes(g_position_, g_normal_, g_color_, config.samples, base + l.lanes, &tables_);
  uint32_t* grey_diffuse = reinterpret_cast<uint32_t*>(base + l.grey);
  uint32_t* grey_shades = reinterpret_cast<uint32_t*>(base + l.grey + align8(4 * kIntensityEntries));
  grey_shades_ = build_grey_shades(*shading_, config.grey_rgb, grey_diffuse, grey_shades, grey_shades + kGreyShades)
                     ? grey_shades
                     : nullptr;
  tables_.grey_diffuse = grey_diffuse;
  ppn_ = &ppn_table(config.source, config.point_size);
  if (lane_ppn_ != nullptr) {
    const uint16_t* table = &(*ppn_)[0][0];
    for (int i = 0; i < kPpnSizes * kPpnAspects; ++i) lane_ppn_[i] = table[i];
    lane_ppn_[kPpnSizes * kPpnAspects] = lane_ppn_[kPpnSizes * kPpnAspects + 1] = 0;
  }
  return RenderStatus::kOk;
}

// A node's per-point constants for the per-point path (the bins): the
// projection in full (the exact and reciprocal modes read the camera-space
// axes) and the point formula's depth and shading terms.
struct PointRenderer::PointSetup {
  NodeProjection proj;
  int64_t depth0;  // (Z - near) << depth shift, below 2^61
  int32_t dz[3];   // depth per sigma, scaled by 2^dshift: |dz| < 2^15
  int dshift;      // 12 - e; negative for a node deeper than 2^27 depth units a sigma
  uint32_t count;
  int32_t near;
  int size;
  // kAffine: every slope and depth term fits 16 bits and every depth the
  // depth word — the tile pass's int32 point formula holds (point_kernel.h).
  bool int32_terms = false;
  PointShade shade;
};

struct PointRenderer::FrameSetup {
  Camera camera;
  const NodeDecoder* decoder;
  // Each mean field value's camera-space terms, [q][3] an axis (build_mean_terms),
  // or null: draw_node forms them.
  const int32_t* mean[3];
  int32_t width_q4, height_q4;
  int depth_shift;
  int16_t light[3], half[3];  // model space, Q14
  bool model_color;  // the node's colour varies: the model's, or by elevation
  int elevation_field;  // -1, or the mean's field the ramp reads (0..2)
  int elevation_bits;   // that field's width
  bool elevation_down;  // the axis points down: the ramp reversed
  bool lit;  // the model has normals and the shading uses them
  bool close_ups;  // nodes may be drawn as discs (RendererConfig::close_ups, without the point cap)
  bool splats;     // drawn nodes are also EWA splats (RendererConfig::splats)
  int close_up_log2;  // close-ups are measured in screen pixels: log2 of the supersampling
  int64_t close_up_gate;  // a or c (1/256 px^2) from which a node may be one: (16 2^(kCloseUpPointsLog2 + close_up_log2))^2
  CloseUpFrame close_up;
};

// Depth: the node's (Z - near) and depth per sigma in the depth word's units.
[[gnu::always_inline]] inline void PointRenderer::set_up_depth(const FrameSetup& f, const int32_t c[3],
                                                              const int32_t axes[3][3], PointSetup& s) {
  // (z - near) << shift for z = Z + (A_z . g) / 2^12, as
  // depth0 + (dz . g) >> dshift with dz = A_z 2^(shift - e) in 16 bits
  // (|A_z| 2^shift < 2^61.1: e <= 47).
  // e from A_z's bit length and the shift; A_z << (shift - e) or
  // A_z >> (e - shift), floored: (A_z 2^shift) >> e in 32 bits.
  s.depth0 = (int64_t{c[2]} - f.camera.near_mu) * (int64_t{1} << f.depth_shift);
  uint32_t az_max = 0;
  for (int k = 0; k < 3; ++k) {
    const uint32_t m = static_cast<uint32_t>(axes[k][2] < 0 ? -axes[k][2] : axes[k][2]);
    if (m > az_max) az_max = m;
  }
  const int bits = az_max == 0 ? 0 : bit_length(az_max) + f.depth_shift;
  const int e = bits > 15 ? bits - 15 : 0;
  for (int k = 0; k < 3; ++k)
    s.dz[k] = e <= f.depth_shift ? axes[k][2] * (1 << (f.depth_shift - e)) : axes[k][2] >> (e - f.depth_shift);
  s.dshift = 12 - e;

}

// A node's colour and shading constants (point_kernel.h's PointShade): its
// colour (the model's, its elevation's or the grey), the light's terms in
// its normal frame, the surface's turn and the colour axes.
template <PointNormals kNormals, bool kColorPoints, bool kSpecular>
[[gnu::always_inline]] inline void PointRenderer::set_up_shade(const FrameSetup& f, const NodeFields& fields,
                                                              const int16_t frame[3][3], const int32_t sk[3],
                                                              PointShade& sh) {
  const NodeDecoder& decoder = *f.decoder;
  uint8_t rgb[3] = {0, 0, 0};
  if (f.elevation_field >= 0) {
    // The mean's cell along the up axis, as a ramp index 0..255.
    uint32_t t = f.elevation_bits == 0 ? 128u : (uint32_t{fields.v[f.elevation_field]} << 8) >> f.elevation_bits;
    if (f.elevation_down) t = 255u - t;
    const uint32_t ramp = elevation_rgb(t);
    rgb[0] = static_cast<uint8_t>(ramp >> 16), rgb[1] = static_cast<uint8_t>(ramp >> 8), rgb[2] = static_cast<uint8_t>(ramp);
  } else if (f.model_color) {
    decoder.color_rgb(fields, rgb);
  }
  sh.base_rgb = f.model_color ? (uint32_t{rgb[0]} << 16) | (uint32_t{rgb[1]} << 8) | rgb[2] : config_.grey_rgb & 0xFFFFFFu;
  if (f.lit) {
    int32_t l[3], h[3];
    angles_.light_terms(decoder.euler(FrameField::kNormal), fields, l, h);
    // sigma_n's sign is the curvature's (negative: concave along t_k): the
    // surface turns with it, sampled normals take the spread.
    const int32_t* sn = decoder.sigma_n_q12(ClassId{fields[Field::kSigmaN]});
    int32_t turn_n[2];
    for (int k = 0; k < 2; ++k) {
      turn_n[k] = sn[k] < -kMaxSigmaN ? -kMaxSigmaN : sn[k] > kMaxSigmaN ? kMaxSigmaN : sn[k];
      sh.sn[k] = static_cast<int16_t>(turn_n[k] < 0 ? -turn_n[k] : turn_n[k]);
      sh.lt[k] = static_cast<int16_t>(l[k]);
      sh.ht[k] = static_cast<int16_t>(h[k]);
    }
    sh.l0 = static_cast<int16_t>((l[2] + 2) >> 2);
    sh.h0 = static_cast<int16_t>((h[2] + 2) >> 2);
    sh.intensity = shading_->diffuse[intensity_index(l[2])];
    sh.specular = kSpecular ? static_cast<uint16_t>(shading_->specular[intensity_index(h[2])]) : 0;
    if constexpr (kNormals == PointNormals::kSurface) {
      // The surface's normal field: a position sample g lands at sum_i g_i
      // sigma_i a_i; its offset along the normal frame's tangent t_k, over
      // the node's positional spread along t_k, is how many sigma_n the
      // normal turns there (a convex patch, its curvature sigma_n /
      // sigma_p; a concave one turns the other way). Only the direction of w_k = (sigma_i a_i . t_k)_i
      // matters, so sigma is scaled to 15 bits first: every term is int32.
      // Per point the angle is then surface_k . g (point_kernel.h).
      int16_t tangent[2][3];
      angles_.normal_tangents(decoder.euler(FrameField::kNormal), fields, tangent);
      const int32_t smax = sk[0] > sk[1] ? (sk[0] > sk[2] ? sk[0] : sk[2]) : (sk[1] > sk[2] ? sk[1] : sk[2]);
      const int scale = bit_length(static_cast<uint64_t>(smax)) > 15 ? bit_length(static_cast<uint64_t>(smax)) - 15 : 0;
      for (int k = 0; k < 2; ++k) {
        int32_t w[3], s2 = 0;
        for (int i = 0; i < 3; ++i) {
          // a_i . t_k: Q14 unit vectors, below 2^28 (+ rounding); w below 2^14.
          const int32_t cosine = (frame[i][0] * tangent[k][0] + frame[i][1] * tangent[k][1] +
                                  frame[i][2] * tangent[k][2] + (1 << 13)) >> 14;
          w[i] = ((sk[i] >> scale) * cosine) >> 15;
          s2 += w[i] * w[i];  // below 3 * 2^28
        }
        if (s2 == 0) continue;
        const RsqrtScale r = rsqrt_scale(*shading_, static_cast<uint64_t>(s2));  // 2^14 / |w|, without a division
        for (int i = 0; i < 3; ++i) {
          // The turn along axis i in Q14 (|.| <= 2^14 (1 + 1/512)), times sigma_n (Q12, <= 2^14).
          const int32_t n = (w[i] * static_cast<int32_t>(r.mul)) >> r.shift;
          const int32_t turn = n > 16416 ? 16416 : n < -16416 ? -16416 : n;
          sh.surface[k][i] = static_cast<int16_t>((turn_n[k] * turn + (1 << 13)) >> 14);
        }
      }
    }
  }
  sh.node_rgb = shade(sh.base_rgb >> 16, (sh.base_rgb >> 8) & 0xFFu, sh.base_rgb & 0xFFu, sh.intensity, sh.specular);
  if constexpr (kColorPoints) {
    // Colour axes in 8-bit levels per sigma, Q7: the frame (Q14) times
    // sigma_c (Q12, < 2^31) times 255, below 2^53; saturated to 16 bits.
    int16_t cf[3][3];
    FrameAngles::model_frame(decoder.euler(FrameField::kColor), fields, Field::kFcTheta, cf);
    const int32_t* sc = decoder.sigma_c_q12(ClassId{fields[Field::kSigmaC]});
    for (int k = 0; k < 3; ++k)
      for (int ch = 0; ch < 3; ++ch) {
        const int64_t w = (int64_t{cf[k][ch]} * sc[k] * 255) >> 19;
        sh.ca[k][ch] = static_cast<int16_t>(w > 32767 ? 32767 : w < -32767 ? -32767 : w);
      }
  }
}

// The affine projection: a node whose terms fit 16 bits and whose depths
// stay inside the depth word, waiting for the tile pass of the tiles it
// touches; false when it does not (its points then go through the bins).
template <PointNormals kNormals, bool kColorPoints>
[[gnu::always_inline]] inline bool PointRenderer::wait_in_tiles(PointSetup& s, FrameStats& stats) {
  const NodeProjection& proj = s.proj;
  const PointShade& sh = s.shade;
  // At most 2 x 2 tiles; its points count against the frame's budget now.
  // Such a node beyond the tile pass's room takes the bins with the tile
  // pass's int32 formula (draw_points).
  const int32_t sx = abs32(proj.mx[0]) + abs32(proj.mx[1]) + abs32(proj.mx[2]);  // below 2^30
  const int32_t sy = abs32(proj.my[0]) + abs32(proj.my[1]) + abs32(proj.my[2]);
  const int32_t reach = sx < (1 << 15) && sy < (1 << 15) && s.dshift >= 0
                            ? ((abs32(s.dz[0]) + abs32(s.dz[1]) + abs32(s.dz[2])) * kGaussianClip) >> s.dshift
                            : -1;
  s.int32_terms = reach >= 0 && s.depth0 - reach - 1 >= 0 && s.depth0 + reach <= 0xFFFFFFFE;
  if (s.int32_terms && s.count >= kTileMinPoints && raster_.item_room(s.count)) {
    // Its span on screen from the samples it draws, which reach no
    // farther than sample_reach_ says (for a few points, little more
    // than half kGaussianClip) — fewer nodes across tile edges.
    const int32_t* g = sample_reach_[sample_reach_bucket(s.count)];
    const auto offsets = [g](const int32_t m[3]) __attribute__((always_inline)) { return abs32(m[0]) * g[0] + abs32(m[1]) * g[1] + abs32(m[2]) * g[2]; };
    const Span spx = pixel_span(proj.x0_q4, offsets(proj.mx), s.size), spy = pixel_span(proj.y0_q4, offsets(proj.my), s.size);
    const int sh_t = internal_.tile_log2;
    const int32_t tx0 = (spx.lo < 0 ? 0 : spx.lo) >> sh_t, ty0 = (spy.lo < 0 ? 0 : spy.lo) >> sh_t;
    const int32_t tx1 = (spx.hi >= internal_.width ? internal_.width - 1 : spx.hi) >> sh_t;
    const int32_t ty1 = (spy.hi >= internal_.height ? internal_.height - 1 : spy.hi) >> sh_t;
    if (spx.hi >= 0 && spy.hi >= 0 && spx.lo < internal_.width && spy.lo < internal_.height && tx1 - tx0 <= 1 &&
        ty1 - ty0 <= 1) {
      const uint32_t item = raster_.items();
      raster_.take_item(s.count);
      const int32_t span[4] = {spx.lo, spx.hi, spy.lo, spy.hi};
      tile_nodes_.store_terms(item, proj.mx, proj.my, s.dz, proj.x0_q4 - (s.size - 1) * 8,
                              proj.y0_q4 - (s.size - 1) * 8, static_cast<uint32_t>(s.depth0), span, s.count,
                              static_cast<uint32_t>(s.dshift));
      tile_nodes_.store_shade<kNormals == PointNormals::kSurface, kColorPoints>(item, sh);
      int slot = 0;
      for (int32_t ty = ty0; ty <= ty1; ++ty)
        for (int32_t tx = tx0; tx <= tx1; ++tx)
          raster_.file_item(item, slot++, static_cast<uint32_t>(ty * raster_.tiles_x() + tx));
      ++stats.nodes_in_tiles;
      stats.points += s.count;
      return true;
    }
  }
  return false;
}

// Close-ups (close_up.h): the node as its 3 sigma disc, shaded as its
// points would be (with sampled normals: by its mean normal), while the
// frame has room for it; false — drawn as points, or culled — otherwise.
template <PointNormals kNormals, bool kSpecular>
[[gnu::noinline, gnu::cold]] bool PointRenderer::take_close_up(const FrameSetup& f, const NodeFields& fields, const int32_t c[3],
                                  const int16_t frame[3][3], const int32_t sk[3], FrameStats& stats) {
  if (close_up_count_ >= close_up_capacity_) return false;
  CloseUp& disc = close_ups_[close_up_count_];
  if (!set_up_close_up(f.close_up, c, frame, sk, &disc)) return false;
  PointShade sh;
  set_up_shade<kNormals, false, kSpecular>(f, fields, frame, sk, sh);
  disc.shade = PackedShade(sh);
  if (f.splats) take_splat(f, fields, c, frame, sk, sh, stats);  // its colour with its neighbours'
  ++close_up_count_;
  ++stats.nodes_drawn;
  ++stats.nodes_close_up;
  return true;
}

// A node whose mean is outside the view (in_view) as its disc, where its 3
// sigma ball reaches into the view: its frame and sigmas formed here, off
// the set-up's path.
template <PointNormals kNormals, bool kSpecular>
[[gnu::noinline, gnu::cold]] bool PointRenderer::close_up_outside(const FrameSetup& f, const NodeFields& fields,
                                                                  const int32_t c[3], FrameStats& stats) {
  const NodeDecoder& decoder = *f.decoder;
  int16_t frame[3][3];
  angles_.position_frame(decoder.euler(FrameField::kPosition), fields, frame);
  const int32_t* sigma = decoder.sigma_p_mu(ClassId{fields[Field::kSigmaP]});
  int32_t sk[3];
  for (int k = 0; k < 3; ++k) sk[k] = sigma[k] < kMaxSigmaP ? sigma[k] : kMaxSigmaP;
  const int32_t largest = sk[0] > sk[1] ? (sk[0] > sk[2] ? sk[0] : sk[2]) : (sk[1] > sk[2] ? sk[1] : sk[2]);
  return close_up_reaches(f.camera, c, largest) && take_close_up<kNormals, kSpecular>(f, fields, c, frame, sk, stats);
}

// The frame's discs over one tile's words, after its points.
template <PointNormals kNormals, bool kSpecular, class Word>
[[gnu::noinline]] void PointRenderer::draw_close_ups(int px0, int py0, Word* words) {
  const int tile = 1 << internal_.tile_log2;
  const int pw = px0 + tile > internal_.width ? internal_.width - px0 : tile;
  const int ph = py0 + tile > internal_.height ? internal_.height - py0 : tile;
  for (uint32_t i = 0; i < close_up_count_; ++i)
    draw_close_up<close_up_normals(kNormals), kSpecular>(close_ups_[i], tables_, reciprocal_, px0, py0, pw, ph, internal_.tile_log2, words);
}

// EWA (ewa.h): the node also a splat, shaded as its points, while the
// frame has room for it — unless its mean normal faces away: its surface's
// front is another splat's, and its back's shading would bleed through
// within the visibility pass's depth (the GL client drops it too).
[[gnu::noinline]] void PointRenderer::take_splat(const FrameSetup& f, const NodeFields& fields, const int32_t c[3],
                                                 const int16_t frame[3][3], const int32_t sk[3], const PointShade& shade,
                                                 FrameStats& stats) {
  if (splat_count_ >= splat_capacity_) return;
  if (f.lit) {
    int16_t t[2][3];
    angles_.normal_tangents(f.decoder->euler(FrameField::kNormal), fields, t);
    int64_t facing = 0;  // (t1 x t2) . c, Q28 MU: the mean normal against the eye's ray to the mean
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      facing += (int64_t{t[0][j]} * t[1][k] - int64_t{t[0][k]} * t[1][j]) * c[i];
    }
    if (facing > 0) return;
  }
  Splat& s = splats_[splat_count_];
  if (!set_up_splat(f.close_up, c, frame, sk, &s)) return;
  s.disc.shade = PackedShade(shade);
  ++splat_count_;
  ++stats.splats;
}

// The frame's splats over one tile's words, after its points and discs.
template <PointNormals kNormals, bool kSpecular, class Word>
[[gnu::noinline]] void PointRenderer::draw_splats(int px0, int py0, Word* words) {
  const int tile = 1 << internal_.tile_log2;
  const int pw = px0 + tile > internal_.width ? internal_.width - px0 : tile;
  const int ph = py0 + tile > internal_.height ? internal_.height - py0 : tile;
  stipple::draw_splats<close_up_normals(kNormals), kSpecular>(splats_, splat_count_, tables_, reciprocal_, px0, py0, pw, ph,
                                                              internal_.tile_log2, words, ewa_sums_);
}

template <Projection P, PointNormals kNormals, bool kColorPoints, bool kSpecular>
void PointRenderer::draw_node(const FrameSetup& f, const NodeFields& fields, uint32_t max_points, FrameStats& stats) {
  const NodeDecoder& decoder = *f.decoder;
  // The mean in camera space, each axis's terms rounded (mean_axis_terms),
  // from the frame's table where it has one.
  int32_t c[3];
  if (f.mean[0] != nullptr) {
    const int32_t *t0 = f.mean[0] + 3 * fields.v[0], *t1 = f.mean[1] + 3 * fields.v[1], *t2 = f.mean[2] + 3 * fields.v[2];
    for (int i = 0; i < 3; ++i) c[i] = t0[i] + t1[i] + t2[i];
  } else {
    camera_mean(f.camera, decoder, fields, c);
  }
  constexpr PointNormals kDisc = close_up_normals(kNormals);
  if (!NodeProjection::in_view(f.camera, c)) {
    // A close-up whose mean lies outside the view: its disc where it reaches into it.
    if (!f.close_ups || !close_up_outside<kDisc, kSpecular>(f, fields, c, stats)) ++stats.nodes_culled;
    return;
  }
  // The axes in camera space (node_setup.h): the frame in Q14 times sigma
  // in MU, at most 2^25 (two box extents: larger only in a hostile file),
  // below 2^25 + 2^11.
  int16_t frame[3][3];
  angles_.position_frame(decoder.euler(FrameField::kPosition), fields, frame);
  const int32_t* sigma = decoder.sigma_p_mu(ClassId{fields[Field::kSigmaP]});
  int32_t axes[3][3], sk[3];
  for (int k = 0; k < 3; ++k) {
    sk[k] = sigma[k] < kMaxSigmaP ? sigma[k] : kMaxSigmaP;
    for (int i = 0; i < 3; ++i) axes[k][i] = mul_q14_fast(frame[k][i], sk[k]);
  }
  PointSetup s;
  NodeProjection& proj = s.proj;
  if (!proj.template setup<P != Projection::kAffine>(f.camera, c, axes)) {
    // Too near for the projection: a close-up's disc.
    if (!f.close_ups || !take_close_up<kDisc, kSpecular>(f, fields, c, frame, sk, stats)) ++stats.nodes_culled;
    return;
  }
  // The gamma-extent (3.5 sigma) on screen, an L1 bound: cull nodes wholly
  // off screen. Screen covariance M M^T for the points-per-node index.
  // |mx|, |my| < 2^28: the extents below 2^28 (int32), the covariance's
  // products 32 x 32 bits into 64.
  int32_t ex = 0, ey = 0;
  int64_t a = 0, b = 0, cc = 0;
  for (int k = 0; k < 3; ++k) {
    const int32_t vx = proj.mx[k] >> 4, vy = proj.my[k] >> 4;  // 1/16 px per sigma
    ex += vx < 0 ? -vx : vx;
    ey += vy < 0 ? -vy : vy;
    a += int64_t{vx} * vx;
    b += int64_t{vx} * vy;
    cc += int64_t{vy} * vy;
  }
  ex = (ex * 7) >> 1;
  ey = (ey * 7) >> 1;
  // Close-ups: one test of the covariance's diagonal (a node's sigma past
  // 1 px on an axis) gates both rules, so other nodes pay an OR and a compare.
  bool more_points = false;
  if (f.close_ups && (a | cc) >= f.close_up_gate) [[unlikely]] {
    if (screen_sigma_beyond(a, b, cc, f.close_up_log2 + kCloseUpSigmaLog2) &&
        take_close_up<kDisc, kSpecular>(f, fields, c, frame, sk, stats))
      return;
    more_points = screen_sigma_beyond(a, b, cc, f.close_up_log2 + kCloseUpPointsLog2);
  }
  if (proj.x0_q4 + ex < 0 || proj.x0_q4 - ex >= f.width_q4 || proj.y0_q4 + ey < 0 || proj.y0_q4 - ey >= f.height_q4) {
    ++stats.nodes_culled;
    return;
  }
  // a, c: (1/16 px)^2 = 1/256 px^2, below 3 * 2^48.
  s.count = points_per_node(*ppn_, ppn_index(a, b, cc), config_.quality_q8, config_.samples);
  // Close-ups' points: a node past 2^kCloseUpPointsLog2 px (beyond the cut's
  // size: a leaf seen close) draws kCloseUpPointsScale_q8 / 256 times its count.
  if (more_points) [[unlikely]] {
    const uint32_t more = s.count * kCloseUpPointsScale_q8 >> 8;
    s.count = more < config_.samples ? more : config_.samples;
  }
  if (s.count > max_points) s.count = max_points;  // the point cap
  s.near = f.camera.near_mu;
  s.size = config_.point_size;

  set_up_depth(f, c, axes, s);
  set_up_shade<kNormals, kColorPoints, kSpecular>(f, fields, frame, sk, s.shade);
  ++stats.nodes_drawn;
  if (f.splats) [[unlikely]] take_splat(f, fields, c, frame, sk, s.shade, stats);
  if constexpr (P == Projection::kAffine) {
    if (wait_in_tiles<kNormals, kColorPoints>(s, stats)) return;
  }
  stats.points += draw_points<P, kNormals, kColorPoints, kSpecular>(s, stats);
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void PointRenderer::draw_tile_nodes(uint32_t tile, int px0, int py0, Word* words) {
  const PointTables& t = tables_;
  if constexpr (avx2::kBuilt) {
    if (lanes_ == PointLanes::kBest) {
      uint32_t n = 0;
      for (uint32_t link = raster_.first_link(tile); link != PointRaster::kNoLink; link = raster_.next_link(link))
        tile_list_[n++] = link / kTileStride;
      avx2::draw_tile<kNormals, kColorPoints, kSpecular>(tile_nodes_, tile_list_, n, t, config_.point_size, words,
                                                         internal_.tile_log2, px0, py0);
      return;
    }
  }
  for (uint32_t link = raster_.first_link(tile); link != PointRaster::kNoLink; link = raster_.next_link(link)) {
    const TileRow n(tile_nodes_.row(link / kTileStride));  // (PointRaster::item_of, the stride known here)
    if (lanes_ == PointLanes::kScalar)
      draw_tile_node_scalar<kNormals, kColorPoints, kSpecular>(n, t, config_.point_size, words, internal_.tile_log2, px0, py0);
    else
      draw_tile_node<kNormals, kColorPoints, kSpecular>(n, t, config_.point_size, words, internal_.tile_log2, px0, py0);
  }
}

template <PointNormals kNormals, bool kColorPoints, bool kSpecular>
void PointRenderer::tile_nodes_of(void* context, uint32_t tile, int px0, int py0, void* words) {
  PointRenderer& r = *static_cast<PointRenderer*>(context);
  // With discs every tile is called, with nodes or none.
  const bool nodes = r.raster_.items() != 0 && r.raster_.first_link(tile) != PointRaster::kNoLink;
  const auto draw = [&](auto* tile_words) {
    if (nodes) r.draw_tile_nodes<kNormals, kColorPoints, kSpecular>(tile, px0, py0, tile_words);
    if (r.close_up_count_ != 0) r.draw_close_ups<kNormals, kSpecular>(px0, py0, tile_words);
    if (r.splat_count_ != 0) r.draw_splats<kNormals, kSpecular>(px0, py0, tile_words);
  };
  if (r.internal_.format == PixelFormat::kRgb565) draw(static_cast<uint32_t*>(words));
  else draw(static_cast<uint64_t*>(words));
}

// The per-point path through the bins: its own function, never inlined,
// so that the ARMv5 build can be checked symbol by symbol for run-time
// helper calls (tests/handheld/per_point_helpers.cmake).
template <Projection P, PointNormals kNormals, bool kColorPoints, bool kSpecular>
uint32_t PointRenderer::draw_points(const PointSetup& s, FrameStats& stats) {
  const NodeProjection& proj = s.proj;
  const PointTables& t = tables_;
  const PackedShade shade(s.shade);
  RasterSink sink{raster_, s.size};
  // A left shift of dz . g (|.| < 2^30.4) by up to 35 bits, saturated at
  // 2^62: the depth of a node deeper than the whole depth range.
  const int64_t limit = s.dshift >= 0 ? 0 : int64_t{1} << (62 + s.dshift);
  uint32_t drawn = 0;
  if constexpr (P == Projection::kAffine) {
    if (s.int32_terms) {
      // The tile pass's formula (draw_tile_node_scalar), the same values:
      // |m . g| < 2^29, and the depth stays within [0, 2^32 - 2].
      const uint32_t mx01 = int16_pair(proj.mx[0], proj.mx[1]), mx2 = int16_pair(proj.mx[2], 0);
      const uint32_t my01 = int16_pair(proj.my[0], proj.my[1]), my2 = int16_pair(proj.my[2], 0);
      const uint32_t dz01 = int16_pair(s.dz[0], s.dz[1]), dz2 = int16_pair(s.dz[2], 0);
      const uint32_t depth0 = static_cast<uint32_t>(s.depth0);
      const int dshift = s.dshift;
      const auto points = [&](auto clamp_angles) {
        for (uint32_t j = 0; j < s.count; ++j) {
          const uint32_t g01 = t.g01[j], g2 = t.g2[j];
          const int32_t x = proj.x0_q4 + (pair_dot(g01, g2, mx01, mx2) >> 16);
          const int32_t y = proj.y0_q4 + (pair_dot(g01, g2, my01, my2) >> 16);
          const uint32_t depth = depth0 + static_cast<uint32_t>(pair_dot(g01, g2, dz01, dz2) >> dshift);
          const uint32_t rgb =
              point_color<kNormals, kColorPoints, kSpecular, false, decltype(clamp_angles)::value>(shade, t, j, g01, g2);
          if (sink.put(x, y, depth, rgb)) ++drawn;
          else ++stats.points_dropped;
        }
      };
      // As in the tile pass: the angles' clamp only where a point may need it.
      if (!angles_in_range<kNormals>(shade)) points(std::true_type{});
      else points(std::false_type{});
      return drawn;
    }
  }
  for (uint32_t j = 0; j < s.count; ++j) {
    const Gaussian3Q12 g = g_position_[j];
    const int64_t dg = int64_t{s.dz[0]} * g.v[0] + int64_t{s.dz[1]} * g.v[1] + int64_t{s.dz[2]} * g.v[2];
    const int64_t off = s.dshift >= 0 ? dg >> s.dshift
                        : dg >= limit ? limit
                        : dg <= -limit ? -limit
                                       : dg * (int64_t{1} << -s.dshift);
    const int64_t d = s.depth0 + off;
    int32_t x, y;
    if constexpr (P == Projection::kAffine) {
      if (d < 0) continue;  // behind the near plane
      x = proj.x0_q4 + narrow<int32_t>((int64_t{proj.mx[0]} * g.v[0] + int64_t{proj.mx[1]} * g.v[1] + int64_t{proj.mx[2]} * g.v[2]) >> 16);
      y = proj.y0_q4 + narrow<int32_t>((int64_t{proj.my[0]} * g.v[0] + int64_t{proj.my[1]} * g.v[1] + int64_t{proj.my[2]} * g.v[2]) >> 16);
    } else {
      ScreenSample p;
      if (!proj.template point<P>(g, s.near, reciprocal_, &p)) continue;
      x = p.x_q4;
      y = p.y_q4;
    }
    const uint32_t depth = d < 0 ? 0u : d > 0xFFFFFFFE ? 0xFFFFFFFEu : static_cast<uint32_t>(d);
    if (sink.put(x, y, depth, point_color<kNormals, kColorPoints, kSpecular>(shade, t, j, t.g01[j], t.g2[j]))) ++drawn;
    else ++stats.points_dropped;
  }
  return drawn;
}

NodeLaneFrame PointRenderer::lane_frame(const FrameSetup& f, const NodeCache& cache) {
  const NodeDecoder& decoder = cache.decoder();
  const SpgHeader& header = cache.header();
  NodeLaneFrame lf;
  lf.records = cache.record_at(0);
  lf.stride = static_cast<uint32_t>(cache.record_stride());
  for (int i = 0; i < kFieldCount; ++i)
    lf.window[i] = cache.decoded() ? FieldWindow{static_cast<uint8_t>(2 * i), 0, 0xFFFF}
                                   : field_window(header.layout, static_cast<Field>(i));
  for (int a = 0; a < 3; ++a) lf.mean[a] = f.mean[a];
  lf.position = angles_.position_table();
  lf.normal = angles_.normal_table();
  lf.light = angles_.light_table();
  for (int i = 0; i < 3; ++i) lf.column2[i] = angles_.column2()[i];
  lf.light_z = angles_.light_z();
  lf.half_z = angles_.half_z();
  const auto euler = [](const EulerTables& e, const SinCosQ14** theta, const SinCosQ14** gamma, uint8_t* psi_shift,
                        uint8_t* phi_shift, uint32_t* mask) {
    *theta = e.theta;
    *gamma = e.gamma;
    *psi_shift = static_cast<uint8_t>(e.gamma_bits - e.psi_bits - 1);
    *phi_shift = static_cast<uint8_t>(e.gamma_bits - e.phi_bits);
    *mask = (1u << e.gamma_bits) - 1u;
  };
  euler(decoder.euler(FrameField::kPosition), &lf.theta_p, &lf.gamma_p, &lf.gamma_psi_shift_p, &lf.gamma_phi_shift_p,
        &lf.gamma_mask_p);
  if (f.lit)
    euler(decoder.euler(FrameField::kNormal), &lf.theta_n, &lf.gamma_n, &lf.gamma_psi_shift_n, &lf.gamma_phi_shift_n,
          &lf.gamma_mask_n);
  lf.sigma_p = decoder.sigma_p_mu(ClassId{0});
  lf.sigma_n = f.lit ? decoder.sigma_n_q12(ClassId{0}) : nullptr;
  lf.near = f.camera.near_mu;
  lf.focal_q4 = f.camera.focal_q4;
  lf.cx_q4 = f.camera.center_q4[0];
  lf.cy_q4 = f.camera.center_q4[1];
  lf.width_q4 = f.width_q4;
  lf.height_q4 = f.height_q4;
  lf.width = internal_.width;
  lf.height = internal_.height;
  lf.depth_shift = f.depth_shift;
  lf.size = config_.point_size;
  lf.tile_log2 = internal_.tile_log2;
  lf.ppn = lane_ppn_;
  lf.quality_q8 = config_.quality_q8;
  lf.samples = config_.samples;
  lf.sample_reach = &sample_reach_[0][0];
  lf.lit = f.lit;
  lf.close_ups = f.close_ups;
  lf.close_up_wide = static_cast<int32_t>(2 * f.close_up_gate);  // a + c, where a or c past the gate may be one
  lf.shading = shading_;
  lf.base_rgb = config_.grey_rgb & 0xFFFFFFu;
  return lf;
}

using DrawFn = void (PointRenderer::*)(const PointRenderer::FrameSetup&, const NodeFields&, uint32_t, FrameStats&);
using LaneFn = uint32_t (*)(const NodeLaneFrame&, uint32_t, uint32_t, TileNodes&, uint32_t, NodeLaneBatch*);

// A frame's kernels, each a template over the variant, chosen together.
struct PointRenderer::Kernels {
  DrawFn draw;               // a node's set-up, then its points through the bins or a wait for the tile pass
  PointRaster::TileFn tile;  // the tile pass over the nodes waiting in a tile
  LaneFn lanes;              // eight nodes' set-up at once in AVX2 lanes (null: none for this variant or build)
};

const PointRenderer::Kernels& PointRenderer::kernels(Projection projection, PointNormals normals, bool color_points,
                                                     bool specular) {
  // Entry ((projection * 3 + normals) * 2 + colour) * 2 + specular.
  constexpr auto at = []<size_t I>(std::integral_constant<size_t, I>) {
    constexpr Projection P = static_cast<Projection>(I / 12);
    constexpr PointNormals N = static_cast<PointNormals>(I / 4 % 3);
    constexpr bool kColor = I / 2 % 2 != 0, kSpecular = I % 2 != 0;
    LaneFn lanes = nullptr;  // the lanes take uniform-colour nodes of the affine projection
    if constexpr (avx2::kBuilt && P == Projection::kAffine && !kColor) lanes = &avx2::set_up_nodes<N, kSpecular>;
    return Kernels{&PointRenderer::draw_node<P, N, kColor, kSpecular>, &PointRenderer::tile_nodes_of<N, kColor, kSpecular>,
                   lanes};
  };
  static constexpr auto table = [&]<size_t... I>(std::index_sequence<I...>) {
    return std::array<Kernels, sizeof...(I)>{at(std::integral_constant<size_t, I>{})...};
  }(std::make_index_sequence<3 * 3 * 2 * 2>{});
  static_assert(static_cast<int>(Projection::kExact) == 2 && static_cast<int>(PointNormals::kSurface) == 2);
  return table[((static_cast<size_t>(projection) * 3 + static_cast<size_t>(normals)) * 2 + color_points) * 2 + specular];
}

// The camera's checks and what follows from it for every node: the internal
// frame's camera, the depth word, the light in model space, the colour mode
// and the angle tables.
RenderStatus PointRenderer::set_up_frame(const NodeCache& cache, const Camera& camera, FrameSetup& f) {
  const SpgHeader& header = cache.header();
  if (camera.focal_q4 < 1 || camera.focal_q4 > kMaxFocalQ4 || camera.near_mu < kCameraMinDistance ||
      camera.far_mu <= camera.near_mu || camera.far_mu > kMaxDepthMu)
    return RenderStatus::kBadCamera;
  for (int k = 0; k < 3; ++k)
    if (camera.eye[k] < -(1 << 29) || camera.eye[k] > (1 << 29)) return RenderStatus::kBadCamera;
  f.camera = camera;
  const int32_t n = config_.supersample;
  if (n > 1) {  // the camera for the internal frame: focal length and principal point scaled
    if (int64_t{camera.focal_q4} * n > kMaxFocalQ4) return RenderStatus::kBadCamera;
    f.camera.focal_q4 = camera.focal_q4 * n;
    f.camera.center_q4[0] = camera.center_q4[0] * n;
    f.camera.center_q4[1] = camera.center_q4[1] * n;
  }
  f.width_q4 = 16 * internal_.width;
  f.height_q4 = 16 * internal_.height;
  // Depth word: (z - near) << shift spans [near, far] in 32 bits.
  const uint32_t range = static_cast<uint32_t>(camera.far_mu - camera.near_mu);
  f.depth_shift = __builtin_clz(range);
  // Light and half vector into model space: R^T v.
  for (int a = 0; a < 3; ++a) {
    int64_t l = 0, h = 0;
    for (int k = 0; k < 3; ++k) {
      l += int64_t{camera.rotation[k][a]} * shading_->light_q14[k];
      h += int64_t{camera.rotation[k][a]} * shading_->half_q14[k];
    }
    f.light[a] = static_cast<int16_t>(l >> 14);
    f.half[a] = static_cast<int16_t>(h >> 14);
  }
  const bool elevation = config_.elevation != SpgAxis::kNone;
  f.model_color = (header.has_color() && !config_.grey) || elevation;
  f.elevation_field = spg_axis_index(config_.elevation);
  f.elevation_down = spg_axis_negative(config_.elevation);
  f.elevation_bits = elevation ? header.layout.bits[f.elevation_field] : 0;
  f.decoder = &cache.decoder();
  f.lit = header.has_normals() && config_.shading != ShadingMode::kNone;
  f.close_ups = close_up_capacity_ > 0 && config_.point_cap == 0;
  f.splats = splat_capacity_ > 0;
  f.close_up_log2 = config_.supersample == 4 ? 2 : config_.supersample == 2 ? 1 : 0;
  f.close_up_gate = int64_t{1} << (2 * (4 + kCloseUpPointsLog2 + f.close_up_log2));
  f.close_up = CloseUpFrame{f.camera.focal_q4, f.camera.center_q4[0], f.camera.center_q4[1], f.camera.near_mu,
                            internal_.width, internal_.height, f.depth_shift};
  tables_.uniform_base = !f.model_color;
  tables_.base_rgb = config_.grey_rgb & 0xFFFFFFu;
  tables_.grey_shade = f.model_color ? nullptr : grey_shades_;
  tables_.grey_shade565 = tables_.grey_shade ? tables_.grey_shade + kGreyShades : nullptr;
  if (!angles_.build(f.camera, cache.decoder(), f.light, f.half)) return RenderStatus::kBadConfig;  // fields too wide
  return RenderStatus::kOk;
}

// Eight nodes at a time in AVX2 lanes (node_lanes.h), from the first, while
// the tile pass and the budget surely hold them; what the lanes leave
// through draw_slot, so the order in which nodes claim the room is the
// scalar loop's. Returns the first node not set up.
template <class DrawSlot>
uint32_t PointRenderer::set_up_in_lanes(const FrameSetup& f, const NodeCache& cache, const Kernels& k,
                                        FrameStats& stats, const DrawSlot& draw_slot) {
  const uint32_t count = cache.count();
  const NodeLaneFrame lf = lane_frame(f, cache);
  const uint32_t tiles_x = static_cast<uint32_t>(raster_.tiles_x());
  NodeLaneBatch batches[kLaneBatches];
  uint32_t first = 0;
  while (first < count) {
    // As many batches as the tile pass and the budget surely hold (each
    // node of them a TileNode, or its scalar set-up's, and every point
    // filed; the lanes write 8 rows a batch past the last taken), so
    // that no node is refused for room.
    uint32_t run = (count - first + 7) / 8;
    if (run > kLaneBatches) run = kLaneBatches;
    while (run > 0 && !raster_.room_for(8 * run + 8, 8 * run * config_.samples)) run /= 2;
    if (run == 0) break;
    const uint32_t slots = count - first < 8 * run ? count - first : 8 * run;
    const uint32_t base = raster_.items();
    uint32_t item = base, points = 0;
    k.lanes(lf, first, slots, tile_nodes_, base, batches);
    for (uint32_t b = 0; b < run; ++b) {
      const NodeLaneBatch& r = batches[b];
      for (uint32_t m = r.tile_mask; m != 0; m &= m - 1) {
        const int lane = __builtin_ctz(m);
        const uint32_t code = r.tiles[lane];
        raster_.file_item_in_tiles(item++, ((code >> 12) & 0xFFFu) * tiles_x + (code & 0xFFFu), code >> 24 & 1u,
                                   code >> 25 & 1u);
        points += r.count[lane];
      }
      stats.nodes_in_lanes += r.tile_count + r.culled_count;
      stats.nodes_drawn += r.tile_count;
      stats.nodes_in_tiles += r.tile_count;
      stats.nodes_culled += r.culled_count;
    }
    raster_.took_items(item - base, points);
    stats.points += points;
    for (uint32_t b = 0; b < run; ++b) {
      const uint32_t lanes = slots - 8 * b < 8 ? slots - 8 * b : 8;
      const uint32_t scalar = ~(batches[b].tile_mask | batches[b].culled_mask) & ((1u << lanes) - 1u);
      for (uint32_t m = scalar; m != 0; m &= m - 1) draw_slot(first + 8 * b + static_cast<uint32_t>(__builtin_ctz(m)));
    }
    first += slots;
  }
  return first;
}

// Supersampling: the screen's coverage bits from the internal frame's (a
// screen pixel is covered where any pixel of its block is), and each screen
// pixel the rounded mean of its n x n block.
void PointRenderer::finish_supersampled(uint8_t* frame, size_t stride) {
  // Locals, not members, in the loops: the frame's bytes may alias nothing
  // the compiler must reload.
  const int32_t n = config_.supersample;
  const uint32_t width = config_.raster.width, height = config_.raster.height;
  const bool rgb888 = config_.raster.format == PixelFormat::kRgb888;
  const uint8_t* const internal = internal_frame_;
  const size_t internal_stride = size_t{internal_.width} * 3;
  if (coverage_ != nullptr) {
    const size_t in_row = coverage_row_bytes(internal_.width), out_row = coverage_row_bytes(config_.raster.width);
    const uint32_t block = (1u << n) - 1;
    for (uint32_t y = 0; y < height; ++y) {
      uint8_t* out = screen_coverage_ + y * out_row;
      for (size_t i = 0; i < out_row; ++i) out[i] = 0;
      for (int32_t dy = 0; dy < n; ++dy) {
        const uint8_t* in = coverage_ + (y * n + static_cast<uint32_t>(dy)) * in_row;
        for (uint32_t x = 0; x < width; ++x) {
          const uint32_t bit = x * static_cast<uint32_t>(n);  // n divides 8: a block never straddles a byte
          if ((in[bit >> 3] >> (bit & 7)) & block) out[x >> 3] = static_cast<uint8_t>(out[x >> 3] | (1u << (x & 7)));
        }
      }
    }
  }
  const uint32_t half = static_cast<uint32_t>(n * n) / 2, shift = n == 2 ? 2 : 4;
  for (uint32_t y = 0; y < height; ++y) {
    uint8_t* out = frame + y * stride;
    for (uint32_t x = 0; x < width; ++x) {
      uint32_t sum[3] = {half, half, half};
      for (int32_t dy = 0; dy < n; ++dy) {
        const uint8_t* p = internal + (y * n + static_cast<uint32_t>(dy)) * internal_stride + size_t{x} * n * 3;
        for (int32_t dx = 0; dx < n; ++dx, p += 3) {
          sum[0] += p[0];
          sum[1] += p[1];
          sum[2] += p[2];
        }
      }
      const uint32_t r = sum[0] >> shift, g = sum[1] >> shift, b = sum[2] >> shift;
      if (rgb888) {
        out[3 * x] = static_cast<uint8_t>(r);
        out[3 * x + 1] = static_cast<uint8_t>(g);
        out[3 * x + 2] = static_cast<uint8_t>(b);
      } else {
        const uint16_t v = rgb565((r << 16) | (g << 8) | b);
        out[2 * x] = static_cast<uint8_t>(v);
        out[2 * x + 1] = static_cast<uint8_t>(v >> 8);
      }
    }
  }
}

RenderStatus PointRenderer::render(const NodeCache& cache, const Camera& camera, uint8_t* frame, size_t stride,
                                   FrameStats* stats_out) {
  if (ppn_ == nullptr) return RenderStatus::kBadConfig;  // not initialized
  if (!cache.ready()) return RenderStatus::kNoStartup;
  FrameSetup f;
  if (const RenderStatus s = set_up_frame(cache, camera, f); s != RenderStatus::kOk) return s;

  // The variant: how normals are taken, per-point colour, specular.
  const SpgHeader& header = cache.header();
  const PointNormals point_normals = !f.lit                                       ? PointNormals::kNode
                                    : config_.shading == ShadingMode::kPerPoint ? PointNormals::kSampled
                                    : config_.shading == ShadingMode::kSurface  ? PointNormals::kSurface
                                                                                : PointNormals::kNode;
  const bool color_points = header.has_color() && !config_.grey && config_.elevation == SpgAxis::kNone &&
                            config_.sample_color;
  const bool specular = f.lit && config_.lighting.specular_q8 > 0;
  const Kernels& k = kernels(config_.projection, point_normals, color_points, specular);

  const uint32_t count = cache.count();
  // The mean table where the fields fit it: for the node lanes, and for
  // draw_node where the cut repays building it (kMeanCellsPerNode).
  const bool mean_fits = header.layout.bits[0] <= kMeanTermBits && header.layout.bits[1] <= kMeanTermBits &&
                         header.layout.bits[2] <= kMeanTermBits;
  const bool node_lanes = k.lanes != nullptr && lane_ppn_ != nullptr && lanes_ == PointLanes::kBest &&
                          !f.model_color && config_.point_cap == 0 && !f.splats && mean_fits && count >= 64;
  const uint32_t mean_cells = (1u << header.layout.bits[0]) + (1u << header.layout.bits[1]) + (1u << header.layout.bits[2]);
  f.mean[0] = f.mean[1] = f.mean[2] = nullptr;
  FrameStats stats;
  stats.nodes = count;
  stats.mean_table = node_lanes || (mean_fits && uint64_t{count} * kMeanCellsPerNode >= mean_cells);
  if (stats.mean_table) build_mean_terms(f.camera, cache.decoder(), mean_terms_, f.mean);

  raster_.begin_frame();
  close_up_count_ = 0;
  splat_count_ = 0;
  // The point cap: a node draws at most point_cap times the original points
  // under it (times the supersampling's n^2, so it means the same on screen).
  const int32_t n = config_.supersample;
  const uint32_t cap_scale = uint32_t{config_.point_cap} * static_cast<uint32_t>(n * n);
  const auto cap_of = [&](uint32_t s) {
    const uint32_t p = cache.points_at(s);
    return cap_scale == 0 || p == 0 ? 0xFFFFFFFFu : cap_scale * p;
  };
  // Records were checked when they were put: every one unpacks to valid classes.
  const RecordUnpacker& unpacker = cache.decoder().unpacker();
  const auto draw_slot = [&](uint32_t s) {
    if (cache.decoded()) (this->*k.draw)(f, cache.fields_at(s), cap_of(s), stats);
    else (this->*k.draw)(f, unpacker.unpack(cache.record_at(s)), cap_of(s), stats);
  };
  // Eight at a time where the lanes take this frame; the rest (and every
  // node when the tile pass or the budget runs short) one by one.
  const uint32_t first = node_lanes ? set_up_in_lanes(f, cache, k, stats, draw_slot) : 0;
  for (uint32_t s = first; s < count; ++s) draw_slot(s);
  raster_.draw(config_.clear_rgb, n == 1 ? frame : internal_frame_, n == 1 ? stride : size_t{internal_.width} * 3,
               coverage_, k.tile, this, close_up_count_ != 0 || splat_count_ != 0);
  if (n > 1) finish_supersampled(frame, stride);
  if (screen_coverage_ != nullptr)
    resolve_frame(frame, stride, config_.raster.format, config_.raster.width, config_.raster.height, screen_coverage_,
                  config_.clear_rgb, resolve_scratch_);
  if (stats_out) *stats_out = stats;
  return RenderStatus::kOk;
}

}  // namespace stipple
