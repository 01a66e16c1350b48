// The fixed-point node decoder gives the same bytes on every platform: each
// node of the bunny (normals) and of a coloured sphere, serialized field by
// field, has the committed CRC-32 (tests/node_decoder_test.cpp checks the
// decoder against the double reference decoder on the host). Also: bad
// records and short storage are refused.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "core/node_decoder.h"
#include "core/node_format.h"
#include "core/spg_format.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

void put(std::vector<uint8_t>& out, int32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(static_cast<uint32_t>(v) >> (8 * i)));
}

// CRC-32 of every node's decoded fields, little-endian, in node order.
uint32_t decoded_crc(const std::vector<uint8_t>& spg) {
  SpgView view;
  EXPECT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4);
  NodeDecoder decoder;
  EXPECT_EQ(decoder.init(view, storage.data(), storage.size() * 4), DecodeStatus::kOk);
  std::vector<uint8_t> bytes;
  for (uint32_t i = 0; i < view.header.node_count; ++i) {
    FixedNode n;
    EXPECT_EQ(decoder.decode(view.records + i * view.record_bytes, &n), DecodeStatus::kOk);
    for (int k = 0; k < 3; ++k) {
      put(bytes, n.mean[k]);
      put(bytes, n.color[k]);
      for (int c = 0; c < 3; ++c) {
        put(bytes, n.axis[k][c]);
        put(bytes, n.normal_frame[k][c]);
        put(bytes, n.color_axis[k][c]);
      }
    }
    put(bytes, n.sigma_n[0]);
    put(bytes, n.sigma_n[1]);
  }
  return crc32(bytes.data(), bytes.size());
}

// A deliberate change of the decoder changes these; the test prints the new values.
TEST(NodeDecoder, DecodesToTheSameBytesOnEveryPlatform) {
  const struct {
    const char* file;
    uint32_t crc;
  } cases[] = {{"tests/golden/bunny_v1.spg", 0x22ef00d6u},
               {"tests/golden/bunny_v2.spg", 0x19e173b3u},
               {"tests/data/sphere600_colour.spg", 0x8e56c137u}};
  for (const auto& c : cases) {
    const uint32_t crc = decoded_crc(test::fixture(c.file));
    std::printf("%s: decoded nodes crc32 %08x\n", c.file, crc);
    EXPECT_EQ(crc, c.crc) << c.file;
  }
}

// The bunny's default file has the curvature's sign: its concave nodes
// decode with a negative sigma_n, their class code's two's complement.
TEST(NodeDecoder, ConcaveNodesDecodeWithANegativeSigmaN) {
  const test::ParsedModel m("tests/golden/bunny_v2.spg");
  ASSERT_TRUE(m.view.header.has_curvature_sign());
  uint32_t concave[2] = {}, convex[2] = {};
  for (uint32_t i = 0; i < m.view.header.node_count; ++i) {
    FixedNode n;
    ASSERT_EQ(m.decoder.decode(m.view.records + size_t{i} * m.view.record_bytes, &n), DecodeStatus::kOk);
    const NodeFields f = unpack_record(m.view.header.layout, m.view.records + size_t{i} * m.view.record_bytes);
    for (int j = 0; j < 2; ++j) {
      const uint16_t code = load_u16le(m.view.sigma_n + 4 * size_t{f[Field::kSigmaN]} + 2 * j);
      ASSERT_EQ(n.sigma_n[j], code >= 0x8000 ? int32_t{code} - 0x10000 : int32_t{code}) << "node " << i;
      (n.sigma_n[j] < 0 ? concave : convex)[j]++;
    }
  }
  std::printf("bunny: concave along the major tangent %u, the minor %u; convex %u, %u of %u nodes\n", concave[0],
              concave[1], convex[0], convex[1], m.view.header.node_count);
  // A scan is convex and concave in about equal shares at its finest scales.
  for (int j = 0; j < 2; ++j) {
    EXPECT_GT(concave[j], m.view.header.node_count / 5) << j;
    EXPECT_GT(convex[j], m.view.header.node_count / 5) << j;
  }
}

// The same scan written both ways (version 2 without the curvature's sign,
// which version 1 cannot carry): version 2's 16-bit codes decode to version
// 1's sigma_n and sigma_c exactly (both are Q12 in the client) and to its
// sigma_p within 2^-12 of the value, plus the rounding to a model unit.
TEST(NodeDecoder, SixteenBitTablesDecodeAsTheFloatTablesDo) {
  const std::vector<uint8_t> f1 = test::fixture("tests/golden/bunny_v1.spg"),
                             f2 = test::fixture("tests/golden/bunny_v2_unsigned.spg");
  SpgView v1, v2;
  ASSERT_TRUE(spg_parse(f1.data(), f1.size(), &v1).ok());
  ASSERT_TRUE(spg_parse(f2.data(), f2.size(), &v2).ok());
  ASSERT_EQ(v1.header.version, 1);
  ASSERT_EQ(v2.header.version, 2);
  for (int t = 0; t < 3; ++t) ASSERT_EQ(v1.header.class_count[t], v2.header.class_count[t]);
  ASSERT_EQ(std::memcmp(v1.records, v2.records, v1.header.node_count * v1.record_bytes), 0);
  std::vector<uint32_t> s1(node_decoder_bytes(v1.header) / 4), s2(node_decoder_bytes(v2.header) / 4);
  NodeDecoder d1, d2;
  ASSERT_EQ(d1.init(v1, s1.data(), s1.size() * 4), DecodeStatus::kOk);
  ASSERT_EQ(d2.init(v2, s2.data(), s2.size() * 4), DecodeStatus::kOk);
  int differ = 0;
  for (uint16_t c = 0; c < v1.header.class_count[0]; ++c) {
    for (int k = 0; k < 3; ++k) {
      const int64_t a = d1.sigma_p_mu(ClassId{c})[k], b = d2.sigma_p_mu(ClassId{c})[k];
      ASSERT_LE(std::llabs(a - b), a / 4096 + 1) << "class " << c << " axis " << k;
      differ += a != b;
    }
  }
  for (uint16_t c = 0; c < v1.header.class_count[1]; ++c)
    for (int k = 0; k < 2; ++k) ASSERT_EQ(d1.sigma_n_q12(ClassId{c})[k], d2.sigma_n_q12(ClassId{c})[k]) << "class " << c;
  EXPECT_GT(differ, 0);  // the codes are not float32 in disguise
}

TEST(NodeDecoder, RejectsBadRecordsAndSmallStorage) {
  const std::vector<uint8_t> spg = test::fixture("tests/golden/bunny_v1.spg");
  SpgView view;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  const size_t need = node_decoder_bytes(view.header);
  std::vector<uint32_t> storage(need / 4);
  NodeDecoder decoder;
  EXPECT_EQ(decoder.init(view, storage.data(), need - 4), DecodeStatus::kStorageTooSmall);
  ASSERT_EQ(decoder.init(view, storage.data(), need), DecodeStatus::kOk);
  // A record whose sigma_n class is past the table: rejected, output untouched.
  std::vector<uint8_t> record(view.records, view.records + view.record_bytes);
  NodeFields f = unpack_record(view.header.layout, record.data());
  f[Field::kSigmaN] = view.header.class_count[1];
  pack_record(view.header.layout, f, record.data());
  FixedNode n{};
  n.mean[0] = 12345;
  EXPECT_EQ(decoder.decode(record.data(), &n), DecodeStatus::kBadClass);
  EXPECT_EQ(n.mean[0], 12345);
  // Angle fields wider than the tables allow are refused at init.
  SpgView wide = view;
  wide.header.layout.bits[static_cast<int>(Field::kFpPhi)] = kMaxAngleBits + 1;
  EXPECT_EQ(decoder.init(wide, storage.data(), need), DecodeStatus::kBadLayout);
}

uint32_t bits_of(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}

// A box whose x axis spans many binary orders of magnitude (from -1.5e-9 to
// 507: exponents 2^-30 and 2^8) while y starts away from zero (10 to 5000).
// Comparing the extents used to shift an already-shifted difference past 63
// bits (a signed overflow before C++20; since then a silent wrap that can
// pick the wrong axis as the largest and shrink the render). Every axis must get its extent in
// model units: the largest 2^24 MU, the others in proportion.
TEST(NodeDecoder, BoxesSpanningManyOrdersOfMagnitude) {
  const std::vector<uint8_t> spg = test::fixture("tests/golden/bunny_v1.spg");
  SpgView view;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
  const struct {
    float min[3], max[3];
    int32_t extent_mu[3];
  } cases[] = {
      {{-1.5e-9f, 10.0f, 0.0f}, {507.0f, 5000.0f, 1.0f}, {1704619, 1 << 24, 3362}},
      // Found by a search over random boxes: the wrapped shift made z look the largest.
      {{-0.000935058575f, 0.042750001f, -4.89410013e-10f}, {114.111061f, 49905.707f, 0.694999993f}, {38362, 1 << 24, 234}},
      {{10.0f, -1.5e-9f, 3.0f}, {5000.0f, 507.0f, 4.0f}, {1 << 24, 1704619, 3362}},
      {{-1.5e-9f, 10.0f, 0.0f}, {507.0f, 600.0f, 1.0f}, {14417031, 1 << 24, 28436}},
      {{-1.5e-9f, 10.0f, 0.0f}, {507.0f, 20.0f, 1.0f}, {1 << 24, 330912, 33091}},
      {{1e-38f, -1e-38f, 1e30f}, {2e-38f, 1e-38f, 3e30f}, {0, 0, 1 << 24}},  // subnormal extents beside a huge one
      {{-3e38f, -1e-45f, 0.0f}, {3e38f, 1e-45f, 0.0f}, {1 << 24, 0, 0}},     // the widest finite box
      {{5.0f, 5.0f, 5.0f}, {5.0f, 5.0f, 5.0f}, {0, 0, 0}},                   // a single point
  };
  for (const auto& c : cases) {
    SpgView v = view;
    for (int a = 0; a < 3; ++a) {
      v.header.bbox_bits[a] = bits_of(c.min[a]);
      v.header.bbox_bits[3 + a] = bits_of(c.max[a]);
    }
    std::vector<uint32_t> storage(node_decoder_bytes(v.header) / 4);
    NodeDecoder decoder;
    ASSERT_EQ(decoder.init(v, storage.data(), storage.size() * 4), DecodeStatus::kOk);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(decoder.extent_mu()[a], c.extent_mu[a]) << c.min[0] << " axis " << a;
    FixedNode n;
    for (uint32_t i = 0; i < v.header.node_count; ++i) {
      ASSERT_EQ(decoder.decode(v.records + i * v.record_bytes, &n), DecodeStatus::kOk);
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(n.mean[a], 0);
        EXPECT_LE(n.mean[a], decoder.extent_mu()[a]);
      }
    }
  }
}

}  // namespace
}  // namespace stipple
