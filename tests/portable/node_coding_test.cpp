// Entropy-coded node batches (core/node_coding.h, protocol 5): the encoder's
// own trees coded and decoded exactly, every value at its extremes, the
// tables' message round trip, and hostile tables and batches — truncated,
// padded, oversized counts, a byte flipped anywhere — refused without a
// value out of range.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "core/node_coding.h"
#include "core/spg_writer.h"
#include "core/stream.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

struct Bunny : test::ParsedModel {
  std::vector<uint64_t> bounds_storage, sender_storage;
  CutBounds bounds;
  StreamSender sender;  // for its cut's points bytes
  explicit Bunny(const char* rel = "tests/golden/bunny_v1.spg") : ParsedModel(rel) {
    bounds_storage.resize(CutBounds::bytes(view.header) / 8 + 1);
    EXPECT_EQ(bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8), CutStatus::kOk);
    sender_storage.resize(StreamSender::storage_bytes(view.header) / 8 + 1);
    EXPECT_TRUE(sender.init(view, bounds, sender_storage.data(), sender_storage.size() * 8));
  }
  NodeFields fields(uint32_t id) const { return unpack_record(view.header.layout, view.records + size_t{id} * view.record_bytes); }
};
const Bunny& bunny() {
  static const Bunny b;
  return b;
}

// A batch as a sender makes it: nodes with their references, splits with their parents.
struct Batch {
  std::vector<CodedEntry> e;
  void add(uint32_t id, uint8_t p, const NodeFields& f, uint32_t reference_id, const NodeFields& reference) {
    CodedEntry x;
    x.id = id;
    x.points = p;
    x.fields = f;
    x.reference_id = reference_id;
    x.reference = reference;
    e.push_back(x);
  }
  void add_split(uint32_t parent, uint8_t parent_points, const NodeFields& pf, uint32_t id, uint8_t p1, const NodeFields& f1,
                 uint8_t p2, const NodeFields& f2) {
    add(id, p1, f1, parent, pf);
    e.back().kind = 1;
    e.back().reference_points = parent_points;
    add(id + 1, p2, f2, 0xFFFFFFFFu, NodeFields{});
    e.back().kind = 2;
  }
  std::vector<uint8_t> encode(const CodeTables& t) const {
    std::vector<uint8_t> out(kMaxPayload);
    const size_t n = encode_coded_nodes(t, e.data(), static_cast<uint32_t>(e.size()), out.data(), out.size());
    EXPECT_GT(n, 0u);
    out.resize(n);
    return out;
  }
};

bool same_fields(const NodeFields& a, const NodeFields& b) {
  for (int k = 0; k < kFieldCount; ++k)
    if (a.v[k] != b.v[k]) return false;
  return true;
}

// Decodes `payload` with the batch's references and parents; true when it
// decodes whole and exactly to the batch. Values out of range fail the
// test at once.
bool decodes_to(const CodeTables& t, const std::vector<uint8_t>& payload, const Batch& b, uint32_t node_count) {
  CodedBatchReader r;
  if (!r.init(t, payload.data(), payload.size(), node_count)) return false;
  bool same = r.count() == b.e.size();
  uint32_t previous = 0;
  while (r.done() < r.count()) {
    const size_t k = r.done() < b.e.size() ? r.done() : 0;
    CodedBatchReader::Entry x;
    if (!r.next(&x)) return false;
    EXPECT_LT(x.id + x.kind, node_count);
    if (r.done() > 0) {
      EXPECT_GT(x.id, previous);
    }
    const CodedEntry& want = b.e[k];
    NodeFields one, two;
    if (x.kind == 0) {
      if (!r.node(want.reference, want.reference_id + 1u == x.id || want.reference_id == x.id + 1u, &one)) return false;
      same = same && want.kind == 0 && x.id == want.id && x.points == want.points && same_fields(one, want.fields);
      previous = x.id;
    } else {
      uint8_t second_points = 0;
      if (!r.split(want.reference, want.reference_points, &one, &two, &second_points)) return false;
      EXPECT_LT(x.parent, node_count);
      same = same && want.kind == 1 && k + 1 < b.e.size() && x.parent == want.reference_id && x.id == want.id &&
             x.points == want.points && same_fields(one, want.fields) && second_points == b.e[k + 1].points &&
             same_fields(two, b.e[k + 1].fields);
      for (int field = 0; field < kFieldCount; ++field) EXPECT_LT(uint32_t{two.v[field]}, 1u << t.layout.bits[field]);
      previous = x.id + 1;
    }
    for (int field = 0; field < kFieldCount; ++field) EXPECT_LT(uint32_t{one.v[field]}, 1u << t.layout.bits[field]);
  }
  return r.finish() && same;
}

TEST(NodeCoding, TheEncodersOwnTreeRoundTripsExactly) {
  const Bunny& m = bunny();
  CodeTables t;
  build_code_tables(m.view, m.sender.cut(), m.view.header, 32768, &t);
  // Every node of the tree, in batches of 500 as a part sends them: each
  // entry referring to the node before it.
  const uint32_t n = m.view.header.node_count;
  size_t coded = 0;
  for (uint32_t first = 0; first < n; first += 500) {
    Batch b;
    for (uint32_t id = first; id < n && id < first + 500; ++id)
      b.add(id, m.sender.cut().points(NodeId{id}), m.fields(id), id > 0 ? id - 1 : 0xFFFFFFFFu,
            id > 0 ? m.fields(id - 1) : NodeFields{});
    const std::vector<uint8_t> payload = b.encode(t);
    coded += payload.size();
    ASSERT_TRUE(decodes_to(t, payload, b, n)) << "batch at " << first;
  }
  // A record and its points byte (13 + 1 bytes) in fewer bytes, ids included.
  std::printf("the bunny's %u nodes: %zu bytes coded, %.2f a node (records %zu)\n", n, coded,
              static_cast<double>(coded) / n, m.view.record_bytes);
  EXPECT_LT(coded, size_t{n} * (m.view.record_bytes + 1) * 7 / 8);
  // The tables cross the wire and come back the same.
  std::vector<uint8_t> message(4096);
  message.resize(write_code_tables(t, message.data(), message.size()));
  ASSERT_GT(message.size(), 4u);
  CodeTables back;
  ASSERT_TRUE(parse_code_tables(message.data(), message.size(), m.view.header, &back));
  EXPECT_EQ(back.delta_fields, t.delta_fields);
  EXPECT_EQ(back.frame_fields, t.frame_fields);
  // The sample chose the normal frame's θ and φ against the node's own
  // position frame (fp's f3 follows the mean normal, fn's z is it).
  const uint32_t frame_angles = 3u << static_cast<int>(Field::kFnTheta);
  EXPECT_EQ(t.frame_fields & frame_angles, frame_angles);
  for (int k = 0; k < kCodeModels; ++k) {
    ASSERT_EQ(back.model[k].count, t.model[k].count) << "model " << k;
    for (int i = 0; i <= t.model[k].count; ++i) ASSERT_EQ(back.model[k].cum[i], t.model[k].cum[i]) << "model " << k;
    for (int b = 0; b < (1 << kCodeStartBits); ++b) ASSERT_EQ(back.model[k].start[b], t.model[k].start[b]) << "model " << k;
  }
}

// Tables with every token alike, for layouts no scan has.
CodeTables flat_tables(const RecordLayout& layout, uint32_t delta_fields) {
  CodeTables t;
  t.layout = layout;
  t.delta_fields = delta_fields;
  for (int k = 0; k < kCodeModels; ++k) {
    const int field = (k - 4) / 4;
    const int bits = k == kIdModel || k == kParentModel ? 32
                     : k == kPointsModel                ? 8
                     : k == kKindModel                  ? 1
                     : (k - 4) % 4 == kSplitContext && !is_position_field(field) ? 0
                                                                                  : layout.bits[field];
    if (bits == 0) continue;
    CodeModel& m = t.model[k];
    m.count = static_cast<uint8_t>(tokens_for_bits(bits));
    for (int i = 0; i <= m.count; ++i) m.cum[i] = static_cast<uint16_t>(i * kCodeTotal / m.count);
    index_code_model(&m);
  }
  return t;
}

TEST(NodeCoding, EveryValueAtItsExtremesRoundTrips) {
  RecordLayout wide;
  for (int f = 0; f < kFieldCount; ++f) wide.bits[f] = static_cast<uint8_t>(1 + f % 16);  // 1 .. 16 bits
  wide.bits[5] = 16;
  // The normal frame's angles as they are, against the reference, and
  // against the position frame's of other widths (4 -> 8, 5 -> 9, 16 -> 10 bits).
  constexpr uint32_t kFrame = 7u << static_cast<int>(Field::kFnTheta);
  for (uint32_t delta : {0u, (1u << kFieldCount) - 1u, 0x2AAAAu, 0x3FFFFu & ~kFrame, 0x10000u}) {
    CodeTables t = flat_tables(wide, delta);
    if (delta == (0x3FFFFu & ~kFrame) || delta == 0x10000u) t.frame_fields = kFrame;
    Batch b;
    const uint32_t ids[] = {0, 1, 2, 17, 0x7FFFFFFFu, 0xFFFFFFF0u, 0xFFFFFFFDu};
    for (size_t i = 0; i < std::size(ids); ++i) {
      NodeFields f, r;
      for (int k = 0; k < kFieldCount; ++k) {
        const uint32_t max = (1u << wide.bits[k]) - 1u;
        f.v[k] = static_cast<uint16_t>(i % 3 == 0 ? 0 : i % 3 == 1 ? max : (max / 3) * (i % 5));
        r.v[k] = static_cast<uint16_t>(i % 2 ? max - f.v[k] : f.v[k] / 2);  // the largest differences both ways
      }
      b.add(ids[i], static_cast<uint8_t>(i % 2 ? 255 : i), f, i > 0 ? ids[i - 1] : 0xFFFFFFFFu, r);
      if (ids[i] == 17) {
        // Two splits: a saturated parent (the second child's points sent)
        // and one that gives them; children at the field's ends.
        NodeFields lo, hi;
        for (int k = 0; k < kFieldCount; ++k) hi.v[k] = static_cast<uint16_t>((1u << wide.bits[k]) - 1u);
        b.add_split(5, 255, hi, 20, 3, lo, 200, hi);
        b.add_split(6, 30, lo, 22, 10, hi, 20, lo);
      }
    }
    ASSERT_TRUE(decodes_to(t, b.encode(t), b, 0xFFFFFFFEu)) << "deltas " << delta;
    // The same batch in a model of fewer nodes is refused at its first id beyond.
    EXPECT_FALSE(decodes_to(t, b.encode(t), b, 0x7FFFFFFFu));
  }
}

// A node's two children as a split against it cost less than as two nodes
// against each other (what a refinement saves: split deltas).
TEST(NodeCoding, SplitsCostLessThanTheirChildrenAsNodes) {
  const Bunny& m = bunny();
  CodeTables t;
  build_code_tables(m.view, m.sender.cut(), m.view.header, 32768, &t);
  const ViewCut& cut = m.sender.cut();
  Batch splits, nodes;
  uint32_t pairs = 0;
  for (uint32_t parent = 300; parent < 1500; ++parent) {
    const uint32_t c = cut.first_child(parent);
    if (cut.first_child(parent + 1) != c + 2) continue;
    const auto points = [&](uint32_t id) { return cut.points(NodeId{id}); };
    splits.add_split(parent, points(parent), m.fields(parent), c, points(c), m.fields(c), points(c + 1), m.fields(c + 1));
    nodes.add(c, points(c), m.fields(c), nodes.e.empty() ? 0xFFFFFFFFu : nodes.e.back().id,
              nodes.e.empty() ? NodeFields{} : nodes.e.back().fields);
    nodes.add(c + 1, points(c + 1), m.fields(c + 1), c, m.fields(c));
    ++pairs;
  }
  const std::vector<uint8_t> as_splits = splits.encode(t), as_nodes = nodes.encode(t);
  ASSERT_TRUE(decodes_to(t, as_splits, splits, m.view.header.node_count));
  ASSERT_TRUE(decodes_to(t, as_nodes, nodes, m.view.header.node_count));
  std::printf("%u refinements: %zu bytes as splits, %zu as nodes (%.2f bytes saved a refinement)\n", pairs,
              as_splits.size(), as_nodes.size(),
              static_cast<double>(as_nodes.size() - as_splits.size()) / pairs);
  EXPECT_LT(as_splits.size(), as_nodes.size() * 9 / 10);
}

// Coded classes (format version 2): the bunny's class tables in two
// pieces a table, exact; every truncation, a padded piece, every bit flip,
// a count beyond the table and a table without classes refused.
TEST(NodeCoding, ClassPiecesRoundTripExactly) {
  const Bunny m("tests/golden/bunny_v2.spg");
  CodeTables t;
  build_code_tables(m.view, m.sender.cut(), m.view.header, 32768, &t);
  ASSERT_TRUE(t.classes);
  // The encoder numbers classes by size: σ1 goes against the class before
  // it in the piece (bit 0 of each table), σ2 against σ1 and so on; not
  // for a version 5 client, which reads neither that nor frame fields.
  EXPECT_EQ(t.class_delta & 0x9u, 0x9u);
  CodeTables five;
  build_code_tables(m.view, m.sender.cut(), m.view.header, 32768, &five, 5);
  EXPECT_EQ(five.class_delta & 0x9u, 0u);
  EXPECT_EQ(five.frame_fields, 0u);
  EXPECT_NE(t.frame_fields, 0u);
  // The tables with class models cross the wire and come back the same.
  std::vector<uint8_t> message(8192);
  message.resize(write_code_tables(t, message.data(), message.size()));
  CodeTables back;
  ASSERT_TRUE(parse_code_tables(message.data(), message.size(), m.view.header, &back));
  EXPECT_EQ(back.class_delta, t.class_delta);
  const uint8_t* tables[3] = {m.view.sigma_p, m.view.sigma_n, m.view.sigma_c};
  size_t coded = 0, plain = 0;
  for (int table = 0; table < 2; ++table) {
    const uint32_t k = spg_class_values(table), n = m.view.header.class_count[table];
    for (int piece = 0; piece < 2; ++piece) {
      std::vector<uint16_t> indices;
      std::vector<uint8_t> values;
      for (uint32_t c = 0; c < n; ++c)
        if ((c % 3 == 0) == (piece == 0)) {
          indices.push_back(static_cast<uint16_t>(c));
          values.insert(values.end(), tables[table] + 2 * k * c, tables[table] + 2 * k * (c + 1));
        }
      std::vector<uint8_t> payload(kMaxPayload);
      payload.resize(encode_coded_classes(back, table, indices.data(), values.data(),
                                          static_cast<uint32_t>(indices.size()), payload.data(), payload.size()));
      ASSERT_GT(payload.size(), 0u);
      coded += payload.size();
      plain += 4 + indices.size() * (1 + 2 * k);
      const auto decodes = [&](const std::vector<uint8_t>& bytes) {
        CodedClassesReader r;
        if (!r.init(back, bytes.data(), bytes.size())) return false;
        bool same = r.table() == table && r.count() == indices.size();
        for (uint32_t i = 0; i < r.count(); ++i) {
          uint32_t index = 0;
          uint8_t v[6];
          if (!r.next(&index, v)) return false;
          EXPECT_LT(index, n);
          same = same && i < indices.size() && index == indices[i] && std::equal(v, v + 2 * k, values.begin() + 2 * k * i);
        }
        return r.finish() && same;
      };
      ASSERT_TRUE(decodes(payload)) << "table " << table << " piece " << piece;
      for (size_t cut = 0; cut < payload.size(); cut += 7)
        EXPECT_FALSE(decodes(std::vector<uint8_t>(payload.begin(), payload.begin() + static_cast<ptrdiff_t>(cut))));
      std::vector<uint8_t> padded = payload;
      padded.push_back(0);
      EXPECT_FALSE(decodes(padded));
      for (size_t at = 4; at < payload.size(); at += 5) {
        std::vector<uint8_t> damaged = payload;
        damaged[at] ^= 0x10;
        EXPECT_FALSE(decodes(damaged)) << "byte " << at;
      }
      std::vector<uint8_t> more = payload;
      store_u16le(more.data() + 2, static_cast<uint16_t>(n + 1));
      EXPECT_FALSE(decodes(more));
      more = payload;
      more[0] = 2;  // sigma_c: the bunny has none
      EXPECT_FALSE(decodes(more));
    }
  }
  std::printf("the bunny's %u + %u classes: %zu bytes coded, %zu as classes messages\n", m.view.header.class_count[0],
              m.view.header.class_count[1], coded, plain);
  EXPECT_LT(coded, plain * 9 / 10);
}

TEST(NodeCoding, HostileTablesAreRefused) {
  SpgHeader header;  // format version 1: no class models
  header.version = 1;
  header.layout = paper_layout(true, false, 2);
  const SpgHeader& layout = header;
  const CodeTables t = flat_tables(header.layout, 1u << static_cast<int>(Field::kPosX));
  std::vector<uint8_t> good(4096);
  good.resize(write_code_tables(t, good.data(), good.size()));
  CodeTables out;
  ASSERT_TRUE(parse_code_tables(good.data(), good.size(), layout, &out));
  for (size_t n = 0; n < good.size(); ++n) EXPECT_FALSE(parse_code_tables(good.data(), n, layout, &out)) << "cut at " << n;
  std::vector<uint8_t> longer = good;
  longer.push_back(0);
  EXPECT_FALSE(parse_code_tables(longer.data(), longer.size(), layout, &out));
  // Tables for another layout (colour fields it lacks) do not parse as this one's.
  SpgHeader colour = header;
  colour.layout = paper_layout(true, true, 2);
  EXPECT_FALSE(parse_code_tables(good.data(), good.size(), colour, &out));
  // A version 2 header expects class models, which these tables lack.
  SpgHeader v2 = header;
  v2.version = 2;
  EXPECT_FALSE(parse_code_tables(good.data(), good.size(), v2, &out));
  // A difference for a field the layout lacks, or beyond the fields.
  std::vector<uint8_t> bad = good;
  bad[2] = 0x02;  // bit 17: sigma_c
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  bad = good;
  bad[3] = 0x80;  // bit 31
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  bad = good;
  bad[2] = 0x10;  // bit 20: between the delta and the frame fields
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  // The normal frame's θ from the position frame's (bit 24): this layout
  // has normals; both ways for one field, or without normals, refused.
  bad = good;
  bad[3] = 0x01;
  ASSERT_TRUE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  EXPECT_EQ(out.frame_fields, 1u << static_cast<int>(Field::kFnTheta));
  EXPECT_EQ(out.delta_fields, 1u << static_cast<int>(Field::kPosX));
  bad[0] = static_cast<uint8_t>(bad[0] | 1u << static_cast<int>(Field::kFnTheta));
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  SpgHeader bare = header;
  bare.layout = paper_layout(false, false, 2);
  CodeTables no_normals = flat_tables(bare.layout, 0);
  std::vector<uint8_t> plain(4096);
  plain.resize(write_code_tables(no_normals, plain.data(), plain.size()));
  ASSERT_TRUE(parse_code_tables(plain.data(), plain.size(), bare, &out));
  plain[3] = 0x02;  // bit 25: fn φ
  EXPECT_FALSE(parse_code_tables(plain.data(), plain.size(), bare, &out));
  // The id model: no tokens, more than its alphabet, frequencies that do not add up.
  bad = good;
  bad[4] = 0;
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  bad = good;
  bad[4] = kMaxTokens + 1;
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
  bad = good;
  bad[5] = static_cast<uint8_t>(bad[5] + 1);  // the first frequency one more
  EXPECT_FALSE(parse_code_tables(bad.data(), bad.size(), layout, &out));
}

TEST(NodeCoding, TruncatedPaddedAndDamagedBatchesAreRefused) {
  const Bunny& m = bunny();
  CodeTables t;
  build_code_tables(m.view, m.sender.cut(), m.view.header, 4096, &t);
  Batch b;
  for (uint32_t id = 200; id < 260; id += 2)
    b.add(id, m.sender.cut().points(NodeId{id}), m.fields(id), id - 2, m.fields(id - 2));
  const std::vector<uint8_t> payload = b.encode(t);
  const uint32_t n = m.view.header.node_count;
  ASSERT_TRUE(decodes_to(t, payload, b, n));
  for (size_t k = 0; k < payload.size(); ++k) {
    const std::vector<uint8_t> cut(payload.begin(), payload.begin() + static_cast<ptrdiff_t>(k));
    EXPECT_FALSE(decodes_to(t, cut, b, n)) << "truncated to " << k;
  }
  std::vector<uint8_t> padded = payload;
  padded.push_back(0);
  EXPECT_FALSE(decodes_to(t, padded, b, n));
  // A count beyond the model's nodes, or one more than the stream holds.
  std::vector<uint8_t> more = payload;
  store_u32le(more.data(), n + 1);
  CodedBatchReader r;
  EXPECT_FALSE(r.init(t, more.data(), more.size(), n));
  store_u32le(more.data(), static_cast<uint32_t>(b.e.size() + 1));
  EXPECT_FALSE(decodes_to(t, more, b, n));
  // A byte flipped anywhere: no value out of range (decodes_to checks each),
  // and never the batch it was.
  for (size_t k = 4; k < payload.size(); ++k)
    for (const uint8_t bit : {uint8_t{1}, uint8_t{0x80}}) {
      std::vector<uint8_t> damaged = payload;
      damaged[k] ^= bit;
      EXPECT_FALSE(decodes_to(t, damaged, b, n)) << "byte " << k << " bit " << int{bit};
    }
}

}  // namespace
}  // namespace stipple
