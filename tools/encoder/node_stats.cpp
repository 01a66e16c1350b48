// stipple host — node statistics (TOG05 §3). See node_stats.h.
#include "tools/encoder/node_stats.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

namespace stipple {

Vec3 any_perpendicular(const Vec3& v) {
  // Cross with the coordinate axis least aligned with v.
  Eigen::Index axis;
  v.cwiseAbs().minCoeff(&axis);
  return v.cross(Vec3::Unit(axis)).normalized();
}

Gaussian3 gaussian_from_covariance(const Vec3& mean, const Mat3& cov) {
  Gaussian3 g;
  g.mean = mean;
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
  const Vec3 lambda = eig.eigenvalues();  // ascending
  for (int k = 0; k < 3; ++k) g.sigma[k] = std::sqrt(std::max(0.0, lambda[2 - k]));
  g.frame.col(0) = eig.eigenvectors().col(2);
  g.frame.col(1) = eig.eigenvectors().col(1);
  g.frame.col(2) = g.frame.col(0).cross(g.frame.col(1)).normalized();
  return g;
}

namespace {

// Mean and sum of centred outer products of value(0) .. value(n - 1), two
// passes (the mean relative to the first value, then the products about it).
template <class Value>
void centred_moments(const Value& value, size_t n, Vec3& mean, Mat3& m2) {
  const Vec3 origin = value(0);
  Vec3 sum = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) sum += value(i) - origin;
  mean = origin + sum / static_cast<double>(n);
  m2 = Mat3::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Vec3 d = value(i) - mean;
    m2.noalias() += d * d.transpose();
  }
}

}  // namespace

Gaussian3 pca3(const Vec3* values, const uint32_t* ids, size_t n) {
  if (n == 0) return Gaussian3{};
  Vec3 mean;
  Mat3 m2;
  centred_moments([&](size_t i) -> const Vec3& { return values[ids[i]]; }, n, mean, m2);
  return gaussian_from_covariance(mean, m2 / static_cast<double>(n));
}

Gaussian3 pca3(const Vec3* values, size_t n) {
  if (n == 0) return Gaussian3{};
  Vec3 mean;
  Mat3 m2;
  centred_moments([&](size_t i) -> const Vec3& { return values[i]; }, n, mean, m2);
  return gaussian_from_covariance(mean, m2 / static_cast<double>(n));
}


void Moments::add(const Moments& o) {
  if (o.count == 0) return;
  if (count == 0) {
    *this = o;
    return;
  }
  // Chan, Golub and LeVeque's pairwise update: exact, and stable where the
  // means are far apart.
  const double n = count + o.count;
  const Vec3 delta = o.mean - mean;
  mean += delta * (o.count / n);
  m2 += o.m2 + delta * delta.transpose() * (count * o.count / n);
  count = n;
}

Moments moments_of(const Vec3* values, size_t n) {
  Moments m;
  if (n == 0) return m;
  m.count = static_cast<double>(n);
  centred_moments([&](size_t i) -> const Vec3& { return values[i]; }, n, m.mean, m.m2);
  return m;
}

Moments color_moments(const PointCloud& cloud, const uint32_t* ids, size_t n, const StatsOptions& o) {
  Moments m;
  if (o.colors && cloud.has_colors() && n > 0) {
    m.count = static_cast<double>(n);
    centred_moments([&](size_t i) -> const Vec3& { return cloud.colors[ids[i]]; }, n, m.mean, m.m2);
  }
  return m;
}

LogMapFrame log_map_frame(const Vec3& normal_sum, size_t n, const Vec3& fallback_z) {
  const double len = normal_sum.norm();
  LogMapFrame f;
  f.m = (len > 1e-9 * static_cast<double>(n) && std::isfinite(len)) ? Vec3(normal_sum / len) : fallback_z;
  f.t1 = any_perpendicular(f.m);
  f.t2 = f.m.cross(f.t1);
  return f;
}

void LogMapSums::add(const LogMapSums& other) {
  cov += other.cov;
  turn += other.turn;
  used += other.used;
}

void accumulate_log_map(const LogMapFrame& f, const Vec3* normals, size_t n, LogMapSums& sums, const Vec3* positions,
                        const Vec3& mean) {
  for (size_t i = 0; i < n; ++i) {
    const Vec3& nv = normals[i];
    if (nv.squaredNorm() == 0) continue;
    const double x = nv.dot(f.t1), y = nv.dot(f.t2), z = nv.dot(f.m);
    const double r2 = x * x + y * y;
    Vec2 uv = Vec2::Zero();
    if (r2 > 0 && z > 0 && r2 < 0.01 * z * z) {
      // Within 0.1 rad of m (most normals of most nodes): theta / r =
      // atan(t) / (t z) with t = r / z, and atan(t) / t = 1 - t^2/3 + t^4/5
      // - ..., whose terms past t^16 / 17 are below 1e-17 here. A third of
      // the hierarchy's time went to atan2 and hypot.
      const double t2 = r2 / (z * z);
      double series = 1.0 / 17;
      for (int k = 15; k >= 1; k -= 2) series = 1.0 / k - t2 * series;
      const double scale = series / z;
      uv = Vec2(scale * x, scale * y);
    } else if (r2 > 0) {
      const double r = std::hypot(x, y);
      const double theta = std::atan2(r, z);  // accurate near 0 and pi, unlike acos
      uv = Vec2(theta * x / r, theta * y / r);
    }
    sums.cov.noalias() += uv * uv.transpose();
    if (positions) sums.turn.noalias() += uv * (positions[i] - mean).transpose();
    ++sums.used;
  }
}

NormalSpread finish_log_map(const LogMapFrame& f, const LogMapSums& sums) {
  const double scale = sums.used > 0 ? 1.0 / static_cast<double>(sums.used) : 1.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(sums.cov * scale);
  NormalSpread s;
  s.sigma = Vec2(std::sqrt(std::max(0.0, eig.eigenvalues()[1])), std::sqrt(std::max(0.0, eig.eigenvalues()[0])));
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  const Vec3 x = (major[0] * f.t1 + major[1] * f.t2).normalized();
  s.frame.col(0) = x;
  s.frame.col(1) = f.m.cross(x);
  s.frame.col(2) = f.m;
  // The turn along each tangent: its log-map direction (the eigenvector)
  // against the positions' offset along it.
  const Eigen::Vector2d minor(-major[1], major[0]);
  s.turn = Vec2(major.dot(sums.turn * s.frame.col(0)), minor.dot(sums.turn * s.frame.col(1))) * scale;
  return s;
}

NormalSpread normal_spread(const Vec3* normals, size_t n, const Vec3& fallback_z, const Vec3* positions, const Vec3& mean) {
  Vec3 sum = Vec3::Zero();
  for (size_t i = 0; i < n; ++i) sum += normals[i];
  const LogMapFrame f = log_map_frame(sum, n, fallback_z);
  LogMapSums sums;
  accumulate_log_map(f, normals, n, sums, positions, mean);
  return finish_log_map(f, sums);
}

void normal_stats(const Vec3* normals, const uint32_t* ids, size_t n, const Vec3& fallback_z, Mat3& frame,
                  Vec2& sigma_n, const Vec3* positions, const Vec3& mean, Vec2* turn) {
  std::vector<Vec3> gathered(n), at(positions ? n : 0);
  for (size_t i = 0; i < n; ++i) gathered[i] = normals[ids[i]];
  for (size_t i = 0; i < at.size(); ++i) at[i] = positions[ids[i]];
  const NormalSpread s = normal_spread(gathered.data(), n, fallback_z, positions ? at.data() : nullptr, mean);
  frame = s.frame;
  sigma_n = s.sigma;
  if (turn) *turn = s.turn;
}

Vec2 signed_sigma_n(const NodeStats& s) {
  return Vec2(s.turn[0] < 0 ? -s.sigma_n[0] : s.sigma_n[0], s.turn[1] < 0 ? -s.sigma_n[1] : s.sigma_n[1]);
}

NodeStats finish_stats(size_t n, const Gaussian3& position, const NormalSpread* normals, const StatsOptions& o) {
  NodeStats s;
  s.count = static_cast<uint32_t>(n);
  Gaussian3& g = s.position;
  g = position;
  if (normals) {
    s.normal_frame = normals->frame;
    s.sigma_n = normals->sigma;
    s.turn = normals->turn;
  }
  const Vec3 normal = normals ? Vec3(s.normal_frame.col(2)) : Vec3::UnitZ();

  const double tiny = std::max(o.sigma_floor, o.vanish_ratio * g.sigma[0]);
  const int vanishing = g.sigma[0] <= o.sigma_floor ? 3 : g.sigma[1] <= tiny ? 2 : g.sigma[2] <= tiny ? 1 : 0;
  Vec3 f1 = g.frame.col(0), f3 = g.frame.col(2);
  if (vanishing == 2) {
    // A line: keep its direction, turn f3 towards the normal.
    const Vec3 projected = normal - normal.dot(f1) * f1;
    f3 = (normals && projected.norm() > 1e-6) ? Vec3(projected.normalized()) : any_perpendicular(f1);
  } else if (vanishing == 3) {
    // A point: f3 along the normal, any tangent pair.
    f3 = normal;
    f1 = any_perpendicular(f3);
  }
  if (normals && f3.dot(normal) < 0) f3 = -f3;
  g.frame.col(0) = f1;
  g.frame.col(2) = f3;
  g.frame.col(1) = f3.cross(f1);
  if (normals && o.shrink_eta0 < 1.0) {
    const double beta = o.shrink_eta0 + (1.0 - o.shrink_eta0) * std::max(0.0, 1.0 - o.shrink_eta1 * std::sqrt(s.sigma_n[0]));
    g.sigma[2] *= beta;
  }
  for (int k = 0; k < 3; ++k) g.sigma[k] = std::max(g.sigma[k], o.sigma_floor);
  if (normals) s.sigma_n = s.sigma_n.cwiseMax(o.spread_floor);

  return s;
}

void set_color_stats(NodeStats& s, const Moments& colors, const StatsOptions& o) {
  if (colors.count == 0) return;
  s.color = gaussian_from_covariance(colors.mean, colors.m2 / colors.count);
  for (int k = 0; k < 3; ++k) s.color.sigma[k] = std::max(s.color.sigma[k], o.spread_floor);
}

NodeStats node_stats(const PointCloud& cloud, const uint32_t* ids, size_t n, const StatsOptions& o) {
  const Gaussian3 position = pca3(cloud.positions.data(), ids, n);
  NormalSpread spread;
  const bool normals = o.normals && cloud.has_normals();
  if (normals)
    normal_stats(cloud.normals.data(), ids, n, position.frame.col(2), spread.frame, spread.sigma, cloud.positions.data(),
                 position.mean, &spread.turn);
  NodeStats s = finish_stats(n, position, normals ? &spread : nullptr, o);
  set_color_stats(s, color_moments(cloud, ids, n, o), o);
  return s;
}

}  // namespace stipple
