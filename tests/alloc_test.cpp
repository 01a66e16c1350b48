// Counts every heap call (operator new/delete and malloc/calloc/realloc/free)
// and checks that core's per-frame paths make none after init: validating a
// .spg, decoding every node, unpacking records, rasterizing, the whole
// client, presenting to the null display, the view cut and both ends of the
// node stream. A positive control first
// proves the counter sees allocations. Built without sanitizers only (they
// replace malloc themselves). Prints "N passed, M failed".
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "platform/file_io.h"
#include "platform/null/null_display.h"
#include "core/cut.h"
#include "core/stream.h"
#include "core/view_cut.h"
#include "raster/client.h"
#include "raster/point_raster.h"

extern "C" void* __libc_malloc(size_t);
extern "C" void* __libc_calloc(size_t, size_t);
extern "C" void* __libc_realloc(void*, size_t);
extern "C" void __libc_free(void*);

namespace {
std::atomic<long> g_heap_calls{0};
void count() { g_heap_calls.fetch_add(1, std::memory_order_relaxed); }
}

extern "C" void* malloc(size_t n) {
  count();
  return __libc_malloc(n);
}
extern "C" void* calloc(size_t a, size_t b) {
  count();
  return __libc_calloc(a, b);
}
extern "C" void* realloc(void* p, size_t n) {
  count();
  return __libc_realloc(p, n);
}
extern "C" void free(void* p) {
  if (p) count();
  __libc_free(p);
}
void* operator new(size_t n) {
  count();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](size_t n) { return operator new(n); }
void operator delete(void* p) noexcept {
  if (p) count();
  __libc_free(p);
}
void operator delete[](void* p) noexcept { operator delete(p); }
void operator delete(void* p, size_t) noexcept { operator delete(p); }
void operator delete[](void* p, size_t) noexcept { operator delete(p); }

int main(int argc, char** argv) {
  int passed = 0, failed = 0;
  auto check = [&](bool ok, const char* what, long calls) {
    std::printf("%s: %s (%ld heap calls)\n", ok ? "PASS" : "FAIL", what, calls);
    (ok ? passed : failed)++;
  };
  // Positive control: the counter sees a new/delete pair.
  // The pointer escapes through a volatile, or the compiler may elide the pair
  // (clang does).
  static int* volatile probe;
  long before = g_heap_calls.load();
  probe = new int(7);
  delete probe;
  check(g_heap_calls.load() - before == 2, "counter sees new and delete", g_heap_calls.load() - before);

  // Init: read the model, size and hand over storage.
  std::vector<uint8_t> spg;
  std::string error;
  if (argc < 2 || !stipple::read_file(argv[1], spg, error)) {
    std::fprintf(stderr, "usage: alloc_test MODEL.spg (%s)\n", error.c_str());
    return 2;
  }
  stipple::SpgView view;
  if (!stipple::spg_parse(spg.data(), spg.size(), &view).ok()) return 2;
  std::vector<uint32_t> storage(stipple::node_decoder_bytes(view.header) / 4 + 1);
  const stipple::RasterConfig raster_config{240, 320, 5, stipple::PixelFormat::kRgb565, 30000};
  std::vector<uint64_t> raster_arena(stipple::point_raster_bytes(raster_config) / 8 + 1);
  stipple::PointRaster raster;
  if (raster.init(raster_config, raster_arena.data(), raster_arena.size() * 8) != stipple::RasterStatus::kOk) return 2;
  std::vector<uint8_t> frame_pixels(240 * 320 * 2);
  stipple::NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size() * 4) != stipple::DecodeStatus::kOk) return 2;

  // After init: 100 passes of validation and decoding, no heap call at all.
  before = g_heap_calls.load();
  long checksum = 0;
  for (int frame = 0; frame < 100; ++frame) {
    stipple::SpgView again;
    checksum += stipple::spg_parse(spg.data(), spg.size(), &again).ok();
    for (uint32_t i = 0; i < view.header.node_count; ++i) {
      stipple::FixedNode node;
      if (decoder.decode(view.records + static_cast<size_t>(i) * view.record_bytes, &node) == stipple::DecodeStatus::kOk)
        checksum += node.mean[0];
    }
  }
  check(g_heap_calls.load() - before == 0, "100 x (spg_parse + decode every node) after init", g_heap_calls.load() - before);

  before = g_heap_calls.load();
  for (int frame = 0; frame < 100; ++frame) {
    raster.begin_frame();
    for (uint32_t i = 0; i < 30000; ++i)
      raster.add(stipple::ScreenPoint{static_cast<int32_t>((i * 7919u) % (240 * 16)), static_cast<int32_t>((i * 104729u) % (320 * 16)),
                                      i * 2654435761u, i * 40503u},
                 1 + static_cast<int>(i % 3));
    raster.draw(0x102030, frame_pixels.data(), 240 * 2);
    checksum += frame_pixels[frame];
  }
  check(g_heap_calls.load() - before == 0, "100 frames of 30,000 points rasterized after init", g_heap_calls.load() - before);

  // The whole client: init over one arena, then startup, nodes, frames from
  // several cameras, node churn and a reload — with no heap call after init.
  stipple::ClientConfig client_config;
  client_config.raster = stipple::RasterConfig{240, 320, 5, stipple::PixelFormat::kRgb565, 60000};
  client_config.node_capacity = 8000;
  std::vector<uint64_t> client_arena(stipple::client_arena_bytes(client_config) / 8 + 1);
  stipple::Client client;
  if (client.init(client_config, client_arena.data(), client_arena.size() * 8) != stipple::ClientStatus::kOk) return 2;
  std::vector<uint8_t> cut_scratch(stipple::cut_scratch_bytes(view.header));
  std::vector<uint32_t> cut(view.header.node_count);
  const size_t startup_bytes = stipple::spg_startup_bytes(view.header.version, view.header.class_count);
  before = g_heap_calls.load();
  bool client_ok = true;
  stipple::FrameStats stats;
  uint32_t discs = 0;  // the third round's close cameras draw close-ups' discs (raster/close_up.h)
  for (int reload = 0; reload < 3; ++reload) {
    client_ok &= client.load_startup(spg.data(), startup_bytes) == stipple::ClientStatus::kOk;
    for (int frame = 0; frame < 30; ++frame) {
      stipple::OrbitView orbit;
      for (int a = 0; a < 3; ++a) orbit.target_mu[a] = decoder.extent_mu()[a] / 2;
      orbit.distance_mu = reload == 2 ? 1 << 22 : 3 << 24;
      orbit.yaw = static_cast<uint32_t>(frame) * 0x08000000u;
      orbit.pitch = static_cast<uint32_t>(reload) * 0x04000000u;
      stipple::Camera camera;
      client_ok &= stipple::orbit_camera(orbit, 240, 320, &camera);
      const stipple::CutRule rule{stipple::CutRule::kProjectedSize, 0, 32};
      const uint32_t n = stipple::simple_cut(view, rule, &decoder, &camera, cut_scratch.data(), cut.data(),
                                             static_cast<uint32_t>(cut.size()));
      // Drop what left the cut (every node, for simplicity, every 10th frame), add what entered.
      if (frame % 10 == 0)
        for (uint32_t i = 0; i < view.header.node_count; ++i)
          if (client.has_node(stipple::NodeId{i})) client_ok &= client.drop_node(stipple::NodeId{i}) == stipple::ClientStatus::kOk;
      for (uint32_t i = 0; i < n && i < client_config.node_capacity; ++i)
        client_ok &= client.put_node(stipple::NodeId{cut[i]}, view.records + static_cast<size_t>(cut[i]) * view.record_bytes,
                                     view.record_bytes) == stipple::ClientStatus::kOk;
      client_ok &= client.render(camera, frame_pixels.data(), 240 * 2, &stats) == stipple::ClientStatus::kOk;
      checksum += frame_pixels[1000 + frame] + stats.points;
      discs += stats.nodes_close_up;
    }
  }
  check(client_ok && discs > 0 && g_heap_calls.load() - before == 0,
        "client: 3 startups, 90 frames with cuts, puts, drops (close-ups' discs among them) after init",
        g_heap_calls.load() - before);

  // EWA splats (raster/ewa.h): their records and a tile's sums in the
  // arena, from near and far, with no heap call after init.
  stipple::ClientConfig ewa_config = client_config;
  ewa_config.ewa = true;
  std::vector<uint64_t> ewa_arena(stipple::client_arena_bytes(ewa_config) / 8 + 1);
  stipple::Client ewa;
  if (ewa.init(ewa_config, ewa_arena.data(), ewa_arena.size() * 8) != stipple::ClientStatus::kOk) return 2;
  before = g_heap_calls.load();
  bool ewa_ok = ewa.load_startup(spg.data(), startup_bytes) == stipple::ClientStatus::kOk;
  uint32_t splats = 0;
  for (int frame = 0; frame < 20; ++frame) {
    stipple::OrbitView orbit;
    for (int a = 0; a < 3; ++a) orbit.target_mu[a] = decoder.extent_mu()[a] / 2;
    orbit.distance_mu = frame % 2 ? 1 << 22 : 3 << 24;
    orbit.yaw = static_cast<uint32_t>(frame) * 0x0C000000u;
    stipple::Camera camera;
    ewa_ok &= stipple::orbit_camera(orbit, 240, 320, &camera);
    const stipple::CutRule rule{stipple::CutRule::kProjectedSize, 0, 32};
    const uint32_t n = stipple::simple_cut(view, rule, &decoder, &camera, cut_scratch.data(), cut.data(),
                                           static_cast<uint32_t>(cut.size()));
    for (uint32_t i = 0; i < view.header.node_count; ++i)
      if (ewa.has_node(stipple::NodeId{i})) ewa_ok &= ewa.drop_node(stipple::NodeId{i}) == stipple::ClientStatus::kOk;
    for (uint32_t i = 0; i < n && i < ewa_config.node_capacity; ++i)
      ewa_ok &= ewa.put_node(stipple::NodeId{cut[i]}, view.records + static_cast<size_t>(cut[i]) * view.record_bytes,
                             view.record_bytes) == stipple::ClientStatus::kOk;
    ewa_ok &= ewa.render(camera, frame_pixels.data(), 240 * 2, &stats) == stipple::ClientStatus::kOk;
    checksum += frame_pixels[2000 + frame];
    splats += stats.splats;
  }
  check(ewa_ok && splats > 0 && g_heap_calls.load() - before == 0, "EWA client: 20 frames near and far after init",
        g_heap_calls.load() - before);

  // The display path: the null display converts and keeps every frame in
  // storage sized when it was made.
  stipple::NullDisplay display(240, 320, stipple::PixelFormat::kRgb565);
  std::string display_error;
  display.push_input(stipple::InputEvent{stipple::InputKind::kButtonDown, stipple::Button::kLeft, 0, 0});
  before = g_heap_calls.load();
  bool display_ok = true;
  for (int frame = 0; frame < 100; ++frame) {
    display_ok &= display.present(frame_pixels.data(), 240 * 2, 240, 320, stipple::PixelFormat::kRgb565, display_error);
    stipple::InputEvent event;
    while (display.poll(&event)) checksum += static_cast<int>(event.kind);
  }
  check(display_ok && display.frames() == 100 && g_heap_calls.load() - before == 0,
        "100 frames presented to the null display", g_heap_calls.load() - before);
  // The node stream's two ends and the view cut under them: a server's
  // sender and a client's receiver over storage sized at start-up, 30 camera
  // updates along an orbit, the frames handed over through a fixed buffer.
  std::vector<uint64_t> bounds_storage(stipple::CutBounds::bytes(view.header) / 8 + 1);
  stipple::CutBounds bounds;
  std::vector<uint64_t> sender_storage(stipple::StreamSender::storage_bytes(view.header) / 8 + 1);
  stipple::StreamSender sender;
  stipple::NodeCacheLimits limits;
  limits.node_capacity = 8000;
  std::vector<uint64_t> cache_storage(stipple::node_cache_bytes(limits) / 8 + 1);
  stipple::NodeCache cache;
  std::vector<uint8_t> reader_storage(stipple::kMaxFrameBytes);
  stipple::StreamReceiver receiver;
  struct Link {
    std::vector<uint8_t> bytes = std::vector<uint8_t>(1 << 21);
    size_t used = 0;
    static bool sink(void* self, const uint8_t* frame, size_t size) {
      auto* l = static_cast<Link*>(self);
      if (l->used + size > l->bytes.size()) return false;
      for (size_t i = 0; i < size; ++i) l->bytes[l->used + i] = frame[i];
      l->used += size;
      return true;
    }
  } link;
  bool stream_ok = bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8) == stipple::CutStatus::kOk &&
                   sender.init(view, bounds, sender_storage.data(), sender_storage.size() * 8) &&
                   cache.init(limits, cache_storage.data(), cache_storage.size() * 8) == stipple::CacheStatus::kOk;
  receiver.init(&cache, reader_storage.data(), reader_storage.size());
  std::vector<uint32_t> part_storage(limits.node_capacity);
  receiver.use_part_storage(part_storage.data(), limits.node_capacity);
  before = g_heap_calls.load();
  stipple::Hello hello;
  hello.cache_capacity = limits.node_capacity;
  hello.attributes |= stipple::kWantCoded;  // protocol 5: the code tables counted and coded batches, both ends
  stream_ok = stream_ok && sender.start(hello, Link::sink, &link);
  for (uint32_t frame = 0; stream_ok && frame < 30; ++frame) {
    stipple::CameraUpdate u;
    u.sequence = frame;
    stipple::OrbitView orbit;
    for (int a = 0; a < 3; ++a) orbit.target_mu[a] = decoder.extent_mu()[a] / 2;
    orbit.distance_mu = 3 << 24;
    orbit.yaw = frame * 0x04000000u;
    stream_ok = stipple::orbit_camera(orbit, 240, 320, &u.camera) && sender.update(u, true, Link::sink, &link) &&
                receiver.receive(link.bytes.data(), link.used) == stipple::ReceiveStatus::kOk && receiver.converged(frame) &&
                cache.count() == sender.cut().sent_count() && receiver.coded();
    link.used = 0;
  }
  check(stream_ok && g_heap_calls.load() - before == 0,
        "stream: startup and 30 camera updates cut, sent (entropy-coded) and received after init", g_heap_calls.load() - before);
  std::printf("checksum %ld\n%d passed, %d failed\n", checksum, passed, failed);
  return failed == 0 ? 0 : 1;
}
