// stipple-make-scan — a synthetic airborne-LiDAR-like scan of any size, for
// the encoder's benchmarks at 10^6..10^9 points (big inputs are made, never
// committed).
//
// The terrain: rolling ground (a sum of sines) with flat-roofed buildings on
// a 40 m grid, sampled at 25 points a square metre over a square whose side
// grows with the count; 1 cm of height noise. Normals are the surface's
// (analytic, +z up), colours follow height and material. Point i depends only
// on i (a SplitMix64 hash), so the same count gives the same bytes on every
// machine, and memory stays a few megabytes whatever the count.
//
// Writes binary little-endian PLY (float32 x y z; float64 where --offset is
// given, so a georeferenced scan keeps its millimetres) or LAS 1.2 (point
// format 0, or 2 with --colour; scale 0.001).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "platform/progress.h"
#include "tools/embedded/options.h"

namespace {

const char kHelp[] =
    "usage: stipple-make-scan --points N -o OUT.ply|OUT.las [--normals] [--colour] [--offset X,Y,Z]\n"
    "\n"
    "Writes a synthetic airborne-LiDAR-like scan of N points (terrain with\n"
    "buildings, 25 points per square metre): the same bytes for the same options\n"
    "on every machine, in a few megabytes of memory whatever N.\n"
    "\n"
    "  --points N        how many points (1 to 4,294,967,295; 1e8 is accepted)\n"
    "  -o, --output F    F.ply: binary PLY; F.las: LAS 1.2\n"
    "  --normals         store the surface's normals (PLY only; LAS has none)\n"
    "  --colour          store RGB (LAS point format 2)\n"
    "  --offset X,Y,Z    add this to every point (a georeferenced scan); PLY\n"
    "                    then stores float64 coordinates\n";

uint64_t splitmix(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
double unit(uint64_t h) { return static_cast<double>(h >> 11) * 0x1.0p-53; }

struct Sample {
  double p[3];
  float n[3];
  uint8_t rgb[3];
};

constexpr double kDensity = 25;  // points per square metre
constexpr double kCell = 40;     // building grid

Sample sample(uint64_t i, double side) {
  const uint64_t h0 = splitmix(2 * i), h1 = splitmix(2 * i + 1);
  const double x = unit(h0) * side, y = unit(h1) * side;
  const double noise = (unit(splitmix(h0 ^ h1)) - 0.5) * 0.02;
  Sample s{};
  // A building: the central 24 m of a cell whose hash says so.
  const int64_t cx = static_cast<int64_t>(x / kCell), cy = static_cast<int64_t>(y / kCell);
  const uint64_t cell = splitmix(static_cast<uint64_t>(cx) * 0x10001ull + static_cast<uint64_t>(cy) + 0x5ca1ab1eull);
  const double fx = x - (static_cast<double>(cx) + 0.5) * kCell, fy = y - (static_cast<double>(cy) + 0.5) * kCell;
  const double ground = 3 * std::sin(x / 37) * std::cos(y / 53) + 1.5 * std::sin((x + y) / 11);
  if (unit(cell) < 0.35 && std::abs(fx) < 12 && std::abs(fy) < 12) {
    s.p[0] = x, s.p[1] = y, s.p[2] = 6 + 14 * unit(splitmix(cell)) + noise;
    s.n[0] = 0, s.n[1] = 0, s.n[2] = 1;
    const uint8_t tone = static_cast<uint8_t>(110 + 100 * unit(splitmix(cell + 1)));
    s.rgb[0] = tone, s.rgb[1] = static_cast<uint8_t>(tone * 0.55), s.rgb[2] = static_cast<uint8_t>(tone * 0.5);
    return s;
  }
  const double dx = 3 * std::cos(x / 37) / 37 * std::cos(y / 53) + 1.5 * std::cos((x + y) / 11) / 11;
  const double dy = -3 * std::sin(x / 37) * std::sin(y / 53) / 53 + 1.5 * std::cos((x + y) / 11) / 11;
  const double len = std::sqrt(dx * dx + dy * dy + 1);
  s.p[0] = x, s.p[1] = y, s.p[2] = ground + noise;
  s.n[0] = static_cast<float>(-dx / len), s.n[1] = static_cast<float>(-dy / len), s.n[2] = static_cast<float>(1 / len);
  const double t = std::clamp((ground + 4.5) / 9, 0.0, 1.0);
  s.rgb[0] = static_cast<uint8_t>(60 + 90 * t), s.rgb[1] = static_cast<uint8_t>(120 + 40 * t), s.rgb[2] = static_cast<uint8_t>(50 + 30 * t);
  return s;
}

void put(std::vector<uint8_t>& out, const void* p, size_t n) {
  const uint8_t* b = static_cast<const uint8_t*>(p);
  out.insert(out.end(), b, b + n);
}
template <class T>
void put(std::vector<uint8_t>& out, T v) {
  put(out, &v, sizeof v);  // little-endian hosts only (x86-64, ARM as built)
}

std::string las_header(uint64_t count, bool colour, const double offset[3], const double lo[3], const double hi[3]) {
  std::vector<uint8_t> h;
  put(h, "LASF", 4);
  put<uint16_t>(h, 0);  // file source id
  put<uint16_t>(h, 0);  // global encoding
  for (int k = 0; k < 16; ++k) put<uint8_t>(h, 0);  // project GUID
  put<uint8_t>(h, 1);
  put<uint8_t>(h, 2);
  char text[32] = {};
  std::snprintf(text, sizeof text, "stipple synthetic");
  put(h, text, 32);  // system identifier
  std::memset(text, 0, sizeof text);
  std::snprintf(text, sizeof text, "stipple-make-scan");
  put(h, text, 32);  // generating software
  put<uint16_t>(h, 1);
  put<uint16_t>(h, 2026);
  put<uint16_t>(h, 227);  // header size
  put<uint32_t>(h, 227);  // offset to point data
  put<uint32_t>(h, 0);    // variable length records
  put<uint8_t>(h, colour ? 2 : 0);
  put<uint16_t>(h, colour ? 26 : 20);
  put<uint32_t>(h, static_cast<uint32_t>(count));
  put<uint32_t>(h, static_cast<uint32_t>(count));  // by return: all first returns
  for (int k = 0; k < 4; ++k) put<uint32_t>(h, 0);
  for (int a = 0; a < 3; ++a) put<double>(h, 0.001);
  for (int a = 0; a < 3; ++a) put<double>(h, offset[a]);
  for (int a = 0; a < 3; ++a) {
    put<double>(h, hi[a] + offset[a]);
    put<double>(h, lo[a] + offset[a]);
  }
  return std::string(h.begin(), h.end());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace stipple;
  cli::Args args(argc, argv, 1);
  if (args.flag("--help") || args.flag("-h")) return std::fputs(kHelp, stdout), 0;
  std::string count_text, output, offset_text;
  args.value("--points", count_text);
  if (!args.value("-o", output)) args.value("--output", output);
  const bool normals = args.flag("--normals"), colour = args.flag("--colour") || args.flag("--color");
  const bool has_offset = args.value("--offset", offset_text);
  const auto fail = [](const std::string& m) { return std::fprintf(stderr, "stipple-make-scan: %s\n", m.c_str()), 2; };
  if (args.bad()) return fail(args.error());
  if (!args.unknown_option().empty()) return fail(args.unknown_option_message());
  if (!args.positionals().empty()) return fail(std::string("unexpected argument '") + args.positionals()[0] + "' (see --help)");
  double count_real = 0;
  if (count_text.empty() || !cli::parse_double(count_text, count_real) || count_real < 1 || count_real > 4294967295.0 ||
      count_real != std::floor(count_real))
    return fail(std::string("--points: expected a whole number from 1 to 4,294,967,295, got '") + count_text + "'");
  const uint64_t count = static_cast<uint64_t>(count_real);
  double offset[3] = {0, 0, 0};
  if (has_offset && !cli::parse_vec3(offset_text, offset)) return fail(std::string("--offset: expected X,Y,Z, got '") + offset_text + "'");
  const bool las = output.size() > 4 && output.compare(output.size() - 4, 4, ".las") == 0;
  const bool ply = output.size() > 4 && output.compare(output.size() - 4, 4, ".ply") == 0;
  if (!las && !ply) return fail(std::string("-o: expected a name ending in .ply or .las, got '") + output + "'");
  if (las && normals) return fail("--normals: LAS stores no normals (write a .ply)");

  const double side = std::sqrt(static_cast<double>(count) / kDensity);
  const std::string partial = output + ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "wb");
  if (!f) return fail(partial + ": " + std::strerror(errno));
  std::string header;
  if (las) {
    const double lo[3] = {0, 0, -4.6}, hi[3] = {side, side, 20.1};
    header = las_header(count, colour, offset, lo, hi);
  } else {
    const char* type = has_offset ? "double" : "float";
    header = "ply\nformat binary_little_endian 1.0\ncomment stipple-make-scan synthetic terrain\nelement vertex ";
    header += std::to_string(count);
    for (const char* axis : {"x", "y", "z"}) header.append("\nproperty ").append(type).append(" ").append(axis);
    header += "\n";
    if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
    if (colour) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    header += "end_header\n";
  }
  bool ok = std::fwrite(header.data(), 1, header.size(), f) == header.size();
  ProgressBar progress(std::string("make-scan ") + output);
  std::vector<uint8_t> chunk;
  constexpr uint64_t kChunk = 1 << 16;
  for (uint64_t at = 0; ok && at < count; at += kChunk) {
    chunk.clear();
    const uint64_t end = std::min(count, at + kChunk);
    for (uint64_t i = at; i < end; ++i) {
      const Sample s = sample(i, side);
      if (las) {
        for (int a = 0; a < 3; ++a) put<int32_t>(chunk, static_cast<int32_t>(std::lround(s.p[a] / 0.001)));
        put<uint16_t>(chunk, 100);  // intensity
        put<uint8_t>(chunk, 0x09);  // return 1 of 1
        put<uint8_t>(chunk, 2);     // classification: ground
        put<int8_t>(chunk, 0);
        put<uint8_t>(chunk, 0);
        put<uint16_t>(chunk, 0);
        if (colour)
          for (int c = 0; c < 3; ++c) put<uint16_t>(chunk, static_cast<uint16_t>(s.rgb[c] * 257));
        continue;
      }
      for (int a = 0; a < 3; ++a) {
        if (has_offset) put<double>(chunk, s.p[a] + offset[a]);
        else put<float>(chunk, static_cast<float>(s.p[a]));
      }
      if (normals) put(chunk, s.n, sizeof s.n);
      if (colour) put(chunk, s.rgb, 3);
    }
    ok = std::fwrite(chunk.data(), 1, chunk.size(), f) == chunk.size();
    progress.update(static_cast<double>(end) / static_cast<double>(count), cli::with_commas(end) + " points");
  }
  progress.finish();
  ok = std::fclose(f) == 0 && ok;
  if (!ok || std::rename(partial.c_str(), output.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(partial.c_str());
    return fail(output + ": " + why);
  }
  std::fprintf(stderr, "stipple-make-scan: %s: %s points, %.0f m square\n", output.c_str(), cli::with_commas(count).c_str(), side);
  return 0;
}
