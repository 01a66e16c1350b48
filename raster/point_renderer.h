// stipple raster — the software point renderer: draws every node a
// NodeCache holds (core/node_cache.h) into a frame, in fixed point.
//
//   size_t n = point_renderer_bytes(config);   // 0: invalid configuration
//   renderer.init(config, storage, n);         // tables, tile bins
//   renderer.render(cache, camera, frame, stride);
//
// After init nothing is allocated, nothing is thrown, and render uses
// integer arithmetic only. Per node and frame: the mean and the sigma-scaled
// axes go to camera space; the projection is linearized at the mean (M,
// 2 x 3, 1/16 px per sigma), which gives the screen covariance M M^T, hence
// the points-per-node index; then sample j = 0 .. n-1 of the Gaussian tables
// becomes one point:
//   kAffine      x = x0 + M g                 (no division per point)
//   kReciprocal  X/Z per point, 1/Z from a 1024-entry table
//   kExact       X/Z per point by integer division
// Shading is Lambert + Blinn specular of per-point sampled normals through
// tables. docs/fixed_point.md gives every format and the measured error of
// each mode. The renderer keeps no node state: the cache is the only input
// besides the camera, so a GPU client can use the same cache without it.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/gaussian_table.h"
#include "core/node_cache.h"
#include "raster/close_up.h"
#include "raster/ewa.h"
#include "raster/node_lanes.h"
#include "raster/node_setup.h"
#include "raster/point_kernel.h"
#include "raster/point_raster.h"
#include "raster/points_per_node.h"
#include "raster/projection.h"
#include "raster/shading.h"

namespace stipple {

// kPerPoint: each point its own sampled normal (TOG05); kSurface: each
// point's normal follows where it lands in the node, the node's normal
// spread along its surface as a convex patch would turn it (DP01's
// differential points, docs/results.md); kPerNode: one normal a node;
// kNone: unlit.
enum class ShadingMode : uint8_t { kPerPoint, kPerNode, kNone, kSurface };

enum class PointLanes : uint8_t { kBest, kBaseline, kScalar };

struct RendererConfig {
  RasterConfig raster;                     // screen, pixel format, tiles, points per frame
  bool normals = true, color = true;       // Gaussian tables to build (attributes a model may have)
  uint16_t samples = 1024;                 // Gaussian table entries = most points per node
  GaussianSource source = GaussianSource::kSobol;
  uint8_t point_size = 2;                  // 1..3 px (the paper drew 1.8 px points)
  uint16_t quality_q8 = 256;               // points-per-node scale (256 = as measured)
  Projection projection = Projection::kAffine;
  ShadingMode shading = ShadingMode::kSurface;  // measured best against the scan (docs/results.md)
  bool sample_color = true;                // per-point colour from sigma_c (else the node's mean colour)
  bool grey = false;                       // ignore the model's colour
  // Colour by elevation (no re-encode): each node's colour from a ramp
  // (elevation_rgb, core/elevation_ramp.h) over the model's box along this axis,
  // low to high — LiDAR's habit; kNone: the model's colour (or grey).
  SpgAxis elevation = SpgAxis::kNone;
  Lighting lighting;
  uint32_t grey_rgb = 0xD8D8D8;            // base colour without colour attributes
  uint32_t clear_rgb = 0x000000;
  // Supersampling (1, 2 or 4): points are drawn into an internal frame of
  // supersample x the screen in each direction (RGB888, from the arena) with
  // the camera scaled to it — so nodes are that much larger there and get
  // their points-per-node count for that size, and a point is point_size
  // internal pixels — and each screen pixel is the mean of its block
  // (integer, rounded). The cut is the screen's: the same nodes, more points.
  uint8_t supersample = 1;
  // The screen-space resolve (raster/resolve.h): fill pinholes, trim the
  // squares' fringe at silhouettes, blend 3 x 3 — on the screen's frame,
  // after supersampling's mean (a pixel covered where any of its block is).
  // Measured best against the scan at a sixth of the frame (docs/results.md).
  bool resolve = true;
  // Sparse scans: a node draws at most point_cap times the original points
  // under it (the counts the stream carries with each node; 0: no cap), so
  // sparse returns stay sparse (docs/results.md).
  uint8_t point_cap = 0;
  // Close-ups: a node whose screen sigma passes kCloseUpSigmaPx (its
  // samples sparser than the pixels they cover: a leaf seen closer than
  // its spacing), or which reaches into the view from a mean outside it,
  // is drawn as its 3 sigma disc, perspective correct and shaded per pixel
  // (raster/close_up.h) — not with the point cap, which keeps sparse scans
  // sparse. Up to close_up_capacity discs a frame; more are drawn as points.
  bool close_ups = true;
  // EWA splatting (raster/ewa.h; `--splat ewa`, TOG05 §8.4's quality mode):
  // up to this many of a frame's drawn nodes are also elliptical Gaussian
  // splats, which colour the pixels the points cover (visibility,
  // accumulation, normalization per tile, in 20 bytes a tile pixel of the
  // arena); 0: points only. A Client asks for its node capacity.
  uint32_t splats = 0;
  // Which loops draw the tile pass's points: the widest this CPU has
  // (kBest: AVX2 on x86-64 where the CPU has it, else SSE2; NEON on ARMv7
  // and AArch64), the build's baseline lanes (SSE2 or NEON), or one point at
  // a time. The same bytes from each (tests/portable/point_kernel_test.cpp).
  PointLanes lanes = PointLanes::kBest;
  // Nodes drawn inside the tile pass per frame (affine projection): a node
  // whose points fall within two tiles a side keeps its per-point constants
  // here (a TileNode) and generates its points straight into each hot tile
  // it touches, instead of filing each point in the bins and reading it
  // back (docs/fixed_point.md, "Speed"). The arena holds rows for this many
  // (136 bytes each: its TileNode and tile links) and lends more from the
  // bins' pool, each what the bins would have taken for its points
  // (PointRaster::take_item); nodes beyond go through the bins; 0: every
  // point through the bins. A Client holds no more than it caches
  // (ClientConfig::node_capacity).
  uint32_t tile_nodes = 1u << 16;
  uint8_t max_angle_bits = 10;             // widest angle field drawn (sizes the per-frame Euler tables)
};

enum class RenderStatus : uint8_t {
  kOk = 0,
  kBadConfig,        // init: a value out of range (render: not initialized)
  kStorageTooSmall,  // init: fewer bytes than point_renderer_bytes
  kNoStartup,        // render: the cache holds no startup message
  kBadCamera,        // render: focal length, near plane or depth range out of range
};

const char* render_status_text(RenderStatus s);

struct FrameStats {
  uint32_t nodes = 0;         // nodes held
  uint32_t nodes_drawn = 0;   // nodes that produced points
  uint32_t nodes_culled = 0;  // behind the near plane or off screen
  uint32_t points = 0;        // points generated and binned
  uint32_t points_dropped = 0;  // refused by a full frame budget
  uint32_t nodes_in_tiles = 0;  // of nodes_drawn: drawn inside the tile pass (RendererConfig::tile_nodes)
  uint32_t nodes_close_up = 0;  // of nodes_drawn: drawn as discs (RendererConfig::close_ups)
  uint32_t splats = 0;          // of nodes_drawn: also EWA splats (RendererConfig::splats)
  uint32_t nodes_in_lanes = 0;  // of nodes: set up 8 at a time in AVX2 lanes, culled or drawn (raster/node_lanes.h)
  bool mean_table = false;      // the means' camera-space terms came from the frame's table (docs/fixed_point.md)
};

bool renderer_config_valid(const RendererConfig& config);

// Sample counts in half octaves: 1, 2, 3, 4, 6, 8, 12, ..., 6144, 8192
// (RendererConfig::samples' most), bucket i's most samples...
inline constexpr int kSampleReachBuckets = 26;
constexpr uint32_t sample_reach_samples(int i) {
  return i < 2 ? static_cast<uint32_t>(i + 1) : (i & 1) ? 2u << (i / 2) : 3u << (i / 2 - 1);
}
// ... and the bucket of a node of n points: the first whose count is n or more.
constexpr int sample_reach_bucket(uint32_t n) {
  if (n <= 2) return n == 0 ? 0 : static_cast<int>(n - 1);
  const uint32_t t = n - 1;
  const int k = 31 - __builtin_clz(t);
  return 2 * k + static_cast<int>((t >> (k - 1)) & 1u);
}

// Storage bytes for a configuration (8-byte aligned pieces), or 0 when invalid.
size_t point_renderer_bytes(const RendererConfig& config);

class PointRenderer {
 public:
  [[nodiscard]] RenderStatus init(const RendererConfig& config, void* storage, size_t bytes);

  // Draws every node `cache` holds into `frame` (height rows of `stride`
  // bytes in the configured pixel format).
  [[nodiscard]] RenderStatus render(const NodeCache& cache, const Camera& camera, uint8_t* frame, size_t stride,
                                    FrameStats* stats = nullptr);

  // What a user changes while it runs (the emulator's buttons): shading,
  // grey and the points-per-node scale — none of them sized the storage.
  // False, and nothing changed, for a value init would refuse.
  [[nodiscard]] bool set_view(ShadingMode shading, bool grey, uint16_t quality_q8);
  // Colour by elevation along `up` while it runs (kNone: off); false before init.
  [[nodiscard]] bool set_elevation(SpgAxis up);
  const RendererConfig& config() const { return config_; }

 // Per frame and per node: defined in point_renderer.cpp.
  struct FrameSetup;
  struct PointSetup;

 private:
  template <Projection P, PointNormals kNormals, bool kColorPoints, bool kSpecular>
  void draw_node(const FrameSetup& f, const NodeFields& fields, uint32_t max_points, FrameStats& stats);
  void set_up_depth(const FrameSetup& f, const int32_t c[3], const int32_t axes[3][3], PointSetup& s);
  template <PointNormals kNormals, bool kColorPoints, bool kSpecular>
  void set_up_shade(const FrameSetup& f, const NodeFields& fields, const int16_t frame[3][3], const int32_t sk[3],
                    PointShade& sh);
  template <PointNormals kNormals, bool kColorPoints>
  bool wait_in_tiles(PointSetup& s, FrameStats& stats);
  template <PointNormals kNormals, bool kSpecular>
  bool take_close_up(const FrameSetup& f, const NodeFields& fields, const int32_t c[3], const int16_t frame[3][3],
                     const int32_t sk[3], FrameStats& stats);
  template <PointNormals kNormals, bool kSpecular>
  bool close_up_outside(const FrameSetup& f, const NodeFields& fields, const int32_t c[3], FrameStats& stats);
  template <PointNormals kNormals, bool kSpecular, class Word>
  void draw_close_ups(int px0, int py0, Word* words);
  void take_splat(const FrameSetup& f, const NodeFields& fields, const int32_t c[3], const int16_t frame[3][3],
                  const int32_t sk[3], const PointShade& shade, FrameStats& stats);
  template <PointNormals kNormals, bool kSpecular, class Word>
  void draw_splats(int px0, int py0, Word* words);
  template <Projection P, PointNormals kNormals, bool kColorPoints, bool kSpecular>
  [[gnu::noinline]] uint32_t draw_points(const PointSetup& setup, FrameStats& stats);
  template <PointNormals kNormals, bool kColorPoints, bool kSpecular, class Word>
  void draw_tile_nodes(uint32_t tile, int px0, int py0, Word* words);
  template <PointNormals kNormals, bool kColorPoints, bool kSpecular>
  static void tile_nodes_of(void* context, uint32_t tile, int px0, int py0, void* words);
  NodeLaneFrame lane_frame(const FrameSetup& f, const NodeCache& cache);
  // The frame's kernels, for one variant — projection x normals x per-point
  // colour x specular — from one table (point_renderer.cpp).
  struct Kernels;
  static const Kernels& kernels(Projection projection, PointNormals normals, bool color_points, bool specular);
  RenderStatus set_up_frame(const NodeCache& cache, const Camera& camera, FrameSetup& f);
  template <class DrawSlot>
  uint32_t set_up_in_lanes(const FrameSetup& f, const NodeCache& cache, const Kernels& k, FrameStats& stats,
                           const DrawSlot& draw_slot);
  void finish_supersampled(uint8_t* frame, size_t stride);

  RendererConfig config_{};
  PointRaster raster_;
  RasterConfig internal_{};          // the raster's: the screen times the supersampling
  uint8_t* internal_frame_ = nullptr;  // supersampling: the internal RGB888 frame
  uint8_t* coverage_ = nullptr;        // resolve: the internal frame's coverage bits
  uint8_t* screen_coverage_ = nullptr; // resolve: the screen's (coverage_ itself without supersampling)
  void* resolve_scratch_ = nullptr;    // resolve: its ring of rows
  Gaussian3Q12* g_position_ = nullptr;
  Gaussian2Q12* g_normal_ = nullptr;
  Gaussian3Q12* g_color_ = nullptr;
  ShadingTables* shading_ = nullptr;
  uint16_t* reciprocal_ = nullptr;  // 1024 entries
  const PpnTable* ppn_ = nullptr;
  PointTables tables_;
  CloseUp* close_ups_ = nullptr;    // the frame's discs
  uint32_t close_up_capacity_ = 0, close_up_count_ = 0;
  Splat* splats_ = nullptr;         // the frame's EWA splats
  uint32_t splat_capacity_ = 0, splat_count_ = 0;
  uint32_t* ewa_sums_ = nullptr;    // one tile's sums (ewa_tile_bytes)
  const uint32_t* grey_shades_ = nullptr;  // the grey shortcut's tables (PointTables::grey_shade), null when the grey is not one
  FrameAngles angles_;
  TileNodes tile_nodes_;            // the raster's items
  uint32_t* tile_list_ = nullptr;   // one tile's nodes (the AVX2 loop's input)
  PointLanes lanes_ = PointLanes::kScalar;  // what config_.lanes resolved to on this CPU
  int32_t* mean_terms_ = nullptr;   // the frame's mean table (build_mean_terms): [axis][q][3]
  uint16_t* lane_ppn_ = nullptr;    // the points-per-node table, padded for 32-bit reads
  // sample_reach_[i][k]: the largest |g_k| (Q12) of the first
  // sample_reach_samples(i) position samples — a node of no more points
  // reaches no farther along its axis k (the tile pass's spans;
  // kGaussianClip bounds them all).
  // (A fourth column, 0, for the node lanes' gathers.)
  int32_t sample_reach_[kSampleReachBuckets][4] = {};
};

}  // namespace stipple
