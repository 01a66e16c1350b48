// Fuzz harness: core's .spg validator, then the host reference decoder on
// whatever it accepts. Must never crash, overrun or hang. Each input is
// checked as it is and again with its last four bytes replaced by the right
// CRC-32, so mutations reach the structural checks behind the checksum.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/spg_format.h"
#include "tools/host/spg_model.h"

namespace {

void check(const uint8_t* data, size_t size) {
  stipple::SpgView view;
  const stipple::SpgResult r = stipple::spg_parse(data, size, &view);
  if (r.ok()) {
    stipple::DecodedModel model;
    std::string error;
    if (!stipple::decode_spg("fuzz.spg", data, size, model, error)) __builtin_trap();  // parse and decode must agree
  } else if (r.offset > size) {
    __builtin_trap();  // an error offset is always inside (or at the end of) the input
  }
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
