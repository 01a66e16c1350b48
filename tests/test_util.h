// Shared helpers for stipple's tests.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tools/encoder/encoder.h"
#include "tools/scan/point_cloud.h"
#include "tools/scan/ply_io.h"
#include "tools/reference/spg_model.h"
#include "tests/portable/test_files.h"

namespace stipple::test {

// Points of an anisotropic Gaussian with the given sigmas and frame.
inline std::vector<Vec3> gaussian_points(size_t n, const Vec3& mean, const Eigen::Matrix3d& frame, const Vec3& sigma,
                                         uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> out;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 g(normal(rng), normal(rng), normal(rng));
    out.push_back(mean + frame * sigma.cwiseProduct(g));
  }
  return out;
}

// Points on a sphere (a surface with outward normals), deterministic.
inline PointCloud sphere_cloud(size_t n, double radius = 1.0, bool with_normals = true) {
  PointCloud c;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
    const double r = std::sqrt(1.0 - z * z);
    const Vec3 p(r * std::cos(golden * static_cast<double>(i)), r * std::sin(golden * static_cast<double>(i)), z);
    c.positions.push_back(radius * p);
    if (with_normals) c.normals.push_back(p);
  }
  return c;
}

// Encodes a copy of `cloud`; a failure fails the calling test.
inline std::vector<uint8_t> encode(PointCloud cloud, const EncodeOptions& options = {}, EncodeReport* report = nullptr) {
  std::vector<uint8_t> spg;
  EncodeReport r;
  std::string error;
  EXPECT_TRUE(encode_cloud(cloud, options, spg, r, error)) << error;
  if (report) *report = r;
  return spg;
}

// Decodes `spg` with the reference decoder; a failure fails the calling test.
inline DecodedModel decode(const std::vector<uint8_t>& spg) {
  DecodedModel m;
  std::string error;
  EXPECT_TRUE(decode_spg("test.spg", spg.data(), spg.size(), m, error)) << error;
  return m;
}

inline std::string shared_data(const std::string& name) { return std::string(STIPPLE_SHARED_DATA) + "/" + name; }

}  // namespace stipple::test
