// .spg version 3 (coded records, core/spg_coded.h) on every target: the
// committed bitstream expands to the version 2 file it was made from, byte
// for byte, and every damaged or hostile coded file is refused — never
// read past, never expanded into a model with a value out of range.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/spg_coded.h"
#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

struct Expanded {
  SpgResult result;
  std::vector<uint8_t> image;
};

Expanded expand(const std::vector<uint8_t>& f) {
  Expanded out;
  SpgView view;
  SpgCodedParts parts;
  out.result = spg_parse_coded(f.data(), f.size(), &view, &parts);
  if (!out.result.ok()) return out;
  out.image.resize(spg_expanded_bytes(view, parts));
  std::vector<uint8_t> points(view.header.node_count);
  out.result = spg_expand(f.data(), view, parts, out.image.data(), points.data());
  return out;
}

void fix_crc(std::vector<uint8_t>& f) { store_u32le(f.data() + f.size() - 4, crc32(f.data(), f.size() - 4)); }

const std::vector<uint8_t>& bunny_v3() {
  static const std::vector<uint8_t> f = test::fixture("tests/golden/bunny_v3.spg");
  return f;
}

TEST(SpgCoded, ExpandsToTheVersionTwoFileByteForByte) {
  const std::vector<uint8_t> v2 = test::fixture("tests/golden/bunny_v2.spg");
  const Expanded e = expand(bunny_v3());
  ASSERT_TRUE(e.result.ok()) << spg_error_text(e.result.error) << " at " << e.result.offset;
  EXPECT_EQ(e.image, v2);
  // The bunny's 6,913 records in 66,491 bytes where version 2 takes 97,319:
  // a third less.
  EXPECT_LT(bunny_v3().size() * 100, v2.size() * 69);
  // Everything before the records is version 2's, but for the version.
  SpgView view;
  SpgCodedParts parts;
  ASSERT_TRUE(spg_parse_coded(bunny_v3().data(), bunny_v3().size(), &view, &parts).ok());
  EXPECT_EQ(view.header.version, kSpgCodedVersion);
  EXPECT_EQ(view.records, nullptr);
  EXPECT_EQ(parts.batch_count, 1u);
  for (size_t i = 0; i < parts.records_offset; ++i)
    if (i != spg_offset::kVersion && i != spg_offset::kVersion + 1) {
      ASSERT_EQ(bunny_v3()[i], v2[i]) << "byte " << i;
    }
}

TEST(SpgCoded, OtherReadersRefuseItByName) {
  SpgView view;
  EXPECT_EQ(spg_parse(bunny_v3().data(), bunny_v3().size(), &view).error, SpgError::kCodedRecords);
  size_t used = 0;
  EXPECT_EQ(spg_parse_startup(bunny_v3().data(), bunny_v3().size(), &view, &used).error, SpgError::kBadVersion);
  const std::vector<uint8_t> v2 = test::fixture("tests/golden/bunny_v2.spg");
  SpgCodedParts parts;
  EXPECT_EQ(spg_parse_coded(v2.data(), v2.size(), &view, &parts).error, SpgError::kBadVersion);
  EXPECT_STREQ(spg_error_text(SpgError::kCodedRecords), "version 3 (coded records) must be expanded before it is read");
}

TEST(SpgCoded, EveryTruncationIsRefused) {
  const std::vector<uint8_t>& f = bunny_v3();
  SpgView view;
  SpgCodedParts parts;
  ASSERT_TRUE(spg_parse_coded(f.data(), f.size(), &view, &parts).ok());
  // Every prefix through the coded section's lengths, then every 97th byte.
  for (size_t n = 0; n < f.size(); n += n < parts.records_offset + 64 ? 1 : 97) {
    const std::vector<uint8_t> prefix(f.begin(), f.begin() + static_cast<ptrdiff_t>(n));
    const SpgResult r = spg_parse_coded(prefix.data(), prefix.size(), &view, &parts);
    ASSERT_FALSE(r.ok()) << "prefix " << n;
    if (n >= 4) {
      ASSERT_EQ(r.error, SpgError::kTruncated) << "prefix " << n;
      EXPECT_GT(r.needed, n);
      EXPECT_LE(r.needed, f.size());
    }
  }
  std::vector<uint8_t> longer = f;
  longer.push_back(0);
  EXPECT_EQ(expand(longer).result.error, SpgError::kTrailingBytes);
}

TEST(SpgCoded, HostileFramingIsRefusedAtItsByte) {
  SpgView view;
  SpgCodedParts parts;
  ASSERT_TRUE(spg_parse_coded(bunny_v3().data(), bunny_v3().size(), &view, &parts).ok());
  const size_t batches_at = parts.records_offset + 4 + parts.tables_bytes;
  const auto with = [&](size_t at, uint32_t v) {
    std::vector<uint8_t> g = bunny_v3();
    store_u32le(g.data() + at, v);
    fix_crc(g);
    return expand(g).result;
  };
  // No batch, more batches than nodes, a batch too short for its state.
  EXPECT_EQ(with(batches_at, 0).error, SpgError::kBadCoded);
  EXPECT_EQ(with(batches_at, 0).offset, batches_at);
  EXPECT_EQ(with(batches_at, 7000).error, SpgError::kBadCoded);
  EXPECT_EQ(with(batches_at + 4, 7).error, SpgError::kBadCoded);
  // Lengths that run past the file read as a file cut short.
  EXPECT_EQ(with(parts.records_offset, 0xFFFFFFFFu).error, SpgError::kTruncated);
  EXPECT_EQ(with(batches_at + 4, 0xFFFFFFF0u).error, SpgError::kTruncated);
  // Tables cut short by one byte, with the batch moved up to fill it.
  {
    std::vector<uint8_t> g = bunny_v3();
    store_u32le(g.data() + parts.records_offset, static_cast<uint32_t>(parts.tables_bytes - 1));
    g.erase(g.begin() + static_cast<ptrdiff_t>(parts.records_offset + 4 + parts.tables_bytes - 1));
    fix_crc(g);
    EXPECT_EQ(expand(g).result.error, SpgError::kBadCoded);
  }
  // The batch's node count one short, and one over.
  const size_t count_at = batches_at + 8;
  const uint32_t count = load_u32le(bunny_v3().data() + count_at);
  EXPECT_EQ(count, view.header.node_count);
  EXPECT_EQ(with(count_at, count - 1).error, SpgError::kBadCoded);
  EXPECT_EQ(with(count_at, count + 1).error, SpgError::kBadCoded);
}

// The CRC-32 refuses any damage; behind it (the CRC made right again),
// the coder itself refuses most of it, and what it takes is a model every
// reader takes: a raw bit of a field flipped (rANS passes raw bits through
// its state) changes that field, and the children coded against it.
TEST(SpgCoded, CorruptBatchesAreRefused) {
  SpgView view;
  SpgCodedParts parts;
  ASSERT_TRUE(spg_parse_coded(bunny_v3().data(), bunny_v3().size(), &view, &parts).ok());
  const std::vector<uint8_t> v2 = test::fixture("tests/golden/bunny_v2.spg");
  const size_t first = parts.records_offset + 4;  // the tables, then the batches
  const size_t span = bunny_v3().size() - 4 - first;
  std::mt19937 rng(7);
  int refused = 0, taken = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> g = bunny_v3();
    const size_t at = first + rng() % span;
    g[at] ^= static_cast<uint8_t>(1u << (rng() % 8));
    ASSERT_FALSE(expand(g).result.ok()) << "trial " << trial;  // the CRC, or a length it reads first
    fix_crc(g);
    const Expanded e = expand(g);
    if (!e.result.ok()) {
      ++refused;
      continue;
    }
    ++taken;
    SpgView image;
    ASSERT_TRUE(spg_parse(e.image.data(), e.image.size(), &image).ok()) << "trial " << trial;
    EXPECT_NE(e.image, v2) << "trial " << trial;
  }
  std::printf("%d of 300 flips refused by the coder, %d taken as another valid model\n", refused, taken);
  EXPECT_GE(refused, 200) << taken << " taken";
}

}  // namespace
}  // namespace stipple
