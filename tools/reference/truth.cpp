// stipple host — the reference picture from the scan. See truth.h.
#include "tools/reference/truth.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace stipple {

Image render_truth(const PointCloud& cloud, const Vec3& bbox_min, const Vec3& bbox_max, const SpgHeader& header,
                   const ClientConfig& config, const ViewSpec& spec, TruthStats* stats) {
  TruthStats st;
  const int w = config.raster.width, h = config.raster.height;
  const ReferenceCamera cam = reference_camera(bbox_min, bbox_max, header, config, spec);
  const Lighting& L = config.lighting;
  const bool lit = cloud.has_normals() && config.shading != ShadingMode::kNone;
  const bool specular = lit && L.specular_q8 > 0;
  const bool color = cloud.has_colors() && !config.grey;
  const Vec3 grey(((config.grey_rgb >> 16) & 255), ((config.grey_rgb >> 8) & 255), (config.grey_rgb & 255));
  // A vertex's colour, as the client shades a point with that normal.
  const auto shade = [&](size_t i) -> Vec3 {
    const Vec3 base = color ? Vec3(cloud.colors[i] * 255.0) : grey;
    if (!lit) return base;
    const Vec3& n = cloud.normals[i];
    const double intensity = cam.ambient + (1 - cam.ambient) * std::max(0.0, cam.light.dot(n));
    const double highlight = specular ? 255 * cam.strength * std::pow(std::max(0.0, cam.half.dot(n)), L.shininess) : 0.0;
    return (base * intensity).array() + highlight;
  };
  const auto pack = [](const Vec3& c) {
    uint32_t rgb = 0;
    for (int k = 0; k < 3; ++k) rgb = (rgb << 8) | static_cast<uint32_t>(std::clamp(std::lround(c[k]), 0L, 255L));
    return rgb;
  };
  std::vector<double> depth(static_cast<size_t>(w) * h, std::numeric_limits<double>::infinity());
  std::vector<uint32_t> color_buf(static_cast<size_t>(w) * h, config.clear_rgb);
  // Camera space and the screen, per vertex.
  std::vector<Vec3> screen(cloud.size());  // x px, y px, z (camera depth)
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Vec3 c = cam.camera_space(cloud.positions[i]);
    screen[i] = Vec3(cam.cx + cam.focal * c.x() / c.z(), cam.cy + cam.focal * c.y() / c.z(), c.z());
  }
  if (!cloud.triangles.empty()) {
    st.mesh = true;
    std::vector<Vec3> shaded(cloud.size());
    std::vector<char> done(cloud.size(), 0);
    for (const auto& t : cloud.triangles) {
      const Vec3 &a = screen[t[0]], &b = screen[t[1]], &c = screen[t[2]];
      if (a.z() <= cam.near || b.z() <= cam.near || c.z() <= cam.near) {
        ++st.skipped;
        continue;
      }
      const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
      if (area == 0 || !std::isfinite(area)) continue;
      const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
      const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
      const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
      const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
      if (x0 > x1 || y0 > y1) continue;
      for (int k = 0; k < 3; ++k)
        if (!done[t[k]]) shaded[t[k]] = shade(t[k]), done[t[k]] = 1;
      bool any = false;
      for (int py = y0; py <= y1; ++py)
        for (int px = x0; px <= x1; ++px) {
          const double x = px + 0.5, y = py + 0.5;
          // Barycentric weights of the pixel centre (either winding: both faces drawn).
          const double wa = ((b.x() - x) * (c.y() - y) - (b.y() - y) * (c.x() - x)) / area;
          const double wb = ((c.x() - x) * (a.y() - y) - (c.y() - y) * (a.x() - x)) / area;
          const double wc = 1 - wa - wb;
          if (wa < 0 || wb < 0 || wc < 0) continue;
          // Depth interpolated as 1/z (perspective-correct), colour in screen space (Gouraud).
          const double z = 1 / (wa / a.z() + wb / b.z() + wc / c.z());
          const size_t i = static_cast<size_t>(py) * w + px;
          if (z >= depth[i]) continue;
          depth[i] = z;
          color_buf[i] = pack(wa * shaded[t[0]] + wb * shaded[t[1]] + wc * shaded[t[2]]);
          any = true;
        }
      st.drawn += any;
    }
  } else {
    const int s = config.point_size;
    for (size_t i = 0; i < cloud.size(); ++i) {
      const Vec3& p = screen[i];
      if (p.z() <= cam.near) {
        ++st.skipped;
        continue;
      }
      const int x0 = static_cast<int>(std::floor(p.x() - (s - 1) / 2.0)), y0 = static_cast<int>(std::floor(p.y() - (s - 1) / 2.0));
      if (x0 + s <= 0 || y0 + s <= 0 || x0 >= w || y0 >= h) continue;
      const uint32_t rgb = pack(shade(i));
      for (int py = std::max(y0, 0); py < std::min(y0 + s, h); ++py)
        for (int px = std::max(x0, 0); px < std::min(x0 + s, w); ++px) {
          const size_t k = static_cast<size_t>(py) * w + px;
          if (p.z() < depth[k]) {
            depth[k] = p.z();
            color_buf[k] = rgb;
          }
        }
      ++st.drawn;
    }
  }
  if (stats) *stats = st;
  return image_of(color_buf, config);
}

}  // namespace stipple
