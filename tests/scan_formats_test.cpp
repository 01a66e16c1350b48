// PCD and LAS readers and the text reader's guesses: every encoding, the
// values exact, each hostile header refused naming its field, every
// truncated prefix refused without a crash.
#include <gtest/gtest.h>

#include <lzf.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "tools/scan/las_io.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }
template <class T>
void put(std::vector<uint8_t>& out, T v) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T));
}
bool parse(const std::string& name, const std::vector<uint8_t>& data, PointCloud& cloud, std::string& error) {
  return parse_point_cloud(name, data.data(), data.size(), cloud, error);
}
bool any_warning(const PointCloud& c, const std::string& text) {
  for (const std::string& w : c.warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

// Three points of x y z (float), normal_x..z (float), rgb (PCL's packed float),
// an intensity the reader skips (count 2); the middle one missing (NaN), as an
// organized cloud of 3 x 1 marks it.
const float kXyz[3][3] = {{1.5f, -2.25f, 3}, {NAN, NAN, NAN}, {-4, 5.5f, 0.125f}};
const float kNormal[3][3] = {{0, 0, 1}, {0, 1, 0}, {NAN, NAN, NAN}};
const uint32_t kRgb[3] = {0x00FF8000u, 0x0000FF00u, 0x00102030u};

std::string pcd_header(const std::string& data, const std::string& viewpoint = "0 0 0 1 0 0 0") {
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z normal_x normal_y normal_z rgb intensity\n"
         "SIZE 4 4 4 4 4 4 4 2\nTYPE F F F F F F F U\nCOUNT 1 1 1 1 1 1 1 2\nWIDTH 3\nHEIGHT 1\nVIEWPOINT " + viewpoint +
         "\nPOINTS 3\nDATA " + data + "\n";
}

std::vector<uint8_t> pcd(const std::string& data, const std::string& viewpoint = "0 0 0 1 0 0 0") {
  std::vector<uint8_t> out = bytes(pcd_header(data, viewpoint));
  if (data == "ascii") {
    std::string body;
    char line[256];
    for (int i = 0; i < 3; ++i) {
      float rgb;
      std::memcpy(&rgb, &kRgb[i], 4);
      std::snprintf(line, sizeof line, "%.9g %.9g %.9g %.9g %.9g %.9g %.9g 7 8\n", kXyz[i][0], kXyz[i][1], kXyz[i][2],
                    kNormal[i][0], kNormal[i][1], kNormal[i][2], rgb);
      body += line;
    }
    out.insert(out.end(), body.begin(), body.end());
    return out;
  }
  // Records packed field after field (binary), or fields one after another (compressed).
  std::vector<uint8_t> aos, soa;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) put(aos, kXyz[i][k]);
    for (int k = 0; k < 3; ++k) put(aos, kNormal[i][k]);
    put(aos, kRgb[i]);
    put(aos, uint16_t{7});
    put(aos, uint16_t{8});
  }
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) put(soa, kXyz[i][k]);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) put(soa, kNormal[i][k]);
  for (int i = 0; i < 3; ++i) put(soa, kRgb[i]);
  for (int i = 0; i < 3; ++i) {
    put(soa, uint16_t{7});
    put(soa, uint16_t{8});
  }
  if (data == "binary") {
    out.insert(out.end(), aos.begin(), aos.end());
  } else {
    std::vector<uint8_t> packed(soa.size() + 64);
    const unsigned n = lzf_compress(soa.data(), static_cast<unsigned>(soa.size()), packed.data(), static_cast<unsigned>(packed.size()));
    EXPECT_GT(n, 0u);
    put(out, static_cast<uint32_t>(n));
    put(out, static_cast<uint32_t>(soa.size()));
    out.insert(out.end(), packed.begin(), packed.begin() + n);
  }
  return out;
}

TEST(Pcd, AsciiBinaryAndCompressedReadTheSamePoints) {
  for (const char* data : {"ascii", "binary", "binary_compressed"}) {
    PointCloud c;
    std::string error;
    ASSERT_TRUE(parse("scan.pcd", pcd(data), c, error)) << data << ": " << error;
    ASSERT_EQ(c.size(), 2u) << data;  // the NaN point dropped
    EXPECT_TRUE(any_warning(c, "1 of 3 points have NaN")) << data;
    EXPECT_EQ(c.positions[0], Vec3(1.5, -2.25, 3)) << data;
    EXPECT_EQ(c.positions[1], Vec3(-4, 5.5, 0.125)) << data;
    ASSERT_TRUE(c.has_normals());
    EXPECT_EQ(c.normals[0], Vec3(0, 0, 1));
    EXPECT_EQ(c.normals[1], Vec3::Zero());  // PCL's NaN normal: kept without one
    EXPECT_TRUE(any_warning(c, "1 points have NaN or zero normals"));
    ASSERT_TRUE(c.has_colors());
    EXPECT_EQ(c.colors[0], Vec3(255, 128, 0) / 255.0);
    EXPECT_EQ(c.colors[1], Vec3(16, 32, 48) / 255.0);
    EXPECT_FALSE(c.has_viewpoint);  // PCL's default: the origin
  }
}

TEST(Pcd, CommentsBeforeTheHeaderAreAPcdStill) {
  // Writers other than PCL put their own comment first, or none at all.
  for (const std::string& first : {std::string("# written by a scanner's export\n# second comment\n"), std::string()}) {
    std::string text(reinterpret_cast<const char*>(pcd("ascii").data()), pcd("ascii").size());
    text.replace(0, text.find('\n') + 1, first);
    PointCloud c;
    std::string error;
    ASSERT_TRUE(parse("scan.pcd", bytes(text), c, error)) << error;
    ASSERT_EQ(c.size(), 2u);  // the NaN point dropped, as from PCL's own header
    EXPECT_EQ(c.positions[1], Vec3(-4, 5.5, 0.125));
    ASSERT_TRUE(c.has_colors());
  }
}

TEST(Pcd, AViewpointOrientsTheScan) {
  PointCloud c;
  std::string error;
  ASSERT_TRUE(parse("scan.pcd", pcd("binary", "10 -2 0.5 1 0 0 0"), c, error)) << error;
  EXPECT_TRUE(c.has_viewpoint);
  EXPECT_EQ(c.viewpoint, Vec3(10, -2, 0.5));
}

TEST(Pcd, HostileHeadersAreRefusedByField) {
  const struct {
    std::string from, to, message;
  } cases[] = {
      {"POINTS 3", "POINTS 4294967296", "POINTS 4294967296 is not WIDTH x HEIGHT"},
      {"WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3", "WIDTH 100000000\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100000000",
       "POINTS 100000000 of 32 bytes need more than the"},
      {"SIZE 4 4 4 4 4 4 4 2", "SIZE 4 4 4 4 4 4 4", "SIZE has 7 entries for 8 fields"},
      {"TYPE F F F F F F F U", "TYPE F F F F F F F Q", "field intensity: TYPE 'Q' is not F, I or U"},
      {"SIZE 4 4 4 4 4 4 4 2", "SIZE 4 4 2 4 4 4 4 2", "field z: a float of 2 bytes"},
      {"FIELDS x y z", "FIELDS x y y", "field y appears twice"},
      {"DATA binary", "DATA zip", "DATA: expected ascii, binary or binary_compressed"},
      {"VERSION 0.7", "VERSIONS 0.7", "unknown keyword 'VERSIONS'"},
      // WIDTH x HEIGHT wraps around 64 bits to POINTS: (2^63 + 1) x 2 = 2.
      {"WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3", "WIDTH 9223372036854775809\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2",
       "WIDTH x HEIGHT (9223372036854775809 x 2) is beyond 2^64 points"},
  };
  for (const auto& k : cases) {
    std::string text(reinterpret_cast<const char*>(pcd("binary").data()), pcd("binary").size());
    const size_t at = text.find(k.from);
    ASSERT_NE(at, std::string::npos) << k.from;
    text.replace(at, k.from.size(), k.to);
    PointCloud c;
    std::string error;
    EXPECT_FALSE(parse("scan.pcd", bytes(text), c, error)) << k.to;
    EXPECT_NE(error.find("scan.pcd: "), std::string::npos) << error;
    EXPECT_NE(error.find(k.message), std::string::npos) << "got: " << error;
  }
  // A compressed block claiming more than it can hold, or corrupt.
  std::vector<uint8_t> z = pcd("binary_compressed");
  const size_t block = pcd_header("binary_compressed").size();
  std::vector<uint8_t> big = z;
  big[block + 4] = 0xFF, big[block + 5] = 0xFF, big[block + 6] = 0xFF, big[block + 7] = 0x7F;
  PointCloud c;
  std::string error;
  EXPECT_FALSE(parse("scan.pcd", big, c, error));
  EXPECT_NE(error.find("the block uncompresses to"), std::string::npos) << error;
  // A POINTS count whose byte size wraps around 64 bits to the block's size:
  // 2^64 / 32 + 3 points of 32 bytes "need" 96 bytes.
  std::string wrapped(reinterpret_cast<const char*>(z.data()), z.size());
  const std::string from = "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3";
  const std::string to = "WIDTH 576460752303423491\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 576460752303423491";
  wrapped.replace(wrapped.find(from), from.size(), to);
  EXPECT_FALSE(parse("scan.pcd", bytes(wrapped), c, error));
  EXPECT_NE(error.find("the block uncompresses to 96 bytes, the header's 576460752303423491 points"), std::string::npos) << error;
  std::vector<uint8_t> bad = z;
  for (size_t i = block + 8; i < bad.size(); ++i) bad[i] = 0xE0;  // back references before the start
  EXPECT_FALSE(parse("scan.pcd", bad, c, error));
  EXPECT_NE(error.find("the LZF block is corrupt"), std::string::npos) << error;
}

// A LAS file: version 1.minor, point format `format`, three points with a
// large offset (a survey's: 5e5 east, 5e6 north), scale 1 mm.
std::vector<uint8_t> las(int minor, int format, uint16_t rgb_max = 65535) {
  const uint16_t header = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
  const uint16_t record[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  const uint16_t rgb_at[11] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};
  std::vector<uint8_t> out(header, 0);
  std::memcpy(out.data(), "LASF", 4);
  out[24] = 1;
  out[25] = static_cast<uint8_t>(minor);
  std::memcpy(&out[94], &header, 2);
  const uint32_t offset = header;
  std::memcpy(&out[96], &offset, 4);
  out[104] = static_cast<uint8_t>(format);
  std::memcpy(&out[105], &record[format], 2);
  const uint32_t count = 3;
  if (minor >= 4 && format >= 6) {
    const uint64_t count64 = 3;
    std::memcpy(&out[247], &count64, 8);
  } else {
    std::memcpy(&out[107], &count, 4);
  }
  const double scale[3] = {0.001, 0.001, 0.001}, shift[3] = {500000, 5000000, 100};
  std::memcpy(&out[131], scale, 24);
  std::memcpy(&out[155], shift, 24);
  const int32_t xyz[3][3] = {{1, 2, 3}, {-1000, 123456789, 0}, {2147483647, -2147483647, 42}};
  for (int i = 0; i < 3; ++i) {
    std::vector<uint8_t> r(record[format], 0);
    std::memcpy(&r[0], xyz[i], 12);
    if (rgb_at[format]) {
      const uint16_t rgb[3] = {rgb_max, static_cast<uint16_t>(rgb_max / 2), static_cast<uint16_t>(i)};
      std::memcpy(&r[rgb_at[format]], rgb, 6);
    }
    // Intensity 100, 400, 0; classes 2 (ground), 6 (building), 9 (water),
    // with the flag bits above the class in formats 0-5.
    const uint16_t intensity[3] = {100, 400, 0};
    const uint8_t classes[3] = {2, 6, 9};
    std::memcpy(&r[12], &intensity[i], 2);
    if (format >= 6) r[16] = classes[i];
    else r[15] = static_cast<uint8_t>(classes[i] | 0xA0);
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}

TEST(Las, EveryPointFormatWithItsOffsetInDoublePrecision) {
  for (int minor : {2, 3, 4})
    for (int format = 0; format <= 10; ++format) {
      if (minor < 4 && format > 5) continue;
      PointCloud c;
      std::string error;
      ASSERT_TRUE(parse("survey.las", las(minor, format), c, error)) << "1." << minor << " format " << format << ": " << error;
      ASSERT_EQ(c.size(), 3u);
      // Millimetres survive the offset: no float32 on the way.
      EXPECT_LT((c.positions[0] - Vec3(500000.001, 5000000.002, 100.003)).cwiseAbs().maxCoeff(), 1e-8);
      EXPECT_LT((c.positions[1] - Vec3(499999.0, 5123456.789, 100)).cwiseAbs().maxCoeff(), 1e-8);
      EXPECT_LT(std::abs(c.positions[2].x() - 2647483.647), 1e-8);
      const bool rgb = format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10;
      ASSERT_EQ(c.has_colors(), rgb) << format;
      if (rgb) {
        EXPECT_EQ(c.colors[0], Vec3(1, 32767.0 / 65535, 0));
        EXPECT_EQ(c.colors[2], Vec3(1, 32767.0 / 65535, 2.0 / 65535));
      }
    }
}

// encode --color-by: intensity as grey (the largest white), classification
// through the ASPRS palette, in every point format (the class byte moves in
// formats 6-10, and formats 0-5 keep flags above the class's five bits);
// another format is refused with them, naming it.
TEST(Las, ColourByIntensityOrClassification) {
  for (int format = 0; format <= 10; ++format) {
    const std::vector<uint8_t> f = las(4, format);
    PointCloud c;
    std::string error;
    ScanOptions o;
    o.color_by = LasColor::kIntensity;
    ASSERT_TRUE(parse_point_cloud("survey.las", f.data(), f.size(), c, error, o)) << format << ": " << error;
    ASSERT_TRUE(c.has_colors()) << format;
    EXPECT_EQ(c.colors[0], Vec3(0.25, 0.25, 0.25)) << format;
    EXPECT_EQ(c.colors[1], Vec3(1, 1, 1)) << format;
    EXPECT_EQ(c.colors[2], Vec3(0, 0, 0)) << format;
    o.color_by = LasColor::kClassification;
    ASSERT_TRUE(parse_point_cloud("survey.las", f.data(), f.size(), c, error, o)) << format << ": " << error;
    const uint8_t classes[3] = {2, 6, 9};
    for (int i = 0; i < 3; ++i) {
      const uint32_t rgb = las_class_rgb(classes[i]);
      EXPECT_EQ(c.colors[static_cast<size_t>(i)], Vec3((rgb >> 16) & 255, (rgb >> 8) & 255, rgb & 255) / 255.0) << format;
    }
  }
  EXPECT_EQ(las_class_rgb(2), 0xA0783Cu);  // ground: brown
  EXPECT_STREQ(las_class_name(9), "water");
  EXPECT_STREQ(las_class_name(200), "");
  PointCloud c;
  std::string error;
  ScanOptions o;
  o.color_by = LasColor::kClassification;
  const std::vector<uint8_t> ply = bytes("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                         "property float z\nend_header\n0 0 0\n");
  EXPECT_FALSE(parse_point_cloud("scan.ply", ply.data(), ply.size(), c, error, o));
  EXPECT_EQ(error, "scan.ply: --color-by classification takes a LAS scan's classification, but this is PLY");
}

TEST(Las, EightBitColourLazAndHostileHeadersAreSaidSo) {
  PointCloud c;
  std::string error;
  ASSERT_TRUE(parse("survey.las", las(2, 2, 200), c, error)) << error;
  EXPECT_EQ(c.colors[0], Vec3(200, 100, 0) / 255.0);
  EXPECT_TRUE(any_warning(c, "read as 8-bit colour"));
  std::vector<uint8_t> f = las(2, 3);
  f[104] = 0x83;  // LASzip's compressed format 3
  EXPECT_FALSE(parse("survey.laz", f, c, error));
  EXPECT_NE(error.find("survey.laz: this is LAZ (compressed LAS"), std::string::npos) << error;
  EXPECT_NE(error.find("laszip"), std::string::npos) << error;
  const struct {
    size_t at;
    std::vector<uint8_t> value;
    std::string message;
  } cases[] = {
      {25, {5}, "LAS version 1.5"},
      {104, {11}, "point data format 11"},
      {105, {10, 0}, "records of 10 bytes, point format 3 needs 34"},
      {107, {0xFF, 0xFF, 0xFF, 0xFF}, "header byte 107: 4294967295 points of 34 bytes need more than"},
      {96, {0xFF, 0xFF, 0, 0}, "header byte 96: point data at byte 65535"},
      {131, {0, 0, 0, 0, 0, 0, 0, 0}, "header byte 131: scale factor x is 0"},
      {94, {10, 0}, "header byte 94: a header size of 10 bytes"},
      {131, {0, 0, 0, 0, 0, 0, 0xE0, 0x7F}, "point 1 (byte 261): X * scale + offset is beyond the range of a double"},  // scale 1.3e308: -1000 x it
  };
  for (const auto& k : cases) {
    std::vector<uint8_t> g = las(2, 3);
    std::copy(k.value.begin(), k.value.end(), g.begin() + static_cast<ptrdiff_t>(k.at));
    EXPECT_FALSE(parse("survey.las", g, c, error)) << k.message;
    EXPECT_NE(error.find(k.message), std::string::npos) << "got: " << error;
  }
}

TEST(ScanFormats, EveryTruncatedPrefixIsRefusedOrReadWithoutACrash) {
  for (const std::vector<uint8_t>& f : {las(4, 7), pcd("binary"), pcd("binary_compressed"), pcd("ascii")}) {
    for (size_t n = 0; n < f.size(); ++n) {
      std::vector<uint8_t> prefix(f.begin(), f.begin() + static_cast<ptrdiff_t>(n));
      PointCloud c;
      std::string error;
      if (parse("cut.pcd", prefix, c, error)) {
        for (const Vec3& p : c.positions) ASSERT_TRUE(p.allFinite());
      } else {
        ASSERT_EQ(error.rfind("cut.pcd: ", 0), 0u) << error;
      }
    }
  }
}

TEST(TextScan, ColourColumnsDecimalCommasAndBinaryFilesAreTold) {
  PointCloud c;
  std::string error;
  // x y z r g b as integers: colour, said.
  ASSERT_TRUE(parse("scan.xyz", bytes("0 0 0 255 128 0\n1 0 0 0 0 10\n"), c, error)) << error;
  EXPECT_FALSE(c.has_normals());
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[0], Vec3(255, 128, 0) / 255.0);
  EXPECT_TRUE(any_warning(c, "columns 4-6 read as r g b"));
  // Unit vectors: normals.
  ASSERT_TRUE(parse("scan.xyz", bytes("0 0 0 0 0 1\n1 0 0 1 0 0\n"), c, error)) << error;
  EXPECT_TRUE(c.has_normals());
  EXPECT_FALSE(c.has_colors());
  // Decimal commas, and semicolons between numbers.
  ASSERT_TRUE(parse("scan.xyz", bytes("1,5 2,25 3\n-4,5 0 1,125\n"), c, error)) << error;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[0], Vec3(1.5, 2.25, 3));
  EXPECT_EQ(c.positions[1], Vec3(-4.5, 0, 1.125));
  EXPECT_TRUE(any_warning(c, "decimal commas"));
  ASSERT_TRUE(parse("scan.csv", bytes("1,5;2,25;3\n"), c, error)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1.5, 2.25, 3));
  ASSERT_TRUE(parse("scan.csv", bytes("1.5,2.25,3\n"), c, error)) << error;  // plain CSV
  EXPECT_EQ(c.positions[0], Vec3(1.5, 2.25, 3));
  // A UTF-8 byte-order mark.
  ASSERT_TRUE(parse("scan.xyz", bytes("\xEF\xBB\xBF" "1 2 3\n"), c, error)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  // PLY behind a byte-order mark, or with its magic in capitals.
  const std::string ply = "\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n";
  ASSERT_TRUE(parse("bom.ply", bytes("\xEF\xBB\xBF" "ply" + ply), c, error)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  EXPECT_TRUE(any_warning(c, "byte-order mark"));
  ASSERT_TRUE(parse("caps.ply", bytes("PLY" + ply), c, error)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  EXPECT_TRUE(any_warning(c, "the PLY magic in capitals"));
  // 1e999 is out of range, said as such.
  EXPECT_FALSE(parse("scan.xyz", bytes("1 2 1e999\n"), c, error));
  EXPECT_NE(error.find("line 1: '1e999' is beyond the range of a double"), std::string::npos) << error;
  // 1e39 is a double but beyond float32, in which a .spg keeps its box:
  // refused naming the line (text) or the point (every format), never an
  // infinity inside the tree. 3e38 is within it.
  EXPECT_FALSE(parse("scan.xyz", bytes("0 0 0\n1 2 3\n1e39 0 0\n"), c, error));
  EXPECT_EQ(error, "scan.xyz: line 3: x = 1e+39 is beyond float32's range (3.403e+38), in which a .spg stores positions");
  EXPECT_FALSE(parse("big.ply", bytes("ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
                                      "property double z\nend_header\n0 0 0\n0 -4e38 0\n"), c, error));
  EXPECT_EQ(error, "big.ply: point 1 (counting from 0): y = -4e+38 is beyond float32's range (3.403e+38), in "
                   "which a .spg stores positions");
  ASSERT_TRUE(parse("scan.xyz", bytes("0 0 0\n1 2 3\n-3e38 0 3e38\n"), c, error)) << error;
  // An empty file says so.
  EXPECT_FALSE(parse("empty.ply", {}, c, error));
  EXPECT_EQ(error, "empty.ply: the file is empty (0 bytes)");
  // A .spg or a binary file given as a scan.
  EXPECT_FALSE(parse("model.spg", bytes(std::string("STPG\x02\x00\x01\x00", 8)), c, error));
  EXPECT_NE(error.find("model.spg: byte 4: this is a .spg model, not a scan"), std::string::npos) << error;
  EXPECT_FALSE(parse("blob.bin", bytes(std::string("12 3\x01\x02", 6)), c, error));
  EXPECT_NE(error.find("blob.bin: byte 4: a binary byte (1)"), std::string::npos) << error;
}

TEST(TextScan, TheFilesPeopleExportAreReadOrNamed) {
  PointCloud c;
  std::string error;
  // CloudCompare's header line: the columns by name, colour 0..255.
  ASSERT_TRUE(parse("cc.txt", bytes("//X,Y,Z,R,G,B\n0,0,0,255,0,0\n1.5,-2,3,0,128,255\n"), c, error)) << error;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Vec3(1.5, -2, 3));
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[1], Vec3(0, 128, 255) / 255.0);
  EXPECT_TRUE(any_warning(c, "cc.txt: line 1 names the columns: read as --columns x,y,z,r,g,b"));
  // Other tools' names, in another order, with columns skipped by name.
  ASSERT_TRUE(parse("h.csv", bytes("Intensity;x;y;z;Nx;Ny;Nz;red\n7;1;2;3;0;0;1;9\n"), c, error)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[0], Vec3(0, 0, 1));
  EXPECT_FALSE(c.has_colors());  // red alone is no colour
  EXPECT_TRUE(any_warning(c, "read as --columns -,x,y,z,nx,ny,nz,- (skipped: Intensity, red)"));
  // A header naming no coordinates: what to do.
  EXPECT_FALSE(parse("h.txt", bytes("# exported\nalpha beta gamma\n1 2 3\n"), c, error));
  EXPECT_EQ(error, "h.txt: line 2: a header line ('alpha beta gamma') names no x, y and z columns: name them with "
                   "--columns (for example --columns x,y,z,-,r,g,b)");
  // Leica PTS: count lines opening each scan position, intensity skipped.
  ASSERT_TRUE(parse("s.pts", bytes("2\n0 0 0 -120 255 0 0\n1 0 0 5 0 255 0\n1\n2 2 2 -2048 1 2 3\n"), c, error)) << error;
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.positions[2], Vec3(2, 2, 2));
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[2], Vec3(1, 2, 3) / 255.0);
  EXPECT_TRUE(any_warning(c, "s.pts: read as Leica PTS (a count line, then x y z intensity r g b; intensity is not kept)"));
  ASSERT_TRUE(parse("s.pts", bytes("3\n0 0 0 1\n1 0 0 2\n"), c, error)) << error;  // x y z intensity, one short
  EXPECT_EQ(c.size(), 2u);
  EXPECT_FALSE(c.has_colors());
  EXPECT_TRUE(any_warning(c, "s.pts: line 1 says 3 points follow, 2 do"));
  // Wavefront OBJ: vertices (MeshLab's colours), faces for normals, the rest skipped.
  const std::string obj = "# exported\nmtllib a.mtl\no part\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nv 0 0 1 1 1 1\n"
                          "vn 0 0 1\nvt 0 0\nusemtl m\ns off\nf 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 -1//1 2//1\n";
  ASSERT_TRUE(parse("m.obj", bytes(obj), c, error)) << error;
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c.positions[3], Vec3(0, 0, 1));
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[1], Vec3(0, 1, 0));
  ASSERT_EQ(c.triangles.size(), 3u);  // one triangle, then a quad fanned into two
  EXPECT_EQ(c.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(c.triangles[2], (std::array<uint32_t, 3>{0, 3, 1}));
  EXPECT_TRUE(any_warning(c, "m.obj: read as Wavefront OBJ: 4 vertices, 3 triangles for normals"));
  EXPECT_FALSE(parse("m.obj", bytes("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), c, error));
  EXPECT_EQ(error, "m.obj: line 4: face vertex 9 beyond the file's 3 vertices");
  EXPECT_FALSE(parse("m.obj", bytes("v 0 0\n"), c, error));
  EXPECT_EQ(error, "m.obj: line 1: a vertex has 2 numbers (expected x y z, x y z w or x y z r g b)");
  // E57: refused by name, with what to do.
  EXPECT_FALSE(parse("site.e57", bytes(std::string("ASTM-E57\0\0\0\0\x01\0\0\0", 16)), c, error));
  EXPECT_EQ(error, "site.e57: this is an E57 file (ASTM E2807), which stipple does not read: convert it to PLY, LAS or "
                   "PTS first (CloudCompare: open it, then File > Save as PLY; PDAL: pdal translate site.e57 scan.las)");
}

TEST(TextScan, NamedColumnsAreReadAsNamed) {
  PointCloud c;
  std::string error;
  ScanOptions o;
  // x y z intensity r g b: seven columns, which the guess would refuse (not
  // r g b a: the intensity is not a byte).
  const std::vector<uint8_t> scan = bytes("1 2 3 0.5 255 0 51\n4 5 6 1.25 0 10 0\n");
  EXPECT_FALSE(parse("scan.xyz", scan, c, error));
  ASSERT_TRUE(parse_text_columns("x,y,z,-,r,g,b", o.columns, error)) << error;
  ASSERT_TRUE(parse_point_cloud("scan.xyz", scan.data(), scan.size(), c, error, o)) << error;
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Vec3(4, 5, 6));
  ASSERT_TRUE(c.has_colors());
  EXPECT_FALSE(c.has_normals());
  EXPECT_EQ(c.colors[0], Vec3(255, 0, 51) / 255.0);
  EXPECT_EQ(c.colors[1], Vec3(0, 10, 0) / 255.0);
  EXPECT_TRUE(c.warnings.empty());  // named, not guessed
  // Any order, spaces as separators in the list: normals first, then the position.
  ASSERT_TRUE(parse_text_columns("nx ny nz z y x", o.columns, error)) << error;
  const std::vector<uint8_t> flipped = bytes("0 0 2 3 2 1\n");
  ASSERT_TRUE(parse_point_cloud("scan.xyz", flipped.data(), flipped.size(), c, error, o)) << error;
  EXPECT_EQ(c.positions[0], Vec3(1, 2, 3));
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[0], Vec3(0, 0, 1));  // normalized
  // A row of another width, and a colour outside 0..255, named by line and column.
  ASSERT_TRUE(parse_text_columns("x,y,z,r,g,b", o.columns, error)) << error;
  const std::vector<uint8_t> short_row = bytes("1 2 3 4 5 6\n1 2 3 4 5\n");
  EXPECT_FALSE(parse_point_cloud("scan.xyz", short_row.data(), short_row.size(), c, error, o));
  EXPECT_EQ(error, "scan.xyz: line 2: expected 6 columns (as --columns names them), got 5");
  const std::vector<uint8_t> wide = bytes("1 2 3 4 5 6\n1 2 3 4 65535 6\n");
  EXPECT_FALSE(parse_point_cloud("scan.xyz", wide.data(), wide.size(), c, error, o));
  EXPECT_EQ(error, "scan.xyz: line 2: column 5 (g) is 65535, but --columns reads r g b as 0..255");
  // A file whose header names its fields.
  const std::vector<uint8_t> ply =
      bytes("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n");
  EXPECT_FALSE(parse_point_cloud("scan.ply", ply.data(), ply.size(), c, error, o));
  EXPECT_EQ(error, "scan.ply: --columns names a text scan's columns, but this is PLY, whose header names them");
}

TEST(TextScan, ColumnListsAreCheckedByName) {
  TextColumns columns;
  std::string error;
  EXPECT_FALSE(parse_text_columns("x,y,z,intensity", columns, error));
  EXPECT_EQ(error, "--columns: unknown column 'intensity' (x y z, nx ny nz, r g b, or - to skip)");
  EXPECT_FALSE(parse_text_columns("x,y,x,z", columns, error));
  EXPECT_EQ(error, "--columns: 'x' named twice");
  EXPECT_FALSE(parse_text_columns("x,y,-", columns, error));
  EXPECT_EQ(error, "--columns: x, y and z are required (got 'x,y,-')");
  EXPECT_FALSE(parse_text_columns("x,y,z,nx,ny", columns, error));
  EXPECT_EQ(error, "--columns: name all of nx, ny, nz or none");
  EXPECT_FALSE(parse_text_columns("x,y,z,r,g", columns, error));
  EXPECT_EQ(error, "--columns: name all of r, g, b or none");
  ASSERT_TRUE(parse_text_columns("-,x,-,y,z,-", columns, error)) << error;
  EXPECT_EQ(columns.fields.size(), 6u);  // skips may repeat
}

}  // namespace
}  // namespace stipple
