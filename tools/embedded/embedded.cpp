// stipple — the embedded default. See embedded.h.
#include "tools/embedded/embedded.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "platform/progress.h"
#include "tools/embedded/model_file.h"
#include "tools/embedded/options.h"

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
  s.orbit_given = true;
  s.up = out.up;
  out = s;
  return true;
}

ViewSpec resolve_view(const ViewSpec& spec, const SpgHeader& header, const int32_t extent_mu[3]) {
  ViewSpec v = spec;
  int thin = 0;
  for (int a = 1; a < 3; ++a)
    if (extent_mu[a] < extent_mu[thin]) thin = a;
  const bool flat = int64_t{extent_mu[thin]} * 2 < extent_mu[(thin + 1) % 3] &&
                    int64_t{extent_mu[thin]} * 2 < extent_mu[(thin + 2) % 3];
  const SpgAxis thin_up = static_cast<SpgAxis>(1 + 2 * thin);
  if (v.up == SpgAxis::kNone) v.up = header.view_hint.up != SpgAxis::kNone ? header.view_hint.up : flat ? thin_up : SpgAxis::kPosY;
  if (v.orbit_given) return v;
  if (header.view_hint.sensor_at_origin) {
    // The eye at the scanner: the orbit's target a short way in front of it.
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      std::memcpy(&lo[a], &header.bbox_bits[a], 4);
      std::memcpy(&hi[a], &header.bbox_bits[3 + a], 4);
    }
    double largest = 0;
    for (int a = 0; a < 3; ++a) largest = std::max(largest, double(hi[a]) - lo[a]);
    if (largest > 0) {
      v.pitch = 0;
      v.fov = 90;
      v.distance = 0.05;
      int32_t basis[3][3];
      orbit_basis(v.up, basis);
      const double yaw = v.yaw * 3.14159265358979323846 / 180;
      const double b[3] = {std::sin(yaw), 0, std::cos(yaw)};  // pitch 0
      v.has_target = true;
      for (int a = 0; a < 3; ++a) {
        // The sensor at the scan's origin: -origin in the stored box's frame.
        double origin = 0;
        std::memcpy(&origin, &header.origin_bits[a], 8);
        const double back = basis[a][0] * b[0] + basis[a][1] * b[1] + basis[a][2] * b[2];
        v.target_mu[a] = (0.0 - origin - lo[a]) / largest * kMu - v.distance * kMu * back;
      }
      return v;
    }
  }
  const SpgAxis side = header.view_hint.sensor_side;
  if (side != SpgAxis::kNone) v.distance = 2;  // the sensor's view: closer than the object default
  if (side == v.up || (side == SpgAxis::kNone && header.view_hint.up == SpgAxis::kNone && flat && v.up == thin_up)) {
    v.pitch = 50;  // from above
  } else if (side != SpgAxis::kNone) {
    // Level with the sensor: the yaw whose horizontal eye direction is the side.
    int32_t basis[3][3];
    orbit_basis(v.up, basis);
    const int code = static_cast<int>(side) - 1;
    const int k = code / 2;
    const double sign = code % 2 ? -1 : 1;
    const double along_x = sign * basis[k][0], along_z = sign * basis[k][2];
    if (along_x != 0 || along_z != 0) {
      v.yaw = std::atan2(along_x, along_z) * 180 / 3.14159265358979323846;
      v.pitch = 0;
    }
  }
  return v;
}

OrbitView orbit_view(const int32_t extent_mu[3], const ViewSpec& spec) {
  OrbitView o;
  for (int a = 0; a < 3; ++a)
    o.target_mu[a] = spec.has_target ? static_cast<int32_t>(std::llround(spec.target_mu[a])) : extent_mu[a] / 2;
  o.distance_mu = static_cast<int32_t>(std::llround(spec.distance * kMu));
  o.yaw = binary_angle(spec.yaw);
  o.pitch = binary_angle(spec.pitch);
  o.fov = binary_angle(spec.fov);
  o.up = spec.up == SpgAxis::kNone ? SpgAxis::kPosY : spec.up;
  return o;
}

CutParams cut_params(const CutRule& rule, const ClientConfig& config) {
  CutParams p;
  p.max_size_q4 = rule.max_size_q4;
  p.max_nodes = config.node_capacity;
  p.cull_frustum = p.cull_backfaces = rule.cull;
  p.width = config.raster.width;
  p.height = config.raster.height;
  for (int k = 0; k < 4; ++k) p.window[k] = rule.window[k];
  return p;
}

ConeRule cone_rule(const CutRule& rule) {
  ConeRule c;
  c.leaf_gamma_q8 = rule.leaf_cone_q8;
  return c;
}

namespace {

// The view-dependent cut over shared bounds, in storage sized by the cut
// (its sent set and an update's scratch, grown while the update asks for
// more), never by the tree.
struct SizedCut {
  std::vector<uint64_t> state, scratch_storage;
  CutScratch scratch;
  ViewCut cut;
  bool update(const CutBounds& bounds, const Camera& camera, const CutParams& params) {
    const uint64_t n = bounds.node_count();
    const uint32_t sent = static_cast<uint32_t>(std::min<uint64_t>(n, params.max_nodes));
    state.assign(view_cut_state_bytes(sent) / 8 + 1, 0);
    if (cut.init(bounds, state.data(), state.size() * 8, &scratch) != CutStatus::kOk) return false;
    uint64_t capacity = std::min<uint64_t>(n, 4096);
    for (;;) {
      scratch_storage.assign(CutScratch::bytes(static_cast<uint32_t>(capacity)) / 8 + 1, 0);
      scratch.init(scratch_storage.data(), scratch_storage.size() * 8);
      const CutStatus s = cut.update(camera, params);
      if (s == CutStatus::kOk) return true;
      if (s != CutStatus::kStorageTooSmall || capacity >= n) return false;
      capacity = std::min<uint64_t>(n, std::max<uint64_t>(capacity + capacity / 2, uint64_t{cut.needed_capacity()} + 1));
    }
  }
};

bool render_with(const SpgView& view, const uint8_t* file, const NodeDecoder& decoder, const CutBounds* shared,
                 ClientConfig config, const CutRule& rule, const ViewSpec& spec, FixedRender& out, std::string& error,
                 int frames, size_t (*heap_probe)()) {
  Camera camera;
  const ViewSpec resolved = resolve_view(spec, view.header, decoder.extent_mu());
  if (config.elevation != SpgAxis::kNone) config.elevation = resolved.up;  // resolve_view always names one
  out.up = resolved.up;
  if (!orbit_camera(orbit_view(decoder.extent_mu(), resolved), config.raster.width, config.raster.height, &camera)) {
    error = "--camera: the view is out of the camera's range";
    return false;
  }
  std::vector<uint32_t> cut;
  std::vector<uint8_t> points;  // the original points under each cut node (what the client caps by)
  SizedCut view_cut;
  if (rule.kind == CutRule::kProjectedSize) {
    // The view-dependent cut, within what the client's cache holds, over
    // the model's bounds (mapped from its cut table, or built here).
    std::vector<uint64_t> own_storage;
    CutBounds own;
    if (shared == nullptr) {
      own_storage.assign(CutBounds::bytes(view.header) / 8 + 1, 0);
      if (own.init(view, decoder, own_storage.data(), own_storage.size() * 8, cone_rule(rule)) != CutStatus::kOk) {
        error = "the view cut failed";
        return false;
      }
      shared = &own;
    }
    if (!view_cut.update(*shared, camera, cut_params(rule, config))) {
      error = "the view cut failed";
      return false;
    }
    out.cut_bytes = own_storage.size() * 8 + view_cut.state.size() * 8 + view_cut.scratch_storage.size() * 8;
    const ViewCut& c = view_cut.cut;
    for (uint32_t i = 0; i < c.sent_count(); ++i) {
      cut.push_back(index_of(c.sent()[i]));
      points.push_back(c.points(c.sent()[i]));
    }
    out.cut_nodes = c.cut_count();
    out.culled_nodes = c.culled_count();
  } else {
    std::vector<uint8_t> scratch(cut_scratch_bytes(view.header));
    cut.resize(view.header.node_count);
    cut.resize(simple_cut(view, rule, &decoder, &camera, scratch.data(), cut.data(), static_cast<uint32_t>(cut.size())));
    config.node_capacity = std::max<uint32_t>(config.node_capacity, static_cast<uint32_t>(cut.size()));
    out.cut_nodes = static_cast<uint32_t>(cut.size());
    out.culled_nodes = 0;
    out.cut_bytes = scratch.size();
    std::vector<uint8_t> all(view.header.node_count);
    spg_node_points(view, all.data(), 1);
    for (const uint32_t id : cut) points.push_back(all[id]);
  }

  // The arena is sized for this file: angle fields wider than the default
  // client's (10 bits; the format allows 16) get their tables.
  for (Field theta : {Field::kFpTheta, Field::kFnTheta, Field::kFcTheta})
    for (int k = 0; k < 3; ++k)
      config.max_angle_bits = std::max<uint8_t>(config.max_angle_bits, view.header.layout.bits[static_cast<int>(theta) + k]);
  config.max_record_bytes = std::max<uint8_t>(config.max_record_bytes, static_cast<uint8_t>(view.record_bytes));
  out.arena_bytes = client_arena_bytes(config);
  if (out.arena_bytes == 0) {
    error = "invalid renderer configuration";
    return false;
  }
  std::vector<uint64_t> arena(out.arena_bytes / 8 + 1);
  Client client;
  ClientStatus s = client.init(config, arena.data(), arena.size() * 8);
  if (s == ClientStatus::kOk) s = client.load_startup(file, spg_startup_bytes(view.header.version, view.header.class_count));
  for (size_t i = 0; s == ClientStatus::kOk && i < cut.size(); ++i)
    s = client.put_node(NodeId{cut[i]}, view.records + static_cast<size_t>(cut[i]) * view.record_bytes, view.record_bytes,
                        points[i]);
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
    error = s == ClientStatus::kBadCamera
                ? std::string("--camera: the view puts the camera out of the client's range (its distance, field of view or the model's size)")
                : std::string("client: ") + client_status_text(s);
    return false;
  }
  image_from_frame(out.frame.data(), stride, config.raster.width, config.raster.height, config.raster.format, out.image);
  out.cut = std::move(cut);
  out.camera = camera;
  return true;
}

}  // namespace

bool render_fixed(const SpgView& view, const uint8_t* file, ClientConfig config, const CutRule& rule,
                  const ViewSpec& spec, FixedRender& out, std::string& error, int frames, size_t (*heap_probe)()) {
  // A decoder over the whole file, as the server side holds; the bounds are
  // built (for the projected-size rule) as the cut needs them.
  std::vector<uint8_t> decoder_storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size()) != DecodeStatus::kOk) {
    error = "the file's angle fields are wider than the decoder supports";
    return false;
  }
  return render_with(view, file, decoder, nullptr, config, rule, spec, out, error, frames, heap_probe);
}

bool render_fixed(const ModelFile& model, ClientConfig config, const CutRule& rule, const ViewSpec& spec,
                  FixedRender& out, std::string& error, int frames, size_t (*heap_probe)()) {
  return render_with(model.view(), model.data(), model.decoder(), &model.bounds(), config, rule, spec, out, error,
                     frames, heap_probe);
}

std::string spg_error_message(const std::string& name, const SpgResult& r, size_t size) {
  if (r.error == SpgError::kTruncated && size == 0) return name + ": the file is empty (0 bytes), not a .spg model";
  if (r.error == SpgError::kTruncated && r.needed > size)
    return name + ": truncated: " + cli::with_commas(size) + " of at least " + cli::with_commas(r.needed) +
           " bytes (the file was cut short, or its header's counts are wrong)";
  return name + ": byte " + std::to_string(r.offset) + ": " + spg_error_text(r.error);
}

std::string spg_error_message(const std::string& name, const SpgResult& r, const uint8_t* data, size_t size) {
  // A scan where a model belongs (the handheld reads only .spg): say what to do.
  const auto starts = [&](const char* s) { return size >= std::strlen(s) && std::memcmp(data, s, std::strlen(s)) == 0; };
  if (r.error == SpgError::kBadMagic && (starts("ply") || starts("LASF") || starts("# .PCD") || starts("VERSION")))
    return name + ": a scan, not a .spg model: encode it first (stipple encode " + name + " -o MODEL.spg)";
  return spg_error_message(name, r, size);
}

}  // namespace stipple
