// PLY and text reader: every encoding, every malformed case named in the issue.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }

template <class T>
void put(std::vector<uint8_t>& out, T v, bool big_endian) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}

bool parse(const std::vector<uint8_t>& data, PointCloud& cloud, std::string& error) {
  return parse_point_cloud("scan.ply", data.data(), data.size(), cloud, error);
}

// Two vertices with double coordinates, float normals, uchar colours, one quad face.
std::vector<uint8_t> binary_ply(bool big_endian) {
  std::string header = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                       " 1.0\ncomment test\nelement vertex 4\nproperty double x\nproperty double y\n"
                       "property double z\nproperty float nx\nproperty float ny\nproperty float nz\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                       "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::vector<uint8_t> out = bytes(header);
  const double xyz[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}};
  for (int i = 0; i < 4; ++i) {
    for (double v : xyz[i]) put(out, v, big_endian);
    put(out, 0.0f, big_endian);
    put(out, 0.0f, big_endian);
    put(out, 2.0f, big_endian);  // normalised on read
    out.push_back(255);
    out.push_back(0);
    out.push_back(51);
  }
  out.push_back(4);
  for (int32_t i = 0; i < 4; ++i) put(out, i, big_endian);
  return out;
}

TEST(Ply, BinaryLittleAndBigEndianAgree) {
  for (bool be : {false, true}) {
    PointCloud c;
    std::string error;
    ASSERT_TRUE(parse(binary_ply(be), c, error)) << error;
    ASSERT_EQ(c.size(), 4u);
    EXPECT_EQ(c.positions[3], Vec3(0, 1, 0.5));
    ASSERT_TRUE(c.has_normals());
    EXPECT_EQ(c.normals[0], Vec3(0, 0, 1));
    ASSERT_TRUE(c.has_colors());
    EXPECT_DOUBLE_EQ(c.colors[0][0], 1.0);
    EXPECT_DOUBLE_EQ(c.colors[0][2], 0.2);
    ASSERT_EQ(c.triangles.size(), 2u);  // quad fan-triangulated
    EXPECT_EQ(c.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
  }
}

TEST(Ply, AsciiWithUshortAndDiffuseColours) {
  PointCloud c;
  std::string error;
  ASSERT_TRUE(parse(bytes("ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float x\r\nproperty float y\r\n"
                          "property float z\r\nproperty ushort diffuse_red\r\nproperty ushort diffuse_green\r\n"
                          "property ushort diffuse_blue\r\nend_header\r\n1 2 3 65535 0 0\r\n-1e-3 4.5 6 0 65535 0\r\n"),
                    c, error))
      << error;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Vec3(-1e-3, 4.5, 6));
  EXPECT_DOUBLE_EQ(c.colors[0][0], 1.0);
  EXPECT_DOUBLE_EQ(c.colors[1][1], 1.0);
  EXPECT_FALSE(c.has_normals());
}

TEST(Ply, FloatColoursAndSkippedElements) {
  PointCloud c;
  std::string error;
  ASSERT_TRUE(parse(bytes("ply\nformat ascii 1.0\nelement camera 1\nproperty float fov\nelement vertex 1\n"
                          "property float x\nproperty float y\nproperty float z\nproperty float red\n"
                          "property float green\nproperty float blue\nproperty list uchar int extra\n"
                          "end_header\n0.5\n1 2 3 0.25 0.5 2.0 2 7 8\n"),
                    c, error))
      << error;
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c.colors[0][0], 0.25);
  EXPECT_DOUBLE_EQ(c.colors[0][2], 1.0);  // clamped
}

TEST(Ply, PlainText) {
  PointCloud c;
  std::string error;
  const std::string text = "# comment\n1 2 3 0 0 1 255 0 0\n4,5,6, 0,1,0, 0,255,0 # trailing\n\n";
  ASSERT_TRUE(parse_point_cloud("pts.xyz", reinterpret_cast<const uint8_t*>(text.data()), text.size(), c, error))
      << error;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Vec3(4, 5, 6));
  EXPECT_EQ(c.normals[1], Vec3(0, 1, 0));
  EXPECT_DOUBLE_EQ(c.colors[1][1], 1.0);
}

struct BadCase {
  const char* name;
  std::string data;
  const char* message;  // must appear in the error
};

// A float32 scan 1e7 from the origin: its points collapse onto a lattice of
// whole units, and most become duplicates. The reader says so (and why);
// an ordinary scan gets no warning.
// Repeats are counted exactly, -0 and +0 as one position, on both sides of
// the size where the keys are sorted in two halves on two threads.
TEST(Ply, CountsRepeatedPositionsExactly) {
  for (const size_t n : {size_t{1000}, size_t{1} << 21}) {
    std::vector<Vec3> points;
    points.reserve(n);
    for (size_t i = 0; i < n; ++i) {
      const double v = static_cast<double>(i / 3);  // each position three times
      points.push_back(Vec3(v, i % 3 == 1 ? -0.0 : 0.0, 2.5));
    }
    EXPECT_EQ(count_duplicate_positions(points), n - (n + 2) / 3) << n;
  }
}

TEST(Ply, WarnsWhenPointsCollapseOntoOneValue) {
  std::string text, spread;
  for (int i = 0; i < 2000; ++i) {
    const float x = static_cast<float>(1e7 + 0.001 * (i % 50)), y = static_cast<float>(1e7 + 0.001 * (i / 50));
    text += std::to_string(x) + " " + std::to_string(y) + " 3.5\n";
    spread += std::to_string(0.001 * (i % 50)) + " " + std::to_string(0.001 * (i / 50)) + " 3.5\n";
  }
  PointCloud cloud;
  std::string error;
  ASSERT_TRUE(parse_point_cloud("far.xyz", reinterpret_cast<const uint8_t*>(text.data()), text.size(), cloud, error)) << error;
  ASSERT_EQ(cloud.warnings.size(), 1u);
  EXPECT_NE(cloud.warnings[0].find("far.xyz: 1999 of 2000 points (100.0 %) repeat another point's position exactly"),
            std::string::npos) << cloud.warnings[0];
  EXPECT_NE(cloud.warnings[0].find("far from the origin"), std::string::npos) << cloud.warnings[0];
  PointCloud near;
  ASSERT_TRUE(parse_point_cloud("near.xyz", reinterpret_cast<const uint8_t*>(spread.data()), spread.size(), near, error));
  EXPECT_TRUE(near.warnings.empty());
}

TEST(Ply, MalformedInputsGiveClearErrors) {
  const std::string hdr = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  std::string nan_bin = bin;
  for (float v : {0.f, 1.f, 2.f, 3.f, std::numeric_limits<float>::quiet_NaN(), 5.f}) {
    char b[4];
    std::memcpy(b, &v, 4);
    nan_bin.append(b, 4);
  }
  const BadCase cases[] = {
      {"no magic: read as text", "plx\n", "line 1: a header line ('plx') names no x, y and z columns"},
      {"no end_header", "ply\nformat ascii 1.0\nelement vertex 1\n", "no end_header"},
      {"unknown type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
       "header line 4: unknown property type 'float128'"},
      {"unknown format", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format"},
      {"no xyz", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n", "lacks scalar x, y and z"},
      {"truncated ascii", hdr + "1 2 3\n4 5" + std::string(10, ' '), "vertex 1, property 'z': file is truncated"},
      {"ascii count too large", hdr + "1 2 3\n", "claims 2 items, more than the 6 bytes after the header can hold"},
      {"bad number", hdr + "1 2 3\n4 5 six\n", "vertex 1, property 'z': malformed number"},
      {"nan ascii", hdr + "1 2 3\nnan 5 6\n", "vertex 1: non-finite coordinate"},
      {"inf ascii", hdr + "1 2 3\n4 inf 6\n", "vertex 1: non-finite coordinate"},
      {"nan binary", nan_bin, "vertex 1: non-finite coordinate"},
      {"truncated binary", bin + std::string(20, '\0'), "claims 2 items, more than the 20 bytes after the header can hold"},
      {"trailing bytes", bin + std::string(28, '\0'), "4 unexpected bytes after the last element"},
      {"4 billion points",
       "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n" + std::string(64, '\0'),
       "claims 4000000000 items"},
      {"face index out of range",
       hdr.substr(0, hdr.size() - 11) + "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n4 5 6\n3 0 1 7\n",
       "face 0, property 'vertex_indices': vertex index 7 out of range"},
      {"huge list", hdr.substr(0, hdr.size() - 11) + "element face 1\nproperty list uint int vertex_indices\nend_header\n1 2 3\n4 5 6\n4000000000 1\n",
       "list length 4000000000 is invalid"},
      {"text columns", "1 2 3\n4 5\n", "line 2: expected 3 columns, got 2"},
      {"text nan", "1 2 nan\n", "line 1: non-finite value"},
  };
  for (const BadCase& bad : cases) {
    PointCloud c;
    std::string error;
    EXPECT_FALSE(parse(bytes(bad.data), c, error)) << bad.name;
    EXPECT_NE(error.find(bad.message), std::string::npos) << bad.name << ": " << error;
    EXPECT_EQ(error.rfind("scan.ply: ", 0), 0u) << bad.name << ": error must name the file: " << error;
  }
}

TEST(Ply, EveryTruncatedPrefixFailsCleanly) {
  const std::vector<uint8_t> good = binary_ply(false);
  for (size_t n = 0; n < good.size(); ++n) {
    std::vector<uint8_t> prefix(good.begin(), good.begin() + static_cast<ptrdiff_t>(n));  // exact-size buffer for ASan
    PointCloud c;
    std::string error;
    EXPECT_FALSE(parse(prefix, c, error)) << "prefix " << n;
    EXPECT_FALSE(error.empty());
  }
}

TEST(Ply, WriteThenReadRoundTrip) {
  PointCloud c;
  c.positions = {Vec3(1, 2, 3), Vec3(-4, 5.5, 6)};
  c.normals = {Vec3(0, 0, 1), Vec3(1, 0, 0)};
  c.colors = {Vec3(1, 0, 0), Vec3(0, 0.2, 1)};
  const std::string path = testing::TempDir() + "roundtrip.ply";
  std::string error;
  ASSERT_TRUE(write_ply(path, c, error)) << error;
  PointCloud back;
  ASSERT_TRUE(read_point_cloud(path, back, error)) << error;
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.positions[1], c.positions[1]);
  EXPECT_EQ(back.normals[1], c.normals[1]);
  EXPECT_DOUBLE_EQ(back.colors[1][1], 51.0 / 255.0);
}

}  // namespace
}  // namespace stipple
