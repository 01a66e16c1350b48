// A model as every program opens it (tools/embedded/model_file.h): its cut
// table written once and then mapped, so that a local render holds what its
// cut and the client's arena need, not what the model's size does; the
// picture is the one of bounds built in memory; a table that is not the
// model's is said so and not used.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/cut_table.h"
#include "core/spg_coded.h"
#include "core/spg_writer.h"
#include "platform/file_io.h"
#include "test_util.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/model_file.h"
#include "tools/encoder/coded_file.h"

namespace stipple {
namespace {

namespace fs = std::filesystem;

std::string model_path(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / "model_file";
  fs::create_directories(dir);
  const std::string path = (dir / name).string();
  fs::remove(path + ".cut");
  return path;
}

ClientConfig device() {
  ClientConfig c;
  c.raster.width = 240;
  c.raster.height = 320;
  return c;
}

TEST(ModelFile, ALocalRenderHoldsWhatItsCutNeedsNotTheModel) {
  struct Measured {
    uint32_t nodes, cut_nodes;
    size_t heap;  // the tables on the heap and the cut's storage
  };
  const CutRule rule{CutRule::kProjectedSize, 0, 32};
  const auto measure = [&](size_t points) {
    const std::string path = model_path("sphere_" + std::to_string(points) + ".spg");
    const std::vector<uint8_t> spg = test::encode(test::sphere_cloud(points));
    std::string error;
    EXPECT_TRUE(write_file_atomic(path, spg, error)) << error;
    bool written = false;
    EXPECT_TRUE(make_cut_table(path, ConeRule{}, error, &written)) << error;
    EXPECT_TRUE(written);
    EXPECT_TRUE(make_cut_table(path, ConeRule{}, error, &written)) << error;
    EXPECT_FALSE(written);  // up to date: left as it is

    ModelFile model;
    EXPECT_TRUE(model.open(path, ConeRule{}, error)) << error;
    EXPECT_TRUE(model.table_mapped()) << model.table_note();
    EXPECT_EQ(model.table_note(), "cut table " + path + ".cut mapped");
    FixedRender mapped, built;
    EXPECT_TRUE(render_fixed(model, device(), rule, ViewSpec{}, mapped, error)) << error;
    EXPECT_TRUE(render_fixed(model.view(), model.data(), device(), rule, ViewSpec{}, built, error)) << error;
    EXPECT_EQ(mapped.cut, built.cut);
    EXPECT_EQ(mapped.frame, built.frame);
    // Bounds built in memory cost 36 bytes a node of the tree; mapped, nothing.
    EXPECT_GE(built.cut_bytes, 36u * model.view().header.node_count);
    return Measured{model.view().header.node_count, mapped.cut_nodes, model.table_bytes() + mapped.cut_bytes};
  };
  const Measured small = measure(20000), large = measure(400000);
  std::printf("sphere: %u nodes, cut %u, %zu bytes; %u nodes, cut %u, %zu bytes\n", small.nodes, small.cut_nodes,
              small.heap, large.nodes, large.cut_nodes, large.heap);
  EXPECT_GT(large.nodes, 10 * small.nodes);
  // The decoder's class tables (fixed by the format's class counts), the
  // sent set (5 bytes a sent node at most) and an update's scratch (32
  // bytes a cut node, grown by half while short).
  for (const Measured& m : {small, large}) EXPECT_LE(m.heap, 160u * 1024 + 5 * 30000 + 48u * std::max(m.cut_nodes, 4096u));
  EXPECT_LT(large.heap, 36u * large.nodes);
}

TEST(ModelFile, ATableThatIsNotTheModelsIsSaidSoAndNotUsed) {
  const std::string a = model_path("a.spg"), b = model_path("b.spg");
  std::string error;
  ASSERT_TRUE(write_file_atomic(a, test::encode(test::sphere_cloud(3000)), error)) << error;
  ASSERT_TRUE(write_file_atomic(b, test::encode(test::sphere_cloud(3001)), error)) << error;
  ASSERT_TRUE(make_cut_table(b, ConeRule{}, error)) << error;

  ModelFile none;
  ASSERT_TRUE(none.open(a, ConeRule{}, error)) << error;
  EXPECT_FALSE(none.table_mapped());
  EXPECT_FALSE(none.table_refused());  // none there: nothing to warn about
  EXPECT_NE(none.table_note().find("no cut table"), std::string::npos) << none.table_note();

  fs::copy_file(b + ".cut", a + ".cut");  // b's table beside a
  ModelFile other;
  ASSERT_TRUE(other.open(a, ConeRule{}, error)) << error;
  EXPECT_TRUE(other.table_refused());
  EXPECT_EQ(other.table_note(), a + ".cut: made from another model (its size, CRC-32 or node count differ); "
                                    "the cut's bounds are built in memory");
  ConeRule wider;
  wider.leaf_gamma_q8 = 512;
  ModelFile rule;
  ASSERT_TRUE(rule.open(b, wider, error)) << error;
  EXPECT_EQ(rule.table_note(), b + ".cut: made for another cone rule (--leaf-cone); the cut's bounds are built in memory");

  // Either way the picture is the model's.
  FixedRender from_other, from_none;
  const CutRule cut{CutRule::kProjectedSize, 0, 32};
  ASSERT_TRUE(render_fixed(other, device(), cut, ViewSpec{}, from_other, error)) << error;
  ASSERT_TRUE(render_fixed(none, device(), cut, ViewSpec{}, from_none, error)) << error;
  EXPECT_EQ(from_other.frame, from_none.frame);

  // A table cut short is named as such; make_cut_table writes it again.
  fs::resize_file(b + ".cut", 100);
  ModelFile shortened;
  ASSERT_TRUE(shortened.open(b, ConeRule{}, error)) << error;
  EXPECT_EQ(shortened.table_note(), b + ".cut: truncated; the cut's bounds are built in memory");
  bool written = false;
  ASSERT_TRUE(make_cut_table(b, ConeRule{}, error, &written)) << error;
  EXPECT_TRUE(written);
  ModelFile again;
  ASSERT_TRUE(again.open(b, ConeRule{}, error)) << error;
  EXPECT_TRUE(again.table_mapped());
}


// A version 3 file (coded records) opens as the version 2 file it was made
// from: the same bytes in memory, the same frame, the cut table made from
// either serving both; damage is named with the file and its byte.
TEST(ModelFile, AVersionThreeFileOpensAsItsVersionTwo) {
  std::string error;
  const std::vector<uint8_t> v2 = test::fixture("tests/golden/bunny_v2.spg");
  std::vector<uint8_t> v3;
  CodedFileReport report;
  ASSERT_TRUE(write_coded_spg(v2.data(), v2.size(), v3, report, error)) << error;
  EXPECT_EQ(v3, test::fixture("tests/golden/bunny_v3.spg"));  // the golden bitstream, as regenerate.sh makes it
  EXPECT_EQ(report.file_bytes, v3.size());
  EXPECT_EQ(report.records_bytes, 6913u * 13u);
  EXPECT_LT(report.coded_bytes * 100, report.records_bytes * 66);
  const std::string p2 = model_path("bunny_v2.spg"), p3 = model_path("bunny_v3.spg");
  ASSERT_TRUE(write_file_atomic(p2, v2, error) && write_file_atomic(p3, v3, error)) << error;
  ModelFile a, b;
  ASSERT_TRUE(a.open(p2, ConeRule{}, error)) << error;
  ASSERT_TRUE(b.open(p3, ConeRule{}, error)) << error;
  ASSERT_EQ(b.file_bytes(), v2.size());
  EXPECT_TRUE(std::equal(v2.begin(), v2.end(), b.data()));
  const CutRule rule{CutRule::kProjectedSize, 0, 32};
  FixedRender ra, rb;
  ASSERT_TRUE(render_fixed(a, device(), rule, ViewSpec{}, ra, error)) << error;
  ASSERT_TRUE(render_fixed(b, device(), rule, ViewSpec{}, rb, error)) << error;
  EXPECT_EQ(ra.frame, rb.frame);
  EXPECT_GT(ra.cut.size(), 500u);
  // read_spg_file (every command's reader) expands it too.
  std::vector<uint8_t> read;
  ASSERT_TRUE(read_spg_file(p3, read, error)) << error;
  EXPECT_EQ(read, v2);

  // A cut's records coded as version 3 codes nodes (what stipple rd and
  // levels give beside the plain records): the bunny's 3,457 leaves in
  // under 80 % of their 13 bytes each, tables included; one node costs its
  // tables.
  {
    SpgView plain;
    ASSERT_TRUE(spg_parse(v2.data(), v2.size(), &plain).ok());
    std::vector<uint32_t> leaves;
    for (uint32_t i = 0; i < plain.header.node_count; ++i)
      if (spg_child_count(plain, i) == 0) leaves.push_back(i);
    ASSERT_EQ(leaves.size(), 3457u);
    const size_t leaf_bytes = coded_cut_bytes(plain, leaves);
    EXPECT_LT(leaf_bytes * 100, leaves.size() * 13 * 80) << leaf_bytes;
    EXPECT_GT(coded_cut_bytes(plain, {0}), 13u);
  }

  // A byte of the batch changed (the CRC made right): refused by the coder
  // at the batch's byte, or it would be another model. Then the CRC's own.
  SpgView view;
  SpgCodedParts parts;
  ASSERT_TRUE(spg_parse_coded(v3.data(), v3.size(), &view, &parts).ok());
  const size_t batch_at = parts.records_offset + 8 + parts.tables_bytes;
  std::vector<uint8_t> bad = v3;
  bad[batch_at + 4 + 4 + 100] ^= 0x5A;
  store_u32le(bad.data() + bad.size() - 4, crc32(bad.data(), bad.size() - 4));
  ASSERT_TRUE(write_file_atomic(p3, bad, error)) << error;
  ModelFile c;
  EXPECT_FALSE(c.open(p3, ConeRule{}, error));
  EXPECT_EQ(error, p3 + ": byte " + std::to_string(batch_at) + ": coded records do not decode (version 3)");
  bad[bad.size() - 1] ^= 1;
  ASSERT_TRUE(write_file_atomic(p3, bad, error)) << error;
  EXPECT_FALSE(read_spg_file(p3, read, error));
  EXPECT_EQ(error, p3 + ": byte " + std::to_string(bad.size() - 4) + ": CRC-32 mismatch (file corrupted)");
}

// Every fixture's kind of tree and record (normals, none, colour, an
// octree) codes and expands exactly (600 points: the code tables' 1.5 KB
// outweigh what coding saves, docs/format.md §5); version 1 (float32
// tables) is not coded.
TEST(ModelFile, EveryKindOfModelCodesExactly) {
  for (const char* name : {"normals", "plain", "colour", "octree"}) {
    const std::vector<uint8_t> v2 = test::fixture(std::string("tests/data/sphere600_") + name + ".spg");
    std::vector<uint8_t> v3;
    CodedFileReport report;
    std::string error;
    ASSERT_TRUE(write_coded_spg(v2.data(), v2.size(), v3, report, error)) << name << ": " << error;
    std::vector<uint8_t> image = v3;
    ASSERT_TRUE(expand_coded_spg(image, name, error)) << name << ": " << error;
    EXPECT_EQ(image, v2) << name;
  }
  const std::vector<uint8_t> v1 = test::fixture("tests/data/sphere600_normals_v1.spg");
  std::vector<uint8_t> v3;
  CodedFileReport report;
  std::string error;
  EXPECT_FALSE(write_coded_spg(v1.data(), v1.size(), v3, report, error));
  EXPECT_EQ(error, "version 3: codes version 2 files (this is version 1)");
}

}  // namespace
}  // namespace stipple
