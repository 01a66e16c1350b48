// stipple host — reference sampler (TOG05 §6). See sampler.h.
#include "tools/reference/sampler.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/sobol.h"

namespace stipple {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

double unit(uint32_t s) { return (static_cast<double>(s) + 0.5) * 0x1.0p-32; }  // (0, 1)

}  // namespace

// Unit-variance 3-D sample from Sobol dimensions d0..d0+2, radius clipped at gamma.
Vec3 reference_gaussian3(uint32_t index, int d0) {
  const double r0 = unit(sobol_u32(index, d0)), r1 = unit(sobol_u32(index, d0 + 1));
  const double r2 = 2 * unit(sobol_u32(index, d0 + 2)) - 1;
  const double tau = std::min(std::sqrt(-2 * std::log(r0)) * std::sqrt(1.5), kGamma);
  const double ring = std::sqrt(std::max(0.0, 1 - r2 * r2));
  return tau * Vec3(ring * std::cos(kTwoPi * r1), ring * std::sin(kTwoPi * r1), r2);
}

Vec2 reference_gaussian2(uint32_t index) {
  const double r0 = unit(sobol_u32(index, 3)), r1 = unit(sobol_u32(index, 4));
  const double tau = std::min(std::sqrt(-2 * std::log(r0)), kGamma);
  return tau * Vec2(std::cos(kTwoPi * r1), std::sin(kTwoPi * r1));
}

uint64_t cut_sample_count(const DecodedModel& model, const std::vector<uint32_t>& cut, uint32_t per_node) {
  uint64_t total = 0;
  for (uint32_t id : cut) total += per_node ? per_node : model.nodes[id].point_count;
  return total;
}

PointCloud sample_cut(const DecodedModel& model, const std::vector<uint32_t>& cut, uint32_t per_node) {
  PointCloud out;
  const bool normals = model.header.has_normals(), colors = model.header.has_color();
  const uint64_t total = cut_sample_count(model, cut, per_node);
  out.positions.reserve(total);
  if (normals) out.normals.reserve(total);
  if (colors) out.colors.reserve(total);
  for (uint32_t id : cut) {
    const DecodedNode& node = model.nodes[id];
    const uint32_t count = per_node ? per_node : node.point_count;
    for (uint32_t j = 0; j < count; ++j) {
      const uint32_t index = j + 1;
      const Vec3 g = reference_gaussian3(index, 0);
      out.positions.push_back(node.position.mean + node.position.frame * node.position.sigma.cwiseProduct(g));
      if (normals) {
        const Vec2 t = reference_gaussian2(index);
        const double a = std::abs(node.sigma_n[0]) * t.x(), b = std::abs(node.sigma_n[1]) * t.y();  // the spread
        const double theta = std::hypot(a, b), phi = std::atan2(b, a);
        const Vec3 local(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        out.normals.push_back((node.normal_frame * local).normalized());
      }
      if (colors) {
        const Vec3 c = node.color.mean + node.color.frame * node.color.sigma.cwiseProduct(reference_gaussian3(index, 5));
        out.colors.push_back(c.cwiseMax(0.0).cwiseMin(1.0));
      }
    }
  }
  return out;
}

}  // namespace stipple
