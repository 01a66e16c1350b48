// Fuzz harness: a scan end to end, as `stipple render SCAN` runs it — read
// (any format parse_point_cloud reads; at most 3,000 points kept, so an
// input runs in milliseconds), encoded with the defaults on one thread, the
// file validated by core's reader and the reference decoder, and drawn by
// the fixed-point client at 64 x 48. Checked: whatever the encoder accepts,
// it writes a file that validates, decodes and draws — a refusal after the
// encoder said yes is a bug, and so is a crash anywhere.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tools/embedded/embedded.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/ply_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stipple;
  PointCloud cloud;
  std::string error;
  if (!parse_point_cloud("fuzz.scan", data, size, cloud, error)) return 0;
  if (cloud.size() > 3000) return 0;
  EncodeOptions o;
  o.tree.threads = 1;
  std::vector<uint8_t> spg;
  EncodeReport report;
  if (!encode_cloud(cloud, o, spg, report, error)) return 0;
  SpgView view;
  if (!spg_parse(spg.data(), spg.size(), &view).ok()) __builtin_trap();
  DecodedModel model;
  if (!decode_spg("fuzz.spg", spg.data(), spg.size(), model, error)) __builtin_trap();
  ClientConfig config;
  config.raster = RasterConfig{64, 48, 5, PixelFormat::kRgb565, 1u << 16};
  FixedRender fixed;
  if (!render_fixed(view, spg.data(), config, CutRule{CutRule::kProjectedSize, 0, 32}, ViewSpec{}, fixed, error)) {
    // The only refusal allowed: a default view the camera cannot take (a
    // scan of one point has no extent to frame).
    if (error.find("camera") == std::string::npos) __builtin_trap();
  }
  return 0;
}
