// stipple — the embedded default, without host libraries: an orbit view in
// user units, the fixed-point client fed a simple cut of a .spg in process,
// and the frame as an RGB888 image. Builds for the handheld too (no Eigen,
// no libpng); the host's renderer (tools/reference/render.h) adds the double
// reference on top.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/cut.h"
#include "core/view_cut.h"
#include "core/spg_format.h"
#include "platform/image.h"
#include "raster/client.h"

namespace stipple {

// An orbit camera in user units: degrees, and the distance from the model's
// centre in units of the model's largest extent; the axis it orbits about.
struct ViewSpec {
  double yaw = 30, pitch = 20, distance = 3, fov = 35;
  bool orbit_given = false;     // --camera gave yaw and pitch: no default from the file
  SpgAxis up = SpgAxis::kNone;  // --up; kNone: from the file (resolve_view)
  bool has_target = false;      // orbit about target_mu instead of the box's centre
  double target_mu[3] = {0, 0, 0};
};

// "yaw,pitch[,distance[,fov]]"; error names the bad part. Sets orbit_given.
bool parse_view(const std::string& text, ViewSpec& out, std::string& error);

// What spg_parse (or spg_parse_startup) refused, for a person:
// "<name>: byte <offset>: <what>", and for a file cut short
// "<name>: truncated: <size> of at least <needed> bytes (...)".
std::string spg_error_message(const std::string& name, const SpgResult& result, size_t size);
// The same, knowing the bytes: a scan given where a model belongs is named
// as one, with the command that encodes it.
std::string spg_error_message(const std::string& name, const SpgResult& result, const uint8_t* data, size_t size);

// The view a user gets for a model (docs/encoder.md, "Orientation"):
//   up: --up, else the file's hint, else the thinnest axis (+) of a flat box
//       (under half of each other extent: terrain), else +y;
//   yaw, pitch and distance, unless --camera gave them: from the sensor's
//       side when the file names one, 2 extents away (level with it, pitch
//       0; from above, pitch 50, when the side is up), from above for a flat
//       box without a hint, from the origin when the sensor stood inside the
//       scan there (level, a 90-degree field of view: the eye at the
//       scanner), else the defaults (30, 20, 3: the bunny's and dragon's
//       golden views).
ViewSpec resolve_view(const ViewSpec& spec, const SpgHeader& header, const int32_t extent_mu[3]);

// The integer orbit for a model whose box spans extent_mu (the decoder's MU),
// for a resolved spec.
OrbitView orbit_view(const int32_t extent_mu[3], const ViewSpec& spec);

struct FixedRender {
  std::vector<uint8_t> frame;  // config format, tightly packed rows
  Image image;
  std::vector<uint32_t> cut;   // node ids drawn (the cut's sent nodes), breadth-first
  uint32_t cut_nodes = 0;      // the whole cut, culled nodes included
  uint32_t culled_nodes = 0;   // in the cut, culled, not sent
  FrameStats stats;
  size_t arena_bytes = 0;
  Camera camera;
  SpgAxis up = SpgAxis::kNone;  // the resolved view's up axis
  std::vector<double> frame_seconds;  // render() wall time of each frame drawn
  size_t heap_bytes = 0;  // heap_probe's answer after the frames (0 without a probe)
  // What the cut took: its bounds when built here (36 bytes a node of the
  // tree), its sent set and an update's scratch (sized by the cut).
  size_t cut_bytes = 0;
};

// The view cut's parameters for a projected-size rule and a client: its
// threshold, culling and window, the client's screen, and its cache as the budget.
CutParams cut_params(const CutRule& rule, const ClientConfig& config);
// The normal cones of a rule (the leaf cone; the rest ConeRule's defaults).
ConeRule cone_rule(const CutRule& rule);

// Cuts the validated `view` by `rule` for the camera, feeds the client the
// startup message and the cut's records, renders the frame `frames` times
// (for timing; every frame is the same). The projected-size rule goes
// through the view-dependent cut, whose sent nodes never exceed
// config.node_capacity (a coarser cut instead); for the level rule the
// capacity is raised to the cut's size. `heap_probe`, when given, is asked for the
// bytes of heap in use once the frames are drawn, while every buffer of the
// run (the file's decoder, the cut, the client's arena, the frame) is alive.
bool render_fixed(const SpgView& view, const uint8_t* file, ClientConfig config, const CutRule& rule,
                  const ViewSpec& spec, FixedRender& out, std::string& error, int frames = 1,
                  size_t (*heap_probe)() = nullptr);
// The same for a model opened as every program opens one (mapped, its cut
// bounds from its cut table): what the run holds besides the mapped pages
// follows the cut and the client's arena, not the model's size. The rule's
// leaf cone must be the one `model` was opened with.
class ModelFile;
bool render_fixed(const ModelFile& model, ClientConfig config, const CutRule& rule, const ViewSpec& spec,
                  FixedRender& out, std::string& error, int frames = 1, size_t (*heap_probe)() = nullptr);

}  // namespace stipple
