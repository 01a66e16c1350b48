// stipple platform — the GL client's renderer: draws core's node cache on
// the GPU (OpenGL 3.3 core, through libepoxy), never through raster/.
//
// GPU decode (the default): each cached node goes to the GPU as the raw
// packed integers of the stream (its record, up to 32 bytes, as two uvec4
// instance attributes); the vertex shader unpacks the bit fields with the
// layout of the startup (offsets and widths as uniforms), decodes the
// position cell, the frames (θ, φ, ψ and Rodrigues, docs/format.md §5) and
// the σ classes (a texture buffer of the decoder's class sigmas, in model
// units), and generates the node's points from a quasi-random Gaussian
// buffer (the client's Sobol table, texture buffer): vertex k of instance i
// is sample k of node i. CPU decode (for comparison): core's fixed-point
// decoder on the CPU, the same shader fed decoded floats.
//
// Points per node: the CPU computes each node's count from its projected
// size — the 2σ ellipse's area in point-sized squares, five times over,
// times the quality, 1 to the Gaussian buffer's size. (Scattered uniformly,
// three times over would cover 95 %; a Gaussian is a seventh as dense at its
// 2σ ellipse as at its centre, and against the software client's measured
// table 3x gives 27.9-30.8 dB on the bunny, 5x 31.2-32.7 dB, 8x 29.8-31.0.)
// raster/'s measured table is not used: the GL client never includes
// raster/. It buckets the nodes by the count rounded up to a power of two
// and issues one instanced draw per bucket; a vertex beyond its node's own
// count is dropped. Points are z-buffered squares of the
// point size; colour is the node's mean (or grey) times Lambert with
// ambient per node; MSAA is the framebuffer's (GlOffscreen, or the window's).
//
// The software client's picture, on the GPU (docs/viewers.md, "The GL
// client's picture"): surface normals (each point's normal turned by where
// its sample lands, the rule of raster/point_renderer.h, in the vertex
// shader) with Blinn specular; the point cap; and the screen-space resolve
// (raster/resolve.h: fill, trim, 3 x 3 blend) as full-screen passes over an
// offscreen frame whose alpha is the coverage, with one more level for
// holes wider than a pixel: a half-resolution fill pushed into the full
// one (the pull-push of Grossman and Dally 1998, with the resolve's rule,
// so silhouettes never grow).
//
// EWA splatting (GlSplat::kEwa, TOG05 §8.4's quality mode): each node one
// elliptical Gaussian splat of its two main axes, in the three passes of
// Botsch, Hornung, Zwicker and Kobbelt, "High-quality surface splatting on
// today's GPUs" (PBG 2005): a visibility pass writes the splats' depth —
// each splat's core, pushed back by its radius, so a tail never hides a
// neighbour's centre; an attribute pass adds each fragment's Gaussian
// weight w = exp(-r^2/2) times its colour, and w, into a floating-point
// target for the fragments within that depth; a normalization pass divides.
// Each splat is a quad in the node's tangent plane (perspective correct:
// the object-space formulation of Ren, Pfister and Zwicker 2002), its radii
// widened to at least a pixel's footprint — their approximation of EWA's
// screen-space low-pass filter — and cut at 3σ. Shading is per pixel, the
// normal turned by the pixel's place in the splat as surface normals turn
// it. Which pixels are covered comes from the points (drawn first, as in
// the default mode) and the resolve: a Gaussian's own outline, at any one
// cut radius, measured 1-2 dB worse at silhouettes on the bunny and the
// dragon (docs/viewers.md).
//
// Close-ups: a node whose σ spans more than 8 px on screen is drawn as its
// 3σ ellipse, opaque and shaded by its mean normal (by the splat program;
// the normal turned across 3σ striped sparse scans' long nodes), in either
// mode: its samples would be sparser than the pixels, and points cannot
// grow past GL's size limit to close that. Smaller nodes that want more
// points than the samples hold draw them larger.
//
// The GL context must be current for every call.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/node_cache.h"

namespace stipple {

enum class GlSplat : uint8_t {
  kPoints,  // Gaussian samples drawn as squares (the software client's)
  kEwa,     // one elliptical Gaussian splat a node, blended (TOG05 §8.4)
};

struct GlRenderOptions {
  bool gpu_decode = true;
  GlSplat splat = GlSplat::kPoints;
  // Each point's normal turned by where its sample lands (the software
  // client's --shading surface); false: the node's mean normal.
  bool surface_normals = true;
  // The screen-space resolve (raster/resolve.h) after the points; the
  // window's MSAA applies only without it (the resolve draws offscreen).
  bool resolve = true;
  uint8_t point_cap = 0;  // a node draws at most this times its original points (0: no cap)
  bool close_ups = true;  // a node past kDiscSigma px as its disc (--close-ups; none with the point cap)
  float specular = 0.25f;  // Blinn highlight's strength (0: none) and shininess
  float shininess = 16.f;
  uint8_t point_size = 2;      // px
  uint16_t quality_q8 = 256;   // points-per-node scale
  uint16_t samples = 1024;     // the Gaussian buffer: most points per node
  bool grey = false;           // ignore the model's colour
  SpgAxis elevation = SpgAxis::kNone;  // colour by height along this axis (core/elevation_ramp.h); kNone: off
  bool lighting = true;        // Lambert per node (else the colour as it is)
  float light[3] = {-4096 / 16384.f, -6144 / 16384.f, -14336 / 16384.f};  // towards the light, camera space
  float ambient = 0.25f;
  uint32_t grey_rgb = 0xD8D8D8, clear_rgb = 0x000000;
};

struct GlFrameStats {
  uint32_t nodes = 0;   // nodes drawn (in front of the near plane)
  uint64_t points = 0;  // points generated
  uint32_t draws = 0;   // instanced draw calls
};

class GlRenderer {
 public:
  GlRenderer() = default;
  GlRenderer(const GlRenderer&) = delete;
  GlRenderer& operator=(const GlRenderer&) = delete;
  ~GlRenderer();

  // Compiles the programs and builds the buffers for the cache's startup
  // (layout, class tables). False with the GL's message.
  bool init(const NodeCache& cache, const GlRenderOptions& options, std::string& error);
  // Draws every cached node for `camera` into the bound framebuffer of
  // width x height pixels (cleared first).
  bool draw(const NodeCache& cache, const Camera& camera, int width, int height, const GlRenderOptions& options,
            GlFrameStats* stats, std::string& error);
  // GL_RENDERER and GL_VERSION, for logs.
  static std::string describe();

 private:
  bool build_programs(std::string& error);
  void upload_sigmas(const NodeCache& cache);
  bool size_targets(int width, int height, std::string& error);
  void set_uniforms(unsigned program, const NodeCache& cache, const Camera& camera, int width, int height,
                    const GlRenderOptions& o) const;
  void full_screen(unsigned program, unsigned texture, const float clear_rgb[3]) const;

  // [decode: CPU, GPU][kind: points, splats]; then the post passes.
  unsigned programs_[2][2] = {{0, 0}, {0, 0}};
  unsigned fill_program_ = 0, blend_program_ = 0, normalize_program_ = 0, pull_program_ = 0;
  unsigned vao_ = 0, instances_ = 0, empty_vao_ = 0;
  // Offscreen targets (sized on first use): the scene (RGBA8, alpha the
  // coverage) and its depth, the filled frame, the half-resolution level of
  // the hole filling, the splats' accumulation.
  unsigned scene_fbo_ = 0, scene_tex_ = 0, depth_rb_ = 0, fill_fbo_ = 0, fill_tex_ = 0, accum_fbo_ = 0, accum_tex_ = 0;
  unsigned coarse_fbo_ = 0, coarse_tex_ = 0;
  int target_width_ = 0, target_height_ = 0;
  unsigned sigma_buffer_ = 0, sigma_texture_ = 0, gauss_buffer_ = 0, gauss_texture_ = 0;
  int field_offset_[18] = {}, field_bits_[18] = {};
  uint16_t samples_ = 0;
  uint32_t uploaded_classes_ = 0;  // the cache's classes_changed() the sigma texture holds
  std::vector<uint8_t> staging_;  // instance data, bucket by bucket
  std::vector<uint32_t> order_;   // cache slots by bucket
  std::vector<uint16_t> counts_;  // per slot
  std::vector<uint8_t> sizes_;    // per slot: point size, px
  std::vector<uint8_t> buckets_;  // per slot: its bucket (kBuckets: a close-up's disc)
  std::vector<FixedNode> decoded_;  // per slot, CPU decode
};

// An offscreen framebuffer (optionally multisampled) to draw into and read
// back: the headless GL client, the tests.
class GlOffscreen {
 public:
  GlOffscreen() = default;
  GlOffscreen(const GlOffscreen&) = delete;
  GlOffscreen& operator=(const GlOffscreen&) = delete;
  ~GlOffscreen();
  bool init(int width, int height, int msaa, std::string& error);
  void bind() const;
  // The picture, rows top to bottom, RGB888 (resolving MSAA).
  bool read(std::vector<uint8_t>& rgb, std::string& error);
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  unsigned fbo_ = 0, color_ = 0, depth_ = 0, resolve_fbo_ = 0, resolve_color_ = 0;
  int width_ = 0, height_ = 0, msaa_ = 0;
};

// Waits until the GL has finished every command (timing).
void gl_finish();

// Reads the bound framebuffer (a window's back buffer), rows top to bottom.
bool gl_read_pixels(int width, int height, std::vector<uint8_t>& rgb, std::string& error);

// A headless OpenGL 3.3 core context through EGL (Mesa's surfaceless
// platform, else the default display with a pbuffer): no window, no X.
class EglContext {
 public:
  EglContext() = default;
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
  ~EglContext();
  bool open(std::string& error);

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
  void* surface_ = nullptr;
};

}  // namespace stipple
