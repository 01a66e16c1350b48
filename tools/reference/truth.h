// stipple host — the reference picture from the scan itself: the original
// scan drawn with the client's camera and lighting (render_reference's
// camera), the picture the client's frames are measured against
// (`stipple truth`, `stipple image-diff`).
//
// A scan with faces is drawn as its mesh: triangles z-buffered at pixel
// centres, Gouraud shading of the per-vertex normals (the encoder's: the
// file's, else its faces'), the client's Lambert + ambient + Blinn specular
// per vertex, interpolated in screen space. A bare point cloud is drawn as
// its points: squares of the client's point size, z-buffered, each shaded
// by its own normal (the file's or the encoder's k-NN estimate).
#pragma once

#include <cstddef>

#include "tools/reference/render.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

struct TruthStats {
  bool mesh = false;
  size_t drawn = 0;     // triangles or points that reached the screen
  size_t skipped = 0;   // behind the near plane (a triangle with any corner there)
};

// `cloud` with normals (empty: unlit); `bbox_min/max` and `header` (its view
// hint) as the encoder stores them, so the camera is the one `stipple
// render` of the encoded model uses.
Image render_truth(const PointCloud& cloud, const Vec3& bbox_min, const Vec3& bbox_max, const SpgHeader& header,
                   const ClientConfig& config, const ViewSpec& spec, TruthStats* stats = nullptr);

}  // namespace stipple
