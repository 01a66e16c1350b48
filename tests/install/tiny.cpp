// A device program built against the installed client library only
// (find_package(stipple) or pkg-config): a .spg's startup and its level-8
// cut handed to the fixed-point client, one 240 x 320 frame drawn, the
// frame's lit pixels and CRC-32 printed. tests/install/install_test.sh.
#include <cstdio>
#include <vector>

#include "core/cut.h"
#include "core/spg_format.h"
#include "raster/client.h"

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: tiny MODEL.spg\n"), 2;
  std::FILE* f = std::fopen(argv[1], "rb");
  if (!f) return std::perror(argv[1]), 1;
  std::vector<uint8_t> file;
  for (int c; (c = std::fgetc(f)) != EOF;) file.push_back(static_cast<uint8_t>(c));
  std::fclose(f);
  stipple::SpgView view;
  const stipple::SpgResult parsed = stipple::spg_parse(file.data(), file.size(), &view);
  if (!parsed.ok()) return std::fprintf(stderr, "%s: %s\n", argv[1], stipple::spg_error_text(parsed.error)), 1;

  stipple::ClientConfig config;
  std::vector<uint64_t> arena(stipple::client_arena_bytes(config) / 8 + 1);
  stipple::Client client;
  if (client.init(config, arena.data(), arena.size() * 8) != stipple::ClientStatus::kOk) return 1;
  size_t startup = 0;
  if (stipple::spg_parse_startup(file.data(), file.size(), &view, &startup).ok() == false ||
      client.load_startup(file.data(), startup) != stipple::ClientStatus::kOk)
    return std::fprintf(stderr, "startup refused\n"), 1;
  (void)stipple::spg_parse(file.data(), file.size(), &view);  // the whole file's view again, for the cut

  stipple::CutRule rule;
  rule.level = 8;
  std::vector<uint8_t> scratch(stipple::cut_scratch_bytes(view.header));
  std::vector<uint32_t> ids(config.node_capacity);
  const uint32_t n = stipple::simple_cut(view, rule, nullptr, nullptr, scratch.data(), ids.data(),
                                         static_cast<uint32_t>(ids.size()));
  for (uint32_t i = 0; i < n && i < ids.size(); ++i)
    if (client.put_node(stipple::NodeId{ids[i]}, view.records + size_t{ids[i]} * view.record_bytes, view.record_bytes) !=
        stipple::ClientStatus::kOk)
      return std::fprintf(stderr, "node %u refused\n", ids[i]), 1;

  stipple::OrbitView orbit;
  for (int a = 0; a < 3; ++a) orbit.target_mu[a] = client.decoder().extent_mu()[a] / 2;
  orbit.distance_mu = 3 * client.decoder().extent_mu()[1];
  stipple::Camera camera;
  if (!stipple::orbit_camera(orbit, 240, 320, &camera)) return 1;
  std::vector<uint8_t> frame(240 * 320 * 2);
  if (client.render(camera, frame.data(), 240 * 2) != stipple::ClientStatus::kOk) return 1;
  size_t lit = 0;
  for (size_t i = 0; i < frame.size(); i += 2) lit += (frame[i] | frame[i + 1]) != 0;
  std::printf("%u nodes, %zu pixels lit, frame crc32 %08x\n", n, lit, stipple::crc32(frame.data(), frame.size()));
  return lit > 0 ? 0 : 1;
}
