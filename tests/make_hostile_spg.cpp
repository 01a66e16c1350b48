// Writes valid but hostile .spg files with core's writer, for the command
// line tests of memory bounds (tests/CMakeLists.txt):
//   leaf_claims_2p28.spg  one leaf claiming 2^28 original points (99 bytes):
//                         `sample --leaves` would reserve ~19 GB
//   tiny_records.spg      2,400,001 nodes of 1-byte records (3.9 MB): a
//                         decoded model would take ~830 MB
//
//   make_hostile_spg OUTPUT_DIR
#include <cstdio>
#include <string>
#include <vector>

#include "core/spg_writer.h"

namespace {

using namespace stipple;

// The narrowest layout the format allows: 1 bit for each field that must be
// present (position, position frame, sigma_p class): 7 bits, a 1-byte record.
SpgHeader narrow_header(uint32_t nodes, uint32_t leaves, uint32_t points, uint16_t depth) {
  SpgHeader h;
  h.version = kSpgVersion;
  h.tree_arity = 2;
  for (int f = 0; f <= static_cast<int>(Field::kSigmaP); ++f) h.layout.bits[f] = 1;
  h.node_count = nodes;
  h.leaf_count = leaves;
  h.point_count = points;
  h.depth = depth;
  for (int a = 0; a < 3; ++a) h.bbox_bits[3 + a] = 0x3F800000u;  // [0, 1]^3
  h.class_count[0] = 1;
  return h;
}

bool write(const std::string& path, const SpgContent& c) {
  std::vector<uint8_t> out(spg_write_bound(c.header));
  size_t n = 0;
  const SpgWriteStatus s = spg_write(c, out.data(), out.size(), &n);
  if (s != SpgWriteStatus::kOk) {
    std::fprintf(stderr, "make_hostile_spg: %s: %s\n", path.c_str(), spg_write_status_text(s));
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "wb");
  const bool ok = f && std::fwrite(out.data(), 1, n, f) == n;
  if (f) std::fclose(f);
  if (!ok) std::fprintf(stderr, "make_hostile_spg: cannot write %s\n", path.c_str());
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_hostile_spg OUTPUT_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  const uint32_t sigma[3] = {0xD800u, 0xD800u, 0xD800u};  // version-2 codes: 1/16 of the box (e = 27, m = 0)
  {
    const uint8_t child[1] = {0};
    const uint32_t points[1] = {1u << 28};
    const uint8_t record[1] = {0};
    if (!write(dir + "/leaf_claims_2p28.spg",
               SpgContent{narrow_header(1, 1, 1u << 28, 0), SpgClassTables{sigma, nullptr, nullptr}, child, points, record}))
      return 1;
  }
  {
    // A complete binary tree in heap order (node i's children are 2i+1, 2i+2:
    // breadth-first, siblings adjacent), one point per leaf.
    const uint32_t n = 2400001, leaves = (n + 1) / 2;
    std::vector<uint8_t> child(n, 0), records(n, 0);
    for (uint32_t i = 0; 2 * i + 2 < n; ++i) child[i] = 2;
    uint16_t depth = 0;
    while ((uint64_t{2} << depth) - 1 < n) ++depth;
    const std::vector<uint32_t> points(leaves, 1);
    if (!write(dir + "/tiny_records.spg", SpgContent{narrow_header(n, leaves, leaves, depth),
                                                       SpgClassTables{sigma, nullptr, nullptr}, child.data(),
                                                       points.data(), records.data()}))
      return 1;
  }
  return 0;
}
