// stipple raster — the handheld client: cache + renderer. See client.h.
#include "raster/client.h"

#include "core/arena.h"

namespace stipple {
namespace {

ClientStatus status_of(CacheStatus s) {
  switch (s) {
    case CacheStatus::kOk: return ClientStatus::kOk;
    case CacheStatus::kBadLimits: return ClientStatus::kBadConfig;
    case CacheStatus::kStorageTooSmall: return ClientStatus::kArenaTooSmall;
    case CacheStatus::kNoStartup: return ClientStatus::kNoStartup;
    case CacheStatus::kBadStartup: return ClientStatus::kBadStartup;
    case CacheStatus::kStartupTooLarge: return ClientStatus::kStartupTooLarge;
    case CacheStatus::kBadRecordSize: return ClientStatus::kBadRecordSize;
    case CacheStatus::kBadRecord: return ClientStatus::kBadRecord;
    case CacheStatus::kFull: return ClientStatus::kCacheFull;
    case CacheStatus::kUnknownNode: return ClientStatus::kUnknownNode;
    case CacheStatus::kBadClasses: return ClientStatus::kBadStartup;
    case CacheStatus::kClassMissing: return ClientStatus::kBadRecord;
  }
  return ClientStatus::kBadConfig;
}

ClientStatus status_of(RenderStatus s) {
  switch (s) {
    case RenderStatus::kOk: return ClientStatus::kOk;
    case RenderStatus::kBadConfig: return ClientStatus::kBadConfig;
    case RenderStatus::kStorageTooSmall: return ClientStatus::kArenaTooSmall;
    case RenderStatus::kNoStartup: return ClientStatus::kNoStartup;
    case RenderStatus::kBadCamera: return ClientStatus::kBadCamera;
  }
  return ClientStatus::kBadConfig;
}

}  // namespace

NodeCacheLimits cache_limits(const ClientConfig& c) {
  NodeCacheLimits l;
  l.node_capacity = c.node_capacity;
  l.decoded = c.cache_decoded;
  l.normals = c.normals;
  l.color = c.color;
  for (int k = 0; k < 3; ++k) l.max_classes[k] = c.max_classes[k];
  l.max_angle_bits = c.max_angle_bits;
  l.max_record_bytes = c.max_record_bytes;
  return l;
}

RendererConfig renderer_config(const ClientConfig& c) {
  RendererConfig r = c;
  if (r.tile_nodes > c.node_capacity) r.tile_nodes = c.node_capacity;  // never more drawn than held
  if (c.ewa) r.splats = c.node_capacity;
  return r;
}

const char* client_status_text(ClientStatus s) {
  switch (s) {
    case ClientStatus::kOk: return "ok";
    case ClientStatus::kBadConfig: return "invalid client configuration";
    case ClientStatus::kArenaTooSmall: return "arena smaller than client_arena_bytes";
    case ClientStatus::kNoStartup: return "no startup message loaded";
    case ClientStatus::kBadStartup: return "startup message is invalid";
    case ClientStatus::kStartupTooLarge: return "startup message needs more than the client was configured for";
    case ClientStatus::kBadRecordSize: return "node record size differs from the startup message's";
    case ClientStatus::kBadRecord: return "node record has a class index beyond its table or nonzero padding";
    case ClientStatus::kCacheFull: return "node cache is full";
    case ClientStatus::kUnknownNode: return "node is not in the cache";
    case ClientStatus::kBadCamera: return "camera out of range";
  }
  return "unknown status";
}

size_t client_arena_bytes(const ClientConfig& config) {
  const size_t cache = node_cache_bytes(cache_limits(config)), renderer = point_renderer_bytes(renderer_config(config));
  return cache == 0 || renderer == 0 ? 0 : align8(cache) + renderer;
}

ClientStatus Client::init(const ClientConfig& config, void* arena, size_t bytes) {
  const size_t cache = node_cache_bytes(cache_limits(config)), renderer = point_renderer_bytes(renderer_config(config));
  if (cache == 0 || renderer == 0) return ClientStatus::kBadConfig;
  if (bytes < align8(cache) + renderer) return ClientStatus::kArenaTooSmall;
  uint8_t* base = static_cast<uint8_t*>(arena);
  const ClientStatus s = status_of(cache_.init(cache_limits(config), base, cache));
  if (s != ClientStatus::kOk) return s;
  return status_of(renderer_.init(renderer_config(config), base + align8(cache), renderer));
}

ClientStatus Client::load_startup(const uint8_t* data, size_t size) { return status_of(cache_.load_startup(data, size)); }

ClientStatus Client::put_node(NodeId id, const uint8_t* record, size_t size, uint8_t points) {
  return status_of(cache_.put(id, record, size, points));
}

ClientStatus Client::drop_node(NodeId id) { return status_of(cache_.drop(id)); }

ClientStatus Client::render(const Camera& camera, uint8_t* frame, size_t stride, FrameStats* stats) {
  return status_of(renderer_.render(cache_, camera, frame, stride, stats));
}

}  // namespace stipple
