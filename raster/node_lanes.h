// stipple raster — the per-node set-up of PointRenderer::draw_node for 8
// nodes at a time, in AVX2 lanes (x86-64 CPUs that have it; the one file
// built with -mavx2 beside the point loop, raster/node_lanes_avx2.cpp).
//
// The same integer formulas as the scalar set-up, lane for lane: the
// record's fields gathered from the cache, the mean through per-frame
// tables of its camera-space terms (draw_node's, rounded per axis), the
// frames through the Euler tables (node_setup.h), 64-bit products where the
// scalar code forms them (two 4-lane multiplies: each operand fits 32 bits),
// one division a lane. What the lanes do not take — a node near the camera
// (Z < 2^16 MU, where 2^46 / Z passes 2^30), one whose slopes or depth terms
// pass 16 bits (it spans many tiles), a model's colours, the point cap —
// they leave to the scalar set-up, which decides it exactly as before. A
// node the lanes take is either culled, for the reasons and with the
// counts of the scalar code, or written to the tile pass's TileNodes with
// the values the scalar code writes (tests/portable/client_test.cpp,
// `Client.LanesDrawTheScalarPicture*`: every pixel and count of the
// frame, on real and random records).
#pragma once

#include <cstdint>

#include "core/node_decoder.h"
#include "core/node_format.h"
#include "raster/node_setup.h"
#include "raster/point_kernel.h"
#include "raster/shading.h"

namespace stipple {

// Everything the lanes read that does not change within a frame.
struct NodeLaneFrame {
  // The records: packed (field windows per field) or unpacked NodeFields.
  const uint8_t* records = nullptr;
  uint32_t stride = 0;
  FieldWindow window[kFieldCount] = {};
  // (R[i][a] (mean_axis_mu(a, q) - eye_a) + 2^13) >> 14, i = 0..2: the
  // camera-space terms of each mean field value, [q][i].
  const int32_t* mean[3] = {};
  // Position and normal frames (node_setup.h), sigma classes.
  const CameraPhi* position = nullptr;
  const CameraPhi* normal = nullptr;  // kSurface: the normal frame's tangents
  const LightPhi* light = nullptr;
  int16_t column2[3] = {}, light_z = 0, half_z = 0;
  const SinCosQ14 *theta_p = nullptr, *gamma_p = nullptr, *theta_n = nullptr, *gamma_n = nullptr;
  uint8_t gamma_psi_shift_p = 0, gamma_phi_shift_p = 0, gamma_psi_shift_n = 0, gamma_phi_shift_n = 0;
  uint32_t gamma_mask_p = 0, gamma_mask_n = 0;
  const int32_t *sigma_p = nullptr, *sigma_n = nullptr;
  // Camera and screen (the internal frame's).
  int32_t near = 0, focal_q4 = 0, cx_q4 = 0, cy_q4 = 0, width_q4 = 0, height_q4 = 0;
  int32_t width = 0, height = 0, depth_shift = 0, size = 2, tile_log2 = 6;
  // Points per node, shading.
  const uint16_t* ppn = nullptr;  // [kPpnSizes][kPpnAspects]
  uint32_t quality_q8 = 256, samples = 1024;
  const int32_t* sample_reach = nullptr;  // PointRenderer::sample_reach_: [sample_reach_bucket(n)][4]
  bool lit = false;
  // Close-ups (raster/close_up.h) in this frame: a node whose mean is out
  // of view, or whose screen sigmas may pass kCloseUpSigmaPx, is the scalar
  // set-up's.
  bool close_ups = false;
  int32_t close_up_wide = 0;  // a + c (1/256 px^2) past which a node may be one
  const ShadingTables* shading = nullptr;
  uint32_t base_rgb = 0;
};

// What the lanes made of 8 nodes.
struct NodeLaneBatch {
  uint32_t tile_mask = 0;    // written to TileNodes, in lane order
  uint32_t culled_mask = 0;  // culled (the other lanes of the batch are the scalar set-up's)
  uint32_t tile_count = 0, culled_count = 0;  // how many of each
  uint32_t count[8] = {};    // a tile lane's points
  // A tile lane's tiles: first x | first y << 12 | (reaches x + 1) << 24 | (reaches y + 1) << 25.
  uint32_t tiles[8] = {};
};

namespace avx2 {
// Sets up nodes first_slot .. first_slot + count - 1, 8 at a time: batch b
// (slots first_slot + 8 b ..) into batches[b]; the tile lanes' TileNodes
// from `base` on, in slot order (8 entries of room past the last are
// written). Returns how many TileNodes were written.
template <PointNormals kNormals, bool kSpecular>
uint32_t set_up_nodes(const NodeLaneFrame& f, uint32_t first_slot, uint32_t count, TileNodes& out, uint32_t base,
                      NodeLaneBatch* batches);

// The lanes' sample_reach_bucket (point_renderer.h), as set_up_nodes forms
// it, of 8 counts from 1 to RendererConfig::samples' most: for the test
// that holds the two alike.
void sample_reach_buckets(const uint32_t count[8], int32_t bucket[8]);
}  // namespace avx2

}  // namespace stipple
