// stipple host — PCD reader. See pcd_io.h.
#include "tools/scan/pcd_io.h"

#include <lzf.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <vector>

namespace stipple {
namespace {

struct Field {
  std::string name;
  size_t size = 4;
  char type = 'F';  // F float, I signed, U unsigned
  size_t count = 1;
  size_t offset = 0;  // within a packed record
  int slot = -1;      // what it is read into: 0-2 x y z, 3-5 the normal, 6 rgb/rgba; -1 skipped
};

struct Header {
  std::vector<Field> fields;
  uint64_t width = 0, height = 1, points = 0;
  bool has_points = false;
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};
  std::string data;
  size_t record = 0;  // bytes of a packed record
};

std::vector<std::string> words(const char* begin, const char* end) {
  std::vector<std::string> out;
  const char* p = begin;
  while (p < end) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    const char* q = p;
    while (q < end && *q != ' ' && *q != '\t' && *q != '\r') ++q;
    if (q > p) out.emplace_back(p, q);
    p = q;
  }
  return out;
}

bool parse_u64(const std::string& s, uint64_t& v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_f64(const std::string& s, double& v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// A value of a field, as a double (integers exactly up to 2^53).
double value_of(const Field& f, const uint8_t* p) {
  uint64_t u = 0;
  for (size_t i = 0; i < f.size; ++i) u |= uint64_t{p[i]} << (8 * i);
  if (f.type == 'F') {
    if (f.size == 4) {
      float x;
      const uint32_t b = static_cast<uint32_t>(u);
      std::memcpy(&x, &b, 4);
      return x;
    }
    double x;
    std::memcpy(&x, &u, 8);
    return x;
  }
  if (f.type == 'U') return static_cast<double>(u);
  const uint64_t sign = uint64_t{1} << (8 * f.size - 1);
  return u & sign ? static_cast<double>(static_cast<int64_t>(u | ~((sign << 1) - 1))) : static_cast<double>(u);
}

// rgb / rgba: four bytes, B G R A in memory (PCL packs 0xAARRGGBB, little-endian).
Vec3 color_of(const uint8_t* p) { return Vec3(p[2], p[1], p[0]) / 255.0; }

}  // namespace

bool looks_like_pcd(const uint8_t* data, size_t size) {
  // PCL writes "# .PCD v0.7 - Point Cloud Data file format" first, but any
  // comment lines may come before the header's first keyword.
  size_t pos = 0;
  while (pos < size && data[pos] == '#') {
    if (size - pos >= 6 && std::memcmp(data + pos, "# .PCD", 6) == 0) return true;
    while (pos < size && data[pos] != '\n') ++pos;
    ++pos;
  }
  const auto starts = [&](const char* s) {
    return pos < size && size - pos >= std::strlen(s) && std::memcmp(data + pos, s, std::strlen(s)) == 0;
  };
  return starts("VERSION ") || starts("VERSION\t") || starts("FIELDS ") || starts("FIELDS\t");
}

bool parse_pcd(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error,
               ScanStream* stream) {
  cloud = PointCloud{};
  Header h;
  size_t pos = 0;
  int line_no = 0;
  const auto fail = [&](const std::string& what) { return error = name + ": " + what, false; };
  const auto at_line = [&](const std::string& what) { return fail("header line " + std::to_string(line_no) + ": " + what); };
  std::vector<std::string> sizes, types, counts;
  // §1 the header, up to and including the DATA line.
  while (h.data.empty()) {
    if (pos >= size) return fail("the header ends before its DATA line");
    size_t eol = pos;
    while (eol < size && data[eol] != '\n') ++eol;
    const char* begin = reinterpret_cast<const char*>(data + pos);
    const char* end = reinterpret_cast<const char*>(data + eol);
    pos = eol < size ? eol + 1 : size;
    ++line_no;
    if (begin < end && *begin == '#') continue;
    for (const char* c = begin; c < end; ++c)
      if (static_cast<unsigned char>(*c) < 0x09 || (static_cast<unsigned char>(*c) > 0x0D && static_cast<unsigned char>(*c) < 0x20))
        return at_line("a control character: not a PCD header");
    const std::vector<std::string> w = words(begin, end);
    if (w.empty()) continue;
    const std::string& key = w[0];
    if (key == "VERSION") continue;
    if (key == "FIELDS" || key == "COLUMNS") {
      h.fields.clear();
      for (size_t i = 1; i < w.size(); ++i) h.fields.push_back(Field{w[i]});
    } else if (key == "SIZE") {
      sizes.assign(w.begin() + 1, w.end());
    } else if (key == "TYPE") {
      types.assign(w.begin() + 1, w.end());
    } else if (key == "COUNT") {
      counts.assign(w.begin() + 1, w.end());
    } else if (key == "WIDTH") {
      if (w.size() != 2 || !parse_u64(w[1], h.width)) return at_line("WIDTH: expected one count");
    } else if (key == "HEIGHT") {
      if (w.size() != 2 || !parse_u64(w[1], h.height) || h.height == 0) return at_line("HEIGHT: expected one count, at least 1");
    } else if (key == "POINTS") {
      if (w.size() != 2 || !parse_u64(w[1], h.points)) return at_line("POINTS: expected one count");
      h.has_points = true;
    } else if (key == "VIEWPOINT") {
      if (w.size() != 8) return at_line("VIEWPOINT: expected tx ty tz qw qx qy qz");
      for (int i = 0; i < 7; ++i)
        if (!parse_f64(w[1 + i], h.viewpoint[i]) || !std::isfinite(h.viewpoint[i]))
          return at_line("VIEWPOINT: '" + w[1 + i] + "' is not a finite number");
    } else if (key == "DATA") {
      if (w.size() != 2 || (w[1] != "ascii" && w[1] != "binary" && w[1] != "binary_compressed"))
        return at_line("DATA: expected ascii, binary or binary_compressed");
      h.data = w[1];
    } else {
      return at_line("unknown keyword '" + key.substr(0, 32) + "'");
    }
  }
  // The fields' layout.
  if (h.fields.empty()) return fail("no FIELDS line");
  if (sizes.size() != h.fields.size()) return fail("SIZE has " + std::to_string(sizes.size()) + " entries for " + std::to_string(h.fields.size()) + " fields");
  if (types.size() != h.fields.size()) return fail("TYPE has " + std::to_string(types.size()) + " entries for " + std::to_string(h.fields.size()) + " fields");
  if (!counts.empty() && counts.size() != h.fields.size())
    return fail("COUNT has " + std::to_string(counts.size()) + " entries for " + std::to_string(h.fields.size()) + " fields");
  int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, irgb = -1;
  for (size_t i = 0; i < h.fields.size(); ++i) {
    Field& f = h.fields[i];
    uint64_t s = 0, c = 1;
    if (!parse_u64(sizes[i], s) || (s != 1 && s != 2 && s != 4 && s != 8)) return fail("field " + f.name + ": SIZE '" + sizes[i] + "' is not 1, 2, 4 or 8");
    if (types[i].size() != 1 || (types[i][0] != 'F' && types[i][0] != 'I' && types[i][0] != 'U'))
      return fail("field " + f.name + ": TYPE '" + types[i] + "' is not F, I or U");
    if (types[i][0] == 'F' && s != 4 && s != 8) return fail("field " + f.name + ": a float of " + sizes[i] + " bytes");
    if (!counts.empty() && (!parse_u64(counts[i], c) || c == 0 || c > 4096)) return fail("field " + f.name + ": COUNT '" + counts[i] + "' is not 1..4096");
    f.size = s;
    f.type = types[i][0];
    f.count = c;
    f.offset = h.record;
    h.record += s * c;
    int* slot = f.name == "x" ? &ix : f.name == "y" ? &iy : f.name == "z" ? &iz : f.name == "normal_x" ? &inx
              : f.name == "normal_y" ? &iny : f.name == "normal_z" ? &inz : f.name == "rgb" || f.name == "rgba" ? &irgb : nullptr;
    if (slot != nullptr) {
      if (*slot >= 0) return fail("field " + f.name + " appears twice");
      if (c != 1) return fail("field " + f.name + ": COUNT must be 1");
      *slot = static_cast<int>(i);
      f.slot = slot == &ix ? 0 : slot == &iy ? 1 : slot == &iz ? 2 : slot == &inx ? 3 : slot == &iny ? 4 : slot == &inz ? 5 : 6;
    }
  }
  if (ix < 0 || iy < 0 || iz < 0) return fail("no x, y and z fields");
  const bool normals = inx >= 0 && iny >= 0 && inz >= 0;
  if (irgb >= 0 && h.fields[irgb].size != 4) return fail("field " + h.fields[irgb].name + ": SIZE must be 4");
  // WIDTH x HEIGHT compared by division: the product can wrap around 64 bits.
  if (h.height != 0 && h.width > UINT64_MAX / h.height)
    return fail("WIDTH x HEIGHT (" + std::to_string(h.width) + " x " + std::to_string(h.height) + ") is beyond 2^64 points");
  if (!h.has_points) h.points = h.width * h.height;
  if (h.width != 0 && h.points != h.width * h.height)
    return fail("POINTS " + std::to_string(h.points) + " is not WIDTH x HEIGHT (" + std::to_string(h.width) + " x " + std::to_string(h.height) + ")");
  const size_t remaining = size - pos;
  // Bound the count by the bytes before anything is sized from it: a packed
  // record each, or at least two characters a value in ascii.
  if (h.data == "binary" && h.points > remaining / h.record)
    return fail("POINTS " + std::to_string(h.points) + " of " + std::to_string(h.record) + " bytes need more than the " +
                std::to_string(remaining) + " bytes after the header");
  if (h.data == "ascii" && h.points > remaining / 2) return fail("POINTS " + std::to_string(h.points) + " cannot fit the " + std::to_string(remaining) + " bytes after the header");

  // §2 the points: one packed record a point, however they were stored.
  std::vector<uint8_t> unpacked;  // binary_compressed: fields one after another
  const uint8_t* records = data + pos;
  if (h.data == "binary_compressed") {
    if (remaining < 8) return fail("byte " + std::to_string(pos) + ": the compressed block's sizes are missing");
    uint32_t packed = 0, raw = 0;
    for (int i = 0; i < 4; ++i) {
      packed |= uint32_t{data[pos + i]} << (8 * i);
      raw |= uint32_t{data[pos + 4 + i]} << (8 * i);
    }
    if (packed > remaining - 8) return fail("byte " + std::to_string(pos) + ": a compressed block of " + std::to_string(packed) + " bytes, " + std::to_string(remaining - 8) + " in the file");
    // Compared by division: POINTS x the record can wrap around 64 bits.
    if (raw % h.record != 0 || raw / h.record != h.points)
      return fail("byte " + std::to_string(pos + 4) + ": the block uncompresses to " + std::to_string(raw) + " bytes, the header's " +
                  std::to_string(h.points) + " points of " + std::to_string(h.record) + " bytes need another size");
    // LZF expands at most ~100x; refuse what no real block does before allocating.
    if (uint64_t{raw} > 200 * uint64_t{packed} + 1024) return fail("byte " + std::to_string(pos + 4) + ": an uncompressed size of " + std::to_string(raw) + " bytes from " + std::to_string(packed) + " is not LZF");
    unpacked.resize(raw);
    if (raw > 0 && lzf_decompress(data + pos + 8, packed, unpacked.data(), raw) != raw)
      return fail("byte " + std::to_string(pos + 8) + ": the LZF block is corrupt");
  }
  const uint64_t n = h.points;
  const uint64_t room = stream ? std::min<uint64_t>(n, kScanChunk) : n;
  cloud.positions.reserve(room);
  if (normals) cloud.normals.reserve(room);
  if (irgb >= 0) cloud.colors.reserve(room);
  std::vector<const uint8_t*> at(h.fields.size());
  size_t values_per_point = 0;  // ascii: a line's words
  for (const Field& f : h.fields) values_per_point += f.count;
  size_t dropped = 0, zero_normals = 0;
  const char* text = reinterpret_cast<const char*>(data + pos);
  const char* text_end = reinterpret_cast<const char*>(data + size);
  uint8_t rgb_bytes[4] = {};
  for (uint64_t i = 0; i < n; ++i) {
    Vec3 p, nrm = Vec3::Zero();
    Vec3 col = Vec3::Zero();
    if (h.data == "ascii") {
      // One point a line: every field's values, whitespace-separated.
      while (text < text_end && (*text == '\n' || *text == '\r')) ++text;
      const char* eol = text;
      while (eol < text_end && *eol != '\n') ++eol;
      const std::vector<std::string> w = words(text, eol);
      text = eol;
      if (w.size() != values_per_point)
        return fail("point " + std::to_string(i) + ": " + std::to_string(w.size()) + " values, expected " + std::to_string(values_per_point));
      size_t k = 0;
      double v[7] = {};
      for (size_t fi = 0; fi < h.fields.size(); ++fi) {
        const Field& f = h.fields[fi];
        for (size_t c = 0; c < f.count; ++c, ++k) {
          if (f.slot < 0) continue;
          double x = 0;
          const std::string& s = w[k];
          if (s == "nan" || s == "NaN" || s == "-nan") x = std::nan("");
          else if (!parse_f64(s, x)) return fail("point " + std::to_string(i) + ", field " + f.name + ": '" + s.substr(0, 32) + "' is not a number");
          if (f.slot == 6) {
            uint32_t bits = 0;
            if (f.type == 'F') {
              const float fl = static_cast<float>(x);
              std::memcpy(&bits, &fl, 4);
            } else {
              bits = x >= 0 && x <= 4294967295.0 ? static_cast<uint32_t>(x) : 0;
            }
            for (int b = 0; b < 4; ++b) rgb_bytes[b] = static_cast<uint8_t>(bits >> (8 * b));
            col = color_of(rgb_bytes);
          } else {
            v[f.slot] = x;
          }
        }
      }
      p = Vec3(v[0], v[1], v[2]);
      nrm = Vec3(v[3], v[4], v[5]);
    } else {
      for (size_t fi = 0; fi < h.fields.size(); ++fi) {
        const Field& f = h.fields[fi];
        at[fi] = h.data == "binary" ? records + i * h.record + f.offset
                                    : unpacked.data() + n * f.offset + i * f.size * f.count;
      }
      p = Vec3(value_of(h.fields[ix], at[ix]), value_of(h.fields[iy], at[iy]), value_of(h.fields[iz], at[iz]));
      if (normals) nrm = Vec3(value_of(h.fields[inx], at[inx]), value_of(h.fields[iny], at[iny]), value_of(h.fields[inz], at[inz]));
      if (irgb >= 0) col = color_of(at[irgb]);
    }
    if (!p.allFinite()) {  // an organized cloud's missing point
      ++dropped;
      continue;
    }
    cloud.positions.push_back(p);
    if (normals) {
      const double len = nrm.norm();
      if (!std::isfinite(len) || len == 0) ++zero_normals;
      cloud.normals.push_back(std::isfinite(len) && len > 0 ? Vec3(nrm / len) : Vec3::Zero());
    }
    if (irgb >= 0) cloud.colors.push_back(col);
    // Bytes read: the text's position, or the records' (a compressed file's
    // block is read whole).
    const uint64_t read = h.data == "ascii" ? static_cast<uint64_t>(reinterpret_cast<const uint8_t*>(text) - data)
                          : h.data == "binary" ? static_cast<uint64_t>(records - data) + (i + 1) * h.record
                                               : size;
    if (stream && !stream->flush(cloud, read, false, error)) return false;
  }
  if (cloud.positions.empty() && !(stream && stream->delivered > 0))
    return fail(dropped > 0 ? "every one of its " + std::to_string(dropped) + " points has a NaN coordinate" : "no points");
  if (dropped > 0)
    cloud.warnings.push_back(name + ": " + std::to_string(dropped) + " of " + std::to_string(n) +
                             " points have NaN or infinite coordinates (an organized cloud's missing points): dropped");
  if (zero_normals > 0)
    cloud.warnings.push_back(name + ": " + std::to_string(zero_normals) + " points have NaN or zero normals: kept without a normal");
  const Vec3 t(h.viewpoint[0], h.viewpoint[1], h.viewpoint[2]);
  if (t != Vec3::Zero()) {
    cloud.has_viewpoint = true;
    cloud.viewpoint = t;
  }
  return true;
}

}  // namespace stipple
