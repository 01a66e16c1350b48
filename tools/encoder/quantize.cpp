// stipple host — field quantizers (TOG05 §5). See quantize.h.
#include "tools/encoder/quantize.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace stipple {
namespace {

constexpr double kPi = std::numbers::pi;

double theta_range(const AngleBits& b) { return b.hemisphere ? kPi / 2 : kPi; }

void rotated_xy(double theta, double phi, Vec3& x, Vec3& y) {
  const double ct = std::cos(theta), st = std::sin(theta), cp = std::cos(phi), sp = std::sin(phi);
  // Rodrigues rotation of the x and y axes by theta about a = (-sin phi, cos phi, 0).
  const Vec3 a(-sp, cp, 0);
  auto rotate = [&](const Vec3& v) { return Vec3(v * ct + a.cross(v) * st + a * a.dot(v) * (1 - ct)); };
  x = rotate(Vec3::UnitX());
  y = rotate(Vec3::UnitY());
}

uint16_t wrap_round(double v, double period, int bits) {
  const double levels = std::ldexp(1.0, bits);
  double q = std::round(v / period * levels);
  q = std::fmod(q, levels);
  if (q < 0) q += levels;
  return static_cast<uint16_t>(q);
}

}  // namespace

AngleBits frame_bits(const RecordLayout& layout, Field theta_field, bool hemisphere) {
  const int t = static_cast<int>(theta_field);
  return AngleBits{layout.bits[t], layout.bits[t + 1], layout.bits[t + 2], hemisphere};
}

FrameCode encode_frame(const Mat3& frame, const AngleBits& bits) {
  Vec3 f1 = frame.col(0), f3 = frame.col(2);
  if (bits.hemisphere && f3.z() < 0) f3 = -f3;  // f1's sign is free as well
  FrameCode code;
  const double theta = std::atan2(std::hypot(f3.x(), f3.y()), f3.z());
  const double max_theta = std::ldexp(1.0, bits.theta) - 1;
  code.theta = static_cast<uint16_t>(std::clamp(std::round(theta / theta_range(bits) * max_theta), 0.0, max_theta));
  const double phi = std::atan2(f3.y(), f3.x());
  code.phi = wrap_round(phi, 2 * kPi, bits.phi);
  Vec3 x, y;
  rotated_xy(code.theta * theta_range(bits) / max_theta, code.phi * 2 * kPi / std::ldexp(1.0, bits.phi), x, y);
  const double psi = std::atan2(f1.dot(y), f1.dot(x));
  code.psi = wrap_round(psi, kPi, bits.psi);
  return code;
}

Mat3 decode_frame(const FrameCode& code, const AngleBits& bits) {
  const double theta = code.theta * theta_range(bits) / (std::ldexp(1.0, bits.theta) - 1);
  const double phi = code.phi * 2 * kPi / std::ldexp(1.0, bits.phi);
  const double psi = code.psi * kPi / std::ldexp(1.0, bits.psi);
  Vec3 x, y;
  rotated_xy(theta, phi, x, y);
  Mat3 m;
  const double c = std::cos(psi), s = std::sin(psi);
  m.col(0) = c * x + s * y;
  m.col(1) = c * y - s * x;
  m.col(2) = x.cross(y);
  return m;
}

uint16_t quantize_cell(double v, double lo, double hi, int bits) {
  const double cells = std::ldexp(1.0, bits);
  if (!(hi > lo)) return 0;
  const double q = std::floor((v - lo) / (hi - lo) * cells);
  return static_cast<uint16_t>(std::clamp(q, 0.0, cells - 1));
}

double dequantize_cell(uint16_t q, double lo, double hi, int bits) {
  if (!(hi > lo)) return lo;
  return lo + (q + 0.5) * (hi - lo) / std::ldexp(1.0, bits);
}

uint16_t quantize_unit(double v, int bits) {
  const double max = std::ldexp(1.0, bits) - 1;
  return static_cast<uint16_t>(std::clamp(std::round(v * max), 0.0, max));
}

double dequantize_unit(uint16_t q, int bits) { return q / (std::ldexp(1.0, bits) - 1); }

uint16_t sigma_p_code(double sigma, double largest_extent) {
  if (!(sigma > 0) || !(largest_extent > 0)) return 0;
  const double r = sigma / largest_extent;  // value = (2048 + m) 2^(e - 42), or m 2^-41 for e = 0
  if (r < std::ldexp(1.0, -30)) return static_cast<uint16_t>(std::nearbyint(std::ldexp(r, 41)));  // 2048 is e = 1, m = 0
  int e2 = 0;
  std::frexp(r, &e2);  // r in [2^(e2-1), 2^e2)
  int e = e2 - 1 + 31;
  if (e > 31) return 0xFFFF;
  double m = std::nearbyint(std::ldexp(r, 42 - e) - 2048);
  if (m >= 2048) m = 0, ++e;  // rounded up into the next binade
  if (e > 31) return 0xFFFF;
  return static_cast<uint16_t>((e << 11) | static_cast<int>(m));
}

double sigma_p_of_code(uint16_t code, double largest_extent) {
  const int e = code >> 11, m = code & 2047;
  return largest_extent * (e == 0 ? std::ldexp(m, -41) : std::ldexp(2048 + m, e - 42));
}

uint16_t q12_code(double value) {
  const double v = static_cast<float>(value) * 4096.0;
  if (!(v > 0)) return 0;
  return static_cast<uint16_t>(std::min(65535.0, std::floor(v + 0.5)));
}

uint16_t q12_signed_code(double value) {
  const double v = static_cast<float>(value) * 4096.0;
  if (!(v == v)) return 0;
  const double rounded = std::clamp(v < 0 ? -std::floor(-v + 0.5) : std::floor(v + 0.5), -32767.0, 32767.0);
  return static_cast<uint16_t>(static_cast<int32_t>(rounded) & 0xFFFF);
}

}  // namespace stipple
