// stipple host — LAS reader. See las_io.h.
#include "tools/scan/las_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace stipple {
namespace {

uint16_t u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t u32(const uint8_t* p) { return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24; }
uint64_t u64(const uint8_t* p) { return uint64_t{u32(p)} | uint64_t{u32(p + 4)} << 32; }
int32_t i32(const uint8_t* p) { return static_cast<int32_t>(u32(p)); }
double f64(const uint8_t* p) {
  const uint64_t b = u64(p);
  double v;
  std::memcpy(&v, &b, 8);
  return v;
}

// Public header block offsets (LAS 1.4 R15, table 3; the same in 1.0-1.3).
constexpr size_t kVersionMajor = 24, kVersionMinor = 25, kHeaderSize = 94, kPointOffset = 96, kPointFormat = 104,
                 kRecordLength = 105, kLegacyCount = 107, kScale = 131, kOffset = 155, kCount14 = 247;

// Bytes of each point format's fixed part, and where its RGB starts (0: none).
constexpr uint16_t kFormatBytes[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
constexpr uint16_t kRgbAt[11] = {0, 0, 20, 28, 0, 28, 0, 30, 30, 0, 30};

struct LasClass {
  uint32_t rgb;
  const char* name;
};
constexpr LasClass kClasses[kLasStandardClasses] = {
    {0x9E9E9E, "never classified"}, {0xC8C8C8, "unclassified"}, {0xA0783C, "ground"},
    {0xB4DC82, "low vegetation"},   {0x5AB446, "medium vegetation"}, {0x1E7828, "high vegetation"},
    {0xDC4632, "building"},         {0xFF00FF, "low point (noise)"}, {0xFFD700, "model key point"},
    {0x3C78DC, "water"},            {0x8C5AB4, "rail"},           {0x646464, "road surface"},
    {0xE6B43C, "overlap"},          {0xF0F050, "wire guard"},     {0xF0C850, "wire conductor"},
    {0xC878C8, "transmission tower"}, {0xF0A0A0, "wire connector"}, {0x8C8CB4, "bridge deck"},
    {0xFF5AFF, "high noise"},
};

}  // namespace

uint32_t las_class_rgb(uint8_t c) { return c < kLasStandardClasses ? kClasses[c].rgb : 0x00A0A0; }
const char* las_class_name(uint8_t c) { return c < kLasStandardClasses ? kClasses[c].name : ""; }

bool looks_like_las(const uint8_t* data, size_t size) { return size >= 4 && std::memcmp(data, "LASF", 4) == 0; }

bool parse_las(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error,
               ScanStream* stream, LasColor color_by) {
  cloud = PointCloud{};
  const auto fail = [&](const std::string& what) { return error = name + ": " + what, false; };
  if (!looks_like_las(data, size)) return fail("not a LAS file (no LASF signature)");
  if (size < 227) return fail("the LAS header is cut short: " + std::to_string(size) + " of at least 227 bytes");
  const int major = data[kVersionMajor], minor = data[kVersionMinor];
  if (major != 1 || minor > 4)
    return fail("header byte 24: LAS version " + std::to_string(major) + "." + std::to_string(minor) + " (this reader takes 1.0 to 1.4)");
  const uint16_t header_size = u16(data + kHeaderSize);
  const size_t least = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
  if (header_size < least || header_size > size)
    return fail("header byte 94: a header size of " + std::to_string(header_size) + " bytes (LAS 1." + std::to_string(minor) +
                " needs " + std::to_string(least) + ", the file has " + std::to_string(size) + ")");
  const uint8_t format_byte = data[kPointFormat];
  if (format_byte & 0xC0)
    return fail("this is LAZ (compressed LAS; point format byte " + std::to_string(format_byte) +
                "), which stipple cannot read: Debian has no LASzip decompressor. Decompress it first, for example "
                "`laszip -i in.laz -o out.las` or `pdal translate in.laz out.las`");
  if (format_byte > 10) return fail("header byte 104: point data format " + std::to_string(format_byte) + " (LAS defines 0 to 10)");
  const uint16_t record = u16(data + kRecordLength);
  if (record < kFormatBytes[format_byte])
    return fail("header byte 105: records of " + std::to_string(record) + " bytes, point format " + std::to_string(format_byte) +
                " needs " + std::to_string(kFormatBytes[format_byte]));
  const uint32_t offset = u32(data + kPointOffset);
  if (offset < header_size || offset > size)
    return fail("header byte 96: point data at byte " + std::to_string(offset) + ", outside the file's " + std::to_string(size) +
                " bytes after its " + std::to_string(header_size) + "-byte header");
  uint64_t count = u32(data + kLegacyCount);
  if (minor >= 4 && u64(data + kCount14) != 0) {
    if (count != 0 && count != u64(data + kCount14))
      return fail("header bytes 107 and 247: the legacy point count " + std::to_string(count) + " contradicts the 64-bit one " +
                  std::to_string(u64(data + kCount14)));
    count = u64(data + kCount14);
  }
  if (count == 0) return fail("no points (header byte 107)");
  if (count > (size - offset) / record)
    return fail("header byte 107: " + std::to_string(count) + " points of " + std::to_string(record) + " bytes need more than the " +
                std::to_string(size - offset) + " bytes after byte " + std::to_string(offset));
  double scale[3], shift[3];
  for (int a = 0; a < 3; ++a) {
    scale[a] = f64(data + kScale + 8 * a);
    shift[a] = f64(data + kOffset + 8 * a);
    if (!std::isfinite(scale[a]) || scale[a] == 0)
      return fail("header byte " + std::to_string(kScale + 8 * a) + ": scale factor " + "xyz"[a] + " is " + std::to_string(scale[a]));
    if (!std::isfinite(shift[a])) return fail("header byte " + std::to_string(kOffset + 8 * a) + ": offset " + "xyz"[a] + " is not finite");
  }
  // Where the colour comes from: RGB (none in formats 0, 1, 4, 6, 9), or
  // intensity or classification, which every format has.
  const size_t rgb_at = color_by == LasColor::kRgb ? kRgbAt[format_byte] : 0;
  const bool by_intensity = color_by == LasColor::kIntensity, by_class = color_by == LasColor::kClassification;
  const size_t class_at = format_byte >= 6 ? 16 : 15;
  const uint8_t class_mask = format_byte >= 6 ? 0xFF : 0x1F;
  const uint64_t room = stream ? std::min<uint64_t>(count, kScanChunk) : count;
  cloud.positions.reserve(room);
  if (rgb_at || by_intensity || by_class) cloud.colors.reserve(room);
  uint16_t brightest = 0;
  for (uint64_t i = 0; i < count; ++i) {
    const uint8_t* p = data + offset + i * record;
    const Vec3 position(i32(p) * scale[0] + shift[0], i32(p + 4) * scale[1] + shift[1], i32(p + 8) * scale[2] + shift[2]);
    if (!position.allFinite())  // a scale or offset near the double's range
      return fail("point " + std::to_string(i) + " (byte " + std::to_string(offset + i * record) +
                  "): X * scale + offset is beyond the range of a double");
    cloud.positions.push_back(position);
    if (rgb_at) {
      const uint16_t r = u16(p + rgb_at), g = u16(p + rgb_at + 2), b = u16(p + rgb_at + 4);
      brightest = std::max({brightest, r, g, b});
      cloud.colors.emplace_back(r, g, b);
    } else if (by_intensity) {
      const uint16_t v = u16(p + 12);
      brightest = std::max(brightest, v);
      cloud.colors.emplace_back(v, v, v);
    } else if (by_class) {
      const uint32_t c = las_class_rgb(static_cast<uint8_t>(p[class_at] & class_mask));
      cloud.colors.emplace_back((c >> 16) & 0xFF, (c >> 8) & 0xFF, c & 0xFF);
    }
    if (stream && !stream->flush(cloud, offset + (i + 1) * record, false, error)) return false;
  }
  if (by_class) {
    if (stream) stream->color_divisor = 255.0;
    else
      for (Vec3& c : cloud.colors) c /= 255.0;
    return true;
  }
  if (by_intensity) {
    // Grey, the file's largest intensity white (an all-zero file: black).
    const double top = std::max<uint16_t>(brightest, 1);
    if (stream) stream->color_divisor = top;
    else
      for (Vec3& c : cloud.colors) c /= top;
    if (brightest == 0) cloud.warnings.push_back(name + ": every intensity is 0: --color-by intensity draws it black");
    return true;
  }
  if (rgb_at && brightest == 0) {
    cloud.colors.clear();
    if (stream) stream->color_divisor = 0;
    cloud.warnings.push_back(name + ": every RGB value is 0: read without colour");
  } else if (rgb_at) {
    const bool eight_bit = brightest <= 255;
    if (stream) stream->color_divisor = eight_bit ? 255.0 : 65535.0;
    else
      for (Vec3& c : cloud.colors) c /= eight_bit ? 255.0 : 65535.0;
    if (eight_bit)
      cloud.warnings.push_back(name + ": every RGB value is 255 or less: read as 8-bit colour (LAS stores 16 bits a channel)");
  }
  return true;
}

}  // namespace stipple
