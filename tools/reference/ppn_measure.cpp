// stipple host — points-per-node measurement. See ppn_measure.h.
#include "tools/reference/ppn_measure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "raster/point_raster.h"

namespace stipple {
namespace {

// The first kPpnMaxCount samples of each source, built once.
const std::vector<Gaussian3Q12>& samples(GaussianSource source) {
  static const std::vector<Gaussian3Q12> tables[2] = {
      [] {
        std::vector<Gaussian3Q12> t(kPpnMaxCount);
        build_gaussian3_table(GaussianSource::kSobol, t.data(), t.size());
        return t;
      }(),
      [] {
        std::vector<Gaussian3Q12> t(kPpnMaxCount);
        build_gaussian3_table(GaussianSource::kPseudo, t.data(), t.size());
        return t;
      }()};
  return tables[source == GaussianSource::kSobol ? 0 : 1];
}

}  // namespace

double ppn_coverage(double sigma1, double sigma2, uint32_t n, const PpnMeasureOptions& options) {
  const std::vector<Gaussian3Q12>& g = samples(options.source);
  n = std::min<uint32_t>(n, static_cast<uint32_t>(g.size()));
  // A frame that holds the 2-sigma ellipse with a margin.
  const int half = static_cast<int>(std::ceil(2 * sigma1)) + 4;
  const int size = 2 * half;
  RasterConfig config;
  config.width = config.height = static_cast<uint16_t>(size);
  config.tile_log2 = 5;
  config.format = PixelFormat::kRgb888;
  config.max_points = 4 * n + 4;  // room for every point's tile entries: none is dropped
  std::vector<uint64_t> arena(point_raster_bytes(config) / 8 + 1);
  PointRaster raster;
  if (raster.init(config, arena.data(), arena.size() * 8) != RasterStatus::kOk) return 0;
  std::vector<uint8_t> frame(static_cast<size_t>(size) * size * 3);
  double total = 0;
  for (int trial = 0; trial < options.trials; ++trial) {
    // Rotation by the golden angle, sub-pixel offsets on a 2-D lattice.
    const double angle = 2 * std::numbers::pi * std::fmod(trial * 0.6180339887498949, 1.0);
    const double ox = half + std::fmod(trial * 0.7548776662466927, 1.0);
    const double oy = half + std::fmod(trial * 0.5698402909980532, 1.0);
    const double c = std::cos(angle), s = std::sin(angle);
    raster.begin_frame();
    for (uint32_t j = 0; j < n; ++j) {
      const double u = sigma1 * g[j].v[0] / 4096.0, v = sigma2 * g[j].v[1] / 4096.0;
      const double x = ox + c * u - s * v, y = oy + s * u + c * v;
      (void)raster.add(ScreenPoint{static_cast<int32_t>(std::lround(x * 16)), static_cast<int32_t>(std::lround(y * 16)), 0,
                                   0xFFFFFF},
                       options.point_size);
    }
    raster.draw(0, frame.data(), static_cast<size_t>(size) * 3);
    // Pixels whose centres lie in the 2-sigma ellipse.
    long inside = 0, covered = 0;
    for (int py = 0; py < size; ++py)
      for (int px = 0; px < size; ++px) {
        const double dx = px + 0.5 - ox, dy = py + 0.5 - oy;
        const double a = (c * dx + s * dy) / sigma1, b = (-s * dx + c * dy) / sigma2;
        if (a * a + b * b > 4) continue;
        ++inside;
        covered += frame[(static_cast<size_t>(py) * size + px) * 3] != 0;
      }
    total += inside == 0 ? 1.0 : static_cast<double>(covered) / static_cast<double>(inside);
  }
  return total / options.trials;
}

uint32_t ppn_points_needed(double sigma1, double sigma2, const PpnMeasureOptions& options) {
  const auto enough = [&](uint32_t n) { return ppn_coverage(sigma1, sigma2, n, options) >= options.coverage; };
  uint32_t hi = 1;
  while (hi < options.max_count && !enough(hi)) hi *= 2;
  if (hi >= options.max_count) {
    hi = options.max_count;
    if (!enough(hi)) return options.max_count;
  }
  uint32_t lo = hi / 2;  // !enough(lo) unless lo == 0
  while (hi - lo > 1) {
    const uint32_t mid = lo + (hi - lo) / 2;
    (enough(mid) ? hi : lo) = mid;
  }
  return hi;
}

void measure_ppn_table(const PpnMeasureOptions& options, PpnTable& out, const std::function<void(double)>& progress) {
  for (auto& row : out)
    for (auto& e : row) e = 0;
  constexpr int kS1Steps = 8 * 10;  // sigma1 = 2^-5 .. 2^5 px
  constexpr int kRatioSteps = 4 * 9;  // sigma2 / sigma1 = 1 .. 2^-9
  for (int i = 0; i <= kS1Steps; ++i) {
    const double s1 = std::exp2(-5.0 + i / 8.0);
    for (int k = 0; k <= kRatioSteps; ++k) {
      const double s2 = s1 * std::exp2(-k / 4.0);
      // The index the client computes from M = diag(16 s1, 16 s2) (1/16 px per sigma).
      const int64_t a = std::llround(256 * s1 * s1), c = std::llround(256 * s2 * s2);
      const PpnIndex idx = ppn_index(a, 0, c);
      const uint32_t n = ppn_points_needed(s1, s2, options);
      uint16_t& e = out[idx.size][idx.aspect];
      e = static_cast<uint16_t>(std::max<uint32_t>(e, n));
    }
    if (progress) progress(static_cast<double>(i + 1) / (kS1Steps + 1));
  }
  // Fill: along size, an unmeasured entry takes the previous size's count;
  // the smallest sizes take 1. Then counts never fall as the size grows.
  for (int d = 0; d < kPpnAspects; ++d) {
    uint16_t last = 1;
    for (int t = 0; t < kPpnSizes; ++t) {
      if (out[t][d] == 0) out[t][d] = last;
      if (out[t][d] < last) out[t][d] = last;
      last = out[t][d];
    }
  }
  // Sizes beyond the grid: the ceiling.
  for (int d = 0; d < kPpnAspects; ++d) out[kPpnSizes - 1][d] = static_cast<uint16_t>(options.max_count);
}

std::string ppn_table_source(const PpnTable tables[2][kPpnPointSizes], const PpnMeasureOptions& options) {
  std::string s;
  char line[320];
  std::snprintf(line, sizeof line,
                "// Generated by `stipple ppn-table --write raster/ppn_table.inc`: coverage %.2f of the 2-sigma\n"
                "// ellipse, %d placements. [source: Sobol, pseudo][point size 1..3][t][d]. Do not edit.\n",
                options.coverage, options.trials);
  s += line;
  for (int src = 0; src < 2; ++src) {
    s += "{\n";
    for (int p = 0; p < kPpnPointSizes; ++p) {
      s += " {\n";
      for (int t = 0; t < kPpnSizes; ++t) {
        s += "  {";
        for (int d = 0; d < kPpnAspects; ++d) {
          std::snprintf(line, sizeof line, "%s%u", d ? "," : "", static_cast<unsigned>(tables[src][p][t][d]));
          s += line;
        }
        s += t + 1 < kPpnSizes ? "},\n" : "}\n";
      }
      s += p + 1 < kPpnPointSizes ? " },\n" : " }\n";
    }
    s += src == 0 ? "},\n" : "}\n";
  }
  return s;
}

}  // namespace stipple
