// stipple raster — the handheld client: node cache, decoder, quasi-random
// point generation, projection, shading and the tile rasterizer over one
// caller-provided arena.
//
//   size_t n = client_arena_bytes(config);     // 0: invalid configuration
//   client.init(config, arena, n);             // carves every table and buffer
//   client.load_startup(msg, size);            // header + class tables (.spg §1-§2)
//   client.put_node(id, record, size);         // decode-checked, cached packed
//   client.drop_node(id);
//   client.render(camera, frame, stride);      // one frame, integer only
//
// After init nothing is allocated, nothing is thrown, and the per-frame path
// (render) uses integer arithmetic only. A record is validated when it is put
// (class indices against the startup tables, padding bits zero) and cached
// in its packed form — 9 to 17 bytes a node — then decoded each frame; or,
// with cache_decoded, decoded once and cached as a FixedNode (116 bytes),
// which trades memory for the per-frame decode.
//
// Per node and frame: the mean and the sigma-scaled axes go to camera space;
// the projection is linearized at the mean (M, 2 x 3, 1/16 px per sigma),
// which gives the screen covariance M M^T, hence the points-per-node index;
// then sample j = 0 .. n-1 of the Gaussian tables becomes one point:
//   kAffine      x = x0 + M g                 (no division per point)
//   kReciprocal  X/Z per point, 1/Z from a 1024-entry table
//   kExact       X/Z per point by integer division
// docs/fixed_point.md gives every format and the measured error of each mode.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/gaussian_table.h"
#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "raster/point_raster.h"
#include "raster/points_per_node.h"
#include "raster/projection.h"
#include "raster/shading.h"

namespace stipple {

enum class ShadingMode : uint8_t { kPerPoint, kPerNode, kNone };

struct ClientConfig {
  RasterConfig raster;                     // screen, pixel format, tiles, points per frame
  uint32_t node_capacity = 30000;          // nodes the cache holds
  bool cache_decoded = false;              // keep decoded nodes (sizeof(FixedNode) bytes each) instead of
                                           // packed records: no per-frame decode, ~7x the cache memory
  bool normals = true, color = true;       // attributes the arena is sized for
  uint16_t max_classes[3] = {4096, 4096, 64};  // sigma_p, sigma_n, sigma_c tables
  uint8_t max_angle_bits = 10;             // widest angle field accepted
  uint16_t samples = 1024;                 // Gaussian table entries = most points per node
  GaussianSource source = GaussianSource::kSobol;
  uint8_t point_size = 2;                  // 1..3 px (the paper drew 1.8 px points)
  uint16_t quality_q8 = 256;               // points-per-node scale (256 = as measured)
  Projection projection = Projection::kAffine;
  ShadingMode shading = ShadingMode::kPerPoint;
  bool sample_color = true;                // per-point colour from sigma_c (else the node's mean colour)
  bool grey = false;                       // ignore the model's colour
  Lighting lighting;
  uint32_t grey_rgb = 0xD8D8D8;            // base colour without colour attributes
  uint32_t clear_rgb = 0x000000;
};

enum class ClientStatus : uint8_t {
  kOk = 0,
  kBadConfig,         // init: a value out of range
  kArenaTooSmall,     // init: fewer bytes than client_arena_bytes
  kNoStartup,         // put/drop/render before a startup message
  kBadStartup,        // load_startup: the message fails validation (see startup_error)
  kStartupTooLarge,   // load_startup: attributes, class tables or angle widths beyond the configuration
  kBadRecordSize,     // put_node: size differs from the startup's record size
  kBadRecord,         // put_node: class index beyond its table or nonzero padding
  kCacheFull,         // put_node: node_capacity nodes already held
  kUnknownNode,       // drop_node: id not held
  kBadCamera,         // render: focal length, near plane or depth range out of range
};

const char* client_status_text(ClientStatus s);

struct FrameStats {
  uint32_t nodes = 0;         // nodes held
  uint32_t nodes_drawn = 0;   // nodes that produced points
  uint32_t nodes_culled = 0;  // behind the near plane or off screen
  uint32_t points = 0;        // points generated and binned
  uint32_t points_dropped = 0;  // refused by a full frame budget
};

// Arena bytes for a configuration, or 0 when it is invalid.
size_t client_arena_bytes(const ClientConfig& config);

class Client {
 public:
  [[nodiscard]] ClientStatus init(const ClientConfig& config, void* arena, size_t bytes);

  // Validates and adopts a startup message (the first bytes of a .spg file,
  // spg_parse_startup); forgets every cached node. The message is copied
  // into the arena as needed: the caller's buffer may go away.
  [[nodiscard]] ClientStatus load_startup(const uint8_t* data, size_t size);
  SpgResult startup_error() const { return startup_error_; }

  // Adds or replaces node `id`.
  [[nodiscard]] ClientStatus put_node(uint32_t id, const uint8_t* record, size_t size);
  [[nodiscard]] ClientStatus drop_node(uint32_t id);
  bool has_node(uint32_t id) const;
  uint32_t node_count() const { return count_; }
  size_t record_bytes() const { return record_bytes_; }

  // Draws every cached node into `frame` (height rows of `stride` bytes in the
  // configured pixel format).
  [[nodiscard]] ClientStatus render(const Camera& camera, uint8_t* frame, size_t stride, FrameStats* stats = nullptr);

  const NodeDecoder& decoder() const { return decoder_; }

 private:
  struct FrameSetup;
  struct PointSetup;
  template <Projection P, bool kShadePoints, bool kColorPoints, bool kSpecular>
  void draw_node(const FrameSetup& f, const FixedNode& node, FrameStats& stats);
  template <Projection P, bool kShadePoints, bool kColorPoints, bool kSpecular>
  [[gnu::noinline]] uint32_t draw_points(const PointSetup& setup, FrameStats& stats);
  uint32_t* find(uint32_t id) const;
  uint32_t home_slot(uint32_t id) const;  // where id's probe sequence starts
  void erase_hash(uint32_t* entry);
  void forget_nodes();

  ClientConfig config_{};
  PointRaster raster_;
  NodeDecoder decoder_;
  bool ready_ = false;
  SpgResult startup_error_{};
  SpgHeader header_{};
  size_t record_bytes_ = 0, record_stride_ = 0, decoder_bytes_ = 0;
  void* decoder_storage_ = nullptr;
  uint8_t* records_ = nullptr;  // node_capacity x record_stride_
  uint32_t* ids_ = nullptr;     // per slot
  uint32_t* hash_ = nullptr;    // slot + 1, 0 = empty; linear probing
  uint32_t hash_mask_ = 0;
  uint32_t count_ = 0;
  Gaussian3Q12* g_position_ = nullptr;
  Gaussian2Q12* g_normal_ = nullptr;
  Gaussian3Q12* g_color_ = nullptr;
  ShadingTables* shading_ = nullptr;
  uint16_t* reciprocal_ = nullptr;  // 1024 entries
  const PpnTable* ppn_ = nullptr;
};

}  // namespace stipple
