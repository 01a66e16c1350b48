// Fuzz harness: the node decoder alone, under every layout the format
// allows. The input's first bytes choose a startup — version, attributes,
// each field's width (1..16 bits), the box's float32 bits, small class
// tables — which core's writer turns into a startup message (or refuses, as
// the reader would); the rest are packed records, each decoded. Checked, for
// every record: the status is kOk or kBadClass, and a refused record leaves
// the output untouched; a decoded one has its mean inside the box (0 .. 2^24
// MU), every frame axis within Q14's unit, sigma_n not negative — and the
// checked build (STIPPLE_CHECK_RANGES) traps on any fixed-point bound that
// does not hold on the way.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/node_decoder.h"
#include "core/spg_format.h"
#include "core/spg_writer.h"

namespace {

struct Input {
  const uint8_t* data;
  size_t size, at = 0;
  uint8_t byte() { return at < size ? data[at++] : 0; }
  uint32_t u32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= uint32_t{byte()} << (8 * i);
    return v;
  }
};

bool within(const int16_t (&frame)[3][3]) {
  for (const auto& axis : frame)
    for (int16_t v : axis)
      if (v < -16384 || v > 16384) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  Input in{data, size};
  SpgHeader h;
  const uint8_t mode = in.byte();  // bit 0 normals, 1 colour, 2 version 1, 3 wide angles
  h.version = (mode & 4) ? 1 : 2;
  h.flags = mode & kAttrKnownMask;
  h.tree_arity = 2;
  for (int f = 0; f < kFieldCount; ++f) {
    const bool normal_field = f >= static_cast<int>(Field::kFnTheta) && f <= static_cast<int>(Field::kSigmaN);
    const bool color_field = f >= static_cast<int>(Field::kColorR);
    const bool present = (!normal_field || h.has_normals()) && (!color_field || h.has_color());
    // Angle tables have 2^bits entries each: wide angles (13-16 bits) only
    // when the mode asks, so most inputs stay fast.
    const bool angle = f != static_cast<int>(Field::kSigmaP) && f != static_cast<int>(Field::kSigmaN) &&
                       f != static_cast<int>(Field::kSigmaC) && (f >= static_cast<int>(Field::kFcTheta) ||
                                                                 (f >= static_cast<int>(Field::kFpTheta) && f < static_cast<int>(Field::kColorR)));
    const int widest = angle && !(mode & 8) ? 12 : kMaxFieldBits;
    h.layout.bits[f] = static_cast<uint8_t>(present ? 1 + in.byte() % widest : 0);
  }
  h.node_count = h.leaf_count = h.point_count = 1;
  for (uint32_t& b : h.bbox_bits) b = in.u32();
  h.class_count[0] = static_cast<uint16_t>(1 + in.byte() % 8);
  h.class_count[1] = static_cast<uint16_t>(h.has_normals() ? 1 + in.byte() % 8 : 0);
  h.class_count[2] = static_cast<uint16_t>(h.has_color() ? 1 + in.byte() % 8 : 0);
  std::vector<uint32_t> tables[3];
  const int per_class[3] = {3, 2, 3};
  for (int t = 0; t < 3; ++t) {
    tables[t].resize(size_t{h.class_count[t]} * per_class[t]);
    for (uint32_t& v : tables[t]) v = h.version == 1 ? in.u32() : (in.u32() & 0xFFFFu);
  }
  if (!tables[0].empty())  // sigma1 >= sigma2 >= sigma3, as the format requires of every class
    for (size_t c = 0; c < tables[0].size(); c += 3)
      if (h.version == 2) {
        if (tables[0][c + 1] > tables[0][c]) tables[0][c + 1] = tables[0][c];
        if (tables[0][c + 2] > tables[0][c + 1]) tables[0][c + 2] = tables[0][c + 1];
      }
  const SpgClassTables classes{tables[0].data(), tables[1].empty() ? nullptr : tables[1].data(),
                               tables[2].empty() ? nullptr : tables[2].data()};
  std::vector<uint8_t> startup(spg_startup_bytes(h.version, h.class_count) + 64);
  size_t written = 0;
  if (spg_write_startup(h, classes, startup.data(), startup.size(), &written) != SpgWriteStatus::kOk) return 0;
  SpgView view;
  size_t used = 0;
  if (!spg_parse_startup(startup.data(), written, &view, &used).ok()) return 0;  // e.g. an unordered float table
  view.record_bytes = static_cast<size_t>(view.header.layout.record_bytes());
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4 + 1);
  NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size() * 4) != DecodeStatus::kOk) return 0;
  const size_t rb = view.record_bytes;
  for (size_t at = in.at; at + rb <= size; at += rb) {
    std::vector<uint8_t> record(data + at, data + at + rb);  // exact size: ASan sees an overrun
    FixedNode n;
    std::memset(&n, 0xA5, sizeof n);
    FixedNode untouched;
    std::memcpy(&untouched, &n, sizeof n);
    const DecodeStatus s = decoder.decode(record.data(), &n);
    if (s == DecodeStatus::kBadClass) {
      if (std::memcmp(&n, &untouched, sizeof n) != 0) __builtin_trap();
      continue;
    }
    if (s != DecodeStatus::kOk) __builtin_trap();
    for (int a = 0; a < 3; ++a)
      if (n.mean[a] < 0 || n.mean[a] > (1 << 24)) __builtin_trap();
    if (!within(n.normal_frame) || n.sigma_n[0] < 0 || n.sigma_n[1] < 0) __builtin_trap();
  }
  return 0;
}
