// stipple raster — the software point renderer. See point_renderer.h;
// formats and measured errors are in docs/fixed_point.md.
#include "raster/point_renderer.h"

#include "raster/resolve.h"

#include "core/arena.h"
#include "core/fixed_range.h"

namespace stipple {
namespace {

constexpr int32_t kMaxFocalQ4 = 1 << 20;
constexpr int32_t kMaxDepthMu = 1 << 30;
constexpr int32_t kMaxSigmaN = 4 << 12;       // theta table covers theta <= 4 rad

struct Layout {
  size_t raster, internal_frame, coverage, screen_coverage, resolve, g_position, g_normal, g_color, shading, reciprocal,
      tile_setups, total;
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
  return r;
}

size_t point_setup_bytes();

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
  l.resolve = take(c.resolve ? resolve_scratch_bytes(c.raster.width) : 0);
  l.g_position = take(sizeof(Gaussian3Q12) * c.samples);
  l.g_normal = take(c.normals ? sizeof(Gaussian2Q12) * c.samples : 0);
  l.g_color = take(c.color ? sizeof(Gaussian3Q12) * c.samples : 0);
  l.shading = take(sizeof(ShadingTables));
  l.reciprocal = take(sizeof(uint16_t) << kReciprocalBits);
  l.tile_setups = take(point_setup_bytes() * size_t{c.tile_nodes});
  l.total = arena.total();
  return l;
}

inline int32_t dot_q14(const int16_t a[3], const int16_t b[3]) {
  return narrow<int32_t>((int64_t{a[0]} * b[0] + int64_t{a[1]} * b[1] + int64_t{a[2]} * b[2]) >> 14);
}


inline uint32_t clamp255(int32_t v) { return v < 0 ? 0u : v > 255 ? 255u : static_cast<uint32_t>(v); }

// Colour after shading: channel * intensity (Q8) + specular, saturated.
inline uint32_t shade(uint32_t r, uint32_t g, uint32_t b, uint32_t intensity, uint32_t specular) {
  const uint32_t rr = ((r * intensity) >> 8) + specular, gg = ((g * intensity) >> 8) + specular,
                 bb = ((b * intensity) >> 8) + specular;
  return ((rr > 255 ? 255 : rr) << 16) | ((gg > 255 ? 255 : gg) << 8) | (bb > 255 ? 255 : bb);
}

// Where draw_points puts a point: filed in the raster's bins (any node) ...
struct RasterSink {
  PointRaster& raster;
  int size;
  bool put(int32_t x_q4, int32_t y_q4, uint32_t depth, uint32_t rgb) {
    return raster.add(ScreenPoint{x_q4, y_q4, depth, rgb}, size);
  }
};

// ... or straight into the hot tile's words (a node whose points all fall
// in that tile: PointRenderer::draw_node proved it, the checked build traps
// otherwise). The same square and the same word as the bins would give.
template <class Word>
struct TileSink {
  Word* words;
  int tile_log2, px0, py0, size;
  bool put(int32_t x_q4, int32_t y_q4, uint32_t depth, uint32_t rgb) {
    const uint32_t color = sizeof(Word) == 4 ? rgb565(rgb) : (rgb & 0xFFFFFFu);
    const Word w = pack_word<Word>(depth, color);
    const int x = ((x_q4 - (size - 1) * 8) >> 4) - px0, y = ((y_q4 - (size - 1) * 8) >> 4) - py0;
    const int tile = 1 << tile_log2;
#if STIPPLE_CHECK_RANGES
    if (x < 0 || y < 0 || x + size > tile || y + size > tile) __builtin_trap();
#endif
    ztest_square(words + (y << tile_log2) + x, tile, static_cast<uint32_t>(size | size << 4), w);
    return true;
  }
};

// The pixels [lo, hi] a node's point squares can cover along one axis, from
// the mean's screen position p0 (Q4) and the slopes m (1/256 px per sigma):
// every sample is within the table's clip per component, so its offset
// (m . g) >> 16 lies in [-(c sum|m|) / 2^16 - 1, (c sum|m|) / 2^16].
struct Span {
  int32_t lo, hi;
};
inline Span pixel_span(int32_t p0_q4, const int32_t m[3], int size) {
  const int64_t sum = abs64(m[0]) + abs64(m[1]) + abs64(m[2]);
  const int64_t d = (sum * kGaussianClip) >> 16;
  const int64_t lo = p0_q4 - d - 1 - (size - 1) * 8, hi = p0_q4 + d - (size - 1) * 8;
  return Span{static_cast<int32_t>(lo >> 4), static_cast<int32_t>((hi >> 4) + size - 1)};
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
  return point_raster_bytes(internal_raster(c)) > 0 && point_raster_bytes(c.raster) > 0 && c.samples >= 1 && c.samples <= 8192 && c.point_size >= 1 &&
         c.point_size <= 3 && c.quality_q8 >= 1 && c.lighting.shininess >= 1 && c.lighting.shininess <= 64 &&
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

RenderStatus PointRenderer::init(const RendererConfig& config, void* storage, size_t bytes) {
  if (!renderer_config_valid(config)) return RenderStatus::kBadConfig;
  const Layout l = layout_of(config);
  if (bytes < l.total) return RenderStatus::kStorageTooSmall;
  uint8_t* base = static_cast<uint8_t*>(storage);
  internal_ = internal_raster(config);
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
  tile_setups_ = config.tile_nodes ? reinterpret_cast<PointSetup*>(base + l.tile_setups) : nullptr;
  build_gaussian3_table(config.source, g_position_, config.samples);
  if (g_normal_) build_gaussian2_table(config.source, g_normal_, config.samples);
  if (g_color_) build_gaussian3_table(config.source, g_color_, config.samples, kColorSobolDim);
  if (!build_shading_tables(config.lighting, shading_)) return RenderStatus::kBadConfig;
  build_reciprocal_table(reciprocal_);
  ppn_ = &ppn_table(config.source, config.point_size);
  return RenderStatus::kOk;
}

struct PointRenderer::PointSetup {
  NodeProjection proj;
  uint32_t count;
  int32_t near;
  int shift, size;
  uint32_t base_r, base_g, base_b, node_rgb, node_intensity, node_specular;
  int32_t sn0, sn1, l0, l1, l2, h0, h1, h2;
  int32_t surface[2][3];  // kSurface: the normal sample (in sigma_n) per position sample component, Q14
  int64_t ca[3][3];  // colour axes, 8-bit levels per sigma in Q8
};

namespace {
size_t point_setup_bytes() { return (sizeof(PointRenderer::PointSetup) + 7) & ~size_t{7}; }
}  // namespace

struct PointRenderer::FrameSetup {
  Camera camera;
  int32_t width_q4, height_q4;
  int depth_shift;
  int16_t light[3], half[3];  // model space, Q14
  bool model_color;
};

template <Projection P, PointRenderer::PointNormals kNormals, bool kColorPoints, bool kSpecular>
void PointRenderer::draw_node(const FrameSetup& f, const SpgHeader& header, const FixedNode& node, uint32_t max_points,
                              FrameStats& stats) {
  // Filled in place — in the tile pass's next free record when there is one,
  // so a node that waits for its tile is not copied: draw_points reads it by
  // reference either way.
  PointSetup local;
  const bool pooled = P == Projection::kAffine && tile_setups_ != nullptr && tile_setup_count_ < config_.tile_nodes;
  PointSetup& setup = pooled ? tile_setups_[tile_setup_count_] : local;
  NodeProjection& proj = setup.proj;
  if (!proj.setup(f.camera, node)) {
    ++stats.nodes_culled;
    return;
  }
  // The gamma-extent (3.5 sigma) on screen, an L1 bound: cull nodes wholly
  // off screen. Screen covariance M M^T for the points-per-node index.
  int64_t ex = 0, ey = 0, a = 0, b = 0, cc = 0;
  for (int k = 0; k < 3; ++k) {
    const int64_t vx = proj.mx[k] >> 4, vy = proj.my[k] >> 4;  // 1/16 px per sigma
    ex += abs64(vx);
    ey += abs64(vy);
    a += vx * vx;
    b += vx * vy;
    cc += vy * vy;
  }
  ex = (ex * 7) >> 1;
  ey = (ey * 7) >> 1;
  if (proj.x0_q4 + ex < 0 || proj.x0_q4 - ex >= f.width_q4 || proj.y0_q4 + ey < 0 || proj.y0_q4 - ey >= f.height_q4) {
    ++stats.nodes_culled;
    return;
  }
  // a, c: (1/16 px)^2 = 1/256 px^2, below 3 * 2^48.
  setup.count = points_per_node(*ppn_, ppn_index(a, b, cc), config_.quality_q8, config_.samples);
  if (setup.count > max_points) setup.count = max_points;  // the point cap
  setup.near = f.camera.near_mu;
  setup.shift = f.depth_shift;
  setup.size = config_.point_size;

  // Base colour and per-node shading terms.
  const uint32_t base = f.model_color ? (uint32_t{node.color[0]} << 16) | (uint32_t{node.color[1]} << 8) | node.color[2]
                                      : config_.grey_rgb & 0xFFFFFFu;
  setup.base_r = base >> 16;
  setup.base_g = (base >> 8) & 0xFF;
  setup.base_b = base & 0xFF;
  const int32_t sn0 = node.sigma_n[0] < kMaxSigmaN ? node.sigma_n[0] : kMaxSigmaN;
  const int32_t sn1 = node.sigma_n[1] < kMaxSigmaN ? node.sigma_n[1] : kMaxSigmaN;
  setup.sn0 = sn0;
  setup.sn1 = sn1;
  setup.l0 = dot_q14(node.normal_frame[2], f.light);
  setup.l1 = narrow<int32_t>((int64_t{dot_q14(node.normal_frame[0], f.light)} * sn0) >> 12);
  setup.l2 = narrow<int32_t>((int64_t{dot_q14(node.normal_frame[1], f.light)} * sn1) >> 12);
  setup.h0 = dot_q14(node.normal_frame[2], f.half);
  setup.h1 = narrow<int32_t>((int64_t{dot_q14(node.normal_frame[0], f.half)} * sn0) >> 12);
  setup.h2 = narrow<int32_t>((int64_t{dot_q14(node.normal_frame[1], f.half)} * sn1) >> 12);
  if constexpr (kNormals == PointNormals::kSurface) {
    // The surface's normal field: a position sample g lands at sum_i g_i
    // axis_i; its offset along the normal frame's tangent f_k, over the
    // node's positional spread along f_k, is how many sigma_n the normal
    // turns there (a convex patch, its curvature sigma_n / sigma_p).
    for (int k = 0; k < 2; ++k) {
      int64_t along[3];
      uint64_t s2 = 0;
      for (int i = 0; i < 3; ++i) {
        along[i] = (int64_t{node.axis[i][0]} * node.normal_frame[k][0] + int64_t{node.axis[i][1]} * node.normal_frame[k][1] +
                    int64_t{node.axis[i][2]} * node.normal_frame[k][2]) >> 14;  // MU
        s2 += static_cast<uint64_t>(along[i] * along[i]);
      }
      if (s2 == 0) {
        setup.surface[k][0] = setup.surface[k][1] = setup.surface[k][2] = 0;
        continue;
      }
      const RsqrtScale r = rsqrt_scale(*shading_, s2);  // 2^14 / spread, without a division
      for (int i = 0; i < 3; ++i) {
        const int64_t v = (along[i] * int64_t{r.mul}) >> r.shift;  // |.| <= 2^14 (1 + 1/512)
        setup.surface[k][i] = static_cast<int32_t>(v > 16416 ? 16416 : v < -16416 ? -16416 : v);
      }
    }
  }
  setup.node_rgb = base;
  setup.node_intensity = 256;
  setup.node_specular = 0;
  if (config_.shading != ShadingMode::kNone && header.has_normals()) {
    setup.node_intensity = shading_->diffuse[intensity_index(setup.l0)];
    if (kSpecular) setup.node_specular = shading_->specular[intensity_index(setup.h0)];
    setup.node_rgb = shade(setup.base_r, setup.base_g, setup.base_b, setup.node_intensity, setup.node_specular);
  }
  // Colour axes in 8-bit levels per sigma, Q8 (saturated: sigma_c comes from the file).
  if (kColorPoints)
    for (int k = 0; k < 3; ++k)
      for (int ch = 0; ch < 3; ++ch) {
        const int64_t v = (int64_t{node.color_axis[k][ch]} * 255) >> 4;
        setup.ca[k][ch] = v > (1 << 24) ? (1 << 24) : v < -(1 << 24) ? -(1 << 24) : v;
      }
  ++stats.nodes_drawn;
  if constexpr (P == Projection::kAffine) {
    // A node inside one tile (and the screen) waits for that tile's pass,
    // where its points go straight into the tile's words; its points count
    // against the frame's budget now.
    if (pooled) {
      const Span sx = pixel_span(proj.x0_q4, proj.mx, setup.size), sy = pixel_span(proj.y0_q4, proj.my, setup.size);
      const int sh = internal_.tile_log2;
      if (sx.lo >= 0 && sy.lo >= 0 && sx.hi < internal_.width && sy.hi < internal_.height && (sx.lo >> sh) == (sx.hi >> sh) &&
          (sy.lo >> sh) == (sy.hi >> sh) && raster_.reserve(setup.count)) {
        const uint32_t tile = static_cast<uint32_t>((sy.lo >> sh) * raster_.tiles_x() + (sx.lo >> sh));
        if (raster_.add_node(tile, tile_setup_count_)) {
          ++tile_setup_count_;
          ++stats.nodes_in_tiles;
          return;
        }
        raster_.reserve_undo(setup.count);
      }
    }
  }
  RasterSink sink{raster_, setup.size};
  stats.points += draw_points<P, kNormals, kColorPoints, kSpecular>(setup, stats, sink);
}

template <PointRenderer::PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
void PointRenderer::draw_tile_nodes(uint32_t tile, int px0, int py0, Word* words, FrameStats& stats) {
  TileSink<Word> sink{words, internal_.tile_log2, px0, py0, config_.point_size};
  for (uint32_t link = raster_.first_link(tile); link != PointRaster::kNoLink; link = raster_.next_link(link))
    stats.points += draw_points<Projection::kAffine, kNormals, kColorPoints, kSpecular>(tile_setups_[raster_.item_of(link)],
                                                                                         stats, sink);
}

template <PointRenderer::PointNormals kNormals, bool kColorPoints, bool kSpecular>
void PointRenderer::tile_nodes_of(void* context, uint32_t tile, int px0, int py0, void* words) {
  TileContext& c = *static_cast<TileContext*>(context);
  if (c.renderer->internal_.format == PixelFormat::kRgb565)
    c.renderer->draw_tile_nodes<kNormals, kColorPoints, kSpecular>(tile, px0, py0, static_cast<uint32_t*>(words), *c.stats);
  else
    c.renderer->draw_tile_nodes<kNormals, kColorPoints, kSpecular>(tile, px0, py0, static_cast<uint64_t*>(words), *c.stats);
}

// The per-point path: its own function, never inlined, so that the ARMv5
// build can be checked symbol by symbol for run-time helper calls
// (tests/handheld/per_point_helpers.cmake).
template <Projection P, PointRenderer::PointNormals kNormals, bool kColorPoints, bool kSpecular, class Sink>
uint32_t PointRenderer::draw_points(const PointSetup& s, FrameStats& stats, Sink& sink) {
  const NodeProjection& proj = s.proj;
  const uint32_t count = s.count;
  const uint32_t base_r = s.base_r, base_g = s.base_g, base_b = s.base_b;
  const uint32_t node_rgb = s.node_rgb, node_intensity = s.node_intensity, node_specular = s.node_specular;
  const int32_t sn0 = s.sn0, sn1 = s.sn1, l0 = s.l0, l1 = s.l1, l2 = s.l2, h0 = s.h0, h1 = s.h1, h2 = s.h2;
  const int64_t(&ca)[3][3] = s.ca;
  const int32_t(&surface)[2][3] = s.surface;
  constexpr bool kShadePoints = kNormals != PointNormals::kNode;
  const int32_t near = s.near;
  const int shift = s.shift;
  uint32_t drawn = 0;
  for (uint32_t j = 0; j < count; ++j) {
    ScreenSample p;
    if (!proj.template point<P>(g_position_[j], near, reciprocal_, &p)) continue;
    const int32_t x = p.x_q4, y = p.y_q4;
    const int64_t z = p.z;
    const uint64_t dz = static_cast<uint64_t>(z - near) << shift;
    const uint32_t depth = dz > 0xFFFFFFFEu ? 0xFFFFFFFEu : static_cast<uint32_t>(dz);
    uint32_t rgb = node_rgb;
    if constexpr (kColorPoints || kShadePoints) {
      uint32_t r = base_r, gg = base_g, bb = base_b;
      if constexpr (kColorPoints) {
        const Gaussian3Q12 q = g_color_[j];
        r = clamp255(static_cast<int32_t>(base_r) + narrow<int32_t>((ca[0][0] * q.v[0] + ca[1][0] * q.v[1] + ca[2][0] * q.v[2]) >> 20));
        gg = clamp255(static_cast<int32_t>(base_g) + narrow<int32_t>((ca[0][1] * q.v[0] + ca[1][1] * q.v[1] + ca[2][1] * q.v[2]) >> 20));
        bb = clamp255(static_cast<int32_t>(base_b) + narrow<int32_t>((ca[0][2] * q.v[0] + ca[1][2] * q.v[1] + ca[2][2] * q.v[2]) >> 20));
      }
      uint32_t intensity = node_intensity, specular = node_specular;
      if constexpr (kShadePoints) {
        Gaussian2Q12 n;
        if constexpr (kNormals == PointNormals::kSurface) {
          const Gaussian3Q12 g = g_position_[j];
          for (int k = 0; k < 2; ++k) {
            const int32_t v = (surface[k][0] * g.v[0] + surface[k][1] * g.v[1] + surface[k][2] * g.v[2]) >> 14;
            n.v[k] = static_cast<int16_t>(v < -32767 ? -32767 : v > 32767 ? 32767 : v);
          }
        } else {
          n = g_normal_[j];
        }
        const int64_t al = (int64_t{sn0} * n.v[0]) >> 12, be = (int64_t{sn1} * n.v[1]) >> 12;  // Q12 radians
        const uint64_t t2 = static_cast<uint64_t>(al * al + be * be) >> kCosSincShift;          // theta^2 cell
        const CosSincQ14 cs = shading_->cos_sinc[t2 < kCosSincEntries ? t2 : kCosSincEntries - 1];
        const int32_t l = narrow<int32_t>((cs.cos * int64_t{l0} + cs.sinc * ((n.v[0] * int64_t{l1} + n.v[1] * int64_t{l2}) >> 12)) >> 14);
        intensity = shading_->diffuse[intensity_index(l)];
        if constexpr (kSpecular) {
          const int32_t h = narrow<int32_t>((cs.cos * int64_t{h0} + cs.sinc * ((n.v[0] * int64_t{h1} + n.v[1] * int64_t{h2}) >> 12)) >> 14);
          specular = shading_->specular[intensity_index(h)];
        }
      }
      rgb = (kShadePoints || config_.shading != ShadingMode::kNone) ? shade(r, gg, bb, intensity, specular)
                                                                    : (r << 16) | (gg << 8) | bb;
    }
    if (sink.put(x, y, depth, rgb)) ++drawn;
    else ++stats.points_dropped;
  }
  return drawn;
}

RenderStatus PointRenderer::render(const NodeCache& cache, const Camera& camera, uint8_t* frame, size_t stride,
                                   FrameStats* stats_out) {
  if (ppn_ == nullptr) return RenderStatus::kBadConfig;  // not initialized
  if (!cache.ready()) return RenderStatus::kNoStartup;
  const SpgHeader& header = cache.header();
  if (camera.focal_q4 < 1 || camera.focal_q4 > kMaxFocalQ4 || camera.near_mu < kCameraMinDistance ||
      camera.far_mu <= camera.near_mu || camera.far_mu > kMaxDepthMu)
    return RenderStatus::kBadCamera;
  for (int k = 0; k < 3; ++k)
    if (camera.eye[k] < -(1 << 29) || camera.eye[k] > (1 << 29)) return RenderStatus::kBadCamera;
  FrameSetup f;
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
  f.model_color = header.has_color() && !config_.grey;

  const bool normals = header.has_normals() && config_.shading != ShadingMode::kNone;
  const PointNormals point_normals = !normals                                    ? PointNormals::kNode
                                    : config_.shading == ShadingMode::kPerPoint ? PointNormals::kSampled
                                    : config_.shading == ShadingMode::kSurface  ? PointNormals::kSurface
                                                                                : PointNormals::kNode;
  const bool color_points = f.model_color && config_.sample_color;
  const bool specular = normals && config_.lighting.specular_q8 > 0;
  using DrawFn = void (PointRenderer::*)(const FrameSetup&, const SpgHeader&, const FixedNode&, uint32_t, FrameStats&);
  const PointRaster::TileFn tile_fn =
      point_normals == PointNormals::kSampled
          ? (color_points ? (specular ? &tile_nodes_of<PointNormals::kSampled, true, true> : &tile_nodes_of<PointNormals::kSampled, true, false>)
                          : (specular ? &tile_nodes_of<PointNormals::kSampled, false, true> : &tile_nodes_of<PointNormals::kSampled, false, false>))
      : point_normals == PointNormals::kSurface
          ? (color_points ? (specular ? &tile_nodes_of<PointNormals::kSurface, true, true> : &tile_nodes_of<PointNormals::kSurface, true, false>)
                          : (specular ? &tile_nodes_of<PointNormals::kSurface, false, true> : &tile_nodes_of<PointNormals::kSurface, false, false>))
          : (color_points ? (specular ? &tile_nodes_of<PointNormals::kNode, true, true> : &tile_nodes_of<PointNormals::kNode, true, false>)
                          : (specular ? &tile_nodes_of<PointNormals::kNode, false, true> : &tile_nodes_of<PointNormals::kNode, false, false>));
#define STIPPLE_PICK_N(P, N)                                                                                       \
  (color_points ? (specular ? &PointRenderer::draw_node<P, N, true, true> : &PointRenderer::draw_node<P, N, true, false>) \
                : (specular ? &PointRenderer::draw_node<P, N, false, true> : &PointRenderer::draw_node<P, N, false, false>))
#define STIPPLE_PICK(P) \
  (point_normals == PointNormals::kSampled   ? STIPPLE_PICK_N(P, PointNormals::kSampled) \
   : point_normals == PointNormals::kSurface ? STIPPLE_PICK_N(P, PointNormals::kSurface) \
                                             : STIPPLE_PICK_N(P, PointNormals::kNode))
  DrawFn draw = config_.projection == Projection::kAffine       ? STIPPLE_PICK(Projection::kAffine)
                : config_.projection == Projection::kReciprocal ? STIPPLE_PICK(Projection::kReciprocal)
                                                                : STIPPLE_PICK(Projection::kExact);
#undef STIPPLE_PICK_N
#undef STIPPLE_PICK

  FrameStats stats;
  const uint32_t count = cache.count();
  stats.nodes = count;
  raster_.begin_frame();
  tile_setup_count_ = 0;
  // The point cap: a node draws at most point_cap times the original points
  // under it (times the supersampling's n^2, so it means the same on screen).
  const uint32_t cap_scale = uint32_t{config_.point_cap} * static_cast<uint32_t>(n * n);
  const auto cap_of = [&](uint32_t s) {
    const uint32_t p = cache.points_at(s);
    return cap_scale == 0 || p == 0 ? 0xFFFFFFFFu : cap_scale * p;
  };
  if (cache.decoded()) {
    for (uint32_t s = 0; s < count; ++s) (this->*draw)(f, header, cache.decoded_at(s), cap_of(s), stats);
  } else {
    FixedNode node;
    for (uint32_t s = 0; s < count; ++s) {
      if (!cache.node_at(s, &node)) continue;  // checked at put
      (this->*draw)(f, header, node, cap_of(s), stats);
    }
  }
  uint8_t* const target = n == 1 ? frame : internal_frame_;
  const size_t target_stride = n == 1 ? stride : size_t{internal_.width} * 3;
  TileContext tile_context{this, &stats};
  raster_.draw(config_.clear_rgb, target, target_stride, coverage_, tile_fn, &tile_context);
  if (n > 1 && coverage_ != nullptr) {
    // The resolve's coverage: a screen pixel is covered where any pixel of its block is.
    const size_t in_row = coverage_row_bytes(internal_.width), out_row = coverage_row_bytes(config_.raster.width);
    const uint32_t block = (1u << n) - 1;
    for (uint32_t y = 0; y < config_.raster.height; ++y) {
      uint8_t* out = screen_coverage_ + y * out_row;
      for (size_t i = 0; i < out_row; ++i) out[i] = 0;
      for (int32_t dy = 0; dy < n; ++dy) {
        const uint8_t* in = coverage_ + (y * n + static_cast<uint32_t>(dy)) * in_row;
        for (uint32_t x = 0; x < config_.raster.width; ++x) {
          const uint32_t bit = x * static_cast<uint32_t>(n);  // n divides 8: a block never straddles a byte
          if ((in[bit >> 3] >> (bit & 7)) & block) out[x >> 3] = static_cast<uint8_t>(out[x >> 3] | (1u << (x & 7)));
        }
      }
    }
  }
  if (n > 1) {
    // Each screen pixel is the rounded mean of its n x n block.
    const uint32_t half = static_cast<uint32_t>(n * n) / 2, shift = n == 2 ? 2 : 4;
    for (uint32_t y = 0; y < config_.raster.height; ++y) {
      uint8_t* out = frame + y * stride;
      for (uint32_t x = 0; x < config_.raster.width; ++x) {
        uint32_t sum[3] = {half, half, half};
        for (int32_t dy = 0; dy < n; ++dy) {
          const uint8_t* p = internal_frame_ + (y * n + static_cast<uint32_t>(dy)) * target_stride + size_t{x} * n * 3;
          for (int32_t dx = 0; dx < n; ++dx, p += 3) {
            sum[0] += p[0];
            sum[1] += p[1];
            sum[2] += p[2];
          }
        }
        const uint32_t r = sum[0] >> shift, g = sum[1] >> shift, b = sum[2] >> shift;
        if (config_.raster.format == PixelFormat::kRgb888) {
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
  if (screen_coverage_ != nullptr)
    resolve_frame(frame, stride, config_.raster.format, config_.raster.width, config_.raster.height, screen_coverage_,
                  config_.clear_rgb, resolve_scratch_);
  if (stats_out) *stats_out = stats;
  return RenderStatus::kOk;
}

}  // namespace stipple
