// A model as every program opens it (tools/embedded/model_file.h): its cut
// table written once and then mapped, so that a local render holds what its
// cut and the client's arena need, not what the model's size does; the
// picture is the one of bounds built in memory; a table that is not the
// model's is said so and not used.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/cut_table.h"
#include "platform/file_io.h"
#include "test_util.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/model_file.h"

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

}  // namespace
}  // namespace stipple
