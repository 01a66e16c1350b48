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
  Gaussian3 color;
};

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
void normal_stats(const Vec3* normals, const uint32_t* ids, size_t n, const Vec3& fallback_z, Mat3& frame,
                  Vec2& sigma_n);

// A node's normal frame (column 2 the mean normal) and sigma_n.
struct NormalSpread {
  Mat3 frame = Mat3::Identity();
  Vec2 sigma = Vec2::Zero();
};
// Of normals[0..n): normal_stats on contiguous normals.
NormalSpread normal_spread(const Vec3* normals, size_t n, const Vec3& fallback_z);
// The same in parts, for sums taken in chunks (tools/encoder/hierarchy.cpp):
// the tangent frame from the normals' sum, the log map's second moments
// added up over any range, then the spread.
struct LogMapFrame {
  Vec3 m, t1, t2;
};
LogMapFrame log_map_frame(const Vec3& normal_sum, size_t n, const Vec3& fallback_z);
void accumulate_log_map(const LogMapFrame& frame, const Vec3* normals, size_t n, Eigen::Matrix2d& cov, size_t& used);
NormalSpread finish_log_map(const LogMapFrame& frame, Eigen::Matrix2d cov, size_t used);

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
