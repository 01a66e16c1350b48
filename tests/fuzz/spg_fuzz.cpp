// Fuzz harness: core's .spg validator, then the host reference decoder on
// whatever it accepts, and the handheld client on the same bytes: the
// input's startup message, then the bytes after it cut into records for
// put_node (accepted or refused), then one frame; a version 3 file expanded
// and decoded. Must never crash, overrun
// or hang. Each input is
// checked as it is and again with its last four bytes replaced by the right
// CRC-32, so mutations reach the structural checks behind the checksum.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/spg_coded.h"
#include "core/spg_format.h"
#include "raster/client.h"
#include "tools/reference/spg_model.h"

namespace {

// A small client, made once: hostile startups must not need a new one.
struct FuzzClient {
  stipple::ClientConfig config;
  std::vector<uint64_t> arena;
  stipple::Client client;
  std::vector<uint8_t> frame;
  FuzzClient() {
    config.raster = stipple::RasterConfig{64, 48, 5, stipple::PixelFormat::kRgb565, 4096};
    config.node_capacity = 256;
    config.samples = 64;
    arena.resize(stipple::client_arena_bytes(config) / 8 + 1);
    frame.resize(64 * 48 * 2);
    if (client.init(config, arena.data(), arena.size() * 8) != stipple::ClientStatus::kOk) __builtin_trap();
  }
};

void check_client(const uint8_t* data, size_t size) {
  static FuzzClient f;
  stipple::SpgView startup;
  size_t used = 0;
  if (!stipple::spg_parse_startup(data, size, &startup, &used).ok()) {
    if (f.client.load_startup(data, size) != stipple::ClientStatus::kBadStartup) __builtin_trap();
    return;
  }
  if (f.client.load_startup(data, used) != stipple::ClientStatus::kOk) return;  // beyond the configuration
  const size_t rb = f.client.record_bytes();
  for (size_t at = used, id = 0; at + rb <= size && id < 256; at += rb, ++id)
    (void)f.client.put_node(stipple::NodeId{static_cast<uint32_t>(id * 2654435761u)}, data + at, rb);
  stipple::OrbitView orbit;
  for (int a = 0; a < 3; ++a) orbit.target_mu[a] = f.client.decoder().extent_mu()[a] / 2;
  stipple::Camera camera;
  if (!stipple::orbit_camera(orbit, 64, 48, &camera)) __builtin_trap();
  if (f.client.render(camera, f.frame.data(), 128) != stipple::ClientStatus::kOk) __builtin_trap();
  // And from inside the model, turned by the input: hostile nodes as
  // close-ups' discs (raster/close_up.h), their means around and behind the eye.
  orbit.distance_mu = 1 << 14;
  orbit.yaw = static_cast<uint32_t>(size * 2654435761u);
  orbit.pitch = static_cast<uint32_t>(size * 40503u) % 0x38000000u;
  if (!stipple::orbit_camera(orbit, 64, 48, &camera)) __builtin_trap();
  if (f.client.render(camera, f.frame.data(), 128) != stipple::ClientStatus::kOk) __builtin_trap();
}

void check(const uint8_t* data, size_t size) {
  stipple::SpgView view;
  const stipple::SpgResult r = stipple::spg_parse(data, size, &view);
  if (r.ok()) {
    stipple::DecodedModel model;
    std::string error;
    if (!stipple::decode_spg("fuzz.spg", data, size, model, error)) __builtin_trap();  // parse and decode must agree
  } else if (r.offset > size) {
    __builtin_trap();  // an error offset is always inside (or at the end of) the input
  } else if (r.error == stipple::SpgError::kCodedRecords) {
    // Version 3: expanded, the image is a model its readers take whole.
    stipple::SpgCodedParts parts;
    const stipple::SpgResult c = stipple::spg_parse_coded(data, size, &view, &parts);
    if (!c.ok() && c.offset > size) __builtin_trap();
    if (c.ok()) {
      std::vector<uint8_t> image(stipple::spg_expanded_bytes(view, parts)), points(view.header.node_count);
      const stipple::SpgResult e = stipple::spg_expand(data, view, parts, image.data(), points.data());
      if (e.ok()) {
        stipple::DecodedModel model;
        std::string error;
        if (!stipple::decode_spg("fuzz.spg", image.data(), image.size(), model, error)) __builtin_trap();
      } else if (e.error == stipple::SpgError::kBadCoded && e.offset > size) {
        __builtin_trap();
      }
    }
  }
  check_client(data, size);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  check(data, size);
  if (size >= 4) {
    std::vector<uint8_t> fixed(data, data + size);  // exact size, so ASan sees overruns
    const uint32_t crc = stipple::crc32(fixed.data(), size - 4);
    for (int i = 0; i < 4; ++i) fixed[size - 4 + static_cast<size_t>(i)] = static_cast<uint8_t>(crc >> (8 * i));
    check(fixed.data(), size);
  }
  return 0;
}
