// stipple core — fixed-point node decoder. See node_decoder.h.
#include "core/node_decoder.h"

#include <initializer_list>

#include "core/fixed_range.h"

namespace stipple {
namespace {

// An exact binary32 value m * 2^e.
struct Dyadic {
  int64_t m = 0;
  int e = 0;
};

Dyadic dyadic_of(uint32_t bits) {
  const int exponent = static_cast<int>((bits >> 23) & 0xFFu);  // finite: checked by spg_parse
  const int64_t mantissa = exponent == 0 ? (bits & 0x7FFFFFu) : ((bits & 0x7FFFFFu) | 0x800000u);
  Dyadic d{mantissa, (exponent == 0 ? -149 : exponent - 150)};
  if (bits >> 31) d.m = -d.m;
  return d;
}

// a - b for two binary32 values (|m| < 2^24). When the exponents differ by
// more than 38 the smaller operand is below 2^-37 of the larger and is
// dropped; otherwise the larger mantissa shifts by at most 38 bits, so the
// result's |m| < 2^62. Only for binary32 operands: a difference fed back in
// could overflow the shift (compare() orders differences).
Dyadic subtract(Dyadic a, Dyadic b) {
  if (a.m == 0) return Dyadic{-b.m, b.e};
  if (b.m == 0) return a;
  if (a.e - b.e > 38) return a;
  if (b.e - a.e > 38) return Dyadic{-b.m, b.e};
  if (a.e > b.e) return Dyadic{(a.m << (a.e - b.e)) - b.m, b.e};
  return Dyadic{a.m - (b.m << (b.e - a.e)), a.e};
}

// Whether a > b, for a, b >= 0 with any mantissa below 2^63: both are
// normalized to a mantissa in [2^62, 2^63) by left shifts (exact), then
// ordered by exponent, then mantissa. No shift can overflow.
bool greater(Dyadic a, Dyadic b) {
  if (a.m <= 0 || b.m <= 0) return a.m > b.m;
  while (a.m < (int64_t{1} << 62)) a.m <<= 1, --a.e;
  while (b.m < (int64_t{1} << 62)) b.m <<= 1, --b.e;
  return a.e != b.e ? a.e > b.e : a.m > b.m;
}

// round(num / den * 2^frac) for num >= 0, den > 0, saturated to [0, limit].
int64_t ratio(Dyadic num, Dyadic den, int frac, int64_t limit) {
  if (num.m <= 0) return 0;
  // Normalize both mantissas to [2^30, 2^31).
  while (num.m >= (int64_t{1} << 31)) num.m >>= 1, ++num.e;
  while (num.m < (int64_t{1} << 30)) num.m <<= 1, --num.e;
  while (den.m >= (int64_t{1} << 31)) den.m >>= 1, ++den.e;
  while (den.m < (int64_t{1} << 30)) den.m <<= 1, --den.e;
  const int64_t q = (num.m << 31) / den.m;  // num.m/den.m * 2^31, in (2^30, 2^32)
  const int shift = num.e - den.e - 31 + frac;
  if (shift >= 0) return shift > 30 || (q << shift) > limit ? limit : q << shift;
  if (-shift > 40) return 0;
  const int64_t v = (q + (int64_t{1} << (-shift - 1))) >> -shift;
  return v > limit ? limit : v;
}

constexpr size_t kAlign = 4;
size_t aligned(size_t n) { return (n + kAlign - 1) / kAlign * kAlign; }

// The Euler form's gamma = psi - phi: a multiple of 2^(32 - gamma_bits).
int gamma_bits_of(const RecordLayout& l, Field theta) {
  const int phi = l.bits[static_cast<int>(theta) + 1], psi = l.bits[static_cast<int>(theta) + 2];
  return phi > psi + 1 ? phi : psi + 1;
}

// Sine/cosine tables of theta, phi, psi and the Euler form's gamma.
size_t frame_table_bytes(const RecordLayout& l, Field theta) {
  const int t = static_cast<int>(theta);
  size_t bytes = 0;
  bool present = true;
  for (int k = 0; k < 3; ++k) {
    if (l.bits[t + k] > 0 && l.bits[t + k] <= kMaxAngleBits)
      bytes += aligned(angle_table_entries(l.bits[t + k]) * sizeof(SinCosQ14));
    else
      present = false;
  }
  if (present) bytes += aligned((size_t{1} << gamma_bits_of(l, theta)) * sizeof(SinCosQ14));
  return bytes;
}

// The box's extent along one axis, and the largest, E (1 for a box that is
// a point: every offset is 0 anyway).
Dyadic axis_extent(const SpgHeader& h, int a) { return subtract(dyadic_of(h.bbox_bits[3 + a]), dyadic_of(h.bbox_bits[a])); }
Dyadic largest_extent(const SpgHeader& h) {
  Dyadic largest;
  for (int a = 0; a < 3; ++a)
    if (greater(axis_extent(h, a), largest)) largest = axis_extent(h, a);
  return largest.m <= 0 ? Dyadic{1, 0} : largest;
}

}  // namespace

size_t node_decoder_bytes(const SpgHeader& h) {
  return frame_table_bytes(h.layout, Field::kFpTheta) + frame_table_bytes(h.layout, Field::kFnTheta) +
         frame_table_bytes(h.layout, Field::kFcTheta) +
         aligned(sizeof(int32_t) * (3u * h.class_count[0] + 2u * h.class_count[1] + 3u * h.class_count[2]));
}

DecodeStatus NodeDecoder::init(const SpgView& view, void* storage, size_t bytes) {
  header_ = view.header;
  const RecordLayout& l = header_.layout;
  for (Field theta : {Field::kFpTheta, Field::kFnTheta, Field::kFcTheta})
    for (int k = 0; k < 3; ++k)  // theta, phi, psi
      if (l.bits[static_cast<int>(theta) + k] > kMaxAngleBits) return DecodeStatus::kBadLayout;
  if (bytes < node_decoder_bytes(header_)) return DecodeStatus::kStorageTooSmall;
  unpacker_.init(l);
  uint8_t* at = static_cast<uint8_t*>(storage);

  // Angle tables, and each frame's Euler form (gamma = psi - phi).
  auto build = [&](Field theta, AngleKind theta_kind, FrameTables& out, EulerTables& euler) {
    const int t = static_cast<int>(theta);
    const SinCosQ14** slots[3] = {&out.theta, &out.phi, &out.psi};
    const AngleKind kinds[3] = {theta_kind, AngleKind::kPhi, AngleKind::kPsi};
    euler = EulerTables{};
    for (int k = 0; k < 3; ++k) {
      const int b = l.bits[t + k];
      if (b == 0) return;
      SinCosQ14* table = reinterpret_cast<SinCosQ14*>(at);
      if (!build_angle_table(kinds[k], b, table, angle_table_entries(b))) return;
      *slots[k] = table;
      at += aligned(angle_table_entries(b) * sizeof(SinCosQ14));
    }
    const int g = gamma_bits_of(l, theta);
    SinCosQ14* gamma = reinterpret_cast<SinCosQ14*>(at);
    for (uint32_t i = 0; i < (1u << g); ++i) gamma[i] = sincos_q14(static_cast<uint32_t>(uint64_t{i} << (32 - g)));
    at += aligned((size_t{1} << g) * sizeof(SinCosQ14));
    euler = EulerTables{out.theta, out.phi, gamma, l.bits[t + 1], l.bits[t + 2], static_cast<uint8_t>(g)};
  };
  build(Field::kFpTheta, AngleKind::kThetaSphere, fp_, euler_[0]);
  build(Field::kFnTheta, AngleKind::kThetaSphere, fn_, euler_[1]);
  build(Field::kFcTheta, AngleKind::kThetaHemisphere, fc_, euler_[2]);

  // Box: extents and the largest, E.
  const Dyadic largest = largest_extent(header_);
  for (int a = 0; a < 3; ++a) {
    axis_scale_q8_[a] = ratio(axis_extent(header_, a), largest, kModelUnitBits + 8, int64_t{1} << (kModelUnitBits + 8));
    extent_mu_[a] = static_cast<int32_t>((axis_scale_q8_[a] + 128) >> 8);
  }

  // Class tables: all of them now, or (a view without tables) zeros until
  // set_classes brings them.
  int32_t* sigmas = reinterpret_cast<int32_t*>(at);
  sigma_p_ = sigmas;
  sigma_n_ = sigma_p_ + 3u * header_.class_count[0];
  sigma_c_ = sigma_n_ + 2u * header_.class_count[1];
  const uint8_t* tables[3] = {view.sigma_p, view.sigma_n, view.sigma_c};
  for (int t = 0; t < 3; ++t) {
    if (header_.class_count[t] == 0) continue;
    if (tables[t] != nullptr) {
      if (!set_classes(t, 0, header_.class_count[t], tables[t])) return DecodeStatus::kBadClass;
    } else {
      int32_t* table = t == 0 ? sigma_p_ : t == 1 ? sigma_n_ : sigma_c_;
      for (uint32_t i = 0; i < spg_class_values(t) * header_.class_count[t]; ++i) table[i] = 0;
    }
  }
  return DecodeStatus::kOk;
}

bool NodeDecoder::set_classes(int table, uint32_t first, uint32_t count, const uint8_t* values) {
  if (table < 0 || table > 2 || first > header_.class_count[table] || count > header_.class_count[table] - first) return false;
  // sigma_p in MU, sigma_n and sigma_c in Q12 — converted from float32
  // (version 1) or read from the 16-bit codes (version 2, where sigma_p is
  // relative to E and sigma_n, sigma_c are Q12 already).
  const bool floats = spg_class_value_bytes(header_.version) == 4;
  const uint32_t per_class = spg_class_values(table);
  int32_t* out = (table == 0 ? sigma_p_ : table == 1 ? sigma_n_ : sigma_c_) + per_class * first;
  if (table == 0) {
    const Dyadic largest = largest_extent(header_);
    const int64_t limit = int64_t{1} << 30;
    for (uint32_t i = 0; i < per_class * count; ++i)
      out[i] = floats ? static_cast<int32_t>(ratio(dyadic_of(load_u32le(values + 4 * i)), largest, kModelUnitBits, limit))
                      : static_cast<int32_t>(spg_sigma_p_code_units(load_u16le(values + 2 * i), kModelUnitBits));
  } else {
    // sigma_n's codes are signed with the curvature sign (concave turns).
    const bool sign = table == 1 && header_.has_curvature_sign();
    for (uint32_t i = 0; i < per_class * count; ++i)
      out[i] = floats ? f32_bits_to_fixed(load_u32le(values + 4 * i), 12, nullptr)
                      : spg_sigma_n_q12(load_u16le(values + 2 * i), sign);
  }
  return true;
}

void NodeDecoder::color_rgb(const NodeFields& f, uint8_t out[3]) const {
  for (int c = 0; c < 3; ++c) {
    const int bits = header_.layout.bits[static_cast<int>(Field::kColorR) + c];
    if (bits == 0) {
      out[c] = 0;
      continue;
    }
    const uint32_t max = (1u << bits) - 1;
    out[c] = static_cast<uint8_t>((f.v[static_cast<int>(Field::kColorR) + c] * 255u + max / 2) / max);
  }
}

DecodeStatus NodeDecoder::decode(const uint8_t* record, FixedNode* out) const {
  return decode(unpacker_.unpack(record), out);
}

DecodeStatus NodeDecoder::decode(const NodeFields& f, FixedNode* out) const {
  const bool normals = header_.has_normals(), color = header_.has_color();
  if (!classes_valid(f)) return DecodeStatus::kBadClass;
  // Straight into *out (the record is valid: nothing below fails); the
  // attributes the model lacks are zero.
  FixedNode& n = *out;
  mean_mu(f, n.mean);
  const FrameQ14 fp = decode_frame_q14(fp_, f[Field::kFpTheta], f[Field::kFpPhi], f[Field::kFpPsi]);
  const int32_t* sp = sigma_p_mu(ClassId{f[Field::kSigmaP]});
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 3; ++c) n.axis[k][c] = mul_q14(fp.axis[k][c], sp[k]);
  if (!normals) {
    for (auto& row : n.normal_frame) row[0] = row[1] = row[2] = 0;
    n.sigma_n[0] = n.sigma_n[1] = 0;
  } else {
    const FrameQ14 fn = decode_frame_q14(fn_, f[Field::kFnTheta], f[Field::kFnPhi], f[Field::kFnPsi]);
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) n.normal_frame[k][c] = fn.axis[k][c];
    const int32_t* sn = sigma_n_q12(ClassId{f[Field::kSigmaN]});
    n.sigma_n[0] = sn[0];
    n.sigma_n[1] = sn[1];
  }
  if (!color) {
    n.color[0] = n.color[1] = n.color[2] = 0;
    for (auto& row : n.color_axis) row[0] = row[1] = row[2] = 0;
  } else {
    color_rgb(f, n.color);
    const FrameQ14 fc = decode_frame_q14(fc_, f[Field::kFcTheta], f[Field::kFcPhi], f[Field::kFcPsi]);
    const int32_t* sc = sigma_c_q12(ClassId{f[Field::kSigmaC]});
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) n.color_axis[k][c] = mul_q14(fc.axis[k][c], sc[k]);
  }
  return DecodeStatus::kOk;
}

}  // namespace stipple
