// stipple host — in-process rendering. See render.h.
#include "tools/reference/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "raster/close_up.h"
#include "tools/reference/sampler.h"

namespace stipple {
namespace {

constexpr double kTurn = 4294967296.0;  // 2^32
constexpr double kMu = 16777216.0;      // 2^24 MU per largest extent

double radians(uint32_t angle) { return angle / kTurn * 2 * std::numbers::pi; }

}  // namespace

ReferenceCamera reference_camera(const Vec3& bbox_min, const Vec3& bbox_max, const SpgHeader& header,
                                 const ClientConfig& config, const ViewSpec& spec) {
  ReferenceCamera cam;
  const int w = config.raster.width, h = config.raster.height;
  // Model units as the fixed decoder defines them.
  const Vec3 extent = bbox_max - bbox_min;
  const double largest = std::max({extent.x(), extent.y(), extent.z(), 0.0}) > 0 ? extent.maxCoeff() : 1.0;
  cam.to_mu = kMu / largest;
  cam.bbox_min = bbox_min;
  int32_t extent_mu[3];
  for (int a = 0; a < 3; ++a) extent_mu[a] = static_cast<int32_t>(std::llround(extent[a] * cam.to_mu));
  const OrbitView o = orbit_view(extent_mu, resolve_view(spec, header, extent_mu));
  // The camera of orbit_camera, in doubles, turned by the same axis permutation.
  const double yaw = radians(o.yaw), pitch = radians(o.pitch), fov = radians(o.fov);
  int32_t permutation[3][3];
  orbit_basis(o.up, permutation);
  Mat3 basis;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) basis(i, j) = permutation[i][j];
  const Vec3 back = basis * Vec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
  const Vec3 right = basis * Vec3(std::cos(yaw), 0, -std::sin(yaw));
  const Vec3 up = back.cross(right);
  cam.R.row(0) = right.transpose();
  cam.R.row(1) = -up.transpose();
  cam.R.row(2) = -back.transpose();
  const Vec3 target(o.target_mu[0], o.target_mu[1], o.target_mu[2]);
  cam.eye = target + o.distance_mu * back;
  cam.focal = (h / 2.0) / std::tan(fov / 2);
  cam.cx = w / 2.0;
  cam.cy = h / 2.0;
  cam.near = std::max(o.distance_mu / 64, kCameraMinDistance);
  // Lighting in camera space, then in the model.
  const Lighting& L = config.lighting;
  const Vec3 light_cam = Vec3(L.light_q14[0], L.light_q14[1], L.light_q14[2]).normalized();
  Vec3 half_cam = (light_cam + Vec3(0, 0, -1));
  half_cam = half_cam.norm() > 0 ? half_cam.normalized() : Vec3(0, 0, -1);
  cam.light = cam.R.transpose() * light_cam;
  cam.half = cam.R.transpose() * half_cam;
  cam.ambient = std::min<int>(L.ambient_q8, 256) / 256.0;
  cam.strength = L.specular_q8 / 256.0;
  return cam;
}

Image image_of(const std::vector<uint32_t>& color_buf, const ClientConfig& config) {
  Image img;
  img.width = config.raster.width;
  img.height = config.raster.height;
  img.rgb.resize(color_buf.size() * 3);
  for (size_t i = 0; i < color_buf.size(); ++i) {
    uint32_t v = color_buf[i];
    if (config.raster.format == PixelFormat::kRgb565) v = rgb888_from_565(rgb565(v));
    img.rgb[3 * i] = static_cast<uint8_t>(v >> 16);
    img.rgb[3 * i + 1] = static_cast<uint8_t>(v >> 8);
    img.rgb[3 * i + 2] = static_cast<uint8_t>(v);
  }
  return img;
}

Image render_reference(const DecodedModel& model, const std::vector<uint32_t>& cut, const ClientConfig& config,
                       const ViewSpec& spec) {
  const int w = config.raster.width, h = config.raster.height;
  const ReferenceCamera cam = reference_camera(model.bbox_min, model.bbox_max, model.header, config, spec);
  const Mat3& R = cam.R;
  const Vec3& eye = cam.eye;
  const double to_mu = cam.to_mu, focal = cam.focal, cx = cam.cx, cy = cam.cy, near = cam.near;
  const Lighting& L = config.lighting;
  const Vec3 light = cam.light, half = cam.half;
  const double ambient = cam.ambient, strength = cam.strength;

  const bool normals = model.header.has_normals() && config.shading != ShadingMode::kNone;
  const bool per_point_normals = normals && config.shading == ShadingMode::kPerPoint;
  const bool surface_normals = normals && config.shading == ShadingMode::kSurface;
  const bool specular = normals && L.specular_q8 > 0;
  const bool color = model.header.has_color() && !config.grey;
  const bool color_points = color && config.sample_color;
  const PpnTable& table = ppn_table(config.source, config.point_size);
  std::vector<Gaussian3Q12> pseudo3(config.samples), pseudo_c(config.samples);
  std::vector<Gaussian2Q12> pseudo2(config.samples);
  if (config.source == GaussianSource::kPseudo) {
    build_gaussian3_table(config.source, pseudo3.data(), pseudo3.size());
    build_gaussian3_table(config.source, pseudo_c.data(), pseudo_c.size(), kColorSobolDim);
    build_gaussian2_table(config.source, pseudo2.data(), pseudo2.size());
  }
  auto g3 = [&](uint32_t j, int dim) -> Vec3 {
    if (config.source == GaussianSource::kSobol) return reference_gaussian3(j + 1, dim);
    const Gaussian3Q12& q = dim == 0 ? pseudo3[j] : pseudo_c[j];
    return Vec3(q.v[0], q.v[1], q.v[2]) / 4096.0;
  };
  auto g2 = [&](uint32_t j) -> Vec2 {
    if (config.source == GaussianSource::kSobol) return reference_gaussian2(j + 1);
    return Vec2(pseudo2[j].v[0], pseudo2[j].v[1]) / 4096.0;
  };

  std::vector<double> depth(static_cast<size_t>(w) * h, std::numeric_limits<double>::infinity());
  std::vector<uint32_t> color_buf(static_cast<size_t>(w) * h, config.clear_rgb);
  const Vec3 grey(((config.grey_rgb >> 16) & 255), ((config.grey_rgb >> 8) & 255), (config.grey_rgb & 255));
  const int s = config.point_size;
  const bool close_ups = config.close_ups && config.point_cap == 0;
  const auto plot = [&](int px, int py, double z, uint32_t rgb) {
    const size_t i = static_cast<size_t>(py) * w + px;
    if (z < depth[i]) {
      depth[i] = z;
      color_buf[i] = rgb;
    }
  };
  for (uint32_t id : cut) {
    const DecodedNode& node = model.nodes[id];
    const Vec3 mean = (node.position.mean - model.bbox_min) * to_mu;
    const Mat3 axes = node.position.frame * node.position.sigma.asDiagonal() * to_mu;  // columns: sigma-scaled axes, MU
    const Vec3 c = R * (mean - eye);
    const Mat3 A = R * axes;  // camera-space axes (columns)
    const Vec3 base = color ? Vec3(node.color.mean * 255.0) : grey;
    const Vec3 n0 = node.normal_frame.col(2);
    // kSurface: the sample's offset along each tangent of the normal frame,
    // in units of the node's spread along it, is how many sigma_n its
    // normal turns (the fixed client's rule, raster/point_renderer.h).
    Eigen::Matrix<double, 2, 3> surface = Eigen::Matrix<double, 2, 3>::Zero();
    if (surface_normals)
      for (int k = 0; k < 2; ++k) {
        const Eigen::RowVector3d along = node.normal_frame.col(k).transpose() * axes;
        if (along.norm() > 0) surface.row(k) = along / along.norm();
      }
    // The colour of position sample g (sigmas along the frame's axes; j
    // indexes the normal and colour samples, -1: the node's mean colour).
    const auto shaded = [&](const Vec3& g, int64_t j) {
      Vec3 col = base;
      if (color_points && j >= 0)
        col = (node.color.mean + node.color.frame * node.color.sigma.cwiseProduct(g3(static_cast<uint32_t>(j), kColorSobolDim))).cwiseMax(0.0).cwiseMin(1.0) * 255.0;
      double intensity = 1, highlight = 0;
      if (normals) {
        Vec3 n = n0;
        if ((per_point_normals && j >= 0) || surface_normals) {
          const Vec2 t = surface_normals ? Vec2(surface * g) : g2(static_cast<uint32_t>(j));
          // Signed sigma_n (the curvature's sign) turns the surface; a sampled normal takes the spread.
          const Vec2 sn = surface_normals ? node.sigma_n : Vec2(node.sigma_n.cwiseAbs());
          const double a = sn[0] * t.x(), b = sn[1] * t.y();
          const double theta = std::hypot(a, b), phi = std::atan2(b, a);
          n = node.normal_frame * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
        }
        intensity = ambient + (1 - ambient) * std::max(0.0, light.dot(n));
        if (specular) highlight = 255 * strength * std::pow(std::max(0.0, half.dot(n)), L.shininess);
      }
      col = (col * intensity).array() + highlight;
      uint32_t rgb = 0;
      for (int k = 0; k < 3; ++k) rgb = (rgb << 8) | static_cast<uint32_t>(std::clamp(std::lround(col[k]), 0L, 255L));
      return rgb;
    };
    // A close-up's disc (raster/close_up.h): every pixel's ray cast at the
    // plane of the two larger axes, within 3 sigma; shaded per pixel by
    // the place it hits.
    const auto disc = [&] {
      const Vec3 sg = node.position.sigma * to_mu;
      const int kn = sg[2] <= sg[1] ? (sg[2] <= sg[0] ? 2 : 0) : (sg[1] <= sg[0] ? 1 : 0);
      const int k1 = kn == 0 ? 1 : 0, k2 = kn == 2 ? 1 : 2;
      const Mat3 F = R * node.position.frame;
      Vec3 n = F.col(kn);
      double nc = n.dot(c);
      if (nc == 0 || !(sg[k1] > 0) || !(sg[k2] > 0)) return;
      if (nc < 0) n = -n, nc = -nc;
      for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
          const Vec3 d(px + 0.5 - cx, py + 0.5 - cy, focal);
          const double wd = n.dot(d);
          if (wd <= 0) continue;
          const Vec3 p = d * (nc / wd);
          if (p.z() < near) continue;
          Vec3 g = Vec3::Zero();
          g[k1] = F.col(k1).dot(p - c) / sg[k1];
          g[k2] = F.col(k2).dot(p - c) / sg[k2];
          if (g[k1] * g[k1] + g[k2] * g[k2] > 9) continue;
          plot(px, py, p.z(), shaded(g, -1));
        }
    };
    if (c.z() <= near || std::abs(c.x()) > 8 * c.z() || std::abs(c.y()) > 8 * c.z()) {
      const double r = 3 * node.position.sigma.maxCoeff() * to_mu, z = c.z() + r;
      if (close_ups && z > near && std::abs(c.x()) - r <= 8 * z && std::abs(c.y()) - r <= 8 * z) disc();
      continue;
    }
    // Jacobian of the projection at the mean, px per MU; M = J A, px per sigma.
    Eigen::Matrix<double, 2, 3> J;
    J << focal / c.z(), 0, -focal * c.x() / (c.z() * c.z()), 0, focal / c.z(), -focal * c.y() / (c.z() * c.z());
    const Eigen::Matrix<double, 2, 3> M = J * A;
    const double sx0 = cx + focal * c.x() / c.z(), sy0 = cy + focal * c.y() / c.z();
    const double ex = 3.5 * M.row(0).cwiseAbs().sum(), ey = 3.5 * M.row(1).cwiseAbs().sum();
    const Eigen::Matrix2d S = M * M.transpose() * 256.0;  // 1/256 px^2
    // sigma1 sigma2 on screen, px^2: past 64 a disc, past 1 twice the points.
    const double area = std::sqrt(std::max(0.0, S.determinant())) / 256.0;
    if (close_ups && area > kCloseUpSigmaPx * kCloseUpSigmaPx) {
      disc();
      continue;
    }
    if (sx0 + ex < 0 || sx0 - ex >= w || sy0 + ey < 0 || sy0 - ey >= h) continue;
    // Saturated to +-2^40, NaN to +2^40 (the index saturates far below):
    // llround of a value beyond 2^63 has no defined result.
    const auto q = [](double v) { return std::llround(v < -0x1p40 ? -0x1p40 : v < 0x1p40 ? v : 0x1p40); };
    uint32_t count = points_per_node(table, ppn_index(q(S(0, 0)), q(S(0, 1)), q(S(1, 1))), config.quality_q8, config.samples);
    if (close_ups && area > double(1 << (2 * kCloseUpPointsLog2)))
      count = std::min<uint32_t>(count * kCloseUpPointsScale_q8 >> 8, config.samples);
    for (uint32_t j = 0; j < count; ++j) {
      const Vec3 p = c + A * g3(j, 0);
      if (p.z() < near) continue;
      if (std::abs(p.x()) > 8 * p.z() || std::abs(p.y()) > 8 * p.z()) continue;
      const double x = cx + focal * p.x() / p.z(), y = cy + focal * p.y() / p.z();
      const uint32_t rgb = shaded(g3(j, 0), j);
      const int x0 = static_cast<int>(std::floor(x - (s - 1) / 2.0)), y0 = static_cast<int>(std::floor(y - (s - 1) / 2.0));
      for (int py = std::max(y0, 0); py < std::min(y0 + s, h); ++py)
        for (int px = std::max(x0, 0); px < std::min(x0 + s, w); ++px) plot(px, py, p.z(), rgb);
    }
  }
  return image_of(color_buf, config);
}

}  // namespace stipple
