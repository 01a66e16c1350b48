// stipple raster — the handheld client: a node cache (core/node_cache.h) and
// the software point renderer (raster/point_renderer.h) over one
// caller-provided arena.
//
//   size_t n = client_arena_bytes(config);     // 0: invalid configuration
//   client.init(config, arena, n);             // carves every table and buffer
//   client.load_startup(msg, size);            // header + class tables (.spg §1-§2)
//   client.put_node(NodeId{id}, record, size); // decode-checked, cached
//   client.drop_node(NodeId{id});
//   client.render(camera, frame, stride);      // one frame, integer only
//
// After init nothing is allocated, nothing is thrown, and the per-frame path
// (render) uses integer arithmetic only. The cache's and the renderer's
// contracts are in their headers; this class only composes them, so a
// client without the software renderer (the GL client) uses NodeCache alone.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/camera.h"
#include "core/node_cache.h"
#include "core/spg_format.h"
#include "raster/point_renderer.h"

namespace stipple {

// The renderer's configuration (raster, normals/colour, samples, shading...)
// and the cache's limits; `normals`, `color` and `max_angle_bits` size both.
struct ClientConfig : RendererConfig {
  uint32_t node_capacity = 30000;          // nodes the cache holds
  bool cache_decoded = false;              // keep decoded nodes (sizeof(FixedNode) bytes each) instead of
                                           // packed records: no per-frame decode, ~7x the cache memory
  uint16_t max_classes[3] = {4096, 4096, 64};  // sigma_p, sigma_n, sigma_c tables
  uint8_t max_record_bytes = 0;            // widest record held packed; 0: the paper's layout
  bool ewa = false;                        // EWA splats (`--splat ewa`): RendererConfig::splats for every node held
};

// The handheld's tile pass: rows for 2,048 nodes (RendererConfig::
// tile_nodes: 136 bytes each with their tile links), more as the tile
// nodes' points spare the bins, every point of the budget binnable, which
// keeps the arena at 240x320 RGB565 with 30,000 cached nodes and a
// 60,000-point budget within 2 MiB, colour or not (docs/fixed_point.md).
inline constexpr uint32_t kHandheldTileNodes = 2048;

// The two halves of a client configuration.
NodeCacheLimits cache_limits(const ClientConfig& config);
RendererConfig renderer_config(const ClientConfig& config);

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

// Arena bytes for a configuration, or 0 when it is invalid.
size_t client_arena_bytes(const ClientConfig& config);

class Client {
 public:
  [[nodiscard]] ClientStatus init(const ClientConfig& config, void* arena, size_t bytes);

  // Validates and adopts a startup message (the first bytes of a .spg file,
  // spg_startup_bytes long); forgets every cached node. The message is
  // copied into the arena as needed: the caller's buffer may go away.
  [[nodiscard]] ClientStatus load_startup(const uint8_t* data, size_t size);
  SpgResult startup_error() const { return cache_.startup_error(); }

  // Adds or replaces node `id`; `points` is the original points under it
  // (saturated at 255, 0 when unknown: ViewCut::points), which
  // RendererConfig::point_cap caps its drawn points by.
  [[nodiscard]] ClientStatus put_node(NodeId id, const uint8_t* record, size_t size, uint8_t points = 0);
  [[nodiscard]] ClientStatus drop_node(NodeId id);
  bool has_node(NodeId id) const { return cache_.has(id); }
  uint32_t node_count() const { return cache_.count(); }
  size_t record_bytes() const { return cache_.record_bytes(); }

  // Draws every cached node into `frame` (height rows of `stride` bytes in the
  // configured pixel format).
  [[nodiscard]] ClientStatus render(const Camera& camera, uint8_t* frame, size_t stride, FrameStats* stats = nullptr);

  // Shading, grey and quality while it runs (PointRenderer::set_view).
  [[nodiscard]] bool set_view(ShadingMode shading, bool grey, uint16_t quality_q8) {
    return renderer_.set_view(shading, grey, quality_q8);
  }
  // Colour by elevation along `up` (PointRenderer::set_elevation).
  [[nodiscard]] bool set_elevation(SpgAxis up) { return renderer_.set_elevation(up); }
  const RendererConfig& view_config() const { return renderer_.config(); }

  const NodeDecoder& decoder() const { return cache_.decoder(); }
  const NodeCache& cache() const { return cache_; }
  // The cache itself, for whatever fills it from a stream (core/stream.h).
  NodeCache& cache() { return cache_; }

 private:
  NodeCache cache_;
  PointRenderer renderer_;
};

}  // namespace stipple
