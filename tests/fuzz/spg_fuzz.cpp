// Fuzz harness: core's .spg validator, then the host reference decoder on
// whatever it accepts. Must never crash, overrun or hang.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/spg_format.h"
#include "tools/host/spg_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  stipple::SpgView view;
  const stipple::SpgResult r = stipple::spg_parse(data, size, &view);
  if (r.ok()) {
    stipple::DecodedModel model;
    std::string error;
    if (!stipple::decode_spg("fuzz.spg", data, size, model, error)) __builtin_trap();  // parse and decode must agree
  } else if (r.offset > size) {
    __builtin_trap();  // an error offset is always inside (or at the end of) the input
  }
  return 0;
}
