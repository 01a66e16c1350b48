// stipple host — per-node statistics (TOG05 §3, "Statistical representation").
//
// Positions: mean, PCA frame (columns f1, f2, f3, right-handed) and standard
// deviations sigma1 >= sigma2 >= sigma3, from centred sums (two passes: the
// mean first, then the covariance of p - mean), so a node far from the origin
// loses no precision. The 3x3 eigenproblem uses Eigen's iterative
// SelfAdjointEigenSolver (accurate for repeated and vanishing eigenvalues,
// unlike closed forms).
//
// Degenerate nodes (a sigma at or below `vanish_ratio * sigma1`, or sigma1 at or
// below the floor), the paper's rules:
//   one vanishing  — the PCA frame (f3 is the plane's normal);
//   two vanishing  — keep f1, turn the frame about f1 so f3 points along the
//                    average normal (any perpendicular without normals);
//   three          — f3 along the average normal (z without normals), f1, f2
//                    any tangent pair.
// With normals, f3 is always flipped to agree with the mean normal. Position
// sigmas are then floored at `sigma_floor` (a length: the encoder scales it
// with the scan), normal and colour sigmas at `spread_floor` (radians and
// colour units, whatever the scan's size).
//
// Normals: z = the mean normal m; each normal is mapped to the tangent plane at
// m by the log map (u, v) = theta (cos phi, sin phi) — theta its angle from m,
// phi its azimuth — and a 2-D PCA about the origin gives sigma_n1 >= sigma_n2
// and the frame fn = (x, y, m) with x the major axis. The log map does not
// add up from children to parent (it is taken about the node's own m), so
// every node reads its normals; sigma_n in radians is what the cut's
// back-face cones rely on (core/view_cut.h), which the tangent projection
// (sin theta, from moments) would understate for wide nodes: with it the
// bunny's cut culled leaves that face the eye (docs/encoder.md).
//
// Colours: 3-D PCA like positions, no orientation rule; the mean and centred
// sum of outer products merge exactly from children (Chan, Golub and
// LeVeque), so a parent never reads its points' colours.

// The curvature's sign (docs/encoder.md "Curvature sign"): along each
// tangent x_k of the normal frame, turn_k = mean of ((p - mean) . x_k)
// (u . x_k), u the normal's log map lifted to 3-D — positive where the normal
// turns the way the surface moves (convex, seen from the normals' side),
// negative where it turns back (concave). Its sign is sigma_n_k's in the
// file (signed_sigma_n); sigma_n stays the spread.
//
// Curvature-aware shrink (docs/encoder.md): sigma3 *= beta with
// beta = eta0 + (1 - eta0) * max(0, 1 - eta1 * sqrt(sigma_n1)).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "tools/scan/point_cloud.h"

namespace stipple {

using Mat3 = Eigen::Matrix3d;
using Vec2 = Eigen::Vector2d;

struct Gaussian3 {
  Vec3 mean = Vec3::Zero();
  Mat3 frame = Mat3::Identity();  // columns: axes 1, 2, 3
  Vec3 sigma = Vec3::Zero();      // descending
};

struct NodeStats {
  uint32_t count = 0;
  Gaussian3 position;
  Mat3 normal_frame = Mat3::Identity();  // column 2 is the mean normal
  Vec2 sigma_n = Vec2::Zero();
  Vec2 turn = Vec2::Zero();  // along the normal frame's tangents: the curvature's sign (above)
  Gaussian3 color;
};
// sigma_n with the curvature's sign: negative along a tangent whose turn is.
Vec2 signed_sigma_n(const NodeStats& s);

struct StatsOptions {
  double sigma_floor = 1e-15;   // positions: a length
  double spread_floor = 1e-12;  // normals (radians) and colours (0..1): not a length
  double vanish_ratio = 1e-6;
  bool normals = true;
  bool colors = true;
  double shrink_eta0 = 0.25;  // 1 disables the shrink (docs/encoder.md has the measurements)
  double shrink_eta1 = 2.0;
};

// Plain PCA of `values[ids[0..n)]`: mean, descending sigmas, right-handed frame.
Gaussian3 pca3(const Vec3* values, const uint32_t* ids, size_t n);
// The same of values[0..n).
Gaussian3 pca3(const Vec3* values, size_t n);
// The same from a mean and covariance.
Gaussian3 gaussian_from_covariance(const Vec3& mean, const Mat3& cov);

// Values as count, mean and centred sum of outer products; a parent's are
// its children's added in order (`add`, exact): the hierarchy's colours from
// the leaves up, the partitions' upper nodes (tools/encoder/merge.h).
struct Moments {
  double count = 0;  // 0: none (no colours in the scan, or not wanted)
  Vec3 mean = Vec3::Zero();
  Mat3 m2 = Mat3::Zero();
  void add(const Moments& other);
};
// Of values[0..n), in pca3's two passes.
Moments moments_of(const Vec3* values, size_t n);
// A node's colours (none when the scan has none or the options want none).
Moments color_moments(const PointCloud& cloud, const uint32_t* ids, size_t n, const StatsOptions& options);

// Mean-normal frame and sigma_n of `normals[ids[0..n)]`. `fallback_z` is used
// when the normals cancel out (or are all zero).
// With positions (about `mean`), the turn too.
void normal_stats(const Vec3* normals, const uint32_t* ids, size_t n, const Vec3& fallback_z, Mat3& frame,
                  Vec2& sigma_n, const Vec3* positions = nullptr, const Vec3& mean = Vec3::Zero(),
                  Vec2* turn = nullptr);

// A node's normal frame (column 2 the mean normal), sigma_n and turn.
struct NormalSpread {
  Mat3 frame = Mat3::Identity();
  Vec2 sigma = Vec2::Zero();
  Vec2 turn = Vec2::Zero();
};
// Of normals[0..n) (and, for the turn, positions[0..n) about `mean`;
// nullptr: no turn): normal_stats on contiguous normals.
NormalSpread normal_spread(const Vec3* normals, size_t n, const Vec3& fallback_z, const Vec3* positions = nullptr,
                           const Vec3& mean = Vec3::Zero());
// The same in parts, for sums taken in chunks (tools/encoder/hierarchy.cpp):
// the tangent frame from the normals' sum, the log map's second moments
// and its products with the positions added up over any range, then the
// spread and the turn.
struct LogMapFrame {
  Vec3 m, t1, t2;
};
struct LogMapSums {
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();  // sum of u u^T, u in (t1, t2)
  Eigen::Matrix<double, 2, 3> turn = Eigen::Matrix<double, 2, 3>::Zero();  // sum of u (p - mean)^T
  size_t used = 0;
  void add(const LogMapSums& other);
};
LogMapFrame log_map_frame(const Vec3& normal_sum, size_t n, const Vec3& fallback_z);
// positions: nullptr leaves the turn alone.
void accumulate_log_map(const LogMapFrame& frame, const Vec3* normals, size_t n, LogMapSums& sums,
                        const Vec3* positions = nullptr, const Vec3& mean = Vec3::Zero());
NormalSpread finish_log_map(const LogMapFrame& frame, const LogMapSums& sums);

// The statistics of a node of n points but its colours: from its positions'
// PCA and its normals' spread (nullptr: none), with the degenerate-node rules
// and the shrink.
NodeStats finish_stats(size_t n, const Gaussian3& position, const NormalSpread* normals, const StatsOptions& options);
// Its colours' Gaussian from their moments (nothing when there are none).
void set_color_stats(NodeStats& stats, const Moments& colors, const StatsOptions& options);
// All of them from the points: finish_stats(pca3(positions)), then
// set_color_stats(color_moments).
NodeStats node_stats(const PointCloud& cloud, const uint32_t* ids, size_t n, const StatsOptions& options);

// A unit vector perpendicular to unit `v`, chosen deterministically.
Vec3 any_perpendicular(const Vec3& v);

}  // namespace stipple
