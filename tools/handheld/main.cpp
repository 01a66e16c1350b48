// stipple-handheld — the handheld client program: reads a .spg, takes a
// simple cut for the camera, runs the fixed-point client over one arena and
// shows the frame on a Linux framebuffer or writes it as PPM. Builds for
// every target in toolchains/; its frames are the same bytes everywhere
// (`--crc` prints their CRC-32, which the golden-image tests check).
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <malloc.h>

#include "platform/file_io.h"
#include "tools/handheld/embedded.h"
#include "tools/handheld/frame_sink.h"

namespace {

const char kUsage[] =
    "usage: stipple-handheld MODEL.spg [options]\n"
    "\n"
    "The handheld client: fixed point, one arena, no heap after start-up. Draws\n"
    "a simple cut of MODEL.spg for an orbit camera.\n"
    "\n"
    "  --size WxH             screen (default 240x320, or the framebuffer's size)\n"
    "  --format rgb565|rgb888 pixel format (default rgb565)\n"
    "  --camera Y,P[,D[,F]]   yaw, pitch (degrees), distance (model extents), field\n"
    "                         of view (degrees); default 30,20,3,35\n"
    "  --max-size PX          cut: split nodes wider than PX pixels (default 2)\n"
    "  --level L              cut: tree level L instead\n"
    "  --max-points N         frame budget (default 1048576)\n"
    "  --cache N              nodes the client's cache holds (default 30000, raised\n"
    "                         to the cut's size)\n"
    "  --projection affine|reciprocal|exact\n"
    "                         per-point projection (default affine)\n"
    "  --frames N             draw N frames (timing; default 1)\n"
    "  -o FRAME.ppm           write the frame (headless)\n"
    "  --fbdev DEVICE         show the frame on a framebuffer (e.g. /dev/fb0)\n"
    "  --crc                  print the CRC-32 of the frame's RGB888 bytes\n"
    "  --memory               print the memory the run holds: the client's arena,\n"
    "                         the frame, the model file, and the heap in use while\n"
    "                         drawing (glibc's mallinfo2)\n";

int fail(const std::string& message) {
  std::fprintf(stderr, "stipple-handheld: %s\n", message.c_str());
  return 1;
}

// Bytes the C library's allocator has handed out and not taken back.
size_t heap_in_use() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

bool parse_uint(const char* text, unsigned long max, unsigned long& out) {
  if (text == nullptr || *text < '0' || *text > '9') return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtoul(text, &end, 10);
  return errno == 0 && *end == '\0' && out <= max;
}

}  // namespace

namespace {

int run(int argc, char** argv) {
  using namespace stipple;
  ClientConfig config;
  config.raster = RasterConfig{240, 320, 5, PixelFormat::kRgb565, 1u << 20};
  CutRule rule{CutRule::kProjectedSize, 0, 32};
  ViewSpec view;
  std::string model, output, fbdev, error;
  bool crc = false, memory = false, sized = false;
  unsigned long frames = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* next = i + 1 < argc ? argv[i + 1] : nullptr;
    unsigned long u = 0;
    if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (a == "--size" && next) {
      const char* x = std::strchr(next, 'x');
      unsigned long w = 0, h = 0;
      if (!x || !parse_uint(std::string(next, x).c_str(), 4096, w) || !parse_uint(x + 1, 4096, h) || !w || !h)
        return fail(std::string("--size: expected WIDTHxHEIGHT within 1..4096, got '") + next + "'");
      config.raster.width = static_cast<uint16_t>(w);
      config.raster.height = static_cast<uint16_t>(h);
      sized = true;
      ++i;
    } else if (a == "--format" && next) {
      if (!std::strcmp(next, "rgb565")) config.raster.format = PixelFormat::kRgb565;
      else if (!std::strcmp(next, "rgb888")) config.raster.format = PixelFormat::kRgb888;
      else return fail(std::string("--format: expected rgb565 or rgb888, got '") + next + "'");
      ++i;
    } else if (a == "--camera" && next) {
      if (!parse_view(next, view, error)) return fail(error);
      ++i;
    } else if (a == "--max-size" && next) {
      const double px = std::strtod(next, nullptr);
      if (!(px >= 0.0625 && px <= 4096)) return fail(std::string("--max-size: expected pixels within [0.0625, 4096], got '") + next + "'");
      rule = CutRule{CutRule::kProjectedSize, 0, static_cast<int32_t>(px * 16 + 0.5)};
      ++i;
    } else if (a == "--level" && next) {
      if (!parse_uint(next, 65535, u)) return fail(std::string("--level: expected a non-negative integer, got '") + next + "'");
      rule = CutRule{CutRule::kLevel, static_cast<uint16_t>(u), 0};
      ++i;
    } else if (a == "--max-points" && next) {
      if (!parse_uint(next, 1ul << 26, u) || u == 0) return fail(std::string("--max-points: expected 1..67108864, got '") + next + "'");
      config.raster.max_points = static_cast<uint32_t>(u);
      ++i;
    } else if (a == "--cache" && next) {
      if (!parse_uint(next, 1ul << 24, u) || u == 0) return fail(std::string("--cache: expected 1..16777216 nodes, got '") + next + "'");
      config.node_capacity = static_cast<uint32_t>(u);
      ++i;
    } else if (a == "--projection" && next) {
      if (!std::strcmp(next, "affine")) config.projection = Projection::kAffine;
      else if (!std::strcmp(next, "reciprocal")) config.projection = Projection::kReciprocal;
      else if (!std::strcmp(next, "exact")) config.projection = Projection::kExact;
      else return fail(std::string("--projection: expected affine, reciprocal or exact, got '") + next + "'");
      ++i;
    } else if (a == "--memory") {
      memory = true;
    } else if (a == "--frames" && next) {
      if (!parse_uint(next, 100000, frames) || frames == 0) return fail(std::string("--frames: expected 1..100000, got '") + next + "'");
      ++i;
    } else if (a == "-o" && next) {
      output = next;
      ++i;
    } else if (a == "--fbdev" && next) {
      fbdev = next;
      ++i;
    } else if (a == "--crc") {
      crc = true;
    } else if (!a.empty() && a[0] == '-') {
      return fail("unknown option '" + a + "' (see --help)");
    } else if (model.empty()) {
      model = a;
    } else {
      return fail("expected one .spg file (see --help)");
    }
  }
  if (model.empty()) return fail("expected a .spg file (see --help)");

  // The framebuffer first: a missing device fails before any work, and its
  // size is the frame's unless --size says otherwise.
  Framebuffer fb;
  if (!fbdev.empty()) {
    if (!fb.open(fbdev, error)) return fail(error);
    if (!sized) {
      config.raster.width = static_cast<uint16_t>(std::min(fb.width(), 4096));
      config.raster.height = static_cast<uint16_t>(std::min(fb.height(), 4096));
    }
  }

  std::vector<uint8_t> file;
  if (!read_file(model, file, error)) return fail(error);
  SpgView spg;
  const SpgResult r = spg_parse(file.data(), file.size(), &spg);
  if (!r.ok()) return fail(model + ": byte " + std::to_string(r.offset) + ": " + spg_error_text(r.error));
  FixedRender frame;
  if (!render_fixed(spg, file.data(), config, rule, view, frame, error, static_cast<int>(frames),
                    memory ? heap_in_use : nullptr))
    return fail(model + ": " + error);
  std::vector<double> t = frame.frame_seconds;
  std::sort(t.begin(), t.end());
  std::printf("%s: %zu nodes, %u points, arena %zu bytes, frame %.3f ms (median of %lu)\n", model.c_str(), frame.cut.size(),
              frame.stats.points, frame.arena_bytes, 1e3 * t[t.size() / 2], frames);
  if (memory)
    std::printf("memory: client arena %zu bytes, frame %zu bytes, model file %zu bytes; heap in use while drawing %zu bytes\n",
                frame.arena_bytes, frame.frame.size(), file.size(), frame.heap_bytes);
  if (crc) std::printf("crc32 %08x\n", crc32(frame.image.rgb.data(), frame.image.rgb.size()));
  if (!output.empty() && !write_ppm(output, frame.image, error)) return fail(error);
  if (!fbdev.empty()) fb.show(frame.image);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Nothing below throws by design; what still escapes (out of memory) ends
  // with a message naming the input, never an abort.
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "stipple-handheld: %s: out of memory\n", argc > 1 ? argv[1] : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stipple-handheld: %s: %s\n", argc > 1 ? argv[1] : "", e.what());
  }
  return 1;
}
