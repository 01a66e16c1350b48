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

#include "core/fixed_trig.h"
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
  int32_t sigma_n[2];     // radians, Q12 (zero without normals)
  uint8_t color[3];       // 8-bit RGB expanded from the record's 5-6-5 (zero without colour)
  int32_t color_axis[3][3];  // colour frame * sigma_c, RGB in Q12 (4096 = full range)
};

// Bytes of storage `NodeDecoder::init` needs for this header (tables, 4-byte aligned).
size_t node_decoder_bytes(const SpgHeader& header);

class NodeDecoder {
 public:
  // `view` must come from a successful spg_parse; `storage` (4-byte aligned,
  // at least node_decoder_bytes(view.header) bytes) must outlive the decoder.
  [[nodiscard]] DecodeStatus init(const SpgView& view, void* storage, size_t bytes);

  // Decodes one packed record (view.record_bytes long).
  [[nodiscard]] DecodeStatus decode(const uint8_t* record, FixedNode* out) const;

  // Extent of the box along each axis, in MU (the largest is 2^24).
  const int32_t* extent_mu() const { return extent_mu_; }
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
  const int32_t* sigma_p_ = nullptr;  // 3 per class, MU
  const int32_t* sigma_n_ = nullptr;  // 2 per class, Q12 radians
  const int32_t* sigma_c_ = nullptr;  // 3 per class, Q12
};

}  // namespace stipple
