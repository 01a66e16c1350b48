// stipple host — the text scans people export. See text_formats.h.
#include "tools/scan/text_formats.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <vector>

namespace stipple {
namespace {

// One line of a text file: its number (from 1) and its text without the
// end-of-line, a UTF-8 byte-order mark or a '#' comment.
struct Line {
  int number = 0;
  std::string text;
};

// The file's lines one by one; false at the end.
class Lines {
 public:
  Lines(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool next(Line& line) {
    if (pos_ >= size_) return false;
    size_t eol = pos_;
    while (eol < size_ && data_[eol] != '\n') ++eol;
    const char* begin = reinterpret_cast<const char*>(data_ + pos_);
    const char* end = reinterpret_cast<const char*>(data_ + eol);
    pos_ = eol + 1;
    line.number = ++number_;
    if (number_ == 1 && end - begin >= 3 && std::memcmp(begin, "\xEF\xBB\xBF", 3) == 0) begin += 3;
    end = std::find(begin, end, '#');
    while (end > begin && (end[-1] == '\r' || end[-1] == ' ' || end[-1] == '\t')) --end;
    line.text.assign(begin, end);
    return true;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  int number_ = 0;
};

// Words separated by whitespace, ',' or ';'.
std::vector<std::string> words_of(const std::string& text) {
  std::vector<std::string> out;
  std::string word;
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == '\r' || c == ',' || c == ';') {
      if (!word.empty()) out.push_back(word), word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) out.push_back(word);
  return out;
}

bool is_number(const std::string& w) {
  double v;
  const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
  return r.ec == std::errc() && r.ptr == w.data() + w.size();
}

bool is_count(const std::string& w) {
  uint64_t v;
  const auto r = std::from_chars(w.data(), w.data() + w.size(), v);
  return r.ec == std::errc() && r.ptr == w.data() + w.size();
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A header word's column, or kSkip.
TextColumns::Field field_of(std::string name) {
  name = lower(name);
  while (!name.empty() && (name[0] == '/' || name[0] == '"' || name[0] == '\'')) name.erase(0, 1);
  while (!name.empty() && (name.back() == '"' || name.back() == '\'')) name.pop_back();
  static const struct {
    const char* name;
    TextColumns::Field field;
  } kNames[] = {{"x", TextColumns::kX},         {"y", TextColumns::kY},         {"z", TextColumns::kZ},
                {"nx", TextColumns::kNx},       {"ny", TextColumns::kNy},       {"nz", TextColumns::kNz},
                {"normal_x", TextColumns::kNx}, {"normal_y", TextColumns::kNy}, {"normal_z", TextColumns::kNz},
                {"r", TextColumns::kR},         {"g", TextColumns::kG},         {"b", TextColumns::kB},
                {"red", TextColumns::kR},       {"green", TextColumns::kG},     {"blue", TextColumns::kB}};
  for (const auto& n : kNames)
    if (name == n.name) return n.field;
  return TextColumns::kSkip;
}

}  // namespace

bool plan_text(const std::string& name, const uint8_t* data, size_t size, const TextColumns& given, TextPlan& plan,
               PointCloud& cloud, std::string& error) {
  plan = TextPlan{};
  plan.columns = given;
  // A binary file: the reader refuses it, naming the byte.
  for (size_t i = 0; i < std::min<size_t>(size, 4096); ++i)
    if (data[i] == 0 || (data[i] < 0x20 && data[i] != '\n' && data[i] != '\r' && data[i] != '\t' && data[i] != '\v' &&
                         data[i] != '\f'))
      return true;
  Lines lines(data, size);
  Line first, second;
  while (lines.next(first) && words_of(first.text).empty()) {
  }
  if (words_of(first.text).empty()) return true;
  while (lines.next(second) && words_of(second.text).empty()) {
  }
  const std::vector<std::string> w1 = words_of(first.text), w2 = words_of(second.text);
  const bool all_names = std::none_of(w1.begin(), w1.end(), is_number);
  if (all_names) {
    // A header line: the columns' names.
    plan.header_line = first.number;
    plan.what = "a header line";
    if (!given.fields.empty()) {
      cloud.warnings.push_back(name + ": line " + std::to_string(first.number) +
                               " names the columns; skipped, as --columns names them");
      return true;
    }
    std::vector<TextColumns::Field> fields;
    int seen[10] = {};
    for (const std::string& w : w1) {
      TextColumns::Field f = field_of(w);
      if (f != TextColumns::kSkip && seen[f]) f = TextColumns::kSkip;  // a name twice: the first one counts
      if (f != TextColumns::kSkip) seen[f] = 1;
      fields.push_back(f);
    }
    if (!seen[TextColumns::kX] || !seen[TextColumns::kY] || !seen[TextColumns::kZ]) {
      error = name + ": line " + std::to_string(first.number) + ": a header line ('" + first.text.substr(0, 60) +
              "') names no x, y and z columns: name them with --columns (for example --columns x,y,z,-,r,g,b)";
      return false;
    }
    // Groups named in part are skipped whole: r g b all or none.
    for (TextColumns::Field group : {TextColumns::kNx, TextColumns::kR}) {
      const int named = seen[group] + seen[group + 1] + seen[group + 2];
      if (named != 3)
        for (TextColumns::Field& f : fields)
          if (f >= group && f <= group + 2) f = TextColumns::kSkip;
    }
    std::string read, skipped;
    static const char* const kShort[] = {"-", "x", "y", "z", "nx", "ny", "nz", "r", "g", "b"};
    for (size_t i = 0; i < fields.size(); ++i) {
      read += std::string(i ? "," : "") + kShort[fields[i]];
      if (fields[i] == TextColumns::kSkip) skipped += std::string(skipped.empty() ? "" : ", ") + w1[i];
    }
    plan.columns.fields = fields;
    cloud.warnings.push_back(name + ": line " + std::to_string(first.number) + " names the columns: read as --columns " +
                             read + (skipped.empty() ? "" : " (skipped: " + skipped + ")"));
    return true;
  }
  if (w1.size() == 1 && is_count(w1[0]) && !w2.empty() &&
      (w2.size() == 3 || w2.size() == 4 || w2.size() == 6 || w2.size() == 7) && std::all_of(w2.begin(), w2.end(), is_number)) {
    // Leica PTS: a count line, then x y z [intensity] [r g b].
    plan.pts = true;
    plan.what = "Leica PTS";
    using F = TextColumns;
    static const std::vector<TextColumns::Field> kLayouts[8] = {
        {}, {}, {}, {F::kX, F::kY, F::kZ}, {F::kX, F::kY, F::kZ, F::kSkip}, {}, {F::kX, F::kY, F::kZ, F::kR, F::kG, F::kB},
        {F::kX, F::kY, F::kZ, F::kSkip, F::kR, F::kG, F::kB}};
    if (given.fields.empty()) plan.columns.fields = kLayouts[w2.size()];
    static const char* const kSaid[8] = {"", "", "", "x y z", "x y z intensity", "", "x y z r g b", "x y z intensity r g b"};
    cloud.warnings.push_back(name + ": read as Leica PTS (a count line, then " +
                             (given.fields.empty() ? std::string(kSaid[w2.size()]) : std::string("--columns' layout")) +
                             (w2.size() == 4 || w2.size() == 7 ? "; intensity is not kept" : "") + ")");
  }
  return true;
}

bool looks_like_obj(const uint8_t* data, size_t size) {
  Lines lines(data, size);
  Line line;
  for (int looked = 0; looked < 64 && lines.next(line);) {
    const std::vector<std::string> w = words_of(line.text);
    if (w.empty()) continue;
    ++looked;
    static const char* const kKeys[] = {"v", "vn", "vt", "vp", "f", "o", "g", "s", "l", "mtllib", "usemtl"};
    if (std::find_if(std::begin(kKeys), std::end(kKeys), [&](const char* k) { return w[0] == k; }) == std::end(kKeys))
      return false;
    if (w[0] == "v") return true;
  }
  return false;
}

bool parse_obj(const std::string& name, const uint8_t* data, size_t size, PointCloud& cloud, std::string& error) {
  cloud = PointCloud{};
  Lines lines(data, size);
  Line line;
  std::vector<Vec3> colours;
  bool some_coloured = false;
  std::vector<std::array<int64_t, 3>> faces;  // 1-based or negative, resolved at the end
  std::vector<size_t> face_lines;
  const auto fail = [&](const std::string& what) { return error = name + ": line " + std::to_string(line.number) + ": " + what, false; };
  while (lines.next(line)) {
    // OBJ separates by whitespace only.
    std::vector<std::string> w;
    for (size_t at = 0; at < line.text.size();) {
      while (at < line.text.size() && (line.text[at] == ' ' || line.text[at] == '\t')) ++at;
      size_t stop = at;
      while (stop < line.text.size() && line.text[stop] != ' ' && line.text[stop] != '\t') ++stop;
      if (stop > at) w.push_back(line.text.substr(at, stop - at));
      at = stop;
    }
    if (w.empty()) continue;
    if (w[0] == "v") {
      if (w.size() != 4 && w.size() != 5 && w.size() != 7)
        return fail("a vertex has " + std::to_string(w.size() - 1) + " numbers (expected x y z, x y z w or x y z r g b)");
      double v[6] = {0, 0, 0, 0, 0, 0};
      for (size_t k = 1; k < w.size(); ++k) {
        const auto r = std::from_chars(w[k].data(), w[k].data() + w[k].size(), v[k - 1]);
        if (r.ec != std::errc() || r.ptr != w[k].data() + w[k].size() || !std::isfinite(v[k - 1]))
          return fail("malformed number '" + w[k].substr(0, 40) + "' in a vertex");
      }
      Vec3 p(v[0], v[1], v[2]);
      if (w.size() == 5 && v[3] != 0) p /= v[3];  // homogeneous w
      cloud.positions.push_back(p);
      if (w.size() == 7) {
        // Colour as MeshLab writes it: 0..1 (0..255 read as such where a value exceeds 1).
        Vec3 c(v[3], v[4], v[5]);
        if (c.maxCoeff() > 1) c /= 255.0;
        if (c.minCoeff() < 0 || c.maxCoeff() > 1) return fail("a vertex colour outside 0..1 (or 0..255)");
        colours.push_back(c);
        some_coloured = true;
      } else {
        colours.push_back(Vec3::Constant(-1));
      }
    } else if (w[0] == "f") {
      if (w.size() < 4) return fail("a face needs at least three vertices");
      std::vector<int64_t> index;
      for (size_t k = 1; k < w.size(); ++k) {
        const std::string vertex = w[k].substr(0, w[k].find('/'));
        int64_t i = 0;
        const auto r = std::from_chars(vertex.data(), vertex.data() + vertex.size(), i);
        if (r.ec != std::errc() || r.ptr != vertex.data() + vertex.size() || i == 0)
          return fail("malformed face vertex '" + w[k].substr(0, 40) + "'");
        // Negative: counting back from the vertices read so far.
        if (i < 0) i += static_cast<int64_t>(cloud.positions.size()) + 1;
        if (i < 1) return fail("face vertex " + w[k] + " refers before the first vertex");
        index.push_back(i);
      }
      for (size_t k = 2; k < index.size(); ++k) {
        faces.push_back({index[0], index[k - 1], index[k]});
        face_lines.push_back(static_cast<size_t>(line.number));
      }
    }
    // vn, vt, vp, l, o, g, s, mtllib, usemtl and others: not points.
  }
  if (cloud.positions.empty()) return error = name + ": no vertices ('v' lines) in what reads as OBJ", false;
  for (size_t i = 0; i < faces.size(); ++i) {
    for (int64_t v : faces[i])
      if (v > static_cast<int64_t>(cloud.positions.size()))
        return error = name + ": line " + std::to_string(face_lines[i]) + ": face vertex " + std::to_string(v) +
                       " beyond the file's " + std::to_string(cloud.positions.size()) + " vertices",
               false;
    cloud.triangles.push_back({static_cast<uint32_t>(faces[i][0] - 1), static_cast<uint32_t>(faces[i][1] - 1),
                               static_cast<uint32_t>(faces[i][2] - 1)});
  }
  if (some_coloured) {
    if (std::any_of(colours.begin(), colours.end(), [](const Vec3& c) { return c.x() < 0; }))
      cloud.warnings.push_back(name + ": some vertices have colours and some not: colours dropped");
    else
      cloud.colors = colours;
  }
  cloud.warnings.push_back(name + ": read as Wavefront OBJ: " + std::to_string(cloud.positions.size()) + " vertices" +
                           (faces.empty() ? "" : ", " + std::to_string(faces.size()) + " triangles for normals"));
  return true;
}

bool looks_like_e57(const uint8_t* data, size_t size) { return size >= 8 && std::memcmp(data, "ASTM-E57", 8) == 0; }

std::string e57_refusal(const std::string& name) {
  return name + ": this is an E57 file (ASTM E2807), which stipple does not read: convert it to PLY, LAS or PTS "
                "first (CloudCompare: open it, then File > Save as PLY; PDAL: pdal translate " + name + " scan.las)";
}

}  // namespace stipple
