// stipple core — packed node records (TOG05 §5, "Classification and quantization").
//
// A node record is a little-endian bit string of quantized fields, packed
// LSB-first in the fixed order of `Field` below. The width of every field comes
// from the `.spg` startup header (`RecordLayout`), so the encoder, the fixed-point
// client and the host reference decoder share one definition.
// The paper's budget (`kPaperLayout`) is 13 bytes without colour, 17 with:
//
//   mu_p        32  (10-11-11; the thinnest bounding-box axis gets 10)
//   f_p         24  (theta 8, phi 10, psi 6)
//   sigma_p     12  class index
//   f_n         24  (theta 8, phi 10, psi 6)     only with normals
//   sigma_n     12  class index                  only with normals
//   mu_c        16  (5-6-5)                      only with colour
//   f_c         10  (theta 4, phi 3, psi 3)      only with colour
//   sigma_c      6  class index                  only with colour
//
// Everything here is integer code: no heap, no exceptions, no floating point.
#pragma once

#include <cstddef>
#include <cstdint>

namespace stipple {

// Distinct index types (draco's lesson): a node id cannot be passed where a
// class id belongs, nor either where a count does. Node ids are breadth-first
// indices into a .spg tree; class ids index a sigma class table.
enum class NodeId : uint32_t {};
enum class ClassId : uint16_t {};
constexpr uint32_t index_of(NodeId id) { return static_cast<uint32_t>(id); }
constexpr uint32_t index_of(ClassId id) { return static_cast<uint32_t>(id); }

enum class Field : uint8_t {
  kPosX, kPosY, kPosZ,
  kFpTheta, kFpPhi, kFpPsi, kSigmaP,
  kFnTheta, kFnPhi, kFnPsi, kSigmaN,
  kColorR, kColorG, kColorB,
  kFcTheta, kFcPhi, kFcPsi, kSigmaC,
};
inline constexpr int kFieldCount = 18;
inline constexpr int kMaxFieldBits = 16;
inline constexpr int kMaxRecordBytes = 32;

// Attribute bits of the startup header's `flags`.
inline constexpr uint16_t kAttrNormals = 1u << 0;
inline constexpr uint16_t kAttrColor = 1u << 1;
// The sigma_n classes are signed (format version 2 on, with normals): a
// negative sigma_n_k is a concave turn along the normal frame's tangent k
// (docs/format.md §2, docs/encoder.md "Curvature sign").
inline constexpr uint16_t kAttrCurvatureSign = 1u << 2;
inline constexpr uint16_t kAttrKnownMask = kAttrNormals | kAttrColor | kAttrCurvatureSign;

// The unpacked integer fields of one record, indexed by `Field`.
struct NodeFields {
  uint16_t v[kFieldCount] = {};
  constexpr uint16_t& operator[](Field f) { return v[static_cast<int>(f)]; }
  constexpr uint16_t operator[](Field f) const { return v[static_cast<int>(f)]; }
};

// Bit widths of every field. A width of 0 means the field is absent (its
// attribute is not in the stream); present fields are 1..16 bits wide.
struct RecordLayout {
  uint8_t bits[kFieldCount] = {};

  constexpr int width(Field f) const { return bits[static_cast<int>(f)]; }
  constexpr int total_bits() const {
    int sum = 0;
    for (uint8_t b : bits) sum += b;
    return sum;
  }
  constexpr int record_bytes() const { return (total_bits() + 7) / 8; }
};

// The paper's layout for the given attributes. `thin_axis` (0, 1 or 2) is the
// bounding-box axis of least extent; it gets 10 bits, the other two 11.
constexpr RecordLayout paper_layout(bool normals, bool color, int thin_axis) {
  RecordLayout l;
  for (int a = 0; a < 3; ++a) l.bits[a] = (a == thin_axis) ? 10 : 11;
  l.bits[static_cast<int>(Field::kFpTheta)] = 8;
  l.bits[static_cast<int>(Field::kFpPhi)] = 10;
  l.bits[static_cast<int>(Field::kFpPsi)] = 6;
  l.bits[static_cast<int>(Field::kSigmaP)] = 12;
  if (normals) {
    l.bits[static_cast<int>(Field::kFnTheta)] = 8;
    l.bits[static_cast<int>(Field::kFnPhi)] = 10;
    l.bits[static_cast<int>(Field::kFnPsi)] = 6;
    l.bits[static_cast<int>(Field::kSigmaN)] = 12;
  }
  if (color) {
    l.bits[static_cast<int>(Field::kColorR)] = 5;
    l.bits[static_cast<int>(Field::kColorG)] = 6;
    l.bits[static_cast<int>(Field::kColorB)] = 5;
    l.bits[static_cast<int>(Field::kFcTheta)] = 4;
    l.bits[static_cast<int>(Field::kFcPhi)] = 3;
    l.bits[static_cast<int>(Field::kFcPsi)] = 3;
    l.bits[static_cast<int>(Field::kSigmaC)] = 6;
  }
  return l;
}
static_assert(paper_layout(true, false, 2).record_bytes() == 13);
static_assert(paper_layout(true, true, 2).record_bytes() == 17);
static_assert(paper_layout(false, false, 2).record_bytes() == 9);

// Writes `fields` into `out[0 .. layout.record_bytes())`, LSB-first in field
// order; padding bits of the last byte are zero. Bits of a field value above
// its width are dropped (the caller quantizes; `fields_fit` checks).
void pack_record(const RecordLayout& layout, const NodeFields& fields, uint8_t* out);

// Reads a record written by `pack_record`. Never reads past
// `in[layout.record_bytes() - 1]`. Fields of width 0 come back as 0.
NodeFields unpack_record(const RecordLayout& layout, const uint8_t* in);

// unpack_record from positions worked out once per layout: the client's
// per-frame path. Fields whose 4-byte window lies inside the record are read
// from it in place; the last few through a zero-padded copy of the record's
// tail. The paper's layouts (any attributes, any thin axis) have their own
// unrolled unpack, every position a constant. Never reads past the record;
// the same fields as unpack_record.
class RecordUnpacker {
 public:
  void init(const RecordLayout& layout);
  NodeFields unpack(const uint8_t* in) const { return fixed_ ? fixed_(in) : unpack_any(in); }

 private:
  NodeFields unpack_any(const uint8_t* in) const;
  NodeFields (*fixed_)(const uint8_t*) = nullptr;
  struct Slot {
    uint8_t field, byte, shift;
    uint16_t mask;
  };
  Slot slots_[kFieldCount] = {};
  uint8_t direct_ = 0, count_ = 0, bytes_ = 0, tail_at_ = 0;
};

// Where field `f` lies in a record: a 32-bit little-endian window read from
// byte `byte` holds it at bit `shift`, `mask` wide (byte + 4 may pass the
// record's end: readers that use this instead of RecordUnpacker make sure
// the bytes are there, e.g. the next record).
struct FieldWindow {
  uint8_t byte = 0, shift = 0;
  uint16_t mask = 0;
};
constexpr FieldWindow field_window(const RecordLayout& layout, Field f) {
  int bit = 0;
  for (int i = 0; i < static_cast<int>(f); ++i) bit += layout.bits[i];
  const int w = layout.bits[static_cast<int>(f)];
  return FieldWindow{static_cast<uint8_t>(bit >> 3), static_cast<uint8_t>(bit & 7),
                     static_cast<uint16_t>(w == 0 ? 0u : (1u << w) - 1u)};
}

// True when every field value fits its width.
bool fields_fit(const RecordLayout& layout, const NodeFields& fields);

}  // namespace stipple
