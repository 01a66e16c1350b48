// Fuzz harness: a cut table (core/cut_table.h) beside the fuzzers' tiny
// model. The first byte picks how the input is read: as a whole table
// (every header check), or as bytes XORed into the model's own table after
// its header, the nodes' CRC-32 then set right, so that mutations reach the
// node checks behind the checksum. A table attach accepts is then used:
// cuts from the root and incremental ones over a short orbit, and three
// refinement windows. Centres and normals are not checked against the model
// (docs/format.md, "The cut table"): hostile ones may give a wrong cut, but
// never a read out of bounds or an overflow (the sanitizers' build).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/cut_table.h"
#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "core/view_cut.h"
#include "platform/file_io.h"

namespace {

using namespace stipple;

struct Model {
  std::vector<uint8_t> file;
  SpgView view;
  std::vector<uint32_t> decoder_storage;
  NodeDecoder decoder;
  std::vector<uint64_t> bounds_storage;
  CutBounds bounds;
  std::vector<uint8_t> table;  // the model's own
  Model() {
    std::string error;
    if (!read_file(STIPPLE_FUZZ_MODEL, file, error) || !spg_parse(file.data(), file.size(), &view).ok()) __builtin_trap();
    decoder_storage.resize(node_decoder_bytes(view.header) / 4 + 1);
    if (decoder.init(view, decoder_storage.data(), decoder_storage.size() * 4) != DecodeStatus::kOk) __builtin_trap();
    bounds_storage.resize(CutBounds::bytes(view.header) / 8 + 1);
    if (bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8) != CutStatus::kOk) __builtin_trap();
    table.resize(cut_table_bytes(view.header.node_count));
    cut_table_header(model_tag(file.data(), file.size()), ConeRule{}, bounds, table.data());
    const uint8_t* nodes = static_cast<const uint8_t*>(bounds.table());
    for (size_t i = kCutTableHeaderBytes; i < table.size(); ++i) table[i] = nodes[i - kCutTableHeaderBytes];
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Model m;
  if (size == 0) return 0;
  std::vector<uint8_t> t;
  if (data[0] % 3 == 0) {
    t.assign(data + 1, data + size);
  } else {
    t = m.table;
    for (size_t k = 1; k < size && kCutTableHeaderBytes + k - 1 < t.size(); ++k) t[kCutTableHeaderBytes + k - 1] ^= data[k];
    store_u32le(t.data() + 60, crc32(t.data() + kCutTableHeaderBytes, t.size() - kCutTableHeaderBytes));
  }
  CutBounds bounds;
  const CutTableResult r =
      cut_table_attach(t.data(), t.size(), m.view, model_tag(m.file.data(), m.file.size()), ConeRule{}, &bounds);
  if (!r.ok()) {
    if (bounds.table() != nullptr) __builtin_trap();  // refused: nothing attached
    return 0;
  }

  const uint32_t n = bounds.node_count();
  std::vector<uint64_t> state(view_cut_state_bytes(n) / 8 + 1), scratch_storage(CutScratch::bytes(n) / 8 + 1);
  std::vector<uint8_t> front(ViewCut::front_bytes(2 * n + 2));
  CutScratch scratch;
  scratch.init(scratch_storage.data(), scratch_storage.size() * 8);
  ViewCut cut;
  if (cut.init(bounds, state.data(), state.size() * 8, &scratch) != CutStatus::kOk) __builtin_trap();
  OrbitView orbit;
  for (int a = 0; a < 3; ++a) orbit.target_mu[a] = m.decoder.extent_mu()[a] / 2;
  orbit.distance_mu = 3 << 24;
  orbit.pitch = 1u << 26;
  for (int incremental = 0; incremental < 2; ++incremental) {
    cut.use_front(incremental ? front.data() : nullptr, front.size());
    for (uint32_t step = 0; step < 6; ++step) {
      orbit.yaw = step * (1u << 25);  // 2.8 degrees a step
      Camera camera;
      if (!orbit_camera(orbit, 240, 320, &camera)) __builtin_trap();
      CutParams p;
      p.max_nodes = step % 3 == 2 ? 8 : 0xFFFFFFFFu;
      if (step == 5) {
        p.window[0] = 40, p.window[1] = 40, p.window[2] = 120, p.window[3] = 200;
        p.accumulate = true;
      }
      const CutStatus s = cut.update(camera, p);
      if (s != CutStatus::kOk) __builtin_trap();  // storage for the whole tree: never refused
      if (cut.sent_count() > n) __builtin_trap();
    }
  }
  return 0;
}
