// The cut table file (core/cut_table.h): bounds attached from a table give
// the cut of bounds built from the model, camera for camera; a table of
// another model, cone rule or version, a corrupt or cut-short one, and one
// whose nodes do not fit the model's tree are refused, naming the node and
// field. Runs on every target: the table's layout is the same there.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "core/cut_table.h"
#include "core/spg_writer.h"
#include "core/view_cut.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

using Model = test::ParsedModel;

const Model& bunny() {
  static const Model m("tests/golden/bunny_v2.spg");
  return m;
}

ModelTag tag(const Model& m) { return model_tag(m.file.data(), m.file.size()); }

// The table of a model's bounds, as `stipple encode` writes it.
struct Table {
  std::vector<uint64_t> storage;
  CutBounds built;
  std::vector<uint8_t> bytes;
  explicit Table(const Model& m, const ConeRule& cones = {}) : storage(CutBounds::bytes(m.view.header) / 8 + 1) {
    EXPECT_EQ(built.init(m.view, m.decoder, storage.data(), storage.size() * 8, cones), CutStatus::kOk);
    bytes.resize(cut_table_bytes(m.view.header.node_count));
    cut_table_header(tag(m), cones, built, bytes.data());
    std::memcpy(bytes.data() + kCutTableHeaderBytes, built.table(), bytes.size() - kCutTableHeaderBytes);
  }
};

// Node `node`'s byte `offset` of the table (36 bytes a node), and the
// nodes' CRC-32 fixed up so that the node checks are reached.
void poke(std::vector<uint8_t>& t, uint32_t node, size_t offset, const void* value, size_t size) {
  std::memcpy(t.data() + kCutTableHeaderBytes + 36 * size_t{node} + offset, value, size);
  store_u32le(t.data() + 60, crc32(t.data() + kCutTableHeaderBytes, t.size() - kCutTableHeaderBytes));
}

std::vector<uint32_t> sent(const ViewCut& c) {
  std::vector<uint32_t> out;
  for (uint32_t i = 0; i < c.sent_count(); ++i) out.push_back(index_of(c.sent()[i]));
  return out;
}

TEST(CutTable, AttachedBoundsGiveTheBuiltBoundsCut) {
  const Model& m = bunny();
  ASSERT_TRUE(m.view.header.has_normals());
  const Table t(m);
  EXPECT_EQ(t.bytes.size(), 64 + 36 * size_t{m.view.header.node_count});
  CutBounds attached;
  const CutTableResult r = cut_table_attach(t.bytes.data(), t.bytes.size(), m.view, tag(m), ConeRule{}, &attached);
  ASSERT_TRUE(r.ok()) << cut_table_error_text(r.error) << " node " << r.node << " " << r.field;
  EXPECT_EQ(attached.table(), t.bytes.data() + kCutTableHeaderBytes);  // mapped, not copied
  EXPECT_EQ(attached.node_count(), m.view.header.node_count);

  struct Over {
    std::vector<uint64_t> state, scratch_storage;
    CutScratch scratch;
    ViewCut cut;
    Over(const CutBounds& b, uint32_t n) : state(view_cut_state_bytes(n) / 8 + 1), scratch_storage(CutScratch::bytes(n) / 8 + 1) {
      scratch.init(scratch_storage.data(), scratch_storage.size() * 8);
      EXPECT_EQ(cut.init(b, state.data(), state.size() * 8, &scratch), CutStatus::kOk);
    }
  };
  const uint32_t n = m.view.header.node_count;
  Over a(t.built, n), b(attached, n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> yaw(0, 360), pitch(-80, 80), distance(0.4, 6);
  for (int i = 0; i < 40; ++i) {
    Camera c;
    ASSERT_TRUE(orbit_camera(test::orbit(m.decoder.extent_mu(), yaw(rng), pitch(rng), distance(rng)), 240, 320, &c));
    CutParams p;
    p.max_nodes = i % 3 == 0 ? 400 : 0xFFFFFFFFu;
    ASSERT_EQ(a.cut.update(c, p), CutStatus::kOk);
    ASSERT_EQ(b.cut.update(c, p), CutStatus::kOk);
    EXPECT_EQ(sent(a.cut), sent(b.cut)) << "camera " << i;
    EXPECT_EQ(a.cut.cut_count(), b.cut.cut_count()) << "camera " << i;
    for (uint32_t k = 0; k < a.cut.sent_count(); ++k)
      ASSERT_EQ(a.cut.points(a.cut.sent()[k]), b.cut.points(b.cut.sent()[k]));
  }
}

TEST(CutTable, AnotherModelsRulesOrVersionIsRefused) {
  const Model& m = bunny();
  const Table t(m);
  CutBounds out;
  const auto attach = [&](const std::vector<uint8_t>& bytes, const ModelTag& with, const ConeRule& cones = {}) {
    return cut_table_attach(bytes.data(), bytes.size(), m.view, with, cones, &out).error;
  };
  EXPECT_EQ(attach(t.bytes, tag(m)), CutTableError::kOk);

  std::vector<uint8_t> b = t.bytes;
  b.resize(63);
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kTruncated);
  b = t.bytes;
  b.pop_back();
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kTruncated);
  b = t.bytes;
  b.push_back(0);
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kTrailingBytes);
  b = t.bytes;
  b[0] = 'X';
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kBadMagic);
  b = t.bytes;
  b[8] = 2;  // version 2
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kBadVersion);
  b = t.bytes;
  b[40] = 1;  // a reserved byte
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kBadVersion);

  ModelTag other = tag(m);
  other.crc ^= 1;  // a re-encoded model of the same size
  EXPECT_EQ(attach(t.bytes, other), CutTableError::kOtherModel);
  other = tag(m);
  other.bytes += 1;
  EXPECT_EQ(attach(t.bytes, other), CutTableError::kOtherModel);

  ConeRule wider;
  wider.leaf_gamma_q8 = 512;
  EXPECT_EQ(attach(t.bytes, tag(m), wider), CutTableError::kOtherCones);
  const Table for_wider(m, wider);
  EXPECT_EQ(attach(for_wider.bytes, tag(m), wider), CutTableError::kOk);
  EXPECT_NE(for_wider.bytes, t.bytes);  // the cones differ

  b = t.bytes;
  b[kCutTableHeaderBytes + 5] ^= 0x40;  // a bit of node 0's centre
  EXPECT_EQ(attach(b, tag(m)), CutTableError::kBadChecksum);
  EXPECT_EQ(out.table(), nullptr);  // nothing attached after a refusal
}

TEST(CutTable, ANodeThatDoesNotFitTheTreeIsNamed) {
  const Model& m = bunny();
  const Table t(m);
  const uint32_t n = m.view.header.node_count;
  uint32_t leaf = 0, internal = 0;
  for (uint32_t i = n; i-- > 0;) (spg_child_count(m.view, i) ? internal : leaf) = i;
  // A leaf's count is checked first where its parent's sum is (the parent
  // comes first in the table), unless that sum saturates.
  uint32_t parent = 0;
  for (uint32_t i = 0, next = 1; i < n; next += spg_child_count(m.view, i), ++i)
    if (leaf >= next && leaf < next + spg_child_count(m.view, i)) parent = i;
  const uint8_t parent_points = t.bytes[kCutTableHeaderBytes + 36 * size_t{parent} + 35];
  struct Case {
    uint32_t node;  // the node changed
    size_t offset;
    int32_t value;
    size_t size;
    const char* field;
    uint32_t named;  // the node the refusal names
  } cases[] = {
      {internal, 34, 0, 1, "children", internal},  // an internal node claims none
      {leaf, 34, 2, 1, "children", leaf},          // a leaf claims two
      {internal, 20, static_cast<int32_t>(n), 4, "first_child", internal},  // children past the tree
      {3, 12, -1, 4, "radius", 3},
      {3, 12, (1 << 30) + 1, 4, "radius", 3},
      {3, 16, 0, 4, "subtree_radius", 3},  // smaller than its own radius
      {3, 30, -2, 2, "cone", 3},
      {3, 32, 1, 2, "padding", 3},
      {leaf, 35, 0, 1, "points", parent_points < 255 ? parent : leaf},  // a leaf's count is not the file's
      {internal, 35, 1, 1, "points", internal},  // not its children's sum
  };
  for (const Case& c : cases) {
    std::vector<uint8_t> b = t.bytes;
    poke(b, c.node, c.offset, &c.value, c.size);
    CutBounds out;
    const CutTableResult r = cut_table_attach(b.data(), b.size(), m.view, tag(m), ConeRule{}, &out);
    EXPECT_EQ(r.error, CutTableError::kBadNode) << c.field;
    EXPECT_EQ(r.node, c.named) << c.field;
    EXPECT_STREQ(r.field, c.field);
    EXPECT_EQ(out.table(), nullptr) << c.field;
  }
}

}  // namespace
}  // namespace stipple
