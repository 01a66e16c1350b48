// The node stream's protocol (core/protocol.h, core/cobs.h): frames round
// trip through the incremental reader however the bytes are split; every
// class of malformed frame is refused with its status and the reader stays
// in it; message payloads parse only when every field is in range; COBS
// round trips at its block boundaries and a deframer resynchronises after
// line noise.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <vector>

#include "core/cobs.h"
#include "core/protocol.h"
#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

void store_u32le_for_test(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

std::vector<uint8_t> frame(MessageType type, uint16_t seq, const std::vector<uint8_t>& payload) {
  std::vector<uint8_t> out(kMaxFrameBytes);
  const size_t n = write_frame(type, seq, payload.data(), payload.size(), out.data(), out.size());
  EXPECT_GT(n, 0u);
  out.resize(n);
  return out;
}

struct Reader {
  std::vector<uint8_t> storage = std::vector<uint8_t>(kMaxFrameBytes);
  FrameReader r;
  Reader() { r.init(storage.data(), storage.size()); }
};

TEST(Protocol, FramesRoundTripInPiecesOfAnySize) {
  std::vector<uint8_t> stream;
  std::vector<std::vector<uint8_t>> payloads;
  std::mt19937 rng(3);
  for (uint16_t s = 0; s < 40; ++s) {
    std::vector<uint8_t> p(rng() % 300);
    for (uint8_t& b : p) b = static_cast<uint8_t>(rng());
    payloads.push_back(p);
    const std::vector<uint8_t> f = frame(MessageType::kNodes, s, p);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  for (size_t piece : {size_t{1}, size_t{7}, size_t{4096}}) {
    Reader rd;
    size_t got = 0;
    for (size_t at = 0; at < stream.size();) {
      at += rd.r.feed(stream.data() + at, std::min(piece, stream.size() - at));
      Frame f;
      FrameStatus s;
      while ((s = rd.r.next(&f)) == FrameStatus::kOk) {
        ASSERT_EQ(f.sequence, got);
        ASSERT_EQ(std::vector<uint8_t>(f.payload, f.payload + f.payload_bytes), payloads[got]);
        ++got;
      }
      ASSERT_EQ(s, FrameStatus::kNeedMore);
    }
    EXPECT_EQ(got, payloads.size()) << piece;
    EXPECT_EQ(rd.r.finish(), FrameStatus::kOk);
  }
  // A payload too long for a frame is refused by the writer.
  std::vector<uint8_t> big(kMaxPayload + 1), out(kMaxFrameBytes + 8);
  EXPECT_EQ(write_frame(MessageType::kNodes, 0, big.data(), big.size(), out.data(), out.size()), 0u);
}

TEST(Protocol, EveryMalformedFrameClassIsRefusedAndTheReaderStaysConsistent) {
  const std::vector<uint8_t> good = frame(MessageType::kKeepAlive, 0, {1, 2, 3});
  struct Case {
    const char* what;
    std::vector<uint8_t> bytes;
    FrameStatus expect;
  };
  std::vector<Case> cases;
  {
    std::vector<uint8_t> b = good;
    b[9] ^= 0x10;  // a payload bit
    cases.push_back({"bad CRC", b, FrameStatus::kBadChecksum});
  }
  {
    std::vector<uint8_t> b = good;
    b[0] = 0x7E;
    cases.push_back({"unknown type", b, FrameStatus::kUnknownType});
  }
  {
    std::vector<uint8_t> b = good;
    b[1] = 1;
    cases.push_back({"flags", b, FrameStatus::kBadFlags});
  }
  {
    std::vector<uint8_t> b = good;
    store_u32le_for_test(b.data() + 4, static_cast<uint32_t>(kMaxPayload + 1));
    cases.push_back({"oversized", b, FrameStatus::kOversized});
  }
  cases.push_back({"out of sequence", frame(MessageType::kKeepAlive, 5, {}), FrameStatus::kOutOfSequence});
  for (const Case& c : cases) {
    Reader rd;
    rd.r.feed(c.bytes.data(), c.bytes.size());
    Frame f;
    EXPECT_EQ(rd.r.next(&f), c.expect) << c.what;
    // The fault sticks (the stream cannot be trusted past it) until reset.
    EXPECT_EQ(rd.r.next(&f), c.expect) << c.what;
    EXPECT_EQ(rd.r.feed(good.data(), good.size()), 0u) << c.what;
    rd.r.reset();
    rd.r.feed(good.data(), good.size());
    EXPECT_EQ(rd.r.next(&f), FrameStatus::kOk) << c.what;
  }
  // Truncated: the stream ends inside a frame.
  Reader rd;
  rd.r.feed(good.data(), good.size() - 1);
  Frame f;
  EXPECT_EQ(rd.r.next(&f), FrameStatus::kNeedMore);
  EXPECT_EQ(rd.r.finish(), FrameStatus::kTruncated);
  // A reader with less storage than a frame refuses it as oversized.
  std::vector<uint8_t> small(64);
  FrameReader tiny;
  tiny.init(small.data(), small.size());
  const std::vector<uint8_t> long_frame = frame(MessageType::kNodes, 0, std::vector<uint8_t>(100, 7));
  tiny.feed(long_frame.data(), long_frame.size());
  EXPECT_EQ(tiny.next(&f), FrameStatus::kOversized);
  for (FrameStatus s : {FrameStatus::kBadChecksum, FrameStatus::kOutOfSequence, FrameStatus::kTruncated})
    EXPECT_STRNE(frame_status_text(s), "unknown status");
}

TEST(Protocol, MessagesParseOnlyInRange) {
  uint8_t buf[kCameraUpdateBytes];
  Hello h;
  h.width = 320;
  h.height = 240;
  h.attributes = kWantNormals;
  h.cache_capacity = 12345;
  ASSERT_EQ(write_hello(h, buf), kHelloBytes);
  Hello back;
  ASSERT_TRUE(parse_hello(buf, kHelloBytes, &back));
  EXPECT_EQ(back.width, 320);
  EXPECT_EQ(back.attributes, kWantNormals);
  EXPECT_EQ(back.cache_capacity, 12345u);
  EXPECT_FALSE(parse_hello(buf, kHelloBytes - 1, &back));
  buf[7] = 0x40;  // an attribute this version does not know
  EXPECT_FALSE(parse_hello(buf, kHelloBytes, &back));
  buf[7] = kResuming;  // version 3's; version 2 knows neither it nor a token
  EXPECT_TRUE(parse_hello(buf, kHelloBytes, &back));
  buf[0] = 2;
  EXPECT_FALSE(parse_hello(buf, kHelloBytes, &back));
  buf[7] = kWantNormals;
  EXPECT_TRUE(parse_hello(buf, kHelloBytes, &back));
  EXPECT_FALSE(parse_hello(buf, kHelloBytes + 4, &back));  // a token after a version 2 hello
  buf[7] = kWantNormals | kWantCoded;  // version 5's coded batches
  EXPECT_FALSE(parse_hello(buf, kHelloBytes, &back));
  buf[0] = 4;
  EXPECT_FALSE(parse_hello(buf, kHelloBytes, &back));
  buf[0] = 5;
  EXPECT_TRUE(parse_hello(buf, kHelloBytes, &back));
  EXPECT_EQ(back.attributes, kWantNormals | kWantCoded);
  buf[7] = kWantNormals | kWantCurvatureSign;  // version 7's curvature sign
  buf[0] = 6;
  EXPECT_FALSE(parse_hello(buf, kHelloBytes, &back));
  buf[0] = 7;
  EXPECT_TRUE(parse_hello(buf, kHelloBytes, &back));
  EXPECT_EQ(back.attributes, kWantNormals | kWantCurvatureSign);

  CameraUpdate c;
  c.sequence = 9;
  ASSERT_TRUE(orbit_camera(OrbitView{}, 240, 320, &c.camera));
  c.window[2] = 100;
  c.window[3] = 50;
  ASSERT_EQ(write_camera_update(c, buf), kCameraUpdateBytes);
  CameraUpdate cb;
  ASSERT_TRUE(parse_camera_update(buf, kCameraUpdateBytes, &cb));
  EXPECT_EQ(cb.sequence, 9u);
  EXPECT_EQ(std::memcmp(&cb.camera, &c.camera, sizeof c.camera), 0);
  EXPECT_EQ(cb.window[2], 100);
  store_u32le_for_test(buf + 4 + 12 * 4, 0);  // focal length 0
  EXPECT_FALSE(parse_camera_update(buf, kCameraUpdateBytes, &cb));

  // Node batches: exact length, ids below the tree's size; each entry the
  // id, the original points under the node, the record.
  std::vector<uint8_t> p(4 + 2 * (4 + 1 + 13));
  store_u32le_for_test(p.data(), 2);
  store_u32le_for_test(p.data() + 4, 7);
  p[4 + 4] = 12;
  store_u32le_for_test(p.data() + 4 + 18, 99);
  p[4 + 18 + 4] = 255;
  NodeBatch nb;
  ASSERT_TRUE(parse_nodes(p.data(), p.size(), 13, 100, &nb));
  EXPECT_EQ(index_of(nb.id(1)), 99u);
  EXPECT_EQ(nb.points(0), 12);
  EXPECT_EQ(nb.points(1), 255);
  EXPECT_EQ(nb.record(1), p.data() + 4 + 18 + 5);
  EXPECT_FALSE(parse_nodes(p.data(), p.size(), 13, 99, &nb));       // id 99 out of range
  EXPECT_FALSE(parse_nodes(p.data(), p.size() - 1, 13, 100, &nb));  // truncated
  store_u32le_for_test(p.data(), 0xFFFFFFFFu);
  EXPECT_FALSE(parse_nodes(p.data(), p.size(), 13, 100, &nb));  // a count the payload cannot hold
  DropBatch db;
  std::vector<uint8_t> d = {1, 0, 0, 0, 5, 0, 0, 0};
  ASSERT_TRUE(parse_drop(d.data(), d.size(), 6, &db));
  EXPECT_EQ(index_of(db.id(0)), 5u);
  EXPECT_FALSE(parse_drop(d.data(), d.size(), 5, &db));
  Fault fault{CloseReason::kBadFrame, FrameStatus::kBadChecksum, 77}, fb;
  uint8_t fbuf[kFaultBytes];
  write_fault(fault, fbuf);
  ASSERT_TRUE(parse_fault(fbuf, kFaultBytes, &fb));
  EXPECT_EQ(fb.sequence, 77);
  fbuf[0] = 200;
  EXPECT_FALSE(parse_fault(fbuf, kFaultBytes, &fb));
  // Acks and resends: a sequence, then two zero bytes.
  uint8_t sbuf[kSequenceBytes];
  uint16_t seq = 0;
  ASSERT_EQ(write_sequence(0xBEEF, sbuf), kSequenceBytes);
  ASSERT_TRUE(parse_sequence(sbuf, kSequenceBytes, &seq));
  EXPECT_EQ(seq, 0xBEEF);
  EXPECT_FALSE(parse_sequence(sbuf, kSequenceBytes - 1, &seq));
  sbuf[3] = 1;
  EXPECT_FALSE(parse_sequence(sbuf, kSequenceBytes, &seq));
  EXPECT_STREQ(message_type_name(static_cast<uint8_t>(MessageType::kResend)), "resend");
}

TEST(Cobs, RoundTripsAtBlockBoundaries) {
  std::mt19937 rng(11);
  for (size_t n : {size_t{0}, size_t{1}, size_t{253}, size_t{254}, size_t{255}, size_t{508}, size_t{1000}}) {
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<uint8_t> data(n);
      for (uint8_t& b : data) b = kind == 0 ? 0 : kind == 1 ? static_cast<uint8_t>(1 + rng() % 255) : static_cast<uint8_t>(rng() % 4);
      std::vector<uint8_t> enc(cobs_bound(n));
      const size_t m = cobs_encode(data.data(), n, enc.data(), enc.size());
      ASSERT_GT(m, 0u);
      for (size_t i = 0; i + 1 < m; ++i) ASSERT_NE(enc[i], 0) << n << " " << kind;
      ASSERT_EQ(enc[m - 1], 0);
      std::vector<uint8_t> dec(n + 1);
      ASSERT_EQ(cobs_decode(enc.data(), m - 1, dec.data()), n) << n << " " << kind;
      dec.resize(n);
      EXPECT_EQ(dec, data) << n << " " << kind;
    }
  }
  uint8_t out[4];
  EXPECT_EQ(cobs_encode(out, 3, out, 4), 0u);  // capacity below the bound
  const uint8_t bad[] = {5, 1, 2};  // a code pointing past the packet
  EXPECT_EQ(cobs_decode(bad, 3, out), SIZE_MAX);
}

TEST(Cobs, DeframerResynchronisesAfterNoise) {
  std::vector<uint8_t> line;
  std::vector<std::vector<uint8_t>> sent;
  for (uint16_t s = 0; s < 20; ++s) {
    const std::vector<uint8_t> f = frame(MessageType::kKeepAlive, s, std::vector<uint8_t>(30 + s, static_cast<uint8_t>(s)));
    sent.push_back(f);
    std::vector<uint8_t> enc(cobs_bound(f.size()));
    enc.resize(cobs_encode(f.data(), f.size(), enc.data(), enc.size()));
    if (s == 5) enc[10] ^= 0x04;                  // a bit flip: the frame's CRC fails
    if (s == 9) enc.erase(enc.begin() + 3, enc.begin() + 8);  // dropped bytes
    if (s == 13) enc.insert(enc.begin() + 4, 200, 0x55);      // a burst of noise
    line.insert(line.end(), enc.begin(), enc.end());
  }
  std::vector<uint8_t> storage(512);
  CobsDeframer d;
  d.init(storage.data(), storage.size());
  std::vector<int> good;
  for (uint8_t byte : line) {
    if (d.push(byte) != CobsStatus::kPacket) continue;
    // Each packet is checked as a frame on its own (its CRC).
    const size_t n = d.packet_bytes();
    if (n >= kFrameHeaderBytes + kFrameTrailerBytes &&
        load_u32le(d.packet() + n - 4) == crc32(d.packet(), n - 4))
      good.push_back(load_u16le(d.packet() + 2));
  }
  std::vector<int> expect;
  for (int s = 0; s < 20; ++s)
    if (s != 5 && s != 9 && s != 13) expect.push_back(s);
  EXPECT_EQ(good, expect);
}

}  // namespace
// Protocol 3's hello token: carried after the fixed fields, compared whole.
// Protocol 4's messages: a class piece's entries (ascending indices as
// LEB128 differences, each followed by its values) and an update-begin round
// trip; a piece naming a table beyond sigma_c, with a nonzero reserved byte
// or no classes, an entry naming a class twice, truncated values and an
// update-begin of the wrong length or with nonzero padding are refused.
TEST(Protocol, ClassPiecesAndUpdateBeginsRoundTripAndRefuseMalformed) {
  std::vector<uint8_t> p(kClassesHeaderBytes);
  ASSERT_EQ(write_classes_header(1, 3, p.data()), kClassesHeaderBytes);
  const uint32_t indices[3] = {0, 5, 400};
  uint32_t previous = 0xFFFFFFFFu;
  for (uint32_t i : indices) {
    uint8_t leb[5];
    const size_t n = store_leb128(leb, i - previous);
    p.insert(p.end(), leb, leb + n);
    previous = i;
    for (int b = 0; b < 4; ++b) p.push_back(static_cast<uint8_t>(i + b));  // sigma_n: 2 codes
  }
  ClassesPiece c;
  ASSERT_TRUE(parse_classes(p.data(), p.size(), &c));
  EXPECT_EQ(c.table, 1);
  EXPECT_EQ(c.count, 3);
  const uint8_t* at = c.entries;
  const uint8_t* end = c.entries + c.entries_bytes;
  previous = 0xFFFFFFFFu;
  for (uint32_t want : indices) {
    uint32_t index = 0;
    const uint8_t* values = nullptr;
    ASSERT_TRUE(next_class_entry(&at, end, 4, &previous, &index, &values));
    EXPECT_EQ(index, want);
    EXPECT_EQ(values[0], static_cast<uint8_t>(want));
  }
  EXPECT_EQ(at, end);
  {  // truncated values
    const uint8_t* t = c.entries;
    previous = 0xFFFFFFFFu;
    uint32_t index = 0;
    const uint8_t* values = nullptr;
    EXPECT_FALSE(next_class_entry(&t, c.entries + 3, 4, &previous, &index, &values));
  }
  {  // a class twice: a difference of 0
    std::vector<uint8_t> twice = {1, 0, 2, 0, 1, 9, 9, 9, 9, 0, 9, 9, 9, 9};
    ClassesPiece d;
    ASSERT_TRUE(parse_classes(twice.data(), twice.size(), &d));
    const uint8_t* t = d.entries;
    previous = 0xFFFFFFFFu;
    uint32_t index = 0;
    const uint8_t* values = nullptr;
    EXPECT_TRUE(next_class_entry(&t, d.entries + d.entries_bytes, 4, &previous, &index, &values));
    EXPECT_FALSE(next_class_entry(&t, d.entries + d.entries_bytes, 4, &previous, &index, &values));
  }
  EXPECT_FALSE(parse_classes(p.data(), kClassesHeaderBytes, &c));  // no entries
  for (size_t at_byte : {size_t{0}, size_t{1}}) {
    std::vector<uint8_t> bad = p;
    bad[at_byte] = at_byte == 0 ? 3 : 1;
    EXPECT_FALSE(parse_classes(bad.data(), bad.size(), &c)) << at_byte;
  }
  std::vector<uint8_t> none = p;
  none[2] = none[3] = 0;
  EXPECT_FALSE(parse_classes(none.data(), none.size(), &c));

  const UpdateBegin u{77, 14633, 128, 1};
  uint8_t b[kUpdateBeginBytes + 1] = {};
  ASSERT_EQ(write_update_begin(u, b), kUpdateBeginBytes);
  UpdateBegin got;
  ASSERT_TRUE(parse_update_begin(b, kUpdateBeginBytes, &got));
  EXPECT_EQ(got.camera_sequence, 77u);
  EXPECT_EQ(got.entering, 14633u);
  EXPECT_EQ(got.leaving, 128u);
  EXPECT_EQ(got.parts_after, 1);
  EXPECT_FALSE(parse_update_begin(b, kUpdateBeginBytes - 1, &got));
  EXPECT_FALSE(parse_update_begin(b, kUpdateBeginBytes + 1, &got));
  b[15] = 1;
  EXPECT_FALSE(parse_update_begin(b, kUpdateBeginBytes, &got));
  EXPECT_STREQ(message_type_name(0x87), "model");
  EXPECT_STREQ(message_type_name(0x88), "classes");
  EXPECT_STREQ(message_type_name(0x89), "update-begin");
}

// Protocol 4's compact batches: ids ascending as LEB128 differences round
// trip with their points and records; a batch naming an id twice, an id
// beyond the model, a truncated entry, bytes after the last entry or more
// entries than a frame holds is refused whole, before any entry is applied.
TEST(Protocol, CompactBatchesRoundTripAndRefuseMalformed) {
  const size_t record_bytes = 3;
  const uint32_t ids[4] = {0, 1, 200, 70000};
  std::vector<uint8_t> nodes(4), drops(4);
  store_u32le_for_test(nodes.data(), 4);
  store_u32le_for_test(drops.data(), 4);
  uint32_t previous = 0xFFFFFFFFu;
  for (uint32_t id : ids) {
    uint8_t leb[5];
    const size_t n = store_leb128(leb, id - previous);
    EXPECT_EQ(leb128_bytes(id - previous), n);
    previous = id;
    nodes.insert(nodes.end(), leb, leb + n);
    drops.insert(drops.end(), leb, leb + n);
    nodes.push_back(static_cast<uint8_t>(id % 251));                  // points
    for (size_t b = 0; b < record_bytes; ++b) nodes.push_back(static_cast<uint8_t>(id + b));  // record
  }
  CompactBatch b;
  ASSERT_TRUE(parse_compact_nodes(nodes.data(), nodes.size(), record_bytes, 70001, &b));
  ASSERT_EQ(b.count, 4u);
  for (uint32_t want : ids) {
    uint32_t id = 0;
    uint8_t points = 0;
    const uint8_t* record = nullptr;
    next_compact(&b, &id, &points, &record);
    EXPECT_EQ(id, want);
    EXPECT_EQ(points, want % 251);
    EXPECT_EQ(record[1], static_cast<uint8_t>(want + 1));
  }
  ASSERT_TRUE(parse_compact_drop(drops.data(), drops.size(), 70001, &b));
  for (uint32_t want : ids) {
    uint32_t id = 0;
    next_compact(&b, &id, nullptr, nullptr);
    EXPECT_EQ(id, want);
  }
  EXPECT_FALSE(parse_compact_nodes(nodes.data(), nodes.size(), record_bytes, 70000, &b));  // 70000 is beyond
  EXPECT_FALSE(parse_compact_drop(drops.data(), drops.size(), 70000, &b));
  EXPECT_FALSE(parse_compact_nodes(nodes.data(), nodes.size() - 1, record_bytes, 70001, &b));  // truncated
  std::vector<uint8_t> longer = nodes;
  longer.push_back(0);
  EXPECT_FALSE(parse_compact_nodes(longer.data(), longer.size(), record_bytes, 70001, &b));  // a byte after
  std::vector<uint8_t> twice = {2, 0, 0, 0, 5, 0};  // ids 4, then 4 again
  EXPECT_FALSE(parse_compact_drop(twice.data(), twice.size(), 100, &b));
  std::vector<uint8_t> many(4);
  store_u32le_for_test(many.data(), kDropsPerFrame + 1);
  EXPECT_FALSE(parse_compact_drop(many.data(), many.size(), 100, &b));
  EXPECT_FALSE(parse_compact_drop(nodes.data(), 3, 100, &b));
}

// Version 4's camera flags: a camera with accumulate is 96 bytes and round
// trips; 92 bytes still parse (no flags); an unknown flag is refused.
TEST(Protocol, CameraFlagsCarryAccumulation) {
  CameraUpdate u;
  ASSERT_TRUE(orbit_camera(OrbitView{}, 240, 320, &u.camera));
  u.window[0] = 1, u.window[2] = 9;
  uint8_t buf[kCameraUpdateFlagsBytes];
  ASSERT_EQ(write_camera_update(u, buf), kCameraUpdateBytes);
  CameraUpdate back;
  ASSERT_TRUE(parse_camera_update(buf, kCameraUpdateBytes, &back));
  EXPECT_FALSE(back.accumulate);
  u.accumulate = true;
  ASSERT_EQ(write_camera_update(u, buf), kCameraUpdateFlagsBytes);
  ASSERT_TRUE(parse_camera_update(buf, kCameraUpdateFlagsBytes, &back));
  EXPECT_TRUE(back.accumulate);
  EXPECT_EQ(back.window[2], 9);
  buf[kCameraUpdateBytes] = 3;
  EXPECT_FALSE(parse_camera_update(buf, kCameraUpdateFlagsBytes, &back));
  EXPECT_FALSE(parse_camera_update(buf, kCameraUpdateBytes + 2, &back));
}

TEST(Protocol, HelloTokenIsCarriedAndComparedWhole) {
  Hello h;
  const char token[] = "correct horse battery staple";
  h.token_bytes = sizeof token - 1;
  std::memcpy(h.token, token, h.token_bytes);
  uint8_t buf[kHelloMaxBytes];
  const size_t n = write_hello(h, buf);
  ASSERT_EQ(n, kHelloBytes + h.token_bytes);
  Hello back;
  ASSERT_TRUE(parse_hello(buf, n, &back));
  const auto* t = reinterpret_cast<const uint8_t*>(token);
  EXPECT_TRUE(hello_token_matches(back, t, sizeof token - 1));
  EXPECT_FALSE(hello_token_matches(back, t, sizeof token - 2));  // a prefix
  uint8_t wrong[sizeof token];
  std::memcpy(wrong, token, sizeof token);
  wrong[20] ^= 1;
  EXPECT_FALSE(hello_token_matches(back, wrong, sizeof token - 1));
  Hello none;
  EXPECT_FALSE(hello_token_matches(none, t, sizeof token - 1));
  EXPECT_TRUE(hello_token_matches(none, t, 0));
  EXPECT_FALSE(parse_hello(buf, kHelloMaxBytes + 1, &back));
}

// Protocol 3's resume: ids ascending across parts of at most
// kResumePartBytes, each a LEB128 difference; a difference of 0 (a node
// named twice) and a cut-off LEB128 are told apart.
TEST(Protocol, ResumePartsCarryAscendingIdsAndRefuseRepeats) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < 5000; ++i) ids.push_back(i * 37 + (i % 3) * 1000000);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  uint32_t at = 0, previous = 0xFFFFFFFFu, read_previous = 0xFFFFFFFFu;
  std::vector<uint32_t> back;
  int parts = 0;
  for (bool last = false; !last; ++parts) {
    uint8_t part[kResumePartBytes];
    const size_t n = write_resume_part(0xC0FFEE, ids.data(), static_cast<uint32_t>(ids.size()), &at, &previous, part, sizeof part);
    ASSERT_GT(n, kResumeHeaderBytes);
    ResumePart p;
    ASSERT_TRUE(parse_resume_part(part, n, &p));
    EXPECT_EQ(p.model_tag, 0xC0FFEEu);
    EXPECT_EQ(p.total, ids.size());
    last = p.last;
    const uint8_t* cursor = p.ids;
    uint32_t id = 0;
    for (ResumeId r; (r = next_resume_id(&cursor, p.ids + p.ids_bytes, &read_previous, &id)) != ResumeId::kEnd;) {
      ASSERT_EQ(r, ResumeId::kId);
      back.push_back(id);
    }
  }
  EXPECT_EQ(back, ids);
  EXPECT_GT(parts, 1);
  const uint8_t twice[] = {5, 0}, cut_off[] = {5, 0x80};
  uint32_t prev = 0xFFFFFFFFu, id = 0;
  const uint8_t* c = twice;
  EXPECT_EQ(next_resume_id(&c, twice + 2, &prev, &id), ResumeId::kId);
  EXPECT_EQ(id, 4u);
  EXPECT_EQ(next_resume_id(&c, twice + 2, &prev, &id), ResumeId::kRepeated);
  prev = 0xFFFFFFFFu;
  c = cut_off;
  EXPECT_EQ(next_resume_id(&c, cut_off + 2, &prev, &id), ResumeId::kId);
  EXPECT_EQ(next_resume_id(&c, cut_off + 2, &prev, &id), ResumeId::kMalformed);
  const uint8_t bad_flags[kResumeHeaderBytes] = {2};
  ResumePart p;
  EXPECT_FALSE(parse_resume_part(bad_flags, sizeof bad_flags, &p));
}

}  // namespace stipple
