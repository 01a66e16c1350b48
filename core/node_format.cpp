// stipple core — bit packing of node records. See node_format.h.
//
// Fields are at most 16 bits wide and start at any bit, so a field spans at
// most 3 bytes: (bit & 7) + 16 <= 23 < 32. Each field is therefore one
// little-endian 32-bit window read from a zero-padded copy of the record,
// shifted and masked — no per-bit loop, no read past the record.
#include "core/node_format.h"

#include <cstring>

namespace stipple {
namespace {

constexpr int kPaddedBytes = kMaxRecordBytes + 4;

// Targets without unaligned loads (ARMv5) compile each 4-byte memcpy below
// and the record's copy into library calls — nine a node for the paper's
// 13-byte record, about 350 instructions. There each field is read byte by
// byte straight from the record: only the bytes it spans (the record's own,
// never past it), each one load.
#if defined(__arm__) && !defined(__ARM_FEATURE_UNALIGNED)
constexpr bool kFieldsByBytes = true;
#else
constexpr bool kFieldsByBytes = false;
#endif

// Four bytes, little-endian: one load on little-endian targets with
// unaligned loads, byte by byte elsewhere.
inline uint32_t load_window32(const uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if constexpr (!kFieldsByBytes) {
    uint32_t v;
    std::memcpy(&v, p, 4);
    return v;
  }
#endif
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

// The fields of a record, each from window(byte, spans): the 32-bit
// little-endian window from the field's first byte, of which it spans 1-3
// bytes. Inlined into unpack_record and, with a constant layout, into each
// paper layout's unrolled unpack.
template <class Window>
[[gnu::always_inline]] inline NodeFields read_fields_with(const RecordLayout& layout, Window window) {
  NodeFields fields;
  int bit = 0;
#pragma GCC unroll 18
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    if (w == 0) continue;
    fields.v[f] = static_cast<uint16_t>((window(bit >> 3, ((bit & 7) + w + 7) >> 3) >> (bit & 7)) & ((1u << w) - 1u));
    bit += w;
  }
  return fields;
}

// From `buf`, a copy of the record followed by four zero bytes (every
// field's window inside).
[[gnu::always_inline]] inline NodeFields read_fields(const RecordLayout& layout, const uint8_t* buf) {
  return read_fields_with(layout, [buf](int at, int) { return load_window32(buf + at); });
}

// On kFieldsByBytes targets: from the record itself, `bytes` long, only the
// bytes each field spans.
[[gnu::always_inline, maybe_unused]] inline NodeFields read_fields_by_bytes(const RecordLayout& layout, const uint8_t* in, int bytes) {
  return read_fields_with(layout, [in, bytes](int at, int spans) {
    uint32_t v = in[at];
    if (spans > 1 && at + 1 < bytes) v |= static_cast<uint32_t>(in[at + 1]) << 8;
    if (spans > 2 && at + 2 < bytes) v |= static_cast<uint32_t>(in[at + 2]) << 16;
    return v;
  });
}

// unpack_record for one of the paper's layouts: every field's position a
// constant, the record copied by a fixed-size copy (or read by bytes).
template <bool kNormals, bool kColor, int kThin>
NodeFields unpack_paper(const uint8_t* in) {
  static constexpr RecordLayout kLayout = paper_layout(kNormals, kColor, kThin);
  constexpr int kBytes = kLayout.record_bytes();
  if constexpr (kFieldsByBytes) {
    return read_fields_by_bytes(kLayout, in, kBytes);
  } else {
    uint8_t buf[kBytes + 4];
    std::memcpy(buf, in, kBytes);
    std::memset(buf + kBytes, 0, 4);
    return read_fields(kLayout, buf);
  }
}

using UnpackFn = NodeFields (*)(const uint8_t*);
template <bool kNormals, bool kColor>
constexpr UnpackFn kPaperUnpack[3] = {unpack_paper<kNormals, kColor, 0>, unpack_paper<kNormals, kColor, 1>,
                                      unpack_paper<kNormals, kColor, 2>};

bool same_layout(const RecordLayout& a, const RecordLayout& b) {
  for (int f = 0; f < kFieldCount; ++f)
    if (a.bits[f] != b.bits[f]) return false;
  return true;
}

}  // namespace

void pack_record(const RecordLayout& layout, const NodeFields& fields, uint8_t* out) {
  uint8_t buf[kPaddedBytes] = {};
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    if (w == 0) continue;
    const uint32_t value = (static_cast<uint32_t>(fields.v[f]) & ((1u << w) - 1u)) << (bit & 7);
    uint8_t* p = buf + (bit >> 3);
    p[0] = static_cast<uint8_t>(p[0] | value);
    p[1] = static_cast<uint8_t>(p[1] | (value >> 8));
    p[2] = static_cast<uint8_t>(p[2] | (value >> 16));
    bit += w;
  }
  const int bytes = layout.record_bytes();
  for (int i = 0; i < bytes; ++i) out[i] = buf[i];
}

NodeFields unpack_record(const RecordLayout& layout, const uint8_t* in) {
  if constexpr (kFieldsByBytes) return read_fields_by_bytes(layout, in, layout.record_bytes());
  uint8_t buf[kPaddedBytes];
  const int bytes = layout.record_bytes();
  std::memcpy(buf, in, static_cast<size_t>(bytes));
  std::memset(buf + bytes, 0, 4);
  return read_fields(layout, buf);
}

void RecordUnpacker::init(const RecordLayout& layout) {
  *this = RecordUnpacker{};
  const bool normals = layout.bits[static_cast<int>(Field::kSigmaN)] != 0;
  const bool color = layout.bits[static_cast<int>(Field::kSigmaC)] != 0;
  for (int thin = 0; thin < 3; ++thin)
    if (same_layout(layout, paper_layout(normals, color, thin)))
      fixed_ = normals ? (color ? kPaperUnpack<true, true>[thin] : kPaperUnpack<true, false>[thin])
                       : (color ? kPaperUnpack<false, true>[thin] : kPaperUnpack<false, false>[thin]);
  bytes_ = static_cast<uint8_t>(layout.record_bytes());
  tail_at_ = bytes_;
  Slot tail[kFieldCount];
  uint8_t tails = 0;
  int bit = 0;
  for (int f = 0; f < kFieldCount; ++f) {
    const int w = layout.bits[f];
    if (w == 0) continue;
    const Slot s{static_cast<uint8_t>(f), static_cast<uint8_t>(bit >> 3), static_cast<uint8_t>(bit & 7),
                 static_cast<uint16_t>((1u << w) - 1u)};
    if (s.byte + 4 <= bytes_) {
      slots_[direct_++] = s;
    } else {
      tail[tails++] = s;
      if (s.byte < tail_at_) tail_at_ = s.byte;
    }
    bit += w;
  }
  for (uint8_t i = 0; i < tails; ++i) slots_[direct_ + i] = tail[i];
  count_ = static_cast<uint8_t>(direct_ + tails);
}

NodeFields RecordUnpacker::unpack_any(const uint8_t* in) const {
  NodeFields fields;
  for (uint8_t i = 0; i < direct_; ++i) {
    const Slot& s = slots_[i];
    fields.v[s.field] = static_cast<uint16_t>((load_window32(in + s.byte) >> s.shift) & s.mask);
  }
  // The tail: at most 4 bytes (a window starts within 3 of the end), then zeros.
  uint8_t tail[8] = {};
  for (int i = 0; tail_at_ + i < bytes_; ++i) tail[i] = in[tail_at_ + i];
  for (uint8_t i = direct_; i < count_; ++i) {
    const Slot& s = slots_[i];
    fields.v[s.field] = static_cast<uint16_t>((load_window32(tail + (s.byte - tail_at_)) >> s.shift) & s.mask);
  }
  return fields;
}

bool fields_fit(const RecordLayout& layout, const NodeFields& fields) {
  for (int f = 0; f < kFieldCount; ++f) {
    if ((static_cast<uint32_t>(fields.v[f]) >> layout.bits[f]) != 0) return false;
  }
  return true;
}

}  // namespace stipple
