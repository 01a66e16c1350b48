// The fixed-point node decoder gives the same bytes on every platform: each
// node of the bunny (normals) and of a coloured sphere, serialized field by
// field, has the committed CRC-32 (tests/node_decoder_test.cpp checks the
// decoder against the double reference decoder on the host). Also: bad
// records and short storage are refused.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "core/node_decoder.h"
#include "core/node_format.h"
#include "core/spg_format.h"
#include "tests/core/test_files.h"

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
  } cases[] = {{"tests/golden/bunny_v1.spg", 0x58aaed0du}, {"tests/data/sphere600_colour.spg", 0x15cd31bau}};
  for (const auto& c : cases) {
    const uint32_t crc = decoded_crc(test::fixture(c.file));
    std::printf("%s: decoded nodes crc32 %08x\n", c.file, crc);
    EXPECT_EQ(crc, c.crc) << c.file;
  }
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

}  // namespace
}  // namespace stipple
