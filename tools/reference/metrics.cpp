// stipple host — Hausdorff / PSNR metrics. See metrics.h.
#include "tools/reference/metrics.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <thread>

#include "tools/scan/kdtree.h"

namespace stipple {

double psnr(double diagonal, double rms) {
  return rms > 0 ? 20 * std::log10(diagonal / rms) : std::numeric_limits<double>::infinity();
}

DirectedDistance directed_distance(const PointCloud& from, const PointCloud& to, int threads) {
  if (from.size() == 0 || to.size() == 0) return DirectedDistance{};
  return directed_distance(from, to, KdTree(to.positions), threads);
}

DirectedDistance directed_distance(const PointCloud& from, const PointCloud& to, const KdTree& tree, int threads) {
  DirectedDistance d;
  if (from.size() == 0 || to.size() == 0) return d;
  const bool normals = from.has_normals() && to.has_normals();
  const bool colors = from.has_colors() && to.has_colors();
  const size_t parts = static_cast<size_t>(std::max(1, threads));
  struct Partial {
    double sum2 = 0, sum = 0, max = 0, angle2 = 0, angle = 0, color2 = 0;
  };
  std::vector<Partial> partial(parts);
  auto work = [&](size_t part) {
    Partial& p = partial[part];
    const size_t lo = from.size() * part / parts, hi = from.size() * (part + 1) / parts;
    for (size_t i = lo; i < hi; ++i) {
      double d2;
      const uint32_t j = tree.nearest(from.positions[i], &d2);
      const double dist = std::sqrt(d2);
      p.sum2 += d2;
      p.sum += dist;
      p.max = std::max(p.max, dist);
      if (normals) {
        const double c = std::clamp(from.normals[i].dot(to.normals[j]), -1.0, 1.0);
        const double deg = std::acos(c) * 180 / std::numbers::pi;
        p.angle += deg;
        p.angle2 += deg * deg;
      }
      if (colors) p.color2 += (from.colors[i] - to.colors[j]).squaredNorm();
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < parts; ++t) pool.emplace_back(work, t);
  work(0);
  for (std::thread& t : pool) t.join();
  Partial total;
  for (const Partial& p : partial) {  // fixed order: deterministic sums
    total.sum2 += p.sum2;
    total.sum += p.sum;
    total.max = std::max(total.max, p.max);
    total.angle += p.angle;
    total.angle2 += p.angle2;
    total.color2 += p.color2;
  }
  const double n = static_cast<double>(from.size());
  d.rms = std::sqrt(total.sum2 / n);
  d.mean = total.sum / n;
  d.max = total.max;
  if (normals) {
    d.normal_rms_deg = std::sqrt(total.angle2 / n);
    d.normal_mean_deg = total.angle / n;
  }
  if (colors) d.color_rms = std::sqrt(total.color2 / n);
  return d;
}

CloudMetrics compare_clouds(const PointCloud& original, const PointCloud& generated, int threads) {
  return compare_clouds(original, KdTree(original.positions), generated, threads);
}

CloudMetrics compare_clouds(const PointCloud& original, const KdTree& original_tree, const PointCloud& generated,
                            int threads) {
  CloudMetrics m;
  m.diagonal = bounding_box(original.positions).diagonal();
  m.generated_to_original = directed_distance(generated, original, original_tree, threads);
  m.original_to_generated = directed_distance(original, generated, threads);
  m.psnr_one_sided = psnr(m.diagonal, m.generated_to_original.rms);
  m.psnr_symmetric = psnr(m.diagonal, std::max(m.generated_to_original.rms, m.original_to_generated.rms));
  m.hausdorff = std::max(m.generated_to_original.max, m.original_to_generated.max);
  return m;
}

}  // namespace stipple
