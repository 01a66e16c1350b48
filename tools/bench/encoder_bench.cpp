// Benchmarks of the host hot paths: encoding (at three sizes, for the n log n
// claim), hierarchy, classification, .spg validation, record unpacking,
// kd-tree queries and PLY parsing.
//
//   build/release/tools/stipple_bench [--benchmark_filter=...]
//
// Uses ../shared/data/dragon.ply when present (STIPPLE_BENCH_SCAN overrides),
// else the bundled bunny.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>

#include "core/divide.h"
#include "core/gaussian_table.h"
#include "core/node_decoder.h"
#include "core/spg_coded.h"
#include "core/spg_format.h"
#include "platform/file_io.h"
#include "core/cut.h"
#ifdef STIPPLE_BENCH_GL
#include "platform/gl/gl_renderer.h"
#endif
#include "core/stream.h"
#include "core/view_cut.h"
#include "raster/client.h"
#include "tools/server/link_timing.h"
#include "tools/server/server.h"
#include "platform/loopback/loopback_transport.h"
#include "raster/point_kernel_avx2.h"
#include "raster/point_raster.h"
#include "raster/resolve.h"
#include <lzf.h>

#include "tools/encoder/classify.h"
#include "tools/encoder/coded_file.h"
#include "tools/encoder/encoder.h"
#include "tools/scan/kdtree.h"
#include "tools/encoder/normals.h"
#include "tools/scan/ply_io.h"
#include "tools/reference/render.h"

namespace stipple {
namespace {

std::string scan_path() {
  if (const char* env = std::getenv("STIPPLE_BENCH_SCAN")) return env;
  const std::string dragon = STIPPLE_SOURCE_DIR "/../shared/data/dragon.ply";
  return std::filesystem::exists(dragon) ? dragon : STIPPLE_SOURCE_DIR "/data/bunny.ply";
}

// The scan with normals from its faces, loaded once.
const PointCloud& scan() {
  static const PointCloud cloud = [] {
    PointCloud c;
    std::string error;
    if (!read_point_cloud(scan_path(), c, error)) std::abort();
    estimate_normals(c);
    c.triangles.clear();
    return c;
  }();
  return cloud;
}

// Every k-th point of the scan (normals kept): sizes n/k for the scaling runs.
PointCloud subsample(size_t k) {
  const PointCloud& full = scan();
  PointCloud c;
  for (size_t i = 0; i < full.size(); i += k) {
    c.positions.push_back(full.positions[i]);
    c.normals.push_back(full.normals[i]);
  }
  return c;
}

void BM_Encode(benchmark::State& state) {
  const PointCloud input = subsample(static_cast<size_t>(state.range(0)));
  std::vector<uint8_t> spg;
  for (auto _ : state) {
    PointCloud c = input;
    EncodeReport r;
    std::string error;
    if (!encode_cloud(c, EncodeOptions{}, spg, r, error)) state.SkipWithError(error.c_str());
    benchmark::DoNotOptimize(spg.data());
  }
  state.counters["points"] = static_cast<double>(input.size());
  state.counters["ns_per_point"] = benchmark::Counter(static_cast<double>(input.size()),
                                                      benchmark::Counter::kIsIterationInvariantRate |
                                                          benchmark::Counter::kInvert);
}
BENCHMARK(BM_Encode)->Arg(4)->Arg(2)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)
    ->ReportAggregatesOnly(true);

void BM_BuildTree(benchmark::State& state) {
  const PointCloud& c = scan();
  for (auto _ : state) benchmark::DoNotOptimize(build_tree(c, TreeOptions{}).nodes.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(c.size()));
}
BENCHMARK(BM_BuildTree)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_ClassifySigmas(benchmark::State& state) {
  std::mt19937_64 rng(1);
  std::lognormal_distribution<double> d(-6, 1);
  std::vector<Vec3> t(static_cast<size_t>(state.range(0)));
  for (Vec3& v : t) {
    double a = d(rng), b = d(rng), c = d(rng);
    if (a < b) std::swap(a, b);
    if (b < c) std::swap(b, c);
    if (a < b) std::swap(a, b);
    v = Vec3(a, b, c);
  }
  for (auto _ : state) benchmark::DoNotOptimize(classify_sigmas(t, 3, 4096).centers.size());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ClassifySigmas)->Arg(100000)->Unit(benchmark::kMillisecond)->Iterations(2);

// The scan encoded with the defaults, once.
const std::vector<uint8_t>& encoded_scan() {
  static const std::vector<uint8_t> spg = [] {
    PointCloud c = scan();
    std::vector<uint8_t> bytes;
    EncodeReport r;
    std::string error;
    if (!encode_cloud(c, EncodeOptions{}, bytes, r, error)) std::abort();
    return bytes;
  }();
  return spg;
}

uint32_t spg_node_count(const std::vector<uint8_t>& spg) { return load_u32le(spg.data() + spg_offset::kNodeCount); }

// A validated view of `encoded_scan()`.
SpgView parsed_scan() {
  const std::vector<uint8_t>& spg = encoded_scan();
  SpgView view;
  if (!spg_parse(spg.data(), spg.size(), &view).ok()) std::abort();
  return view;
}

void BM_SpgParse(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  SpgView view;
  for (auto _ : state) {
    const SpgResult r = spg_parse(spg.data(), spg.size(), &view);
    benchmark::DoNotOptimize(r);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(spg.size()));
  state.counters["nodes"] = view.header.node_count;
}
BENCHMARK(BM_SpgParse)->Unit(benchmark::kMillisecond);

// Format version 3 (docs/format.md §5, "Coded records"): the scan's file
// coded (the tables counted on every record, the batches, the check that
// it expands back), and expanded as every reader opens it.
void BM_SpgCode(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  std::vector<uint8_t> coded;
  CodedFileReport report;
  std::string error;
  for (auto _ : state)
    if (!write_coded_spg(spg.data(), spg.size(), coded, report, error)) state.SkipWithError(error.c_str());
  state.counters["nodes"] = static_cast<double>(spg_node_count(spg));
  state.counters["bytes"] = static_cast<double>(coded.size());
  state.counters["v2_bytes"] = static_cast<double>(spg.size());
  state.counters["nodes_per_s"] = benchmark::Counter(static_cast<double>(spg_node_count(spg)), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SpgCode)->Unit(benchmark::kMillisecond);

void BM_SpgExpand(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  std::vector<uint8_t> coded;
  CodedFileReport report;
  std::string error;
  if (!write_coded_spg(spg.data(), spg.size(), coded, report, error)) return state.SkipWithError(error.c_str());
  SpgView view;
  SpgCodedParts parts;
  if (!spg_parse_coded(coded.data(), coded.size(), &view, &parts).ok()) return state.SkipWithError("parse");
  std::vector<uint8_t> image(spg_expanded_bytes(view, parts)), points(view.header.node_count);
  for (auto _ : state) {
    const SpgResult r = spg_expand(coded.data(), view, parts, image.data(), points.data());
    if (!r.ok()) state.SkipWithError("expand");
  }
  state.counters["nodes_per_s"] =
      benchmark::Counter(static_cast<double>(view.header.node_count), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SpgExpand)->Unit(benchmark::kMillisecond);

void BM_UnpackRecord(benchmark::State& state) {
  const SpgView view = parsed_scan();
  const uint32_t n = view.header.node_count;
  uint32_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(unpack_record(view.header.layout, view.records + static_cast<size_t>(i) * view.record_bytes));
    i = i + 1 == n ? 0 : i + 1;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_UnpackRecord);

void BM_DecodeNodeFixed(benchmark::State& state) {
  const SpgView view = parsed_scan();
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4);
  NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size() * 4) != DecodeStatus::kOk) state.SkipWithError("init");
  const uint32_t n = view.header.node_count;
  uint32_t i = 0;
  FixedNode node;
  for (auto _ : state) {
    benchmark::DoNotOptimize(decoder.decode(view.records + static_cast<size_t>(i) * view.record_bytes, &node));
    benchmark::DoNotOptimize(node);
    i = i + 1 == n ? 0 : i + 1;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecodeNodeFixed);

void BM_DecoderInit(benchmark::State& state) {
  const SpgView view = parsed_scan();
  std::vector<uint32_t> storage(node_decoder_bytes(view.header) / 4);
  NodeDecoder decoder;
  for (auto _ : state) benchmark::DoNotOptimize(decoder.init(view, storage.data(), storage.size() * 4));
}
BENCHMARK(BM_DecoderInit)->Unit(benchmark::kMicrosecond);

void BM_GaussianTable(benchmark::State& state) {
  std::vector<Gaussian3Q12> table(static_cast<size_t>(state.range(0)));
  for (auto _ : state) {
    build_gaussian3_table(GaussianSource::kSobol, table.data(), table.size());
    benchmark::DoNotOptimize(table.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_GaussianTable)->Arg(1024)->Unit(benchmark::kMicrosecond);

// Rasterize 30 K points (sizes 1-3) into a 240x320 RGB565 or 640x480 RGB888 frame.
// The exact projection's floored divisions (f X_p / Z_p): Arg 0 divides
// with the instruction (or the compiler's helper), Arg 1 by multiplication
// (core/divide.h, what STIPPLE_HW_DIVIDE=OFF builds use).
void BM_FloorDiv(benchmark::State& state) {
  std::mt19937_64 rng(5);
  std::vector<int64_t> n(4096), d(4096);
  for (size_t i = 0; i < n.size(); ++i) {
    d[i] = 4096 + static_cast<int64_t>(rng() >> 34);
    n[i] = (static_cast<int64_t>(rng() % 16384) - 8192) * (d[i] >> 4) + static_cast<int64_t>(rng() % 1000);
  }
  const bool soft = state.range(0) != 0;
  int64_t sum = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < n.size(); ++i) {
      if (soft) {
        sum += floor_div_soft(n[i], d[i]);
      } else {
        const int64_t q = n[i] / d[i];
        sum += q * d[i] > n[i] ? q - 1 : q;
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(n.size()));
}
BENCHMARK(BM_FloorDiv)->Arg(0)->Arg(1);

void BM_RasterFrame(benchmark::State& state) {
  const bool large = state.range(0) != 0;
  RasterConfig c{static_cast<uint16_t>(large ? 640 : 240), static_cast<uint16_t>(large ? 480 : 320), 6,
                 large ? PixelFormat::kRgb888 : PixelFormat::kRgb565, 30000};
  c.avx2 = state.range(1) != 0 && avx2::supported();  // the tiles' clear and write-out in AVX2
  std::vector<uint64_t> arena(point_raster_bytes(c) / 8 + 1);
  PointRaster raster;
  if (raster.init(c, arena.data(), arena.size() * 8) != RasterStatus::kOk) state.SkipWithError("init");
  std::vector<uint8_t> frame(static_cast<size_t>(c.width) * c.height * bytes_per_pixel(c.format));
  std::mt19937 rng(1);
  std::vector<ScreenPoint> pts(30000);
  for (ScreenPoint& p : pts)
    p = ScreenPoint{static_cast<int32_t>(rng() % (c.width * 16u)), static_cast<int32_t>(rng() % (c.height * 16u)),
                    static_cast<uint32_t>(rng()), static_cast<uint32_t>(rng() & 0xFFFFFF)};
  for (auto _ : state) {
    raster.begin_frame();
    for (size_t i = 0; i < pts.size(); ++i) raster.add(pts[i], 1 + static_cast<int>(i % 3));
    raster.draw(0, frame.data(), static_cast<size_t>(c.width) * bytes_per_pixel(c.format));
    benchmark::DoNotOptimize(frame.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(pts.size()));
}
BENCHMARK(BM_RasterFrame)->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1})->Unit(benchmark::kMicrosecond);

// One client frame of the scan at 640 x 480 RGB888 from the default view,
// the cut's projected-size threshold chosen so that about 30,000 nodes are
// in view (the setting), per sampled normal, the resolve off. Arg 0:
// lanes (0 best — AVX2 where the CPU has it —, 1 the baseline's SSE2, 2
// scalar); arg 1: point size (1 or 2 px); arg 2: 0 packed cache (unpacked
// each frame), 1 unpacked cache; arg 3: projection (0 affine, 1
// reciprocal, 2 exact). Counters: points per frame and points per second;
// the set-up of every node, the sampling, transform, shading, z-test and
// write of every point are inside the timed render().
// The cut of the simple projected-size rule whose threshold (1/16 px) gives
// nearest 30,000 nodes for `camera`: the frame benchmarks' load.
std::vector<uint32_t> cut_near_30000(const SpgView& view, const NodeDecoder& decoder, const Camera& camera) {
  std::vector<uint8_t> scratch(cut_scratch_bytes(view.header));
  std::vector<uint32_t> cut(view.header.node_count);
  uint32_t n = 0;
  for (int32_t q4 = 8; q4 <= 4096; q4 += q4 / 8) {
    n = simple_cut(view, CutRule{CutRule::kProjectedSize, 0, q4}, &decoder, &camera, scratch.data(), cut.data(),
                   static_cast<uint32_t>(cut.size()));
    if (n <= 30000) break;
  }
  cut.resize(n);
  return cut;
}

// The frame benchmarks' scene: the default orbit camera at 640x480 and the
// cut near 30,000 nodes for it.
struct FrameScene {
  std::vector<uint8_t> storage;
  NodeDecoder decoder;
  Camera camera;
  std::vector<uint32_t> cut;
  explicit FrameScene(const SpgView& view) : storage(node_decoder_bytes(view.header)) {
    if (decoder.init(view, storage.data(), storage.size()) != DecodeStatus::kOk ||
        !orbit_camera(orbit_view(decoder.extent_mu(), ViewSpec{}), 640, 480, &camera))
      std::abort();
    cut = cut_near_30000(view, decoder, camera);
  }
};

void BM_ClientFrame(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  ClientConfig c;
  c.raster.width = 640;
  c.raster.height = 480;
  c.raster.format = PixelFormat::kRgb888;
  c.raster.max_points = 1u << 21;
  c.lanes = static_cast<PointLanes>(state.range(0));
  c.point_size = static_cast<uint8_t>(state.range(1));
  c.cache_decoded = state.range(2) != 0;
  c.projection = static_cast<Projection>(state.range(3));
  c.shading = ShadingMode::kPerPoint;
  c.resolve = false;
  c.node_capacity = view.header.node_count;
  const FrameScene scene(view);
  const Camera& camera = scene.camera;
  const std::vector<uint32_t>& cut = scene.cut;
  const uint32_t n = static_cast<uint32_t>(cut.size());
  std::vector<uint64_t> arena(client_arena_bytes(c) / 8 + 1);
  Client client;
  if (client.init(c, arena.data(), arena.size() * 8) != ClientStatus::kOk ||
      client.load_startup(spg.data(), spg_startup_bytes(view.header.version, view.header.class_count)) != ClientStatus::kOk)
    std::abort();
  for (uint32_t i = 0; i < n; ++i)
    if (client.put_node(NodeId{cut[i]}, view.records + static_cast<size_t>(cut[i]) * view.record_bytes, view.record_bytes) !=
        ClientStatus::kOk)
      std::abort();
  std::vector<uint8_t> frame(640 * 480 * 3);
  FrameStats stats;
  for (auto _ : state) {
    if (client.render(camera, frame.data(), 640 * 3, &stats) != ClientStatus::kOk) std::abort();
    benchmark::DoNotOptimize(frame.data());
  }
  state.counters["nodes"] = stats.nodes;
  state.counters["points"] = stats.points;
  state.counters["points_per_s"] = benchmark::Counter(static_cast<double>(stats.points), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["ns_per_point"] = benchmark::Counter(static_cast<double>(stats.points), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert) ;
}
BENCHMARK(BM_ClientFrame)
    ->ArgNames({"lanes", "px", "unpacked", "projection"})
    ->Args({0, 2, 0, 0})
    ->Args({0, 1, 0, 0})
    ->Args({1, 2, 0, 0})
    ->Args({1, 1, 0, 0})
    ->Args({2, 2, 0, 0})
    ->Args({2, 1, 0, 0})
    ->Args({0, 2, 1, 0})
    ->Args({0, 2, 0, 1})
    ->Args({0, 2, 0, 2})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// Close-ups (raster/close_up.h): a scanned plane of 64 x 64 points, one
// unit apart, from arg 0's view — 0: face on from a tenth of its spacing
// (the whole screen one disc deep), 1: face on from 0.05 of the model (a
// few hundred discs), 2: at 30 degrees from 0.3 (discs near, points far) —
// at arg 1's screen (0: the handheld's 240 x 320 RGB565, 1: 640 x 480
// RGB888), the default client (surface normals, the resolve). Counters:
// the discs and the points of the frame.
// EWA splats (raster/ewa.h) against the default points: the same cut,
// 640 x 480, the client's defaults (surface normals, the resolve).
void BM_EwaFrame(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  ClientConfig c;
  c.raster = RasterConfig{640, 480, kDefaultTileLog2, PixelFormat::kRgb888, 1u << 21};
  c.node_capacity = view.header.node_count;
  c.ewa = state.range(0) != 0;
  const FrameScene scene(view);
  std::vector<uint64_t> arena(client_arena_bytes(c) / 8 + 1);
  Client client;
  if (client.init(c, arena.data(), arena.size() * 8) != ClientStatus::kOk ||
      client.load_startup(spg.data(), spg_startup_bytes(view.header.version, view.header.class_count)) != ClientStatus::kOk)
    std::abort();
  for (const uint32_t id : scene.cut)
    if (client.put_node(NodeId{id}, view.records + size_t{id} * view.record_bytes, view.record_bytes) != ClientStatus::kOk)
      std::abort();
  std::vector<uint8_t> frame(640 * 480 * 3);
  FrameStats stats;
  for (auto _ : state) {
    if (client.render(scene.camera, frame.data(), 640 * 3, &stats) != ClientStatus::kOk) std::abort();
    benchmark::DoNotOptimize(frame.data());
  }
  state.counters["nodes"] = stats.nodes;
  state.counters["splats"] = stats.splats;
  state.counters["points"] = stats.points;
}
BENCHMARK(BM_EwaFrame)->ArgNames({"ewa"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_CloseUpFrame(benchmark::State& state) {
  static const std::vector<uint8_t> spg = [] {
    std::vector<uint8_t> bytes;
    EncodeReport r;
    std::string error;
    PointCloud plane = grid_plane(64);
    if (!encode_cloud(plane, EncodeOptions{}, bytes, r, error)) std::abort();
    return bytes;
  }();
  SpgView view;
  if (!spg_parse(spg.data(), spg.size(), &view).ok()) std::abort();
  const bool large = state.range(1) != 0;
  ClientConfig c;
  c.raster = RasterConfig{static_cast<uint16_t>(large ? 640 : 240), static_cast<uint16_t>(large ? 480 : 320),
                          kDefaultTileLog2, large ? PixelFormat::kRgb888 : PixelFormat::kRgb565, 1u << 21};
  const char* views[] = {"0,90,0.0016", "0,90,0.05", "20,30,0.3"};
  ViewSpec spec;
  std::string error;
  if (!parse_view(views[state.range(0)], spec, error)) std::abort();
  FixedRender fixed;  // the cut, the camera and the frame as stipple render draws them
  if (!render_fixed(view, spg.data(), c, CutRule{CutRule::kProjectedSize, 0, 32}, spec, fixed, error)) std::abort();
  c.node_capacity = view.header.node_count;
  std::vector<uint64_t> arena(client_arena_bytes(c) / 8 + 1);
  Client client;
  if (client.init(c, arena.data(), arena.size() * 8) != ClientStatus::kOk ||
      client.load_startup(spg.data(), spg_startup_bytes(view.header.version, view.header.class_count)) != ClientStatus::kOk)
    std::abort();
  for (uint32_t id : fixed.cut)
    if (client.put_node(NodeId{id}, view.records + size_t{id} * view.record_bytes, view.record_bytes) != ClientStatus::kOk)
      std::abort();
  const size_t stride = size_t{c.raster.width} * bytes_per_pixel(c.raster.format);
  std::vector<uint8_t> frame(stride * c.raster.height);
  FrameStats stats;
  for (auto _ : state) {
    if (client.render(fixed.camera, frame.data(), stride, &stats) != ClientStatus::kOk) std::abort();
    benchmark::DoNotOptimize(frame.data());
  }
  state.counters["discs"] = stats.nodes_close_up;
  state.counters["points"] = stats.points;
}
BENCHMARK(BM_CloseUpFrame)
    ->ArgNames({"view", "large"})
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({2, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Unit(benchmark::kMillisecond);

// The screen-space resolve of a finished frame (raster/resolve.h): the
// coverage of arg 0's share of the pixels (percent) in scattered blobs, at
// 240 x 320 RGB565 (arg 1 = 0) or 640 x 480 RGB888 (1).
void BM_Resolve(benchmark::State& state) {
  const bool large = state.range(1) != 0;
  const uint16_t w = large ? 640 : 240, h = large ? 480 : 320;
  const PixelFormat f = large ? PixelFormat::kRgb888 : PixelFormat::kRgb565;
  std::vector<uint8_t> frame(size_t{w} * h * bytes_per_pixel(f)), coverage(coverage_bytes(w, h), 0);
  std::vector<uint64_t> scratch(resolve_scratch_bytes(w, f) / 8 + 1);
  std::mt19937 rng(3);
  for (uint8_t& b : frame) b = static_cast<uint8_t>(rng());
  // A disc in the middle covering the share, with pinholes.
  const double radius = std::sqrt(static_cast<double>(state.range(0)) / 100.0 * w * h / 3.14159265);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (std::hypot(x - w / 2.0, y - h / 2.0) < radius && rng() % 16 != 0)
        coverage[size_t(y) * coverage_row_bytes(w) + x / 8] |= static_cast<uint8_t>(1u << (x % 8));
  const std::vector<uint8_t> drawn = frame;
  for (auto _ : state) {
    frame = drawn;
    resolve_frame(frame.data(), size_t{w} * bytes_per_pixel(f), f, w, h, coverage.data(), 0, scratch.data());
    benchmark::DoNotOptimize(frame.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t{w} * h);
}
BENCHMARK(BM_Resolve)->Args({30, 0})->Args({30, 1})->Unit(benchmark::kMicrosecond);

// The frame's cost as the fit issue 15 states it — constant + per node x
// nodes + per point x points — so a higher point count per node cannot
// flatter a per-point figure. Twelve frames of BM_ClientFrame's scene (the
// packed cache, the defaults otherwise; arg 0: 0 the default shading, 1 per
// sampled normal with the resolve off, the measurement; arg 1: the
// lanes, as BM_ClientFrame's arg 0): a quarter,
// half or all of the cut's nodes (every 4th, 2nd, each) at quality 0.5, 1, 2
// and 4; each the median of 5 frames; least squares over the twelve.
// Reported in microseconds and nanoseconds (wall clock: run it on a quiet
// core; tools/bench/frame_fit.sh gives the same fit in callgrind counts).
void BM_FrameFit(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  const FrameScene scene(view);
  struct Sample {
    double nodes, points, seconds;
  };
  std::vector<Sample> samples;
  std::vector<uint8_t> frame(640 * 480 * 3);
  for (auto _ : state) {
    samples.clear();
    for (uint32_t every : {4u, 2u, 1u}) {
      for (int quality : {128, 256, 512, 1024}) {
        ClientConfig c;
        c.raster.width = 640;
        c.raster.height = 480;
        c.raster.format = PixelFormat::kRgb888;
        c.raster.max_points = 1u << 22;
        c.lanes = static_cast<PointLanes>(state.range(1));
        c.node_capacity = view.header.node_count;
        c.quality_q8 = static_cast<uint16_t>(quality);
        if (state.range(0) == 1) {
          c.shading = ShadingMode::kPerPoint;
          c.resolve = false;
        }
        std::vector<uint64_t> arena(client_arena_bytes(c) / 8 + 1);
        Client client;
        if (client.init(c, arena.data(), arena.size() * 8) != ClientStatus::kOk ||
            client.load_startup(spg.data(), spg_startup_bytes(view.header.version, view.header.class_count)) !=
                ClientStatus::kOk)
          std::abort();
        for (size_t i = 0; i < scene.cut.size(); i += every)
          if (client.put_node(NodeId{scene.cut[i]}, view.records + size_t{scene.cut[i]} * view.record_bytes,
                              view.record_bytes) != ClientStatus::kOk)
            std::abort();
        FrameStats stats;
        std::vector<double> times;
        for (int r = 0; r < 5; ++r) {
          const auto t0 = std::chrono::steady_clock::now();
          if (client.render(scene.camera, frame.data(), 640 * 3, &stats) != ClientStatus::kOk) std::abort();
          benchmark::DoNotOptimize(frame.data());
          times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        }
        std::sort(times.begin(), times.end());
        samples.push_back({static_cast<double>(stats.nodes_drawn), static_cast<double>(stats.points), times[2]});
      }
    }
  }
  // Normal equations of t = c + a n + b p, solved by Cramer's rule.
  double m[3][3] = {}, v[3] = {};
  for (const Sample& s : samples) {
    const double x[3] = {1, s.nodes, s.points};
    for (int i = 0; i < 3; ++i) {
      v[i] += x[i] * s.seconds;
      for (int j = 0; j < 3; ++j) m[i][j] += x[i] * x[j];
    }
  }
  const auto det = [](const double a[3][3]) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  const double d = det(m);
  double fit[3];
  for (int k = 0; k < 3; ++k) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] = j == k ? v[i] : m[i][j];
    fit[k] = det(a) / d;
  }
  state.counters["const_us"] = fit[0] * 1e6;
  state.counters["ns_per_node"] = fit[1] * 1e9;
  state.counters["ns_per_point"] = fit[2] * 1e9;
}
BENCHMARK(BM_FrameFit)
    ->ArgNames({"issue", "lanes"})
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

#ifdef STIPPLE_BENCH_GL
// The GL client's frame (platform/gl) on whatever EGL offers (Mesa's
// llvmpipe without a GPU) for BM_ClientFrame's cut and camera at 640x480:
// arg 0 = 1 decodes in the vertex shader, 0 on the CPU; arg 1 the picture:
// 0 the default (surface normals, specular, the resolve), 1 EWA splats,
// 2 the picture before them (per-node Lambert, no resolve). The per-node
// counts, the upload, the draws, the passes and glFinish are inside the
// timed loop.
void BM_GlFrame(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  const FrameScene scene(view);
  const Camera& camera = scene.camera;
  const std::vector<uint32_t>& cut = scene.cut;
  NodeCacheLimits limits;
  limits.node_capacity = view.header.node_count;
  std::vector<uint64_t> cache_storage(node_cache_bytes(limits) / 8 + 1);
  NodeCache cache;
  if (cache.init(limits, cache_storage.data(), cache_storage.size() * 8) != CacheStatus::kOk ||
      cache.load_startup(spg.data(), spg_startup_bytes(view.header.version, view.header.class_count)) != CacheStatus::kOk)
    std::abort();
  for (uint32_t id : cut)
    if (cache.put(NodeId{id}, view.records + size_t{id} * view.record_bytes, view.record_bytes) != CacheStatus::kOk) std::abort();
  EglContext egl;
  std::string error;
  if (!egl.open(error)) {
    state.SkipWithError(error.c_str());
    return;
  }
  GlRenderOptions o;
  o.gpu_decode = state.range(0) != 0;
  if (state.range(1) == 1) o.splat = GlSplat::kEwa;
  if (state.range(1) == 2) o.surface_normals = false, o.resolve = false, o.specular = 0;
  GlRenderer renderer;
  GlOffscreen target;
  if (!renderer.init(cache, o, error) || !target.init(640, 480, 0, error)) std::abort();
  target.bind();
  GlFrameStats stats;
  for (auto _ : state) {
    if (!renderer.draw(cache, camera, 640, 480, o, &stats, error)) std::abort();
    gl_finish();
  }
  state.SetLabel(GlRenderer::describe());
  state.counters["nodes"] = stats.nodes;
  state.counters["points"] = static_cast<double>(stats.points);
  state.counters["nodes_per_s"] = benchmark::Counter(stats.nodes, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["points_per_s"] = benchmark::Counter(static_cast<double>(stats.points), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_GlFrame)->Args({1, 0})->Args({0, 0})->Args({1, 1})->Args({1, 2})->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(3)->ReportAggregatesOnly(true);
#endif

// The view-dependent cut's update along a 120-step orbit of the scan at
// 240x320 (arg 0: culling off, 1: on, 2: on and incremental, 3: on, with a
// node budget of a quarter of the budget-free cut, docs/cut.md "Budget"):
// the server's cost per camera update.
void BM_ViewCutUpdate(benchmark::State& state) {
  const SpgView view = parsed_scan();
  std::vector<uint8_t> storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size()) != DecodeStatus::kOk) std::abort();
  std::vector<uint64_t> cut_storage(view_cut_bytes(view.header) / 8 + 1);
  ViewCut cut;
  if (cut.init(view, decoder, cut_storage.data(), cut_storage.size() * 8) != CutStatus::kOk) std::abort();
  std::vector<uint64_t> front;
  if (state.range(0) == 2) {
    front.resize(ViewCut::front_bytes(view.header.node_count) / 8 + 1);
    cut.use_front(front.data(), front.size() * 8);
  }
  std::vector<Camera> cameras(120);
  for (size_t i = 0; i < cameras.size(); ++i) {
    ViewSpec s;
    s.yaw = 30 + 3.0 * static_cast<double>(i);
    if (!orbit_camera(orbit_view(decoder.extent_mu(), s), 240, 320, &cameras[i])) std::abort();
  }
  CutParams p;
  p.cull_frustum = p.cull_backfaces = state.range(0) != 0;
  if (state.range(0) == 3) {
    if (cut.update(cameras[0], p) != CutStatus::kOk) std::abort();
    p.max_nodes = cut.sent_count() / 4;
  }
  size_t i = 0;
  double nodes = 0;
  for (auto _ : state) {
    if (cut.update(cameras[i++ % cameras.size()], p) != CutStatus::kOk) std::abort();
    nodes += cut.cut_count();
  }
  state.counters["cut_nodes"] = nodes / static_cast<double>(state.iterations());
  state.counters["ns_per_cut_node"] =
      benchmark::Counter(nodes, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ViewCutUpdate)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

// Time to the first image, to a whole silhouette (90 % of the converged
// one's pixels) and to the converged view over an emulated link
// (platform/shaper, simulated clock: the figures are link time, not CPU
// time), then a 12-step orbit of 30-degree steps and one of 3-degree steps.
// Args: the link (0 115,200-baud serial, 1 USB 1.1, 2 802.11b), the screen
// (0 240x320, 1 640x480). The scan: STIPPLE_BENCH_SCAN or the dragon.
void BM_LinkTime(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  std::vector<uint8_t> storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size()) != DecodeStatus::kOk) std::abort();
  const bool vga = state.range(1) == 1;
  const uint16_t w = vga ? 640 : 240, h = vga ? 480 : 320;
  const auto orbit = [&](double step, size_t n) {
    std::vector<Camera> cameras(n);
    for (size_t i = 0; i < cameras.size(); ++i) {
      ViewSpec s;
      s.yaw = 30 + step * static_cast<double>(i);
      if (!orbit_camera(orbit_view(decoder.extent_mu(), s), w, h, &cameras[i])) std::abort();
    }
    return cameras;
  };
  const LinkProfile links[] = {kSerial115200, kUsb11, k80211b};
  const LinkProfile link = links[state.range(0)];
  ClientConfig c;
  c.raster = RasterConfig{w, h, 5, PixelFormat::kRgb565, vga ? 600000u : 200000u};
  c.node_capacity = 60000;
  LinkTiming t, fine;
  std::string error;
  for (auto _ : state)
    if (!time_over_link(spg, link, link, c, orbit(30, 13), t, error, state.range(2) == 1) ||
        !time_over_link(spg, link, link, c, orbit(3, 13), fine, error, state.range(2) == 1))
      state.SkipWithError(error.c_str());
  state.counters["first_image_s"] = t.first_image_s;
  state.counters["silhouette90_s"] = t.silhouette_s;
  state.counters["converged_s"] = t.converged_s;
  state.counters["converged_bytes"] = static_cast<double>(t.converged_bytes);
  state.counters["orbit30_step_s"] = t.orbit_step_s;
  state.counters["orbit30_step_bytes"] = t.orbit_step_bytes;
  state.counters["orbit3_step_bytes"] = fine.orbit_step_bytes;
  state.counters["cut_nodes"] = t.cut_nodes;
}
BENCHMARK(BM_LinkTime)
    ->Args({0, 0, 1})->Args({2, 0, 1})->Args({0, 1, 1})->Args({2, 1, 1})->Args({1, 0, 1})
    ->Args({0, 0, 0})->Args({0, 1, 0})
    ->Unit(benchmark::kMillisecond)->Iterations(1);

// Split deltas (protocol 5's coded batches): a 240x320 client with a
// 60,000-node cache follows a 60-step orbit of 3-degree steps, its entering
// nodes sent with splits (arg 1) or each child as a node (arg 0). Counters:
// bytes a step, splits a step (a node's two children against it), and, with
// splits, the bytes a refinement saves against the run without.
void BM_SplitDeltas(benchmark::State& state) {
  const SpgView view = parsed_scan();
  std::vector<uint32_t> decoder_storage(node_decoder_bytes(view.header) / 4 + 1);
  NodeDecoder decoder;
  std::vector<uint64_t> bounds_storage(CutBounds::bytes(view.header) / 8 + 1);
  CutBounds bounds;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size() * 4) != DecodeStatus::kOk ||
      bounds.init(view, decoder, bounds_storage.data(), bounds_storage.size() * 8) != CutStatus::kOk)
    std::abort();
  const auto run = [&](bool splits, double* step_bytes, double* step_splits) {
    std::vector<uint64_t> storage(StreamSender::storage_bytes(view.header) / 8 + 1);
    StreamSender sender;
    if (!sender.init(view, bounds, storage.data(), storage.size() * 8)) std::abort();
    sender.use_split_deltas(splits);
    uint64_t bytes = 0;
    const FrameSink sink = [](void* total, const uint8_t*, size_t size) {
      *static_cast<uint64_t*>(total) += size;
      return true;
    };
    Hello hello;
    hello.cache_capacity = 60000;
    hello.attributes |= kWantCoded;
    if (!sender.start(hello, sink, &bytes)) std::abort();
    uint64_t cold = 0, cold_splits = 0;
    for (uint32_t step = 0; step <= 60; ++step) {
      ViewSpec s;
      s.yaw = 30 + 3.0 * step;
      CameraUpdate u;
      u.sequence = step;
      if (!orbit_camera(orbit_view(decoder.extent_mu(), s), 240, 320, &u.camera) || !sender.update(u, true, sink, &bytes))
        std::abort();
      if (step == 0) {
        cold = bytes;
        cold_splits = sender.splits_sent();
      }
    }
    *step_bytes = static_cast<double>(bytes - cold) / 60;
    *step_splits = static_cast<double>(sender.splits_sent() - cold_splits) / 60;
  };
  double bytes = 0, splits = 0, without = 0, none = 0;
  for (auto _ : state) {
    run(state.range(0) == 1, &bytes, &splits);
    if (state.range(0) == 1) run(false, &without, &none);
  }
  state.counters["step_bytes"] = bytes;
  state.counters["step_splits"] = splits;
  if (state.range(0) == 1) {
    state.counters["step_bytes_without"] = without;
    state.counters["saved_per_split"] = splits > 0 ? (without - bytes) / splits : 0;
  }
}
BENCHMARK(BM_SplitDeltas)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

// One server core, N loopback clients each sending a camera per round (a
// 120-step orbit each, staggered) and draining what comes back unread: the
// server's cost per camera update. Counter: updates per second. Args: N,
// and 1 for clients asking for coded batches (protocol 5), 0 for compact.
void BM_ServerClients(benchmark::State& state) {
  const std::vector<uint8_t>& spg = encoded_scan();
  const SpgView view = parsed_scan();
  std::vector<uint8_t> storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, storage.data(), storage.size()) != DecodeStatus::kOk) std::abort();
  std::vector<Camera> cameras(120);
  for (size_t i = 0; i < cameras.size(); ++i) {
    ViewSpec s;
    s.yaw = 3.0 * static_cast<double>(i);
    if (!orbit_camera(orbit_view(decoder.extent_mu(), s), 240, 320, &cameras[i])) std::abort();
  }
  const int n = static_cast<int>(state.range(0));
  Server server;
  std::string error;
  if (!server.init(spg, "model", ServerOptions{}, error)) std::abort();
  std::vector<std::unique_ptr<LoopbackPipe>> pipes;
  std::vector<uint16_t> seq(static_cast<size_t>(n), 0);
  uint8_t payload[kCameraUpdateBytes], frame[256], sink[65536];
  const auto send = [&](int k, MessageType type, size_t size) {
    const size_t len = write_frame(type, seq[static_cast<size_t>(k)]++, payload, size, frame, sizeof frame);
    size_t moved = 0;
    (void)pipes[static_cast<size_t>(k)]->client().write(frame, len, &moved);
  };
  const auto drain = [&] {
    for (auto& p : pipes) {
      size_t got = 0;
      while (p->client().read(sink, sizeof sink, &got) == TransportStatus::kOk && got > 0) {
      }
    }
  };
  for (int k = 0; k < n; ++k) {
    pipes.push_back(std::make_unique<LoopbackPipe>(1 << 22));
    server.add_client(std::make_unique<TransportRef>(pipes.back()->server()), -1, "bench");
    Hello hello;
    if (state.range(1) == 1) hello.attributes |= kWantCoded;
    write_hello(hello, payload);
    send(k, MessageType::kHello, kHelloBytes);
  }
  server.step(0);
  drain();
  size_t round = 0;
  const auto one_round = [&] {
    for (int k = 0; k < n; ++k) {
      CameraUpdate u;
      u.sequence = static_cast<uint32_t>(round);
      u.camera = cameras[(round + static_cast<size_t>(k) * 7) % cameras.size()];
      write_camera_update(u, payload);
      send(k, MessageType::kCamera, kCameraUpdateBytes);
    }
    server.step(0);
    drain();
    ++round;
  };
  one_round();  // the cold start (every client's whole first cut) is not the steady state
  for (auto _ : state) one_round();
  state.counters["updates_per_s"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ServerClients)->Args({64, 0})->Args({64, 1})->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_KdNearest(benchmark::State& state) {
  const PointCloud& c = scan();
  const KdTree tree(c.positions);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(tree.nearest(c.positions[i] + Vec3(1e-4, -1e-4, 1e-4)));
    i = (i + 7919) % c.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KdNearest);

// Normal estimation (k-NN, PCA, orientation) over N coincident points: the
// case that went quadratic on distance ties (issue 10).
void BM_NormalsCoincident(benchmark::State& state) {
  for (auto _ : state) {
    PointCloud c;
    c.positions.assign(static_cast<size_t>(state.range(0)), Vec3(1e7, 1e7, 5.0));
    estimate_normals(c, 12);
    benchmark::DoNotOptimize(c.normals.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_NormalsCoincident)->Arg(200000)->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3);

void BM_PlyParse(benchmark::State& state) {
  std::vector<uint8_t> bytes;
  std::string error;
  if (!read_file(scan_path(), bytes, error)) state.SkipWithError(error.c_str());
  for (auto _ : state) {
    PointCloud c;
    benchmark::DoNotOptimize(parse_point_cloud("scan", bytes.data(), bytes.size(), c, error));
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(bytes.size()));
}
BENCHMARK(BM_PlyParse)->Unit(benchmark::kMillisecond);

// Every reader on the scan's points (positions and normals, as float32),
// rewritten in memory in its format: 0 PCD ascii, 1 PCD binary, 2 PCD
// binary_compressed, 3 LAS 1.4 format 6 (mm scale, a 1e6 offset), 4 text
// x y z nx ny nz. Throughput is of the bytes parsed.
std::vector<uint8_t> scan_as(int format) {
  const PointCloud& c = scan();
  const size_t n = c.size();
  std::vector<uint8_t> out;
  const auto text = [&](const std::string& s) { out.insert(out.end(), s.begin(), s.end()); };
  const auto f32 = [&](double v) {
    const float f = static_cast<float>(v);
    uint8_t b[4];
    std::memcpy(b, &f, 4);
    out.insert(out.end(), b, b + 4);
  };
  char line[160];
  if (format <= 2) {
    text("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
         "COUNT 1 1 1 1 1 1\nWIDTH " + std::to_string(n) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) +
         "\nDATA " + (format == 0 ? "ascii" : format == 1 ? "binary" : "binary_compressed") + "\n");
    if (format == 0) {
      for (size_t i = 0; i < n; ++i) {
        const Vec3 &p = c.positions[i], &q = c.normals[i];
        std::snprintf(line, sizeof line, "%.7g %.7g %.7g %.7g %.7g %.7g\n", p.x(), p.y(), p.z(), q.x(), q.y(), q.z());
        text(line);
      }
    } else {
      std::vector<uint8_t> body;
      std::swap(out, body);
      for (int k = 0; k < 6; ++k)  // fields one after another (compressed), or records (binary) below
        for (size_t i = 0; i < (format == 2 ? n : 0); ++i) f32(k < 3 ? c.positions[i][k] : c.normals[i][k - 3]);
      for (size_t i = 0; i < (format == 1 ? n : 0); ++i)
        for (int k = 0; k < 6; ++k) f32(k < 3 ? c.positions[i][k] : c.normals[i][k - 3]);
      std::swap(out, body);
      if (format == 1) {
        out.insert(out.end(), body.begin(), body.end());
      } else {
        std::vector<uint8_t> packed(body.size() + body.size() / 16 + 64);
        const unsigned m = lzf_compress(body.data(), static_cast<unsigned>(body.size()), packed.data(), static_cast<unsigned>(packed.size()));
        const uint32_t sizes[2] = {m, static_cast<uint32_t>(body.size())};
        out.insert(out.end(), reinterpret_cast<const uint8_t*>(sizes), reinterpret_cast<const uint8_t*>(sizes) + 8);
        out.insert(out.end(), packed.begin(), packed.begin() + m);
      }
    }
  } else if (format == 3) {
    out.assign(375, 0);
    std::memcpy(out.data(), "LASF", 4);
    out[24] = 1, out[25] = 4, out[94] = 375 & 255, out[95] = 375 >> 8, out[96] = 375 & 255, out[97] = 375 >> 8;
    out[104] = 6, out[105] = 30;
    const double scale[3] = {1e-6, 1e-6, 1e-6}, offset[3] = {1e6, 1e6, 0};
    const uint64_t count = n;
    std::memcpy(&out[131], scale, 24);
    std::memcpy(&out[155], offset, 24);
    std::memcpy(&out[247], &count, 8);
    for (size_t i = 0; i < n; ++i) {
      uint8_t r[30] = {};
      for (int k = 0; k < 3; ++k) {
        const int32_t v = static_cast<int32_t>(std::llround(c.positions[i][k] / 1e-6));
        std::memcpy(r + 4 * k, &v, 4);
      }
      out.insert(out.end(), r, r + 30);
    }
  } else {
    for (size_t i = 0; i < n; ++i) {
      const Vec3 &p = c.positions[i], &q = c.normals[i];
      std::snprintf(line, sizeof line, "%.7g %.7g %.7g %.7g %.7g %.7g\n", p.x(), p.y(), p.z(), q.x(), q.y(), q.z());
      text(line);
    }
  }
  return out;
}

void BM_ReadScan(benchmark::State& state) {
  const std::vector<uint8_t> bytes = scan_as(static_cast<int>(state.range(0)));
  std::string error;
  for (auto _ : state) {
    PointCloud c;
    if (!parse_point_cloud("scan", bytes.data(), bytes.size(), c, error)) state.SkipWithError(error.c_str());
    benchmark::DoNotOptimize(c.positions.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(bytes.size()));
  state.counters["points"] = static_cast<double>(scan().size());
}
BENCHMARK(BM_ReadScan)->DenseRange(0, 4)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace stipple

BENCHMARK_MAIN();
