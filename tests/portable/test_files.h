// Fixture files and small helpers for the portable suite (core and raster),
// which runs on the host and, cross-built, on every target under qemu-user:
// the standard library, core and raster only — no platform, no tools.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/camera.h"
#include "core/node_decoder.h"
#include "core/spg_format.h"

namespace stipple::test {

inline std::string source_path(const std::string& rel) { return std::string(STIPPLE_SOURCE_DIR) + "/" + rel; }

// The bytes of a committed file (path relative to the source tree); a
// failure fails the calling test.
inline std::vector<uint8_t> fixture(const std::string& rel) {
  std::vector<uint8_t> bytes;
  std::FILE* f = std::fopen(source_path(rel).c_str(), "rb");
  EXPECT_NE(f, nullptr) << source_path(rel);
  if (f == nullptr) return bytes;
  uint8_t chunk[65536];
  for (size_t n; (n = std::fread(chunk, 1, sizeof chunk, f)) > 0;) bytes.insert(bytes.end(), chunk, chunk + n);
  EXPECT_EQ(std::ferror(f), 0) << source_path(rel);
  std::fclose(f);
  return bytes;
}

// A committed .spg, parsed, with its fixed-point decoder.
struct ParsedModel {
  std::vector<uint8_t> file;
  SpgView view;
  std::vector<uint32_t> decoder_storage;
  NodeDecoder decoder;
  explicit ParsedModel(const char* rel) : file(fixture(rel)) {
    EXPECT_TRUE(spg_parse(file.data(), file.size(), &view).ok()) << rel;
    decoder_storage.resize(node_decoder_bytes(view.header) / 4 + 1);
    EXPECT_EQ(decoder.init(view, decoder_storage.data(), decoder_storage.size() * 4), DecodeStatus::kOk) << rel;
  }
};

// An orbit in degrees and model extents about the box's centre, as `stipple
// render --camera yaw,pitch,distance,fov` builds it (+y up).
inline OrbitView orbit(const int32_t extent_mu[3], double yaw, double pitch, double distance = 3, double fov = 35) {
  const auto angle = [](double degrees) {
    const double turns = degrees / 360.0 - std::floor(degrees / 360.0);
    return static_cast<uint32_t>(static_cast<uint64_t>(std::llround(turns * 4294967296.0)) & 0xFFFFFFFFu);
  };
  OrbitView o;
  for (int a = 0; a < 3; ++a) o.target_mu[a] = extent_mu[a] / 2;
  o.distance_mu = static_cast<int32_t>(std::llround(distance * 16777216.0));
  o.yaw = angle(yaw);
  o.pitch = angle(pitch);
  o.fov = angle(fov);
  return o;
}

}  // namespace stipple::test
