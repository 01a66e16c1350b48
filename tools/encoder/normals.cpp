// stipple host — normal estimation (faces, or k-NN PCA + MST orientation).
#include "tools/encoder/normals.h"

#include <algorithm>
#include <atomic>
#include <queue>
#include <thread>

#include "tools/scan/kdtree.h"
#include "tools/encoder/node_stats.h"

namespace stipple {

void estimate_normals(PointCloud& cloud, int k, const ScanFrame& frame,
                      const std::function<void(double, const char*)>& progress, int threads) {
  if (cloud.has_normals()) return;
  const size_t n = cloud.size();
  const std::vector<Vec3>& p = cloud.positions;
  std::vector<Vec3> normals(n, Vec3::Zero());
  for (const auto& t : cloud.triangles) {
    const Vec3 c = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    for (uint32_t v : t) normals[v] += c;
  }
  std::vector<uint32_t> missing;
  for (size_t i = 0; i < n; ++i) {
    const double len = normals[i].norm();
    if (len > 0 && std::isfinite(len)) normals[i] /= len;
    else missing.push_back(static_cast<uint32_t>(i));
  }
  if (!missing.empty() && n >= 2) {
    const bool from_faces = missing.size() < n;  // some normals came from faces
    const KdTree tree(p, threads);
    const size_t kk = std::min<size_t>(static_cast<size_t>(std::clamp(k, 3, 64)), n);
    // Neighbour lists are kept only when orientation must be propagated.
    std::vector<uint32_t> graph;
    const bool propagate = !from_faces && frame.orient == OrientMode::kOutward;
    if (propagate) graph.resize(n * kk);
    // Each point's normal depends on the points alone, so the threads may take
    // them in any order: the tree's, which keeps neighbours' queries close in
    // memory. Face normals are read, never written, here (`missing` ones only).
    std::vector<uint8_t> is_missing(n, 0);
    for (uint32_t i : missing) is_missing[i] = 1;
    std::vector<uint32_t> todo;
    todo.reserve(missing.size());
    for (uint32_t i : tree.spatial_order())
      if (is_missing[i]) todo.push_back(i);
    std::vector<Vec3> estimated(n, Vec3::Zero());
    std::atomic<size_t> next{0}, finished{0};
    constexpr size_t kBlock = 4096;
    auto worker = [&](bool report) {
      std::vector<uint32_t> nb;
      for (size_t lo; (lo = next.fetch_add(kBlock)) < todo.size();) {
        for (size_t m = lo; m < std::min(todo.size(), lo + kBlock); ++m) {
          const uint32_t i = todo[m];
          tree.knearest(p[i], kk, nb);
          // The smallest-variance axis of the neighbourhood.
          Vec3 nrm = nb.size() >= 3 ? Vec3(pca3(p.data(), nb.data(), nb.size()).frame.col(2)) : Vec3::UnitZ();
          if (!nrm.allFinite()) nrm = Vec3::UnitZ();
          if (from_faces) {
            Vec3 ref = Vec3::Zero();
            for (uint32_t j : nb) ref += normals[j];
            if (nrm.dot(ref) < 0) nrm = -nrm;
          } else if (propagate) {
            std::copy(nb.begin(), nb.end(), graph.begin() + static_cast<ptrdiff_t>(i * kk));
          }
          estimated[i] = nrm;
        }
        const size_t done = finished.fetch_add(kBlock) + kBlock;
        if (report && progress) progress(0.5 * static_cast<double>(std::min(done, todo.size())) / static_cast<double>(todo.size()), "normals");
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(worker, false);
    worker(true);
    for (std::thread& t : pool) t.join();
    for (uint32_t i : missing) normals[i] = estimated[i];
    if (!from_faces && frame.orient == OrientMode::kSensor) {
      for (size_t i = 0; i < n; ++i)
        if (normals[i].dot(frame.viewpoint - p[i]) < 0) normals[i] = -normals[i];
    } else if (!from_faces && frame.orient == OrientMode::kUp) {
      for (size_t i = 0; i < n; ++i)
        if (normals[i].dot(frame.up) < 0) normals[i] = -normals[i];
    } else if (!from_faces) {
      // Orientation: Prim's algorithm over the k-NN graph, flipping each newly
      // reached normal to agree with the one that reached it. Each connected
      // component starts at its point farthest from the centroid, facing away.
      Vec3 centroid = Vec3::Zero();
      for (const Vec3& q : p) centroid += q;
      centroid /= static_cast<double>(n);
      if (frame.has_centre) centroid = frame.centre;
      std::vector<uint8_t> done(n, 0);
      std::vector<uint32_t> by_distance(n);
      std::vector<double> d2(n);
      for (uint32_t i = 0; i < n; ++i) {
        by_distance[i] = i;
        d2[i] = (p[i] - centroid).squaredNorm();
      }
      std::stable_sort(by_distance.begin(), by_distance.end(), [&](uint32_t a, uint32_t b) { return d2[a] > d2[b]; });
      using Edge = std::pair<double, std::pair<uint32_t, uint32_t>>;  // cost, (to, from)
      std::priority_queue<Edge, std::vector<Edge>, std::greater<Edge>> heap;
      size_t reached = 0;
      for (uint32_t seed : by_distance) {
        if (done[seed]) continue;
        if (normals[seed].dot(p[seed] - centroid) < 0) normals[seed] = -normals[seed];
        heap.push({0.0, {seed, seed}});
        while (!heap.empty()) {
          const auto [cost, edge] = heap.top();
          heap.pop();
          const uint32_t v = edge.first, from = edge.second;
          if (done[v]) continue;
          done[v] = 1;
          if (v != from && normals[v].dot(normals[from]) < 0) normals[v] = -normals[v];
          if (progress && (++reached & 4095) == 0)
            progress(0.5 + 0.5 * static_cast<double>(reached) / static_cast<double>(n), "orienting normals");
          for (size_t j = 0; j < kk; ++j) {
            const uint32_t w = graph[v * kk + j];
            if (!done[w]) heap.push({1.0 - std::abs(normals[v].dot(normals[w])), {w, v}});
          }
        }
      }
    }
  }
  cloud.normals = std::move(normals);
}

}  // namespace stipple
