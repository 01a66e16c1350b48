// Runs a fuzz harness over the files named on the command line, so every
// build (not only clang's libFuzzer build) exercises the harnesses on seeds.
#include <cstddef>
#include <cstdio>
#include <vector>

#include "platform/file_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    std::vector<uint8_t> bytes;
    std::string error;
    if (!stipple::read_file(argv[i], bytes, error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
    // Every prefix too: the cheapest way to reach each truncation path.
    for (size_t n = 0; n <= bytes.size(); n += 1 + bytes.size() / 256) {
      std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<ptrdiff_t>(n));
      LLVMFuzzerTestOneInput(prefix.data(), prefix.size());
    }
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    std::printf("%s: ok\n", argv[i]);
  }
  return 0;
}
