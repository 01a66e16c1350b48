// stipple core — fixed-point node decoder (TOG05 §5, "Decoding").
//
// Model units (MU): the bounding box's largest extent E spans 2^24 MU, with
// the origin at the box minimum, so every mean lies in [0, 2^24] and a node's
// scaled axes f_k * sigma_k, which never exceed E, fit int32 with room to
// spare. (The reference decoder's doubles map to MU by (p - min) * 2^24 / E.)
//
// `init` converts the startup header once — the float32 box and class tables
// become integers by exact binary32 arithmetic (no floating point), the
// angle tables are built — into storage the caller provides
// (`node_decoder_bytes`). `decode` is then allocation-free and integer-only,
// and checks every field against the header: a class index beyond its table
// is `kBadClass` and the node is not written.
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/fixed_range.h"
#include "core/fixed_trig.h"
#include "core/node_format.h"
#include "core/spg_format.h"

namespace stipple {

inline constexpr int kModelUnitBits = 24;  // E = 2^24 MU

enum class DecodeStatus : uint8_t {
  kOk = 0,
  kStorageTooSmall,  // init: fewer bytes than node_decoder_bytes()
  kBadLayout,        // init: an angle field wider than kMaxAngleBits
  kBadClass,         // decode: a class index beyond its table
};

struct FixedNode {
  int32_t mean[3];        // MU
  int32_t axis[3][3];     // axis[k] = f_(k+1) * sigma_(k+1), (x, y, z) in MU
  int16_t normal_frame[3][3];  // Q14; normal_frame[2] is the mean normal (zero without normals)
  int32_t sigma_n[2];     // radians, Q12 (zero without normals); negative: a concave turn
  uint8_t color[3];       // 8-bit RGB expanded from the record's 5-6-5 (zero without colour)
  int32_t color_axis[3][3];  // colour frame * sigma_c, RGB in Q12 (4096 = full range)
};

// A frame field in Euler form, for clients that take frames straight to
// camera space: the Rodrigues rotation of docs/format.md §5 (x and y turned
// by theta about (-sin phi, cos phi, 0), then by psi about f3) is
//   F = Rz(phi) Ry(theta) Rz(gamma),  gamma = psi - phi,
// so a camera R turns it into (R Rz(phi)) Ry(theta) Rz(gamma): a per-frame
// table over phi, then two plane rotations per node. phi and psi are exact
// binary angles (q 2^(32-b_phi), q 2^(31-b_psi)), so gamma is too: a
// multiple of 2^(32 - gamma_bits), gamma_bits = max(b_phi, b_psi + 1), whose
// sine and cosine come from one table of 2^gamma_bits entries.
struct EulerTables {
  const SinCosQ14* theta = nullptr;  // 2^b_theta entries (the field's own)
  const SinCosQ14* phi = nullptr;    // 2^b_phi entries
  const SinCosQ14* gamma = nullptr;  // 2^gamma_bits entries
  uint8_t phi_bits = 0, psi_bits = 0, gamma_bits = 0;
  // The gamma table's index of psi - phi, for field values below 2^bits.
  uint32_t gamma_index(uint32_t q_phi, uint32_t q_psi) const {
    return ((q_psi << (gamma_bits - psi_bits - 1)) - (q_phi << (gamma_bits - phi_bits))) & ((1u << gamma_bits) - 1u);
  }
};

// Which frame field of a record.
enum class FrameField : uint8_t { kPosition, kNormal, kColor };

// Bytes of storage `NodeDecoder::init` needs for this header (tables, 4-byte aligned).
size_t node_decoder_bytes(const SpgHeader& header);

class NodeDecoder {
 public:
  // `view` must come from a successful spg_parse; `storage` (4-byte aligned,
  // at least node_decoder_bytes(view.header) bytes) must outlive the decoder.
  [[nodiscard]] DecodeStatus init(const SpgView& view, void* storage, size_t bytes);

  // Class tables in pieces (a stream of protocol version 4): init over a view
  // without tables (null sigma_p) holds zeros for every class, and
  // set_classes converts `count` classes of table 0 (sigma_p), 1 (sigma_n) or
  // 2 (sigma_c) from `first` on, from values in the header's version
  // (docs/format.md §2); false, and nothing set, beyond the header's count.
  // Which classes have come is the node cache's to know.
  [[nodiscard]] bool set_classes(int table, uint32_t first, uint32_t count, const uint8_t* values);

  // Decodes one packed record (view.record_bytes long).
  [[nodiscard]] DecodeStatus decode(const uint8_t* record, FixedNode* out) const;
  // The same from the record's unpacked fields.
  [[nodiscard]] DecodeStatus decode(const NodeFields& fields, FixedNode* out) const;

  // Extent of the box along each axis, in MU (the largest is 2^24).
  const int32_t* extent_mu() const { return extent_mu_; }

  // The parts of decode, for a client that decodes a record its own way
  // (raster/point_renderer.cpp takes the frames straight to camera space):
  // the unpacker, the mean, a frame field's Euler tables, the colour.
  const RecordUnpacker& unpacker() const { return unpacker_; }
  // Fields checked against the header's class tables (what decode refuses).
  bool classes_valid(const NodeFields& f) const {
    return f[Field::kSigmaP] < header_.class_count[0] &&
           (!header_.has_normals() || f[Field::kSigmaN] < header_.class_count[1]) &&
           (!header_.has_color() || f[Field::kSigmaC] < header_.class_count[2]);
  }
  // The mean in MU: cell centre (q + 1/2) extent / 2^b, rounded.
  int32_t mean_axis_mu(int axis, uint32_t q) const {
    // (2q + 1) extent / 2^(b+1): below 2^17 * 2^32.
    const int64_t v = (2 * static_cast<int64_t>(q) + 1) * axis_scale_q8_[axis];
    const int shift = header_.layout.bits[axis] + 1 + 8;
    return narrow<int32_t>((v + (int64_t{1} << (shift - 1))) >> shift);
  }
  // Every cell centre of one axis, mean_axis_mu(axis, q) for q = 0 .. 2^b - 1,
  // into out[q * stride]: the same sums, one 64-bit addition a cell. Returns 2^b.
  uint32_t mean_axis_cells(int axis, int32_t* out, size_t stride) const {
    const int shift = header_.layout.bits[axis] + 1 + 8;
    const int64_t step = 2 * axis_scale_q8_[axis];
    const uint32_t cells = 1u << header_.layout.bits[axis];
    int64_t v = axis_scale_q8_[axis] + (int64_t{1} << (shift - 1));
    for (uint32_t q = 0; q < cells; ++q, v += step) out[q * stride] = narrow<int32_t>(v >> shift);
    return cells;
  }
  void mean_mu(const NodeFields& f, int32_t out[3]) const {
    for (int a = 0; a < 3; ++a) out[a] = mean_axis_mu(a, f.v[a]);
  }
  // 8-bit RGB of the record's colour fields (zero without colour).
  void color_rgb(const NodeFields& f, uint8_t out[3]) const;
  const EulerTables& euler(FrameField frame) const { return euler_[static_cast<int>(frame)]; }
  // A class's sigmas as the decoder holds them (for a GPU client's tables):
  // sigma_p 3 values in MU, sigma_n 2 in Q12 radians, sigma_c 3 in Q12. The
  // class must be below the header's count for that table.
  const int32_t* sigma_p_mu(ClassId c) const { return sigma_p_ + 3u * index_of(c); }
  const int32_t* sigma_n_q12(ClassId c) const { return sigma_n_ + 2u * index_of(c); }
  const int32_t* sigma_c_q12(ClassId c) const { return sigma_c_ + 3u * index_of(c); }

 private:
  SpgHeader header_{};
  RecordUnpacker unpacker_;
  int64_t axis_scale_q8_[3] = {};  // extent_a / E * 2^32
  int32_t extent_mu_[3] = {};
  FrameTables fp_{}, fn_{}, fc_{};
  EulerTables euler_[3] = {};
  int32_t* sigma_p_ = nullptr;  // 3 per class, MU
  int32_t* sigma_n_ = nullptr;  // 2 per class, Q12 radians
  int32_t* sigma_c_ = nullptr;  // 3 per class, Q12
};

}  // namespace stipple
