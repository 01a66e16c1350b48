// Fixture files for the core and raster suites, which run on the host and,
// cross-built, on every target under qemu-user: only the standard library
// and platform/file_io.h here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "platform/file_io.h"

namespace stipple::test {

inline std::string source_path(const std::string& rel) { return std::string(STIPPLE_SOURCE_DIR) + "/" + rel; }

// The bytes of a committed file (path relative to the source tree); a
// failure fails the calling test.
inline std::vector<uint8_t> fixture(const std::string& rel) {
  std::vector<uint8_t> bytes;
  std::string error;
  EXPECT_TRUE(read_file(source_path(rel), bytes, error)) << error;
  return bytes;
}

}  // namespace stipple::test
