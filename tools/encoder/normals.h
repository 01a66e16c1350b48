// stipple host — normals for scans that have none.
//
// Meshes: area-weighted average of incident face normals (a face's cross
// product is twice its area times its normal, so summing cross products
// weights by area). Vertices on no face, and bare point clouds: PCA of the k
// nearest neighbours (smallest-variance axis), oriented consistently by
// propagation along a minimum spanning tree of the k-NN graph with edge cost
// 1 - |n_i . n_j| (Hoppe et al., "Surface reconstruction from unorganized
// points", SIGGRAPH 1992); each connected component starts at its point
// farthest from the centroid with its normal facing away from it — unless
// `frame` (tools/encoder/orientation.h) says the scan has a sensor (each normal
// faces the viewpoint) or is terrain (each faces up). Deterministic for a
// given input.
#pragma once

#include <functional>

#include "tools/encoder/orientation.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

// Fills `cloud.normals` if empty. `k` is the neighbourhood size (3..64).
// `progress(fraction, phase)` is called now and then with fraction in [0, 1],
// from the calling thread. The k-NN fits run on `threads` threads; the result
// is the same for any count.
void estimate_normals(PointCloud& cloud, int k = 12, const ScanFrame& frame = {},
                      const std::function<void(double, const char*)>& progress = {}, int threads = 2);

}  // namespace stipple
