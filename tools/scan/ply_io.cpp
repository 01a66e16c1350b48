// stipple host — PLY and plain-text scan reader, PLY writer. See ply_io.h.
#include "tools/scan/ply_io.h"
#include "tools/scan/text_formats.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <thread>

#include "platform/file_io.h"
#include "tools/scan/las_io.h"
#include "tools/scan/pcd_io.h"

namespace stipple {

Box3 bounding_box(const std::vector<Vec3>& points) {
  Box3 box;
  if (points.empty()) return box;
  box.min = box.max = points[0];
  for (const Vec3& p : points) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

namespace {

enum class Type : uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parse_type(const std::string& s, Type& t) {
  static const std::pair<const char*, Type> kNames[] = {
      {"char", Type::kInt8},     {"int8", Type::kInt8},       {"uchar", Type::kUint8},
      {"uint8", Type::kUint8},   {"short", Type::kInt16},     {"int16", Type::kInt16},
      {"ushort", Type::kUint16}, {"uint16", Type::kUint16},   {"int", Type::kInt32},
      {"int32", Type::kInt32},   {"uint", Type::kUint32},     {"uint32", Type::kUint32},
      {"float", Type::kFloat32}, {"float32", Type::kFloat32}, {"double", Type::kFloat64},
      {"float64", Type::kFloat64}};
  for (const auto& [name, type] : kNames)
    if (s == name) {
      t = type;
      return true;
    }
  return false;
}

size_t type_size(Type t) {
  switch (t) {
    case Type::kInt8: case Type::kUint8: return 1;
    case Type::kInt16: case Type::kUint16: return 2;
    case Type::kInt32: case Type::kUint32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 1;
}

// Scale that maps an integer colour channel to [0, 1].
double color_scale(Type t) {
  switch (t) {
    case Type::kInt8: return 1.0 / 127.0;
    case Type::kUint8: return 1.0 / 255.0;
    case Type::kInt16: return 1.0 / 32767.0;
    case Type::kUint16: return 1.0 / 65535.0;
    case Type::kInt32: return 1.0 / 2147483647.0;
    case Type::kUint32: return 1.0 / 4294967295.0;
    case Type::kFloat32: case Type::kFloat64: return 1.0;
  }
  return 1.0;
}

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool is_list = false;
  Type count_type = Type::kUint8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
};

enum class Format { kAscii, kBinaryLE, kBinaryBE };

// Bounds-checked input: every read reports failure instead of overrunning.
class Input {
 public:
  Input(const uint8_t* data, size_t size, size_t pos, Format format)
      : data_(data), size_(size), pos_(pos), format_(format) {}

  size_t pos() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }

  // Reads one scalar of type `t`. Returns false at end of input or on a
  // malformed ASCII token.
  bool read(Type t, double& value) {
    if (format_ == Format::kAscii) return read_ascii(t, value);
    const size_t n = type_size(t);
    if (remaining() < n) return false;
    uint8_t b[8];
    std::memcpy(b, data_ + pos_, n);
    pos_ += n;
    if (format_ == Format::kBinaryBE) std::reverse(b, b + n);
    switch (t) {
      case Type::kInt8: value = static_cast<int8_t>(b[0]); break;
      case Type::kUint8: value = b[0]; break;
      case Type::kInt16: { int16_t v; std::memcpy(&v, b, 2); value = v; break; }
      case Type::kUint16: { uint16_t v; std::memcpy(&v, b, 2); value = v; break; }
      case Type::kInt32: { int32_t v; std::memcpy(&v, b, 4); value = v; break; }
      case Type::kUint32: { uint32_t v; std::memcpy(&v, b, 4); value = v; break; }
      case Type::kFloat32: { float v; std::memcpy(&v, b, 4); value = v; break; }
      case Type::kFloat64: { double v; std::memcpy(&v, b, 8); value = v; break; }
    }
    return true;
  }

  bool ascii_error() const { return ascii_error_; }

 private:
  bool read_ascii(Type t, double& value) {
    while (pos_ < size_ && std::isspace(data_[pos_])) ++pos_;
    if (pos_ >= size_) return false;
    const char* begin = reinterpret_cast<const char*>(data_ + pos_);
    const char* end = reinterpret_cast<const char*>(data_ + size_);
    const char* stop = begin;
    while (stop < end && !std::isspace(static_cast<unsigned char>(*stop))) ++stop;
    std::from_chars_result r;
    if (t == Type::kFloat32 || t == Type::kFloat64) {
      r = std::from_chars(begin, stop, value);
      // from_chars does not accept "nan"/"inf" spelled with a sign prefix '+'; both are rejected later anyway.
    } else {
      long long v = 0;
      r = std::from_chars(begin, stop, v);
      value = static_cast<double>(v);
    }
    if (r.ec != std::errc() || r.ptr != stop) {
      ascii_error_ = true;
      return false;
    }
    pos_ += static_cast<size_t>(stop - begin);
    return true;
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_;
  Format format_;
  bool ascii_error_ = false;
};

std::string at_byte(size_t pos) { return "byte " + std::to_string(pos); }

// "x = 1e+39 is beyond float32's range (3.403e+38), in which a .spg stores positions".
std::string beyond_float(int axis, double value) {
  char text[160];
  std::snprintf(text, sizeof text, "%c = %.9g is beyond float32's range (%.4g), in which a .spg stores positions",
                "xyz"[axis], value, kMaxCoordinate);
  return text;
}

std::string word_of(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

bool parse_ply(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud,
               std::string& error, ScanStream* stream) {
  // Header: text lines up to and including "end_header".
  std::vector<Element> elements;
  Format format = Format::kAscii;
  bool have_format = false;
  size_t pos = 0;
  int line_no = 0;
  bool ended = false;
  while (pos < size && !ended) {
    size_t eol = pos;
    while (eol < size && data[eol] != '\n') ++eol;
    if (eol >= size) break;  // header must end with a newline after end_header
    std::string line(reinterpret_cast<const char*>(data + pos), eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    ++line_no;
    const std::string where = name + ": header line " + std::to_string(line_no) + ": ";
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (line_no == 1) {
      if (key != "ply") {
        error = where + "missing 'ply' magic";
        return false;
      }
      continue;
    }
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      std::string f, version;
      words >> f >> version;
      if (f == "ascii") format = Format::kAscii;
      else if (f == "binary_little_endian") format = Format::kBinaryLE;
      else if (f == "binary_big_endian") format = Format::kBinaryBE;
      else {
        error = where + "unknown format '" + f + "'";
        return false;
      }
      if (version != "1.0") {
        error = where + "unsupported PLY version '" + version + "'";
        return false;
      }
      have_format = true;
    } else if (key == "element") {
      Element e;
      std::string count;
      words >> e.name >> count;
      const auto r = std::from_chars(count.data(), count.data() + count.size(), e.count);
      if (e.name.empty() || count.empty() || r.ec != std::errc() || r.ptr != count.data() + count.size()) {
        error = where + "malformed element line '" + line + "'";
        return false;
      }
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) {
        error = where + "property before any element";
        return false;
      }
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        if (!parse_type(count_type, p.count_type) || !parse_type(item_type, p.type) ||
            p.count_type == Type::kFloat32 || p.count_type == Type::kFloat64) {
          error = where + "unknown or invalid list property types '" + count_type + " " + item_type + "'";
          return false;
        }
        p.is_list = true;
      } else {
        words >> p.name;
        if (!parse_type(type, p.type)) {
          error = where + "unknown property type '" + type + "'";
          return false;
        }
      }
      if (p.name.empty()) {
        error = where + "property without a name";
        return false;
      }
      elements.back().properties.push_back(p);
    } else if (key == "end_header") {
      ended = true;
    } else {
      error = where + "unknown header keyword '" + key + "'";
      return false;
    }
  }
  if (!ended) {
    error = name + ": header has no end_header line";
    return false;
  }
  if (!have_format) {
    error = name + ": header has no format line";
    return false;
  }

  // Locate the vertex element and the properties we use.
  const Element* vertex = nullptr;
  for (const Element& e : elements)
    if (e.name == "vertex") vertex = &e;
  if (!vertex) {
    error = name + ": no 'vertex' element";
    return false;
  }
  auto find = [&](const Element& e, const char* n) -> int {
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].name == n && !e.properties[i].is_list) return static_cast<int>(i);
    return -1;
  };
  const int ix = find(*vertex, "x"), iy = find(*vertex, "y"), iz = find(*vertex, "z");
  if (ix < 0 || iy < 0 || iz < 0) {
    error = name + ": vertex element lacks scalar x, y and z properties";
    return false;
  }
  int in_[3] = {find(*vertex, "nx"), find(*vertex, "ny"), find(*vertex, "nz")};
  const bool has_normals = in_[0] >= 0 && in_[1] >= 0 && in_[2] >= 0;
  int ic[3] = {find(*vertex, "red"), find(*vertex, "green"), find(*vertex, "blue")};
  if (ic[0] < 0 || ic[1] < 0 || ic[2] < 0) {
    ic[0] = find(*vertex, "diffuse_red");
    ic[1] = find(*vertex, "diffuse_green");
    ic[2] = find(*vertex, "diffuse_blue");
  }
  const bool has_colors = ic[0] >= 0 && ic[1] >= 0 && ic[2] >= 0;

  // Every element costs at least this many bytes; reject counts the file cannot hold.
  uint64_t bytes_needed = 0;
  for (const Element& e : elements) {
    uint64_t min_bytes = 0;
    for (const Property& p : e.properties)
      min_bytes += format == Format::kAscii ? 2 : (p.is_list ? type_size(p.count_type) : type_size(p.type));
    if (e.count > 0 && min_bytes == 0) {
      error = name + ": element '" + e.name + "' has " + std::to_string(e.count) + " items but no properties";
      return false;
    }
    if (e.count > std::numeric_limits<uint32_t>::max() ||
        (min_bytes > 0 && e.count > (size - pos + 1) / min_bytes)) {
      error = name + ": element '" + e.name + "' claims " + std::to_string(e.count) +
              " items, more than the " + std::to_string(size - pos) + " bytes after the header can hold";
      return false;
    }
    bytes_needed += e.count * min_bytes;
  }
  if (format != Format::kAscii && bytes_needed > size - pos) {
    error = name + ": file is truncated: the header's elements need at least " + std::to_string(bytes_needed) +
            " bytes after the header, the file has " + std::to_string(size - pos);
    return false;
  }

  cloud = PointCloud{};
  const uint64_t room = stream ? std::min<uint64_t>(vertex->count, kScanChunk) : vertex->count;
  cloud.positions.reserve(room);
  if (has_normals) cloud.normals.reserve(room);
  if (has_colors) cloud.colors.reserve(room);

  Input in(data, size, pos, format);
  std::vector<double> values;
  for (const Element& e : elements) {
    const bool is_vertex = &e == vertex;
    const bool is_face = e.name == "face";
    int face_list = -1;
    if (is_face)
      for (size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].is_list &&
            (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index"))
          face_list = static_cast<int>(i);
    values.assign(e.properties.size(), 0.0);
    std::vector<uint32_t> face;
    for (uint64_t item = 0; item < e.count; ++item) {
      for (size_t pi = 0; pi < e.properties.size(); ++pi) {
        const Property& p = e.properties[pi];
        const size_t start = in.pos();
        auto fail = [&](const std::string& what) {
          error = name + ": " + at_byte(start) + ": " + e.name + " " + std::to_string(item) + ", property '" +
                  p.name + "': " + what;
          return false;
        };
        auto read_fail = [&]() {
          return fail(in.ascii_error() ? "malformed number" : "file is truncated");
        };
        if (!p.is_list) {
          if (!in.read(p.type, values[pi])) return read_fail();
          continue;
        }
        double count_value;
        if (!in.read(p.count_type, count_value)) return read_fail();
        if (count_value < 0 || count_value > 1e6)
          return fail("list length " + std::to_string(static_cast<long long>(count_value)) + " is invalid (0 to 1,000,000)");
        if (count_value * (format == Format::kAscii ? 2.0 : static_cast<double>(type_size(p.type))) >
            static_cast<double>(in.remaining()) + 1.0)
          return fail("file is truncated: a list of " + std::to_string(static_cast<long long>(count_value)) + " items, " +
                      std::to_string(in.remaining()) + " bytes left");
        const auto n = static_cast<size_t>(count_value);
        const bool keep = is_face && static_cast<int>(pi) == face_list;
        face.clear();
        for (size_t k = 0; k < n; ++k) {
          double v;
          if (!in.read(p.type, v)) return read_fail();
          if (keep) {
            if (!(v >= 0 && v < static_cast<double>(vertex->count)))
              return fail("vertex index " + std::to_string(static_cast<long long>(v)) + " out of range [0, " +
                          std::to_string(vertex->count) + ")");
            face.push_back(static_cast<uint32_t>(v));
          }
        }
        for (size_t k = 2; k < face.size(); ++k) {
          if (stream) ++stream->triangles;
          else cloud.triangles.push_back({face[0], face[k - 1], face[k]});
        }
      }
      if (!is_vertex) continue;
      const Vec3 p(values[ix], values[iy], values[iz]);
      if (!p.allFinite()) {
        error = name + ": vertex " + std::to_string(item) + ": non-finite coordinate (" + std::to_string(p.x()) +
                ", " + std::to_string(p.y()) + ", " + std::to_string(p.z()) + ")";
        return false;
      }
      cloud.positions.push_back(p);
      if (has_normals) {
        Vec3 n(values[in_[0]], values[in_[1]], values[in_[2]]);
        if (!n.allFinite()) {
          error = name + ": vertex " + std::to_string(item) + ": non-finite normal";
          return false;
        }
        const double len = n.norm();
        cloud.normals.push_back(len > 0 ? Vec3(n / len) : Vec3::Zero());
      }
      if (has_colors) {
        Vec3 c;
        for (int k = 0; k < 3; ++k)
          c[k] = values[ic[k]] * color_scale(vertex->properties[static_cast<size_t>(ic[k])].type);
        if (!c.allFinite()) {
          error = name + ": vertex " + std::to_string(item) + ": non-finite colour";
          return false;
        }
        cloud.colors.push_back(c.cwiseMax(0.0).cwiseMin(1.0));
      }
      if (stream && !stream->flush(cloud, in.pos(), false, error)) return false;
    }
  }
  if (format != Format::kAscii && in.remaining() != 0) {
    error = name + ": " + at_byte(in.pos()) + ": " + std::to_string(in.remaining()) +
            " unexpected bytes after the last element (counts disagree with the file size)";
    return false;
  }
  if (cloud.positions.empty() && !(stream && stream->delivered > 0)) {
    error = name + ": no vertices";
    return false;
  }
  return true;
}

// Plain text. Separators: whitespace, ',' and ';' — except in a file whose
// numbers use decimal commas (European spreadsheets: "1,5 2,25 3"), which is
// told by its first data line: three or more whitespace- or ';'-separated
// words, none with a '.', at least one with a single ','.
bool parse_text(const std::string& name, const uint8_t* data, size_t size, const TextPlan& plan, PointCloud& cloud,
                std::string& error, ScanStream* stream) {
  const TextColumns& layout = plan.columns;
  // Where each field sits in a row, when the user named the columns.
  int at[10];
  std::fill(at, at + 10, -1);
  for (size_t i = 0; i < layout.fields.size(); ++i) at[layout.fields[i]] = static_cast<int>(i);
  const bool named = !layout.fields.empty();
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
  // A binary file or a .spg given as a scan: say so instead of quoting its bytes.
  const size_t probe = std::min<size_t>(size, 4096);
  for (size_t i = 0; i < probe; ++i) {
    const unsigned char c = data[i];
    if (c == 0 || (c < 0x20 && c != '\n' && c != '\r' && c != '\t' && c != '\v' && c != '\f')) {
      const bool spg = size >= 4 && std::memcmp(data, "STPG", 4) == 0;
      error = name + ": byte " + std::to_string(i) + ": " +
              (spg ? std::string("this is a .spg model, not a scan (stipple info or render read it)")
                   : "a binary byte (" + std::to_string(c) + ") in what would be a text scan: not PLY, PCD, LAS or text");
      return false;
    }
  }
  size_t pos = 0;
  int line_no = 0;
  bool decimal_comma = false, decided = false;
  size_t columns = 0;
  std::vector<double> row, extra;  // extra: columns 4-6 of a 6-column file, decided at the end
  // What decides them, as they come (a scan read in chunks keeps no extras).
  bool integers = true, above_one = false, unit = true;
  // PTS: the last count line, the count it gave and the points since.
  int count_line = 0;
  uint64_t count_said = 0, count_seen = 0;
  const auto check_count = [&]() {
    if (count_line > 0 && count_seen != count_said)
      cloud.warnings.push_back(name + ": line " + std::to_string(count_line) + " says " + std::to_string(count_said) +
                               " points follow, " + std::to_string(count_seen) + " do");
  };
  while (pos < size) {
    size_t eol = pos;
    while (eol < size && data[eol] != '\n') ++eol;
    const char* begin = reinterpret_cast<const char*>(data + pos);
    const char* end = reinterpret_cast<const char*>(data + eol);
    pos = eol + 1;
    ++line_no;
    if (line_no == plan.header_line) continue;  // the columns' names (plan_text read them)
    if (line_no == 1 && end - begin >= 3 && std::memcmp(begin, "\xEF\xBB\xBF", 3) == 0) begin += 3;  // a UTF-8 byte-order mark
    const char* hash = std::find(begin, end, '#');
    end = hash;
    if (!decided) {
      // The first line with a number decides the separators.
      size_t words = 0, commas = 0;
      bool dot = false, many = false, any = false;
      for (const char* p = begin; p < end;) {
        while (p < end && (is_space(*p) || *p == ';')) ++p;
        if (p >= end) break;
        size_t c = 0;
        for (; p < end && !is_space(*p) && *p != ';'; ++p) {
          c += *p == ',';
          dot = dot || *p == '.';
          any = any || (*p >= '0' && *p <= '9');
        }
        ++words;
        commas += c > 0;
        many = many || c > 1;
      }
      if (any) {
        decimal_comma = words >= 3 && commas > 0 && !dot && !many;
        decided = true;
      }
      if (decimal_comma) cloud.warnings.push_back(name + ": read with decimal commas (\"1,5\" is 1.5), as its first line suggests");
    }
    row.clear();
    const char* p = begin;
    while (true) {
      while (p < end && (is_space(*p) || *p == ';' || (!decimal_comma && *p == ','))) ++p;
      if (p >= end) break;
      const char* stop = p;
      while (stop < end && !is_space(*stop) && *stop != ';' && (decimal_comma || *stop != ',')) ++stop;
      std::string word(p, stop);
      if (decimal_comma) std::replace(word.begin(), word.end(), ',', '.');
      double v;
      const auto r = std::from_chars(word.data(), word.data() + word.size(), v);
      if (r.ec == std::errc::result_out_of_range) {
        error = name + ": line " + std::to_string(line_no) + ": '" + word.substr(0, 40) + "' is beyond the range of a double";
        return false;
      }
      if (r.ec != std::errc() || r.ptr != word.data() + word.size()) {
        error = name + ": line " + std::to_string(line_no) + ": malformed number '" + word.substr(0, 40) + "'";
        return false;
      }
      if (!std::isfinite(v)) {
        error = name + ": line " + std::to_string(line_no) + ": non-finite value";
        return false;
      }
      row.push_back(v);
      p = stop;
    }
    if (row.empty()) continue;
    // (A count beyond 2^53 is no count a file holds: read as a row, refused by its width.)
    if (plan.pts && row.size() == 1 && row[0] >= 0 && row[0] <= 9007199254740992.0 && row[0] == std::floor(row[0])) {
      check_count();  // a PTS count line: another section (scan position) begins
      count_line = line_no;
      count_said = static_cast<uint64_t>(row[0]);
      count_seen = 0;
      continue;
    }
    ++count_seen;
    // A coordinate past float32's range: the line named (parse_point_cloud
    // checks every format's points again, by index).
    for (size_t k = 0; k < row.size() && k < 3; ++k) {
      const size_t column = named ? static_cast<size_t>(at[TextColumns::kX + k]) : k;
      if (column < row.size() && !(std::abs(row[column]) <= kMaxCoordinate)) {
        error = name + ": line " + std::to_string(line_no) + ": " + beyond_float(static_cast<int>(k), row[column]);
        return false;
      }
    }
    if (named) {
      if (row.size() != layout.fields.size()) {
        error = name + ": line " + std::to_string(line_no) + ": expected " + std::to_string(layout.fields.size()) +
                " columns (as --columns names them), got " + std::to_string(row.size());
        return false;
      }
      cloud.positions.emplace_back(row[at[TextColumns::kX]], row[at[TextColumns::kY]], row[at[TextColumns::kZ]]);
      if (at[TextColumns::kNx] >= 0) {
        const Vec3 n(row[at[TextColumns::kNx]], row[at[TextColumns::kNy]], row[at[TextColumns::kNz]]);
        const double len = n.norm();
        cloud.normals.push_back(len > 0 ? Vec3(n / len) : Vec3::Zero());
      }
      if (at[TextColumns::kR] >= 0) {
        Vec3 c;
        for (int k = 0; k < 3; ++k) {
          const int column = at[TextColumns::kR + k];
          c[k] = row[static_cast<size_t>(column)];
          if (!(c[k] >= 0 && c[k] <= 255)) {
            error = name + ": line " + std::to_string(line_no) + ": column " + std::to_string(column + 1) + " (" +
                    "rgb"[k] + ") is " + word_of(c[k]) + ", but --columns reads r g b as 0..255";
            return false;
          }
        }
        cloud.colors.push_back(c / 255.0);
      }
      if (stream && !stream->flush(cloud, pos, false, error)) return false;
      continue;
    }
    if (columns == 0) {
      columns = row.size();
      if (columns != 3 && columns != 6 && columns != 7 && columns != 9) {
        error = name + ": line " + std::to_string(line_no) +
                ": expected 3, 6, 7 or 9 columns (x y z, x y z nx ny nz or x y z r g b, x y z r g b a, x y z nx ny nz r g b), got " +
                std::to_string(columns);
        return false;
      }
    } else if (row.size() != columns) {
      error = name + ": line " + std::to_string(line_no) + ": expected " + std::to_string(columns) + " columns, got " +
              std::to_string(row.size());
      return false;
    }
    cloud.positions.emplace_back(row[0], row[1], row[2]);
    if (columns == 6 || columns == 7) {
      for (size_t k = 3; k < 6; ++k) {
        const double v = row[k];
        integers = integers && v >= 0 && v <= 255 && v == std::floor(v);
        above_one = above_one || v > 1;
        unit = unit && std::abs(v) <= 1.0 + 1e-6;
      }
      if (!stream) extra.insert(extra.end(), row.begin() + 3, row.begin() + 6);
    }
    if (columns == 9) {
      Vec3 n(row[3], row[4], row[5]);
      const double len = n.norm();
      cloud.normals.push_back(len > 0 ? Vec3(n / len) : Vec3::Zero());
      cloud.colors.push_back((Vec3(row[6], row[7], row[8]) / 255.0).cwiseMax(0.0).cwiseMin(1.0));
    }
    if (stream && !stream->flush(cloud, pos, false, error)) return false;
  }
  check_count();
  if (cloud.positions.empty() && !(stream && stream->delivered > 0)) {
    error = name + ": no points";
    return false;
  }
  if (columns == 6 || columns == 7) {
    // x y z and three more: colour when every one is an integer in 0..255
    // and some exceeds 1 (or there are seven columns: r g b a), normals
    // otherwise. Said, since it is a guess. A scan read in chunks was
    // delivered without them: it is read again with the columns named.
    if (columns == 7 && !integers) {
      error = name + ": 7 columns are read as x y z r g b a, but columns 4-7 are not integers 0..255";
      return false;
    }
    const bool colors = columns == 7 || (integers && above_one);
    if (stream) stream->text_columns = colors ? (columns == 7 ? "x,y,z,r,g,b,-" : "x,y,z,r,g,b") : "x,y,z,nx,ny,nz";
    if (colors) {
      for (size_t i = 0; i < extra.size(); i += 3) cloud.colors.emplace_back(extra[i] / 255, extra[i + 1] / 255, extra[i + 2] / 255);
      cloud.warnings.push_back(name + ": columns 4-6 read as r g b (integers 0..255); normals would be unit vectors");
    } else {
      for (size_t i = 0; i < extra.size(); i += 3) {
        const Vec3 n(extra[i], extra[i + 1], extra[i + 2]);
        const double len = n.norm();
        cloud.normals.push_back(len > 0 ? Vec3(n / len) : Vec3::Zero());
      }
      if (!unit) cloud.warnings.push_back(name + ": columns 4-6 read as normals, though they are not unit vectors (normalized)");
    }
  }
  return true;
}

}  // namespace

std::string beyond_float_range(const std::vector<Vec3>& points, uint64_t first) {
  for (size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(points[i][a]) <= kMaxCoordinate))
        return "point " + std::to_string(first + i) + " (counting from 0): " + beyond_float(a, points[i][a]);
  return {};
}

bool ScanStream::flush(PointCloud& cloud, uint64_t bytes_read, bool last, std::string& error) {
  if (cloud.positions.size() < kScanChunk && !(last && !cloud.positions.empty())) return true;
  if (!deliver(cloud, delivered, bytes_read, error)) return false;
  delivered += cloud.positions.size();
  cloud.positions.clear();
  cloud.normals.clear();
  cloud.colors.clear();
  return true;
}

std::string duplicate_warning(const std::string& name, uint64_t duplicates, uint64_t points, const Box3& box) {
  // Many points on one value: float32 coordinates far from the origin round
  // onto a coarse lattice (at 1e7, steps of 1), and the scan collapses.
  if (duplicates < 100 || duplicates * 100 < points) return {};
  const double far = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  char text[256];
  std::snprintf(text, sizeof text, "%s: %llu of %llu points (%.1f %%) repeat another point's position exactly%s",
                name.c_str(), static_cast<unsigned long long>(duplicates), static_cast<unsigned long long>(points),
                100.0 * static_cast<double>(duplicates) / static_cast<double>(points),
                (box.diagonal() > 0 && far > 1e5 * box.diagonal()) || (box.diagonal() == 0 && far >= 1e5)
                    ? "; the coordinates are far from the origin for their extent: float32 values there round onto a "
                      "coarse lattice (subtract an offset before storing them as float)"
                    : "");
  return text;
}

size_t count_duplicate_positions(const std::vector<Vec3>& points) {
  // Sorting 64-bit keys, not indices into the points: a scan of 10^7 points
  // is counted in a fraction of a second instead of seconds of cache misses.
  // A key is the position's bits hashed; equal keys are then compared as
  // positions, so the count is exact unless two different positions collide
  // in 64 bits and interleave with a repeat (about n^2 / 2^65: never at 10^9).
  const auto bits = [](double v) {
    uint64_t b;
    v += 0.0;  // -0 and +0 are one position
    std::memcpy(&b, &v, 8);
    return b;
  };
  const auto mix = [](uint64_t x) {  // SplitMix64's finaliser
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  };
  std::vector<std::pair<uint64_t, uint32_t>> keys(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    keys[i] = {mix(mix(mix(bits(p.x())) ^ bits(p.y())) ^ bits(p.z())), static_cast<uint32_t>(i)};
  }
  // Two halves sorted at once, then merged: the same order as one sort (the
  // pairs are distinct), in about half the time on two cores.
  const auto middle = keys.begin() + static_cast<std::ptrdiff_t>(keys.size() / 2);
  if (keys.size() >= (1u << 20)) {
    std::thread half([&] { std::sort(keys.begin(), middle); });
    std::sort(middle, keys.end());
    half.join();
    std::inplace_merge(keys.begin(), middle, keys.end());
  } else {
    std::sort(keys.begin(), keys.end());
  }
  size_t duplicates = 0;
  for (size_t i = 1; i < keys.size(); ++i)
    duplicates += keys[i].first == keys[i - 1].first && points[keys[i].second] == points[keys[i - 1].second];
  return duplicates;
}

bool parse_text_columns(const std::string& spec, TextColumns& columns, std::string& error) {
  static const struct {
    const char* name;
    TextColumns::Field field;
  } kNames[] = {{"x", TextColumns::kX},   {"y", TextColumns::kY},   {"z", TextColumns::kZ},
                {"nx", TextColumns::kNx}, {"ny", TextColumns::kNy}, {"nz", TextColumns::kNz},
                {"r", TextColumns::kR},   {"g", TextColumns::kG},   {"b", TextColumns::kB},
                {"-", TextColumns::kSkip}};
  columns.fields.clear();
  int seen[10] = {};
  for (size_t at = 0; at <= spec.size();) {
    size_t stop = spec.find_first_of(", ", at);
    if (stop == std::string::npos) stop = spec.size();
    const std::string word = spec.substr(at, stop - at);
    at = stop + 1;
    if (word.empty()) continue;
    const auto* hit = std::find_if(std::begin(kNames), std::end(kNames), [&](const auto& n) { return word == n.name; });
    if (hit == std::end(kNames))
      return error = "--columns: unknown column '" + word + "' (x y z, nx ny nz, r g b, or - to skip)", false;
    if (hit->field != TextColumns::kSkip && seen[hit->field]++)
      return error = "--columns: '" + word + "' named twice", false;
    columns.fields.push_back(hit->field);
  }
  if (!seen[TextColumns::kX] || !seen[TextColumns::kY] || !seen[TextColumns::kZ])
    return error = "--columns: x, y and z are required (got '" + spec + "')", false;
  const int normals = seen[TextColumns::kNx] + seen[TextColumns::kNy] + seen[TextColumns::kNz];
  const int colours = seen[TextColumns::kR] + seen[TextColumns::kG] + seen[TextColumns::kB];
  if (normals != 0 && normals != 3) return error = "--columns: name all of nx, ny, nz or none", false;
  if (colours != 0 && colours != 3) return error = "--columns: name all of r, g, b or none", false;
  return true;
}

namespace {

enum class ScanFormat { kPly, kLas, kPcd, kObj, kText };

// What parse_point_cloud and stream_point_cloud do before a reader: the
// file's signature told, its quirks mended (said in `note`), the refusals.
bool open_scan(const std::string& name, const uint8_t*& data, size_t& size, const ScanOptions& options,
               std::vector<uint8_t>& fixed, std::string& note, ScanFormat& format, std::string& error) {
  // A UTF-8 byte-order mark before a PLY header, or the magic in capitals
  // ("PLY", which PLY does not allow but some writers produce): read it as
  // PLY, and say so.
  if (size >= 3 && std::memcmp(data, "\xEF\xBB\xBF", 3) == 0 && size >= 6 &&
      (std::memcmp(data + 3, "ply", 3) == 0 || std::memcmp(data + 3, "PLY", 3) == 0)) {
    data += 3;
    size -= 3;
    note = "a UTF-8 byte-order mark before the PLY header: skipped";
  }
  if (size >= 4 && std::memcmp(data, "PLY", 3) == 0 && (data[3] == '\n' || data[3] == '\r')) {
    fixed.assign(data, data + size);
    std::memcpy(fixed.data(), "ply", 3);
    data = fixed.data();
    note += std::string(note.empty() ? "" : "; ") + "the PLY magic in capitals ('PLY'): read as 'ply'";
  }
  if (size == 0) {
    error = name + ": the file is empty (0 bytes)";
    return false;
  }
  if (looks_like_e57(data, size)) {
    error = e57_refusal(name);
    return false;
  }
  format = size >= 3 && std::memcmp(data, "ply", 3) == 0 ? ScanFormat::kPly
           : looks_like_las(data, size)                    ? ScanFormat::kLas
           : looks_like_pcd(data, size)                    ? ScanFormat::kPcd
           : looks_like_obj(data, size)                    ? ScanFormat::kObj
                                                           : ScanFormat::kText;
  if (format != ScanFormat::kText && !options.columns.fields.empty()) {
    error = name + ": --columns names a text scan's columns, but this is " +
            (format == ScanFormat::kPly ? "PLY" : format == ScanFormat::kLas ? "LAS" : format == ScanFormat::kPcd ? "PCD" : "OBJ") +
            ", whose " + (format == ScanFormat::kObj ? "'v' lines are" : "header names") + " them";
    return false;
  }
  if (format != ScanFormat::kLas && options.color_by != LasColor::kRgb) {
    error = name + ": --color-by " + (options.color_by == LasColor::kIntensity ? "intensity" : "classification") +
            " takes a LAS scan's " + (options.color_by == LasColor::kIntensity ? "intensity" : "classification") +
            ", but this is " +
            (format == ScanFormat::kPly ? "PLY" : format == ScanFormat::kPcd ? "PCD" : format == ScanFormat::kObj ? "OBJ" : "text");
    return false;
  }
  return true;
}

}  // namespace

bool parse_point_cloud(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud,
                       std::string& error, const ScanOptions& options) {
  std::vector<uint8_t> fixed;
  std::string note;
  ScanFormat format;
  if (!open_scan(name, data, size, options, fixed, note, format, error)) return false;
  bool ok = false;
  switch (format) {
    case ScanFormat::kPly: ok = parse_ply(name, data, size, cloud, error, nullptr); break;
    case ScanFormat::kLas: ok = parse_las(name, data, size, cloud, error, nullptr, options.color_by); break;
    case ScanFormat::kPcd: ok = parse_pcd(name, data, size, cloud, error); break;
    case ScanFormat::kObj: ok = parse_obj(name, data, size, cloud, error); break;
    case ScanFormat::kText: {
      TextPlan plan;
      cloud = PointCloud{};
      ok = plan_text(name, data, size, options.columns, plan, cloud, error) &&
           parse_text(name, data, size, plan, cloud, error, nullptr);
      break;
    }
  }
  if (!ok) return false;
  if (std::string what = beyond_float_range(cloud.positions); !what.empty()) return error = name + ": " + what, false;
  if (!note.empty()) cloud.warnings.insert(cloud.warnings.begin(), name + ": " + note);
  const size_t duplicates = count_duplicate_positions(cloud.positions);
  if (std::string w = duplicate_warning(name, duplicates, cloud.size(), bounding_box(cloud.positions)); !w.empty())
    cloud.warnings.push_back(w);
  return true;
}

bool scan_streams(const std::string& path) {
  // Every format but OBJ; a file that cannot be read or is refused gets the
  // same message either way.
  MappedFile file;
  std::string error;
  return file.open(path, error) && !looks_like_obj(file.data(), file.size());
}

bool stream_point_cloud(const std::string& path, ScanStream& stream, PointCloud& rest, std::string& error,
                        const ScanOptions& options) {
  MappedFile file;
  if (!file.open(path, error)) return false;
  const uint8_t* data = file.data();
  size_t size = file.size();
  std::vector<uint8_t> fixed;
  std::string note;
  ScanFormat format;
  if (!open_scan(path, data, size, options, fixed, note, format, error)) return false;
  if (format == ScanFormat::kObj) return error = path + ": an OBJ scan is read whole, not in chunks (read_point_cloud)", false;
  // Each chunk checked as parse_point_cloud checks the whole; the file's
  // pages behind the reader are given back (a scan larger than memory).
  ScanStream inner;
  inner.deliver = [&](PointCloud& chunk, uint64_t first, uint64_t bytes_read, std::string& why) {
    if (std::string what = beyond_float_range(chunk.positions, first); !what.empty()) return why = path + ": " + what, false;
    if (!stream.deliver(chunk, first, bytes_read, why)) return false;
    if (fixed.empty()) file.release_before(static_cast<size_t>(bytes_read) + static_cast<size_t>(data - file.data()));
    return true;
  };
  rest = PointCloud{};
  bool ok = false;
  uint64_t end = size;
  switch (format) {
    case ScanFormat::kPly: ok = parse_ply(path, data, size, rest, error, &inner); break;
    case ScanFormat::kLas: ok = parse_las(path, data, size, rest, error, &inner, options.color_by); break;
    case ScanFormat::kPcd: ok = parse_pcd(path, data, size, rest, error, &inner); break;
    case ScanFormat::kText: {
      TextPlan plan;
      ok = plan_text(path, data, size, options.columns, plan, rest, error) &&
           parse_text(path, data, size, plan, rest, error, &inner);
      break;
    }
    case ScanFormat::kObj: break;
  }
  if (!ok || !inner.flush(rest, end, true, error)) return false;
  stream.delivered = inner.delivered;
  stream.triangles = inner.triangles;
  stream.color_divisor = inner.color_divisor;
  stream.text_columns = inner.text_columns;
  if (!note.empty()) rest.warnings.insert(rest.warnings.begin(), path + ": " + note);
  return true;
}

bool read_point_cloud(const std::string& path, PointCloud& cloud, std::string& error, const ScanOptions& options) {
  std::vector<uint8_t> bytes;
  if (!read_file(path, bytes, error)) return false;
  return parse_point_cloud(path, bytes.data(), bytes.size(), cloud, error, options);
}

bool write_ply(const std::string& path, const PointCloud& cloud, std::string& error) {
  // Positions in double: a float32 position loses everything below 1 unit
  // at 1e7 from the origin (a survey's coordinates), so a sampled model read
  // back would measure the format, not the model.
  for (size_t i = 0; i < cloud.size(); ++i)
    if (!cloud.positions[i].allFinite())
      return error = path + ": point " + std::to_string(i) + " is not finite: nothing written", false;
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by stipple\nelement vertex " +
                       std::to_string(cloud.size()) + "\nproperty double x\nproperty double y\nproperty double z\n";
  if (cloud.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (cloud.has_colors()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "end_header\n";
  std::vector<uint8_t> out(header.begin(), header.end());
  const size_t stride = 24 + (cloud.has_normals() ? 12 : 0) + (cloud.has_colors() ? 3 : 0);
  out.reserve(out.size() + stride * cloud.size());
  auto put_float = [&](double v) {
    const float f = std::isfinite(v) ? static_cast<float>(std::clamp(v, -1.0, 1.0)) : 0.0f;  // unit normals
    uint8_t b[4];
    std::memcpy(b, &f, 4);  // little-endian host (x86-64, ARM Linux)
    out.insert(out.end(), b, b + 4);
  };
  auto put_double = [&](double v) {
    uint8_t b[8];
    std::memcpy(b, &v, 8);
    out.insert(out.end(), b, b + 8);
  };
  for (size_t i = 0; i < cloud.size(); ++i) {
    for (int k = 0; k < 3; ++k) put_double(cloud.positions[i][k]);
    if (cloud.has_normals())
      for (int k = 0; k < 3; ++k) put_float(cloud.normals[i][k]);
    if (cloud.has_colors())
      for (int k = 0; k < 3; ++k)
        out.push_back(static_cast<uint8_t>(std::lround(std::clamp(cloud.colors[i][k], 0.0, 1.0) * 255.0)));
  }
  return write_file_atomic(path, out, error);
}

}  // namespace stipple
