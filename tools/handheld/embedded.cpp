// stipple — the embedded default. See embedded.h.
#include "tools/handheld/embedded.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "platform/progress.h"

namespace stipple {
namespace {

constexpr double kTurn = 4294967296.0;  // 2^32
constexpr double kMu = 16777216.0;      // 2^24 MU per largest extent

uint32_t binary_angle(double degrees) {
  const double turns = degrees / 360.0 - std::floor(degrees / 360.0);
  return static_cast<uint32_t>(static_cast<uint64_t>(std::llround(turns * kTurn)) & 0xFFFFFFFFu);
}


}  // namespace

bool parse_view(const std::string& text, ViewSpec& out, std::string& error) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    char* end = nullptr;
    const double d = std::strtod(part.c_str(), &end);
    if (part.empty() || *end != '\0' || !std::isfinite(d)) {
      error = "--camera: '" + part + "' is not a number (expected yaw,pitch[,distance[,fov]] in degrees)";
      return false;
    }
    v.push_back(d);
  }
  if (v.size() < 2 || v.size() > 4) {
    error = "--camera: expected yaw,pitch[,distance[,fov]], got '" + text + "'";
    return false;
  }
  ViewSpec s;
  s.yaw = v[0];
  s.pitch = v[1];
  if (v.size() > 2) s.distance = v[2];
  if (v.size() > 3) s.fov = v[3];
  if (s.pitch < -90 || s.pitch > 90) return error = "--camera: pitch must be within [-90, 90] degrees", false;
  if (!(s.distance >= 0.001 && s.distance <= 16))
    return error = "--camera: distance must be within [0.001, 16] model extents", false;
  if (!(s.fov >= 1 && s.fov <= 170)) return error = "--camera: field of view must be within [1, 170] degrees", false;
  out = s;
  return true;
}

OrbitView orbit_view(const int32_t extent_mu[3], const ViewSpec& spec) {
  OrbitView o;
  for (int a = 0; a < 3; ++a) o.target_mu[a] = extent_mu[a] / 2;
  o.distance_mu = static_cast<int32_t>(std::llround(spec.distance * kMu));
  o.yaw = binary_angle(spec.yaw);
  o.pitch = binary_angle(spec.pitch);
  o.fov = binary_angle(spec.fov);
  return o;
}

Image frame_to_image(const std::vector<uint8_t>& frame, const RasterConfig& config) {
  Image img;
  img.width = config.width;
  img.height = config.height;
  const size_t pixels = static_cast<size_t>(config.width) * config.height;
  img.rgb.resize(pixels * 3);
  for (size_t i = 0; i < pixels; ++i) {
    if (config.format == PixelFormat::kRgb888) {
      for (int c = 0; c < 3; ++c) img.rgb[3 * i + c] = frame[3 * i + c];
    } else {
      const uint32_t v = rgb888_from_565(static_cast<uint16_t>(frame[2 * i] | (frame[2 * i + 1] << 8)));
      img.rgb[3 * i] = static_cast<uint8_t>(v >> 16);
      img.rgb[3 * i + 1] = static_cast<uint8_t>(v >> 8);
      img.rgb[3 * i + 2] = static_cast<uint8_t>(v);
    }
  }
  return img;
}

double image_psnr(const Image& a, const Image& b) {
  if (a.rgb.size() != b.rgb.size() || a.rgb.empty()) return 0;
  double sum = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = static_cast<double>(a.rgb[i]) - b.rgb[i];
    sum += d * d;
  }
  if (sum == 0) return std::numeric_limits<double>::infinity();
  return 10 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(a.rgb.size())));
}

bool render_fixed(const SpgView& view, const uint8_t* file, ClientConfig config, const CutRule& rule,
                  const ViewSpec& spec, FixedRender& out, std::string& error, int frames, size_t (*heap_probe)()) {
  // The cut: a decoder over the whole file, as the server side will hold.
  std::vector<uint8_t> decoder_storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size()) != DecodeStatus::kOk) {
    error = "the file's angle fields are wider than the decoder supports";
    return false;
  }
  Camera camera;
  if (!orbit_camera(orbit_view(decoder.extent_mu(), spec), config.raster.width, config.raster.height, &camera)) {
    error = "--camera: the view is out of the camera's range";
    return false;
  }
  std::vector<uint8_t> scratch(cut_scratch_bytes(view.header));
  std::vector<uint32_t> cut(view.header.node_count);
  cut.resize(simple_cut(view, rule, &decoder, &camera, scratch.data(), cut.data(), static_cast<uint32_t>(cut.size())));
  config.node_capacity = std::max<uint32_t>(config.node_capacity, static_cast<uint32_t>(cut.size()));

  out.arena_bytes = client_arena_bytes(config);
  if (out.arena_bytes == 0) {
    error = "invalid renderer configuration";
    return false;
  }
  std::vector<uint64_t> arena(out.arena_bytes / 8 + 1);
  Client client;
  ClientStatus s = client.init(config, arena.data(), arena.size() * 8);
  if (s == ClientStatus::kOk) s = client.load_startup(file, spg_startup_bytes(view.header.class_count));
  for (size_t i = 0; s == ClientStatus::kOk && i < cut.size(); ++i)
    s = client.put_node(cut[i], view.records + static_cast<size_t>(cut[i]) * view.record_bytes, view.record_bytes);
  const size_t stride = static_cast<size_t>(config.raster.width) * bytes_per_pixel(config.raster.format);
  out.frame.assign(stride * config.raster.height, 0);
  out.frame_seconds.clear();
  for (int f = 0; s == ClientStatus::kOk && f < std::max(frames, 1); ++f) {
    const double start = monotonic_seconds();
    s = client.render(camera, out.frame.data(), stride, &out.stats);
    out.frame_seconds.push_back(monotonic_seconds() - start);
  }
  out.heap_bytes = heap_probe ? heap_probe() : 0;
  if (s != ClientStatus::kOk) {
    error = std::string("client: ") + client_status_text(s);
    return false;
  }
  out.image = frame_to_image(out.frame, config.raster);
  out.cut = std::move(cut);
  out.camera = camera;
  return true;
}

}  // namespace stipple
