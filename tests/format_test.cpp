// The encoder's .spg files: every variant round-trips through the reference
// decoder, the fixtures of tests/portable/format_test.cpp are what the encoder
// writes, and the reference decoder names the byte of a hostile header.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/spg_format.h"
#include "platform/file_io.h"
#include "test_util.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/spg_model.h"

namespace stipple {
namespace {

std::vector<uint8_t> small_spg(bool normals = true, bool colors = false, bool octree = false, int version = kSpgVersion) {
  PointCloud cloud = test::sphere_cloud(600);
  if (colors)
    for (const Vec3& p : cloud.positions) cloud.colors.push_back((p + Vec3::Ones()) / 2);
  EncodeOptions o;
  o.normals = normals;
  o.tree.octree = octree;
  o.tree.leaf_size = 8;
  o.format_version = version;
  return test::encode(cloud, o);
}

void fix_crc(std::vector<uint8_t>& f) {
  const uint32_t c = crc32(f.data(), f.size() - 4);
  for (int i = 0; i < 4; ++i) f[f.size() - 4 + static_cast<size_t>(i)] = static_cast<uint8_t>(c >> (8 * i));
}

TEST(SpgFormat, RoundTripEveryVariant) {
  for (int variant = 0; variant < 4; ++variant) {
    const bool normals = variant != 1, colors = variant == 2, octree = variant == 3;
    const DecodedModel m = test::decode(small_spg(normals, colors, octree));
    EXPECT_EQ(m.nodes[0].point_count, 600u);
    EXPECT_EQ(m.header.has_normals(), normals);
    EXPECT_EQ(m.header.has_color(), colors);
  }
}

// STIPPLE_WRITE_FIXTURES=1 stipple_tests --gtest_filter=SpgFormat.Fixtures*
// rewrites them after a deliberate change of the encoder.
TEST(SpgFormat, FixturesAreTheEncodersOutput) {
  const struct {
    const char* name;
    bool normals, colors, octree;
    int version;
  } variants[] = {{"normals", true, false, false, kSpgVersion}, {"plain", false, false, false, kSpgVersion},
                  {"colour", true, true, false, kSpgVersion},   {"octree", true, false, true, kSpgVersion},
                  {"normals_v1", true, false, false, 1}};
  for (const auto& v : variants) {
    const std::string path = test::source_path(std::string("tests/data/sphere600_") + v.name + ".spg");
    const std::vector<uint8_t> f = small_spg(v.normals, v.colors, v.octree, v.version);
    std::string error;
    if (std::getenv("STIPPLE_WRITE_FIXTURES")) {
      ASSERT_TRUE(write_file_atomic(path, f, error)) << error;
    }
    std::vector<uint8_t> committed;
    ASSERT_TRUE(read_file(path, committed, error)) << error;
    EXPECT_TRUE(f == committed) << path << " is not what the encoder writes now";
  }
}

TEST(SpgFormat, ReferenceDecoderNamesTheByte) {
  std::vector<uint8_t> g = small_spg();
  g[8] = 3;  // tree arity
  fix_crc(g);
  DecodedModel m;
  std::string error;
  EXPECT_FALSE(decode_spg("hostile.spg", g.data(), g.size(), m, error));
  EXPECT_EQ(error.rfind("hostile.spg: byte 8", 0), 0u) << error;
}

}  // namespace
}  // namespace stipple
