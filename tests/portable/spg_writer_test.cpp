// The .spg writer against the reader: every committed file, taken apart by
// spg_parse and written again, comes back byte for byte; the startup message
// is the file's prefix; a short buffer, and content the reader would refuse,
// are refused with their status and nothing is claimed written.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

// What spg_write takes, recovered from a parsed file.
struct Parts {
  SpgView view;
  std::vector<uint32_t> tables[3];
  std::vector<uint8_t> child_counts;
  std::vector<uint32_t> leaf_points;
  std::vector<uint8_t> records;
  SpgContent content() const {
    return SpgContent{view.header, SpgClassTables{tables[0].data(), tables[1].data(), tables[2].data()},
                      child_counts.data(), leaf_points.data(), records.data()};
  }
};

Parts take_apart(const std::vector<uint8_t>& file) {
  Parts p;
  EXPECT_TRUE(spg_parse(file.data(), file.size(), &p.view).ok());
  const SpgHeader& h = p.view.header;
  const uint8_t* tables[3] = {p.view.sigma_p, p.view.sigma_n, p.view.sigma_c};
  const uint32_t per_class[3] = {3, 2, 3};
  for (int c = 0; c < 3; ++c)
    for (uint32_t i = 0; i < per_class[c] * h.class_count[c]; ++i)
      p.tables[c].push_back(h.version == 1 ? load_u32le(tables[c] + 4 * i) : load_u16le(tables[c] + 2 * i));
  for (uint32_t i = 0; i < h.node_count; ++i) p.child_counts.push_back(static_cast<uint8_t>(spg_child_count(p.view, i)));
  const uint8_t* at = p.view.leaf_counts;
  for (uint32_t i = 0; i < h.leaf_count; ++i) {
    uint32_t v = 0;
    for (int shift = 0;; shift += 7) {
      const uint8_t b = *at++;
      v |= static_cast<uint32_t>(b & 0x7F) << shift;
      if (!(b & 0x80)) break;
    }
    p.leaf_points.push_back(v);
  }
  p.records.assign(p.view.records, p.view.records + size_t{h.node_count} * p.view.record_bytes);
  return p;
}

const char* const kFiles[] = {"tests/golden/bunny_v1.spg", "tests/golden/bunny_v2.spg",
                              "tests/data/sphere600_normals_v1.spg", "tests/data/sphere600_normals.spg",
                              "tests/data/sphere600_plain.spg", "tests/data/sphere600_colour.spg",
                              "tests/data/sphere600_octree.spg"};

TEST(SpgWriter, RewritesEveryCommittedFileByteForByte) {
  for (const char* name : kFiles) {
    const std::vector<uint8_t> file = test::fixture(name);
    const Parts p = take_apart(file);
    const size_t bound = spg_write_bound(p.view.header);
    ASSERT_GE(bound, file.size()) << name;
    std::vector<uint8_t> out(bound, 0xAA);
    size_t written = 0;
    ASSERT_EQ(spg_write(p.content(), out.data(), out.size(), &written), SpgWriteStatus::kOk) << name;
    out.resize(written);
    EXPECT_EQ(out, file) << name;
    // The startup message alone: the file's prefix, spg_startup_bytes long.
    std::vector<uint8_t> startup(spg_startup_bytes(p.view.header.version, p.view.header.class_count));
    ASSERT_EQ(spg_write_startup(p.view.header, p.content().classes, startup.data(), startup.size(), &written),
              SpgWriteStatus::kOk);
    EXPECT_EQ(written, startup.size());
    EXPECT_TRUE(std::equal(startup.begin(), startup.end(), file.begin())) << name;
    EXPECT_EQ(static_cast<size_t>(p.view.topology - file.data()), startup.size()) << name;
  }
}

TEST(SpgWriter, ShortBuffersAreRefused) {
  const std::vector<uint8_t> file = test::fixture("tests/data/sphere600_colour.spg");
  const Parts p = take_apart(file);
  std::vector<uint8_t> out(file.size());
  for (size_t capacity = 0; capacity < file.size(); capacity += 1 + capacity / 7) {
    size_t written = 12345;
    EXPECT_EQ(spg_write(p.content(), out.data(), capacity, &written), SpgWriteStatus::kOutputTooSmall) << capacity;
    EXPECT_EQ(written, 12345u);
  }
  size_t written = 0;
  EXPECT_EQ(spg_write_startup(p.view.header, p.content().classes, out.data(), 75, &written),
            SpgWriteStatus::kOutputTooSmall);
}

TEST(SpgWriter, ContentTheReaderWouldRefuseIsRefused) {
  const std::vector<uint8_t> file = test::fixture("tests/data/sphere600_normals.spg");
  std::vector<uint8_t> out(file.size() + 64);
  size_t written = 0;
  const auto write = [&](const Parts& p) { return spg_write(p.content(), out.data(), out.size(), &written); };
  {
    Parts p = take_apart(file);
    p.child_counts[0] = 3;  // a binary tree
    EXPECT_EQ(write(p), SpgWriteStatus::kBadTree);
  }
  {
    Parts p = take_apart(file);
    p.child_counts[0] = 0;  // the root a leaf: one leaf too many, orphans below
    EXPECT_EQ(write(p), SpgWriteStatus::kBadTree);
  }
  {
    Parts p = take_apart(file);
    p.leaf_points[3] = 0;
    EXPECT_EQ(write(p), SpgWriteStatus::kBadLeafCount);
  }
  {
    Parts p = take_apart(file);
    ++p.leaf_points[3];  // no longer sums to the point count
    EXPECT_EQ(write(p), SpgWriteStatus::kBadLeafCount);
  }
  {
    Parts p = take_apart(file);
    NodeFields f = unpack_record(p.view.header.layout, p.records.data());
    f[Field::kSigmaP] = p.view.header.class_count[0];
    pack_record(p.view.header.layout, f, p.records.data());
    EXPECT_EQ(write(p), SpgWriteStatus::kBadRecord);
  }
  {
    Parts p = take_apart(file);
    p.tables[0][1] = 0x10000u;  // a version-2 code beyond 16 bits
    EXPECT_EQ(write(p), SpgWriteStatus::kBadHeader);
  }
  {
    const std::vector<uint8_t> v1 = test::fixture("tests/data/sphere600_normals_v1.spg");
    std::vector<uint8_t> out1(v1.size() + 64);
    const auto write1 = [&](const Parts& p) { return spg_write(p.content(), out1.data(), out1.size(), &written); };
    Parts p = take_apart(v1);
    ASSERT_EQ(write1(p), SpgWriteStatus::kOk);
    p.tables[0][1] = 0x7FC00000u;  // a NaN sigma in version 1's float32 table
    EXPECT_EQ(write1(p), SpgWriteStatus::kBadHeader);
    p.tables[0][1] = 0x3D800000u;
    p.view.header.version = 3;  // a version the reader does not know
    EXPECT_EQ(write1(p), SpgWriteStatus::kBadHeader);
  }
  {
    Parts p = take_apart(file);
    p.view.header.depth = 99;
    EXPECT_EQ(write(p), SpgWriteStatus::kBadTree);
  }
  // A view hint survives the round trip.
  Parts p = take_apart(file);
  p.view.header.view_hint = SpgViewHint{SpgAxis::kNegY, SpgAxis::kNegZ, true};
  ASSERT_EQ(write(p), SpgWriteStatus::kOk);
  SpgView back;
  ASSERT_TRUE(spg_parse(out.data(), written, &back).ok());
  EXPECT_EQ(back.header.view_hint.up, SpgAxis::kNegY);
  EXPECT_EQ(back.header.view_hint.sensor_side, SpgAxis::kNegZ);
  EXPECT_TRUE(back.header.view_hint.sensor_at_origin);
}

}  // namespace
}  // namespace stipple
