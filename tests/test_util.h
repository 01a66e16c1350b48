// Shared helpers for stipple's tests.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/node_format.h"
#include "core/spg_writer.h"
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

// The same model with every frame angle widened to 13-16 bits (docs/format.md
// §5 allows up to 16), each value scaled to the same angle: a valid .spg a
// client sized for the paper's 8-10-6 bits cannot hold as it is.
inline std::vector<uint8_t> widen_angles(const std::vector<uint8_t>& file) {
  SpgView view;
  EXPECT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
  const DecodedModel model = decode(file);
  SpgHeader wide = view.header;
  const int widths[6] = {14, 16, 13, 15, 16, 13};  // fp theta phi psi, fn theta phi psi
  const Field fields[6] = {Field::kFpTheta, Field::kFpPhi, Field::kFpPsi, Field::kFnTheta, Field::kFnPhi, Field::kFnPsi};
  for (int k = 0; k < 6; ++k) wide.layout.bits[static_cast<int>(fields[k])] = static_cast<uint8_t>(widths[k]);
  const size_t rb = static_cast<size_t>(wide.layout.record_bytes());
  std::vector<uint8_t> records(rb * view.header.node_count), child(view.header.node_count);
  std::vector<uint32_t> leaves;
  for (uint32_t i = 0; i < view.header.node_count; ++i) {
    NodeFields f = unpack_record(view.header.layout, view.records + size_t{i} * view.record_bytes);
    for (int k = 0; k < 6; ++k) {
      const int from = view.header.layout.bits[static_cast<int>(fields[k])], to = widths[k];
      const double q = f[fields[k]];
      // theta: q pi / (2^b - 1), poles exact; phi and psi: q 2pi / 2^b, q pi / 2^b.
      const bool theta = k % 3 == 0;
      f[fields[k]] = static_cast<uint16_t>(theta ? std::lround(q * ((1 << to) - 1) / ((1 << from) - 1)) : std::lround(q * (1 << (to - from))));
    }
    pack_record(wide.layout, f, records.data() + size_t{i} * rb);
    child[i] = static_cast<uint8_t>(spg_child_count(view, i));
    if (child[i] == 0) leaves.push_back(model.nodes[i].point_count);
  }
  const size_t value_bytes = spg_class_value_bytes(view.header.version);
  std::vector<uint32_t> tables[3];
  const uint8_t* t[3] = {view.sigma_p, view.sigma_n, view.sigma_c};
  const uint32_t per[3] = {3, 2, 3};
  for (int c = 0; c < 3; ++c)
    for (uint32_t i = 0; i < per[c] * view.header.class_count[c]; ++i)
      tables[c].push_back(value_bytes == 2 ? load_u16le(t[c] + 2 * i) : load_u32le(t[c] + 4 * i));
  const SpgContent content{wide, SpgClassTables{tables[0].data(), tables[1].data(), tables[2].data()}, child.data(),
                           leaves.data(), records.data()};
  std::vector<uint8_t> out(spg_write_bound(wide));
  size_t written = 0;
  EXPECT_EQ(spg_write(content, out.data(), out.size(), &written), SpgWriteStatus::kOk);
  out.resize(written);
  return out;
}

// The bundled bunny's scan, prepared as the encoder prepares it (normals
// from its faces, its frame), beside a golden file of it: what the
// pictures of the model are measured against (render_truth of `scan` in
// `model`'s box). `ok` once all of it read.
struct BunnyAndScan {
  PointCloud scan;
  ScanFrame frame;  // prepare_scan's
  std::vector<uint8_t> file;
  SpgView view;
  DecodedModel model;
  bool ok = false;
  explicit BunnyAndScan(const char* golden) : file(fixture(golden)) {
    std::string error;
    const bool read = read_point_cloud(source_path("data/bunny.ply"), scan, error);
    EXPECT_TRUE(read) << error;
    frame = prepare_scan(scan, EncodeOptions{});
    const bool parsed = spg_parse(file.data(), file.size(), &view).ok();
    EXPECT_TRUE(parsed) << golden;
    const bool decoded = decode_spg("bunny", file.data(), file.size(), model, error);
    EXPECT_TRUE(decoded) << error;
    ok = read && parsed && decoded;
  }
};

}  // namespace stipple::test
