// Node records and the .spg container: exact packing, and every kind of
// damaged or hostile file refused with its field and byte.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "core/node_format.h"
#include "core/spg_format.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

TEST(NodeFormat, PaperBudget) {
  EXPECT_EQ(paper_layout(true, false, 0).record_bytes(), 13);
  EXPECT_EQ(paper_layout(true, true, 1).record_bytes(), 17);
  EXPECT_EQ(paper_layout(false, false, 2).total_bits(), 68);
  const RecordLayout l = paper_layout(true, true, 1);
  EXPECT_EQ(l.width(Field::kPosY), 10);
  EXPECT_EQ(l.width(Field::kPosX), 11);
  EXPECT_EQ(l.total_bits(), 136);
}

// The client's unpacker (the paper's layouts unrolled, any other from
// positions worked out at init) reads every field as unpack_record does: all
// twelve paper layouts and random ones of every width, on random records.
TEST(NodeFormat, RecordUnpackerAgreesWithUnpackRecord) {
  std::mt19937 rng(15);
  std::vector<RecordLayout> layouts;
  for (int n = 0; n < 2; ++n)
    for (int c = 0; c < 2; ++c)
      for (int thin = 0; thin < 3; ++thin) layouts.push_back(paper_layout(n != 0, c != 0, thin));
  for (int i = 0; i < 200; ++i) {
    RecordLayout l;
    const bool n = rng() & 1, c = rng() & 1;
    for (int f = 0; f < kFieldCount; ++f) {
      const bool normal_field = f >= static_cast<int>(Field::kFnTheta) && f <= static_cast<int>(Field::kSigmaN);
      const bool color_field = f >= static_cast<int>(Field::kColorR);
      if ((!normal_field || n) && (!color_field || c)) l.bits[f] = static_cast<uint8_t>(1 + rng() % kMaxFieldBits);
    }
    layouts.push_back(l);
  }
  for (const RecordLayout& l : layouts) {
    RecordUnpacker u;
    u.init(l);
    for (int r = 0; r < 50; ++r) {
      std::vector<uint8_t> record(static_cast<size_t>(l.record_bytes()));  // exact size: ASan sees an overread
      for (uint8_t& b : record) b = static_cast<uint8_t>(rng());
      const NodeFields want = unpack_record(l, record.data()), got = u.unpack(record.data());
      for (int f = 0; f < kFieldCount; ++f) ASSERT_EQ(got.v[f], want.v[f]) << "field " << f << ", " << l.record_bytes() << " bytes";
    }
  }
}

TEST(NodeFormat, PackUnpackExact) {
  const RecordLayout l = paper_layout(true, true, 2);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    NodeFields f;
    for (int k = 0; k < kFieldCount; ++k) {
      const uint32_t max = (1u << l.bits[k]) - 1;
      f.v[k] = static_cast<uint16_t>(trial == 0 ? max : trial == 1 ? 0 : rng() & max);
    }
    ASSERT_TRUE(fields_fit(l, f));
    uint8_t buf[kMaxRecordBytes];
    pack_record(l, f, buf);
    const NodeFields back = unpack_record(l, buf);
    for (int k = 0; k < kFieldCount; ++k) ASSERT_EQ(back.v[k], f.v[k]) << "field " << k;
  }
}

TEST(NodeFormat, FrozenBitLayout) {
  // A record whose bytes were worked out by hand from docs/format.md §5:
  // pos x = 0x7FF (11 bits), y = 1, z = 0 (10 bits); theta = 0xAB; the rest 0.
  const RecordLayout l = paper_layout(false, false, 2);
  NodeFields f;
  f[Field::kPosX] = 0x7FF;
  f[Field::kPosY] = 1;
  f[Field::kFpTheta] = 0xAB;
  uint8_t buf[16] = {};
  pack_record(l, f, buf);
  // bits 0-10: x; bit 11: y's LSB; bits 32-39: theta.
  const uint8_t expect[9] = {0xFF, 0x0F, 0x00, 0x00, 0xAB, 0x00, 0x00, 0x00, 0x00};
  for (int i = 0; i < 9; ++i) EXPECT_EQ(buf[i], expect[i]) << "byte " << i;
  NodeFields too_big = f;
  too_big[Field::kFpPsi] = 64;  // 6 bits
  EXPECT_FALSE(fields_fit(l, too_big));
}

TEST(Crc32, KnownValue) {
  const uint8_t text[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(crc32(text, 9), 0xCBF43926u);
}

// The encoder's output for a 600-point sphere in each variant, committed so
// that these tests need no encoder (tests/format_test.cpp checks the files
// are still what the encoder writes).
struct Variant {
  const char* name;
  bool normals, colors, octree;
  uint16_t version;
};
constexpr Variant kVariants[] = {{"normals", true, false, false, 2},   {"plain", false, false, false, 2},
                                 {"colour", true, true, false, 2},     {"octree", true, false, true, 2},
                                 {"normals_v1", true, false, false, 1}};

std::vector<uint8_t> sphere_spg(const char* variant) {
  return test::fixture(std::string("tests/data/sphere600_") + variant + ".spg");
}

void fix_crc(std::vector<uint8_t>& f) {
  const uint32_t c = crc32(f.data(), f.size() - 4);
  for (int i = 0; i < 4; ++i) f[f.size() - 4 + static_cast<size_t>(i)] = static_cast<uint8_t>(c >> (8 * i));
}

SpgError parse_error(const std::vector<uint8_t>& f) {
  SpgView v;
  return spg_parse(f.data(), f.size(), &v).error;
}

TEST(SpgFormat, EveryVariantParses) {
  for (const Variant& variant : kVariants) {
    const std::vector<uint8_t> f = sphere_spg(variant.name);
    SpgView v;
    const SpgResult r = spg_parse(f.data(), f.size(), &v);
    ASSERT_TRUE(r.ok()) << variant.name << ": " << spg_error_text(r.error) << " at " << r.offset;
    EXPECT_EQ(v.header.point_count, 600u);
    EXPECT_EQ(v.header.has_normals(), variant.normals);
    EXPECT_EQ(v.header.has_color(), variant.colors);
    EXPECT_EQ(v.header.tree_arity, variant.octree ? 8 : 2);
    EXPECT_EQ(v.record_bytes, variant.colors ? 17u : variant.normals ? 13u : 9u);
    EXPECT_EQ(v.header.version, variant.version);
    // The tables' bytes: 12 + 8 per class in version 1, 6 + 4 from version 2.
    const size_t b = variant.version == 1 ? 4 : 2;
    EXPECT_EQ(static_cast<size_t>(v.sigma_n - v.sigma_p), 3 * b * v.header.class_count[0]);
    EXPECT_EQ(spg_startup_bytes(v.header.version, v.header.class_count),
              spg_fixed_header_bytes(variant.version) + b * (3u * v.header.class_count[0] + 2u * v.header.class_count[1] + 3u * v.header.class_count[2]));
  }
}

TEST(SpgFormat, EveryTruncatedPrefixIsRejected) {
  const std::vector<uint8_t> f = sphere_spg("colour");
  for (size_t n = 0; n < f.size(); ++n) {
    std::vector<uint8_t> prefix(f.begin(), f.begin() + static_cast<ptrdiff_t>(n));
    const SpgError e = parse_error(prefix);
    ASSERT_NE(e, SpgError::kOk) << "prefix " << n;
    // Past the magic, a prefix reads as what it is: a file cut short, with
    // the bytes it needs at least — more than it has, no more than the file.
    if (n >= 4) {
      SpgView v;
      const SpgResult r = spg_parse(prefix.data(), prefix.size(), &v);
      ASSERT_EQ(r.error, SpgError::kTruncated) << "prefix " << n;
      EXPECT_GT(r.needed, n) << "prefix " << n;
      EXPECT_LE(r.needed, f.size()) << "prefix " << n;
    }
  }
  std::vector<uint8_t> longer = f;
  longer.push_back(0);
  EXPECT_EQ(parse_error(longer), SpgError::kTrailingBytes);
}

TEST(SpgFormat, EverySingleBitFlipIsRejected) {
  const std::vector<uint8_t> f = sphere_spg("normals");
  std::mt19937 rng(3);
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<uint8_t> g = f;
    g[rng() % g.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
    ASSERT_NE(parse_error(g), SpgError::kOk) << "trial " << trial;
  }
}

TEST(SpgFormat, HostileHeadersAreRefusedByField) {
  const std::vector<uint8_t> f = sphere_spg("normals");
  struct Case {
    size_t offset;
    std::vector<uint8_t> value;
    SpgError expect;
  };
  const Case cases[] = {
      {0, {'S', 'T', 'P', 'X'}, SpgError::kBadMagic},
      {4, {0, 0}, SpgError::kBadVersion},
      {4, {3, 0}, SpgError::kCodedRecords},  // version 3: expanded first (core/spg_coded.h)
      {4, {4, 0}, SpgError::kBadVersion},
      {6, {4, 0}, SpgError::kBadFlags},                   // a curvature sign without normals
      {6, {9, 0}, SpgError::kBadFlags},                   // an unknown attribute
      {8, {3}, SpgError::kBadArity},
      {9, {17}, SpgError::kBadLayout},
      {10, {17}, SpgError::kBadLayout},                   // a field of 17 bits
      {10 + 11, {5}, SpgError::kBadLayout},               // colour field present without the flag
      {28, {0xFF, 0xFF, 0xFF, 0xFF}, SpgError::kTruncated},  // 4 billion nodes: more bytes than the file has
      {32, {0, 0, 0, 0}, SpgError::kBadCounts},
      {36, {1, 0, 0, 0}, SpgError::kBadCounts},
      {40, {99, 0}, SpgError::kBadDepth},
      {42, {7, 0}, SpgError::kBadLayout},                 // view hint: up axis code 7
      {42, {0x38, 0}, SpgError::kBadLayout},              // sensor side code 7
      {42, {0x80, 0}, SpgError::kBadLayout},              // a hint bit beyond the defined ones
      {44, {0, 0, 0xC0, 0x7F}, SpgError::kBadFloat},      // NaN bbox
      {44, {0, 0, 0x80, 0x7F}, SpgError::kBadFloat},      // +inf
      {44, {0, 0, 0x80, 0x4F}, SpgError::kBadBoundingBox},  // min x = 4.3e9 > max x
      {76, {0, 0, 0, 0, 0, 0, 0xF8, 0x7F}, SpgError::kBadFloat},  // version 2's origin x: NaN
      {92, {0, 0, 0, 0, 0, 0, 0xF0, 0xFF}, SpgError::kBadFloat},  // origin z: -inf
      {68, {0, 0}, SpgError::kBadClassCount},
      {68, {0x01, 0x10}, SpgError::kBadClassCount},       // 4097 classes in 12 bits
  };
  for (const Case& c : cases) {
    std::vector<uint8_t> g = f;
    std::copy(c.value.begin(), c.value.end(), g.begin() + static_cast<ptrdiff_t>(c.offset));
    fix_crc(g);
    SpgView v;
    const SpgResult r = spg_parse(g.data(), g.size(), &v);
    EXPECT_EQ(r.error, c.expect) << "offset " << c.offset << ": got " << spg_error_text(r.error);
  }
  // Version 1's float32 tables: NaN, infinite and negative sigmas are refused
  // at their byte. Version 2's codes have no such values: any 16 bits parse.
  const std::vector<uint8_t> f1 = sphere_spg("normals_v1");
  const Case float_cases[] = {
      {76, {0, 0, 0xC0, 0xFF}, SpgError::kBadFloat},  // NaN sigma
      {80, {0, 0, 0x80, 0x7F}, SpgError::kBadFloat},  // +inf
      {84, {0, 0, 0x80, 0xBF}, SpgError::kBadFloat},  // negative sigma
      {6, {5, 0}, SpgError::kBadFlags},               // a curvature sign needs version 2's codes
  };
  for (const Case& c : float_cases) {
    std::vector<uint8_t> g = f1;
    std::copy(c.value.begin(), c.value.end(), g.begin() + static_cast<ptrdiff_t>(c.offset));
    fix_crc(g);
    SpgView v;
    const SpgResult r = spg_parse(g.data(), g.size(), &v);
    EXPECT_EQ(r.error, c.expect) << "version 1, offset " << c.offset << ": got " << spg_error_text(r.error);
    EXPECT_EQ(r.offset, c.offset);
  }
  std::vector<uint8_t> g = f;
  for (size_t i = spg_fixed_header_bytes(2); i < spg_fixed_header_bytes(2) + 6; ++i) g[i] = 0xFF;  // the largest sigma_p code, thrice
  fix_crc(g);
  EXPECT_EQ(parse_error(g), SpgError::kOk);
}

// sigma_n's codes with the curvature's sign are two's complement; without
// it, unsigned as before (docs/format.md §2).
TEST(SpgFormat, SignedSigmaNCodes) {
  EXPECT_EQ(spg_sigma_n_q12(0x0400, true), 1024);
  EXPECT_EQ(spg_sigma_n_q12(0xFC00, true), -1024);
  EXPECT_EQ(spg_sigma_n_q12(0x8001, true), -32767);
  EXPECT_EQ(spg_sigma_n_q12(0xFC00, false), 0xFC00);
  EXPECT_EQ(spg_sigma_n_magnitude(0xFC00, true), 1024);
  EXPECT_EQ(spg_sigma_n_magnitude(0x8000, true), 32768);
  EXPECT_EQ(spg_sigma_n_magnitude(0xFC00, false), 0xFC00);
}

// Version 2's sigma_p code: a 16-bit float relative to the box (docs/format.md
// §2), decoded by shifts alone.
TEST(SpgFormat, SigmaPCodesDecodeByShifts) {
  EXPECT_EQ(spg_sigma_p_code_units(0, 24), 0u);
  EXPECT_EQ(spg_sigma_p_code_units(27u << 11, 24), 1u << 20);           // 2^-4 E
  EXPECT_EQ(spg_sigma_p_code_units((27u << 11) | 1024, 24), 3u << 19);  // 1.5 x 2^-4 E
  EXPECT_EQ(spg_sigma_p_code_units(31u << 11, 24), 1u << 24);           // E
  EXPECT_EQ(spg_sigma_p_code_units(0xFFFF, 24), 4095u << 13);           // the largest: 2 E less one step
  EXPECT_EQ(spg_sigma_p_code_units(0xFFFF, 30), 4095u << 19);           // still below 2^32
  EXPECT_EQ(spg_sigma_p_code_units(1u << 11, 30), 1u);                  // 2^-30 E
  EXPECT_EQ(spg_sigma_p_code_units(2047, 41), 2047u);                   // below 2^-30 E: m 2^-41 E
  EXPECT_EQ(spg_sigma_p_code_units(1, 24), 0u);                         // rounds to nothing
  // Monotonic and continuous across the binades: each step is one mantissa unit.
  for (uint32_t c = 1; c <= 0xFFFF; ++c)
    ASSERT_LE(spg_sigma_p_code_units(static_cast<uint16_t>(c - 1), 30), spg_sigma_p_code_units(static_cast<uint16_t>(c), 30))
        << c;
}

// The original points under every node: the leaves' counts, summed up the
// tree and saturated at 255; a view without leaf counts knows none.
TEST(SpgFormat, NodePointsAreTheLeafCountsSummedAndSaturated) {
  for (const Variant& variant : kVariants) {
    const std::vector<uint8_t> f = sphere_spg(variant.name);
    SpgView v;
    ASSERT_TRUE(spg_parse(f.data(), f.size(), &v).ok());
    const uint32_t n = v.header.node_count;
    std::vector<uint8_t> points(2 * n, 0xEE);
    spg_node_points(v, points.data(), 2);  // strided: every other byte
    // The exact counts, the slow way: leaves in order, then sums bottom up.
    std::vector<uint32_t> exact(n, 0), first(n, 0);
    const uint8_t* at = v.leaf_counts;
    for (uint32_t i = 0, next = 1; i < n; ++i) {
      first[i] = next;
      next += spg_child_count(v, i);
      if (spg_child_count(v, i) == 0)
        for (int shift = 0;; shift += 7) {
          exact[i] |= static_cast<uint32_t>(*at & 0x7F) << shift;
          if (!(*at++ & 0x80)) break;
        }
    }
    for (uint32_t i = n; i-- > 0;)
      for (uint32_t c = 0; c < spg_child_count(v, i); ++c) exact[i] += exact[first[i] + c];
    EXPECT_EQ(exact[0], 600u);
    EXPECT_EQ(points[0], 255) << variant.name;
    for (uint32_t i = 0; i < n; ++i) {
      ASSERT_EQ(points[2 * i], exact[i] < 255 ? exact[i] : 255u) << variant.name << " node " << i;
      ASSERT_EQ(points[2 * i + 1], 0xEE);  // the stride's other bytes untouched
    }
    SpgView startup_only;
    size_t used = 0;
    ASSERT_TRUE(spg_parse_startup(f.data(), f.size(), &startup_only, &used).ok());
    startup_only.header.node_count = 3;
    uint8_t none[3] = {9, 9, 9};
    spg_node_points(startup_only, none, 1);
    EXPECT_EQ(none[0] | none[1] | none[2], 0);
  }
}

TEST(SpgFormat, RecordClassIndexBeyondTable) {
  std::vector<uint8_t> f = sphere_spg("normals");
  SpgView v;
  ASSERT_TRUE(spg_parse(f.data(), f.size(), &v).ok());
  const size_t records_at = static_cast<size_t>(v.records - f.data());
  const uint16_t classes = v.header.class_count[0];
  ASSERT_LT(classes, 4096);
  NodeFields fields = unpack_record(v.header.layout, v.records);
  fields[Field::kSigmaP] = classes;  // one past the end
  pack_record(v.header.layout, fields, f.data() + records_at);
  fix_crc(f);
  const SpgResult r = spg_parse(f.data(), f.size(), &v);
  EXPECT_EQ(r.error, SpgError::kBadRecord);
  EXPECT_EQ(r.offset, records_at);
}

TEST(SpgFormat, TopologyAndLeafCountDamage) {
  const std::vector<uint8_t> f = sphere_spg("normals");
  SpgView v;
  ASSERT_TRUE(spg_parse(f.data(), f.size(), &v).ok());
  const size_t topo = static_cast<size_t>(v.topology - f.data());
  const size_t leaves = static_cast<size_t>(v.leaf_counts - f.data());
  std::vector<uint8_t> g = f;
  g[topo] = 0;  // the root becomes a leaf: orphans follow
  fix_crc(g);
  EXPECT_EQ(parse_error(g), SpgError::kBadTree);
  g = f;
  g[leaves] = 0;  // a leaf of zero points
  fix_crc(g);
  EXPECT_EQ(parse_error(g), SpgError::kBadLeafCount);
  g = f;
  g[leaves] = static_cast<uint8_t>(g[leaves] + 1);  // sum no longer matches point_count
  fix_crc(g);
  EXPECT_EQ(parse_error(g), SpgError::kBadLeafCount);
}

}  // namespace
}  // namespace stipple
