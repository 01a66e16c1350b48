// stipple tools — the shared render options. See render_options.h.
#include "tools/embedded/render_options.h"

#include <cmath>

namespace stipple {
namespace {

bool parse_size(const std::string& text, uint16_t& w, uint16_t& h) {
  const size_t x = text.find('x');
  unsigned long long a = 0, b = 0;
  if (x == std::string::npos || !cli::parse_uint(text.substr(0, x), 4096, a) || !cli::parse_uint(text.substr(x + 1), 4096, b) ||
      a == 0 || b == 0)
    return false;
  w = static_cast<uint16_t>(a);
  h = static_cast<uint16_t>(b);
  return true;
}

}  // namespace

const char kRenderOptionsHelp[] =
    "view:\n"
    "  --size WxH             screen (default 240x320)\n"
    "  --format rgb565|rgb888 pixel format (default rgb565)\n"
    "  --camera Y,P[,D[,F]]   orbit: yaw and pitch in degrees, distance from the\n"
    "                         centre in model extents, vertical field of view in\n"
    "                         degrees (default 30,20,3,35; from the file's sensor\n"
    "                         side when it names one)\n"
    "  --up AXIS              the axis the orbit turns about: +x -x +y -y +z -z\n"
    "                         (default: the file's hint, else the thinnest axis of a\n"
    "                         flat model, else +y)\n"
    "cut:\n"
    "  --max-size PX          split nodes whose projected 3.5-sigma radius exceeds PX\n"
    "                         pixels (default 2, the paper's threshold)\n"
    "  --level L              instead: the nodes at tree level L and the leaves above\n"
    "  --no-cull              keep nodes outside the view and facing away (the cut\n"
    "                         culls them by their sphere and normal cone by default)\n"
    "  --leaf-cone G          a leaf's normal cone in sigma_n1 (default 1; 3.5 culls\n"
    "                         fewer nodes and loses no silhouette pixel, 0 the most:\n"
    "                         docs/cut.md)\n"
    "  --window X0,Y0,X1,Y1   refine only nodes that project into this rectangle (px;\n"
    "                         TOG05's on-demand mode)\n"
    "client:\n"
    "  --no-coding            from a server: node batches as protocol 4's entries\n"
    "                         (LEB128 ids, whole records), not entropy-coded\n"
    "                         (protocol 5's default, ~16 % fewer bytes:\n"
    "                         docs/protocol.md \"Coded batches\")\n"
    "  --projection affine|reciprocal|exact   per-point projection (default affine)\n"
    "  --shading point|surface|node|none      Lambert per sampled normal, per normal\n"
    "                                         following the surface (DP01), per node,\n"
    "                                         or none (default surface:\n"
    "                                         docs/results.md)\n"
    "  --no-specular          Lambert only\n"
    "  --grey                 ignore the model's colours\n"
    "  --color model|elevation  the model's colours (default), or a ramp of height\n"
    "                         along the view's up axis, blue low to red high\n"
    "                         (LiDAR's habit; no re-encode)\n"
    "  --mean-color           one colour per node (no per-point colour sampling)\n"
    "  --quality Q            points-per-node scale, 0.01..16 (default 1)\n"
    "  --point-size N         1..3 px (default 2)\n"
    "  --supersample N        draw at N x N the screen's pixels (points of the point\n"
    "                         size there) and average each block: 1, 2 or 4\n"
    "  --point-cap K          draw a node with at most K times the original points\n"
    "                         under it (0: no cap; keeps sparse scans sparse)\n"
    "  --resolve on|off       the screen-space resolve: fill pinholes, trim the\n"
    "                         points' fringe at silhouettes, blend 3x3\n"
    "                         (default on: docs/results.md)\n"
    "  --splat points|ewa     points (default), or EWA splats colouring what the\n"
    "                         points cover (visibility, weighted accumulation,\n"
    "                         normalization: TOG05's quality mode, docs/fixed_point.md\n"
    "                         \"EWA\"; 20 bytes a tile pixel more, not the handheld's)\n"
    "  --close-ups on|off     draw a node larger on screen than its samples cover\n"
    "                         (8 px sigma: a leaf seen closer than its spacing) as\n"
    "                         its 3 sigma disc, so the surface stays closed\n"
    "                         (default on; off with --point-cap)\n"
    "  --pseudo               pseudo-random instead of Sobol samples\n"
    "  --samples N            Gaussian table entries = most points per node (default 1024)\n"
    "  --max-points N         frame budget (default 1048576)\n"
    "  --tile-nodes N         nodes drawn inside the tile pass, their points written\n"
    "                         straight into the tile (default 65536, on the handheld\n"
    "                         2048: its arena; 0: every point through the bins;\n"
    "                         the same picture either way)\n"
    "  --lanes best|baseline|scalar   the client's SIMD: the widest this CPU has\n"
    "                         (AVX2 on x86-64 where it has it), the build's\n"
    "                         baseline (SSE2, NEON), or none (default best; on the\n"
    "                         handheld baseline: its arena) — the same picture\n"
    "  --cache-decoded        cache records unpacked into their fields (no\n"
    "                         per-frame unpacking; 36 bytes a node instead of 13-17)\n"
    "  --cache N              nodes the client's cache holds (default 30000): the\n"
    "                         cut is coarser rather than larger (--level: raised to\n"
    "                         the level's size)\n";

bool parse_leaf_cone(const std::string& value, uint16_t& q8, std::string& error) {
  double g = 0;
  if (!cli::parse_double(value, g) || !(g >= 0 && g <= 8))
    return error = "--leaf-cone: expected a multiple of sigma_n1 within [0, 8], got '" + value + "'", false;
  q8 = static_cast<uint16_t>(std::lround(g * 256));
  return true;
}

bool parse_render_options(cli::Args& args, RenderOptions& o, std::string& error) {
  std::string v;
  ClientConfig& c = o.config;
  c.raster.width = 240;
  c.raster.height = 320;
  c.raster.max_points = 1u << 20;
  c.tile_nodes = 1u << 16;
  if (args.value("--size", v)) {
    if (!parse_size(v, c.raster.width, c.raster.height))
      return error = "--size: expected WIDTHxHEIGHT within 1..4096, got '" + v + "'", false;
    o.sized = true;
  }
  if (args.value("--format", v)) {
    if (v == "rgb565") c.raster.format = PixelFormat::kRgb565;
    else if (v == "rgb888") c.raster.format = PixelFormat::kRgb888;
    else return error = "--format: expected rgb565 or rgb888, got '" + v + "'", false;
  }
  if (args.value("--camera", v) && !parse_view(v, o.view, error)) return false;
  if (args.value("--up", v) && !spg_parse_axis(v.c_str(), &o.view.up))
    return error = "--up: expected +x, -x, +y, -y, +z or -z, got '" + v + "'", false;
  const bool has_level = args.value("--level", v);
  if (has_level) {
    unsigned long long level = 0;
    if (!cli::parse_uint(v, 65535, level)) return error = "--level: expected a non-negative integer, got '" + v + "'", false;
    o.rule.kind = CutRule::kLevel;
    o.rule.level = static_cast<uint16_t>(level);
  } else {
    o.rule.kind = CutRule::kProjectedSize;
  }
  if (args.value("--max-size", v)) {
    double px = 0;
    if (has_level) return error = "--max-size and --level are alternatives; give one", false;
    if (!cli::parse_double(v, px) || !(px >= 0.0625 && px <= 4096))
      return error = "--max-size: expected pixels within [0.0625, 4096], got '" + v + "'", false;
    o.rule.max_size_q4 = static_cast<int32_t>(std::lround(px * 16));
  }
  if (args.value("--projection", v)) {
    if (v == "affine") c.projection = Projection::kAffine;
    else if (v == "reciprocal") c.projection = Projection::kReciprocal;
    else if (v == "exact") c.projection = Projection::kExact;
    else return error = "--projection: expected affine, reciprocal or exact, got '" + v + "'", false;
  }
  if (args.value("--shading", v)) {
    if (v == "point") c.shading = ShadingMode::kPerPoint;
    else if (v == "node") c.shading = ShadingMode::kPerNode;
    else if (v == "none") c.shading = ShadingMode::kNone;
    else if (v == "surface") c.shading = ShadingMode::kSurface;
    else return error = "--shading: expected point, surface, node or none, got '" + v + "'", false;
  }
  if (args.value("--resolve", v)) {
    if (v == "on") c.resolve = true;
    else if (v == "off") c.resolve = false;
    else return error = "--resolve: expected on or off, got '" + v + "'", false;
  }
  if (args.value("--splat", v)) {
    if (v == "points") c.ewa = false;
    else if (v == "ewa") c.ewa = true;
    else return error = "--splat: expected points or ewa, got '" + v + "'", false;
  }
  if (args.value("--close-ups", v)) {
    if (v == "on") c.close_ups = true;
    else if (v == "off") c.close_ups = false;
    else return error = "--close-ups: expected on or off, got '" + v + "'", false;
  }
  if (args.flag("--no-specular")) c.lighting.specular_q8 = 0;
  if (args.flag("--grey")) c.grey = true;
  if (std::string mode; args.value("--color", mode)) {
    if (mode != "model" && mode != "elevation") return error = "--color: expected model or elevation, got '" + mode + "'", false;
    // The axis is the view's up, known once the view is resolved (render_fixed, the viewers).
    c.elevation = mode == "elevation" ? SpgAxis::kPosZ : SpgAxis::kNone;
  }
  if (args.flag("--mean-color")) c.sample_color = false;
  if (args.flag("--pseudo")) c.source = GaussianSource::kPseudo;
  if (args.flag("--cache-decoded")) c.cache_decoded = true;
  if (args.value("--quality", v)) {
    double q = 0;
    if (!cli::parse_double(v, q) || !(q >= 0.01 && q <= 16))
      return error = "--quality: expected a scale within [0.01, 16], got '" + v + "'", false;
    c.quality_q8 = static_cast<uint16_t>(std::lround(q * 256));
  }
  unsigned long long u = 0;
  if (args.value("--point-cap", v)) {
    if (!cli::parse_uint(v, 255, u)) return error = "--point-cap: expected 0..255, got '" + v + "'", false;
    c.point_cap = static_cast<uint8_t>(u);
  }
  if (args.value("--supersample", v)) {
    if (!cli::parse_uint(v, 4, u) || (u != 1 && u != 2 && u != 4))
      return error = "--supersample: expected 1, 2 or 4, got '" + v + "'", false;
    c.supersample = static_cast<uint8_t>(u);
  }
  if (args.value("--point-size", v)) {
    if (!cli::parse_uint(v, 3, u) || u < 1) return error = "--point-size: expected 1, 2 or 3, got '" + v + "'", false;
    c.point_size = static_cast<uint8_t>(u);
  }
  if (args.value("--samples", v)) {
    if (!cli::parse_uint(v, 8192, u) || u < 1) return error = "--samples: expected 1..8192, got '" + v + "'", false;
    c.samples = static_cast<uint16_t>(u);
  }
  if (args.value("--max-points", v)) {
    if (!cli::parse_uint(v, 1u << 26, u) || u < 1) return error = "--max-points: expected 1..67108864, got '" + v + "'", false;
    c.raster.max_points = static_cast<uint32_t>(u);
  }
  if (args.value("--lanes", v)) {
    if (v == "best") c.lanes = PointLanes::kBest;
    else if (v == "baseline") c.lanes = PointLanes::kBaseline;
    else if (v == "scalar") c.lanes = PointLanes::kScalar;
    else return error = "--lanes: expected best, baseline or scalar, got '" + v + "'", false;
    o.lanes_given = true;
  }
  if (args.value("--tile-nodes", v)) {
    if (!cli::parse_uint(v, 1u << 24, u)) return error = "--tile-nodes: expected 0..16777216, got '" + v + "'", false;
    c.tile_nodes = static_cast<uint32_t>(u);
    o.tile_nodes_given = true;
  }
  if (args.flag("--no-cull")) o.rule.cull = false;
  if (args.flag("--no-coding")) o.coded = false;
  if (args.value("--leaf-cone", v) && !parse_leaf_cone(v, o.rule.leaf_cone_q8, error)) return false;
  if (args.value("--window", v)) {
    double w[4];
    const size_t last = v.rfind(',');
    if (last == std::string::npos || !cli::parse_vec3(v.substr(0, last), w) || !cli::parse_double(v.substr(last + 1), w[3]) ||
        w[0] < 0 || w[1] < 0 || w[2] <= w[0] || w[3] <= w[1] || w[2] > 4096 || w[3] > 4096)
      return error = "--window: expected X0,Y0,X1,Y1 in pixels with X0 < X1 and Y0 < Y1, got '" + v + "'", false;
    for (int k = 0; k < 4; ++k) o.rule.window[k] = static_cast<int32_t>(w[k]);
  }
  if (args.value("--cache", v)) {
    if (!cli::parse_uint(v, 1u << 24, u) || u < 1) return error = "--cache: expected 1..16777216 nodes, got '" + v + "'", false;
    c.node_capacity = static_cast<uint32_t>(u);
  }
  return !args.bad() || (error = args.error(), false);
}

}  // namespace stipple
