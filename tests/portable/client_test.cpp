// The handheld client's API (raster/client.h): arena sizing, startup and
// record validation, the node cache, and what it draws — against the double
// reference renderer (tests/render_reference_test.cpp) and against itself
// under cache churn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <set>
#include <vector>

#include "core/cut.h"
#include "core/fixed_trig.h"
#include "raster/client.h"
#include "raster/point_kernel_avx2.h"
#include "raster/projection.h"
#include "tests/portable/test_files.h"

namespace stipple {
namespace {

struct Model {
  std::vector<uint8_t> file;
  SpgView view;
  size_t startup_bytes = 0;
};

Model read_model(const char* file) {
  Model out;
  out.file = test::fixture(file);
  EXPECT_TRUE(spg_parse(out.file.data(), out.file.size(), &out.view).ok());
  out.startup_bytes = spg_startup_bytes(out.view.header.version, out.view.header.class_count);
  return out;
}

const Model& bunny() {
  static const Model m = read_model("tests/golden/bunny_v1.spg");
  return m;
}

const Model& bunny_v2() {
  static const Model m = read_model("tests/golden/bunny_v2.spg");
  return m;
}

ClientConfig small_config(uint32_t capacity = 8000) {
  ClientConfig c;
  c.raster = RasterConfig{240, 320, 5, PixelFormat::kRgb565, 200000};
  c.node_capacity = capacity;
  return c;
}

struct Harness {
  std::vector<uint64_t> arena;
  Client client;
  explicit Harness(const ClientConfig& c) : arena(client_arena_bytes(c) / 8 + 1) {
    EXPECT_EQ(client.init(c, arena.data(), arena.size() * 8), ClientStatus::kOk);
  }
};

const uint8_t* record(uint32_t id) { return bunny().view.records + static_cast<size_t>(id) * bunny().view.record_bytes; }

Camera camera_for(const Client& client, double yaw, double pitch, uint16_t w = 240, uint16_t h = 320) {
  Camera cam;
  EXPECT_TRUE(orbit_camera(test::orbit(client.decoder().extent_mu(), yaw, pitch), w, h, &cam));
  return cam;
}

std::vector<uint8_t> draw(Client& client, const Camera& cam, FrameStats* stats = nullptr) {
  std::vector<uint8_t> frame(240 * 320 * 2, 0xAB);
  EXPECT_EQ(client.render(cam, frame.data(), 240 * 2, stats), ClientStatus::kOk);
  return frame;
}

TEST(Client, ArenaSizeIsExactAndChecked) {
  const ClientConfig c = small_config();
  const size_t need = client_arena_bytes(c);
  ASSERT_GT(need, 0u);
  std::vector<uint64_t> arena(need / 8);
  Client client;
  EXPECT_EQ(client.init(c, arena.data(), need - 1), ClientStatus::kArenaTooSmall);
  EXPECT_EQ(client.init(c, arena.data(), need), ClientStatus::kOk);
  ClientConfig bad = c;
  bad.point_size = 4;
  EXPECT_EQ(client_arena_bytes(bad), 0u);
  EXPECT_EQ(client.init(bad, arena.data(), need), ClientStatus::kBadConfig);
  bad = c;
  bad.lighting.light_q14[0] = bad.lighting.light_q14[1] = bad.lighting.light_q14[2] = 0;
  EXPECT_EQ(client.init(bad, arena.data(), need), ClientStatus::kBadConfig);
  bad = c;
  bad.raster.width = 0;
  EXPECT_EQ(client_arena_bytes(bad), 0u);
}

TEST(Client, HandheldArenaAt240x320With30KNodes) {
  // The configuration docs/fixed_point.md reports: normals, no colour (the
  // bunny and dragon scans), 30 K cached nodes, a 60 K-point frame budget.
  // The raster's default tiles and the handheld's tile pass (kHandheldTileNodes).
  ClientConfig c;
  c.tile_nodes = kHandheldTileNodes;
  c.lanes = PointLanes::kBaseline;  // the device's (no x86 node-lane tables)
  c.raster = RasterConfig{};
  c.raster.width = 240;
  c.raster.height = 320;
  c.raster.format = PixelFormat::kRgb565;
  c.raster.max_points = 60000;
  c.node_capacity = 30000;
  c.color = false;
  const size_t bytes = client_arena_bytes(c);
  c.color = true;
  const size_t with_color = client_arena_bytes(c);
  std::printf("arena at 240x320, 30,000 nodes, 60,000 points: %zu bytes (%zu with colour)\n", bytes, with_color);
  EXPECT_LE(bytes, 2u << 20);
  EXPECT_LE(with_color, 2u << 20);
}

TEST(Client, RefusesWorkBeforeStartupAndBadStartups) {
  Harness h(small_config());
  Camera cam{};
  std::vector<uint8_t> frame(240 * 320 * 2);
  EXPECT_EQ(h.client.put_node(NodeId{0}, record(0), bunny().view.record_bytes), ClientStatus::kNoStartup);
  EXPECT_EQ(h.client.drop_node(NodeId{0}), ClientStatus::kNoStartup);
  EXPECT_EQ(h.client.render(cam, frame.data(), 480), ClientStatus::kNoStartup);

  std::vector<uint8_t> startup(bunny().file.begin(), bunny().file.begin() + static_cast<long>(bunny().startup_bytes));
  // Truncated inside the class tables.
  EXPECT_EQ(h.client.load_startup(startup.data(), startup.size() - 1), ClientStatus::kBadStartup);
  EXPECT_EQ(h.client.startup_error().error, SpgError::kTruncated);
  // A NaN in the sigma_p table: the error names its byte.
  std::vector<uint8_t> nan = startup;
  const size_t at = kSpgFixedHeaderBytes + 4;
  nan[at] = 0x00, nan[at + 1] = 0x00, nan[at + 2] = 0xC0, nan[at + 3] = 0x7F;
  EXPECT_EQ(h.client.load_startup(nan.data(), nan.size()), ClientStatus::kBadStartup);
  EXPECT_EQ(h.client.startup_error().error, SpgError::kBadFloat);
  EXPECT_EQ(h.client.startup_error().offset, at);
  // More classes than the arena was sized for.
  ClientConfig tight = small_config();
  tight.max_classes[0] = 16;
  Harness t(tight);
  EXPECT_EQ(t.client.load_startup(startup.data(), startup.size()), ClientStatus::kStartupTooLarge);
  // Normals the configuration does not accept.
  ClientConfig bare = small_config();
  bare.normals = false;
  Harness b(bare);
  EXPECT_EQ(b.client.load_startup(startup.data(), startup.size()), ClientStatus::kStartupTooLarge);
  // The good one, from a copy that then goes away.
  {
    std::vector<uint8_t> copy = startup;
    EXPECT_EQ(h.client.load_startup(copy.data(), copy.size()), ClientStatus::kOk);
  }
  EXPECT_EQ(h.client.record_bytes(), bunny().view.record_bytes);
  EXPECT_EQ(h.client.put_node(NodeId{0}, record(0), bunny().view.record_bytes), ClientStatus::kOk);
}

TEST(Client, ValidatesRecordsAndCacheBounds) {
  Harness h(small_config(4));
  ASSERT_EQ(h.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  const size_t rb = bunny().view.record_bytes;
  EXPECT_EQ(h.client.put_node(NodeId{1}, record(1), rb - 1), ClientStatus::kBadRecordSize);
  // A sigma_p class index beyond the table: all ones in the record's class field.
  std::vector<uint8_t> bad(record(1), record(1) + rb);
  const RecordLayout& l = bunny().view.header.layout;
  NodeFields f = unpack_record(l, bad.data());
  f.v[static_cast<int>(Field::kSigmaP)] = static_cast<uint16_t>((1u << l.width(Field::kSigmaP)) - 1);
  ASSERT_GE(f[Field::kSigmaP], bunny().view.header.class_count[0]);
  pack_record(l, f, bad.data());
  EXPECT_EQ(h.client.put_node(NodeId{1}, bad.data(), rb), ClientStatus::kBadRecord);
  EXPECT_FALSE(h.client.has_node(NodeId{1}));
  for (uint32_t id = 0; id < 4; ++id) EXPECT_EQ(h.client.put_node(NodeId{id * 1000}, record(id), rb), ClientStatus::kOk);
  EXPECT_EQ(h.client.put_node(NodeId{7}, record(7), rb), ClientStatus::kCacheFull);
  EXPECT_EQ(h.client.put_node(NodeId{2000}, record(9), rb), ClientStatus::kOk);  // replacing is not adding
  EXPECT_EQ(h.client.node_count(), 4u);
  EXPECT_EQ(h.client.drop_node(NodeId{5}), ClientStatus::kUnknownNode);
  EXPECT_EQ(h.client.drop_node(NodeId{0}), ClientStatus::kOk);
  EXPECT_EQ(h.client.drop_node(NodeId{0}), ClientStatus::kUnknownNode);
  EXPECT_EQ(h.client.put_node(NodeId{7}, record(7), rb), ClientStatus::kOk);
  Camera cam{};
  std::vector<uint8_t> frame(240 * 320 * 2);
  EXPECT_EQ(h.client.render(cam, frame.data(), 480), ClientStatus::kBadCamera);
}

// The cache is a set: any order of puts and drops that ends with the same
// nodes draws the same frame as loading those nodes fresh.
TEST(Client, FrameDependsOnlyOnTheCachedSet) {
  const uint32_t n = bunny().view.header.node_count;
  const size_t rb = bunny().view.record_bytes;
  ClientConfig c = small_config(n);
  c.raster.max_points = 1u << 21;  // no point dropped: the budget would make the frame order-dependent
  Harness churn(c), fresh(c);
  ASSERT_EQ(churn.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  ASSERT_EQ(fresh.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  std::mt19937 rng(7);
  std::vector<bool> held(n, false);
  for (int step = 0; step < 60000; ++step) {
    const uint32_t id = static_cast<uint32_t>(rng() % n);
    if (held[id] && rng() % 2) {
      ASSERT_EQ(churn.client.drop_node(NodeId{id}), ClientStatus::kOk);
      held[id] = false;
    } else {
      ASSERT_EQ(churn.client.put_node(NodeId{id}, record(id), rb), ClientStatus::kOk);
      held[id] = true;
    }
  }
  uint32_t count = 0;
  for (uint32_t id = 0; id < n; ++id) {
    EXPECT_EQ(churn.client.has_node(NodeId{id}), static_cast<bool>(held[id])) << id;
    if (held[id]) {
      ++count;
      ASSERT_EQ(fresh.client.put_node(NodeId{id}, record(id), rb), ClientStatus::kOk);
    }
  }
  EXPECT_EQ(churn.client.node_count(), count);
  const Camera cam = camera_for(fresh.client, 30, 20);
  FrameStats a, b;
  EXPECT_EQ(draw(churn.client, cam, &a), draw(fresh.client, cam, &b));
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.points_dropped, 0u);
  EXPECT_GT(a.points, 10000u);
}

// EWA splats (raster/ewa.h) colour the pixels the points cover and no
// other: the same background, pixel for pixel, as the points' frame, and
// the same bytes on every target (integer throughout; the frames' CRC-32s
// are the host's). A splat whose mean normal faces away is none.
TEST(Client, EwaSplatsColourWhatThePointsCoverTheSameOnEveryTarget) {
  const Model& m = bunny_v2();
  const uint32_t n = m.view.header.node_count;
  ClientConfig c = small_config(n);
  c.raster.max_points = 1u << 21;
  ClientConfig e = c;
  e.ewa = true;
  Harness points(c), splats(e);
  ASSERT_EQ(points.client.load_startup(m.file.data(), m.startup_bytes), ClientStatus::kOk);
  ASSERT_EQ(splats.client.load_startup(m.file.data(), m.startup_bytes), ClientStatus::kOk);
  for (uint32_t id = 0; id < n; ++id) {
    if (spg_child_count(m.view, id) != 0) continue;  // the leaves
    const uint8_t* r = m.view.records + size_t{id} * m.view.record_bytes;
    ASSERT_EQ(points.client.put_node(NodeId{id}, r, m.view.record_bytes), ClientStatus::kOk);
    ASSERT_EQ(splats.client.put_node(NodeId{id}, r, m.view.record_bytes), ClientStatus::kOk);
  }
  const struct {
    double yaw, pitch;
    uint32_t crc;
  } views[] = {{30, 20, 0xdb7e080fu}, {200, -10, 0xe6bbc435u}};
  for (const auto& v : views) {
    const Camera cam = camera_for(splats.client, v.yaw, v.pitch);
    FrameStats ps, es;
    const std::vector<uint8_t> p = draw(points.client, cam, &ps), f = draw(splats.client, cam, &es);
    size_t covered = 0, recoloured = 0;
    for (size_t i = 0; i < p.size(); i += 2) {
      const bool p_bg = p[i] == 0 && p[i + 1] == 0, f_bg = f[i] == 0 && f[i + 1] == 0;
      ASSERT_EQ(p_bg, f_bg) << "pixel " << i / 2;
      covered += !p_bg;
      recoloured += !p_bg && (p[i] != f[i] || p[i + 1] != f[i + 1]);
    }
    const uint32_t crc = crc32(f.data(), f.size());
    std::printf("yaw %.0f: %u splats of %u nodes drawn, %zu of %zu covered pixels recoloured, frame crc32 %08x\n", v.yaw,
                es.splats, es.nodes_drawn, recoloured, covered, crc);
    EXPECT_EQ(ps.splats, 0u);
    EXPECT_GT(es.splats, es.nodes_drawn / 3);  // about half the leaves face the eye
    EXPECT_LT(es.splats, es.nodes_drawn);
    EXPECT_GT(recoloured, covered / 2);
    EXPECT_EQ(crc, v.crc);
  }
}

TEST(Client, DrawsNothingBehindTheCameraAndCountsCulls) {
  const uint32_t n = bunny().view.header.node_count;
  Harness h(small_config(n));
  ASSERT_EQ(h.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  for (uint32_t id = 0; id < n; ++id) ASSERT_EQ(h.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes), ClientStatus::kOk);
  Camera cam = camera_for(h.client, 0, 0);
  // Turn the camera around: the model is behind it.
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 2; ++r) cam.rotation[r == 0 ? 0 : 2][k] = -cam.rotation[r == 0 ? 0 : 2][k];
  FrameStats stats;
  const std::vector<uint8_t> frame = draw(h.client, cam, &stats);
  EXPECT_EQ(stats.points, 0u);
  EXPECT_EQ(stats.nodes_culled, n);
  EXPECT_TRUE(std::all_of(frame.begin(), frame.end(), [](uint8_t v) { return v == 0; }));  // cleared to black
}

// The frame's mean table, built where the cut repays it, gives draw_node
// the terms it would form itself: a few nodes (below the table's threshold)
// draw the frame they draw beside enough nodes behind the camera to pass
// it, in each projection, with and without SIMD point lanes.
TEST(Client, MeanTableGivesTheTermsDrawNodeForms) {
  const SpgView& v = bunny().view;
  const uint32_t n = v.header.node_count;
  constexpr uint32_t kFew = 300;
  for (Projection projection : {Projection::kAffine, Projection::kExact})
    for (PointLanes lanes : {PointLanes::kBaseline, PointLanes::kScalar}) {
      ClientConfig c = small_config(n);
      c.raster.max_points = 1u << 21;  // no point dropped
      c.projection = projection;
      c.lanes = lanes;  // not the x86 node lanes, which always read the table
      c.close_ups = false;  // the nodes behind the eye culled by their means, none drawn as the discs they reach
      Harness few(c), many(c);
      ASSERT_EQ(few.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
      ASSERT_EQ(many.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
      // The eye at the model's centre, looking as the orbit camera does: the
      // nodes behind it are culled by their camera-space mean (in_view).
      Camera cam = camera_for(few.client, 30, 20);
      const int32_t* extent = few.client.decoder().extent_mu();
      for (int k = 0; k < 3; ++k) cam.eye[k] = extent[k] / 2;
      cam.near_mu = kCameraMinDistance;
      const auto behind = [&](uint32_t id) {
        const NodeFields f = unpack_record(v.header.layout, record(id));
        int32_t m[3] = {0, 0, 0};
        for (int i = 0; i < 3; ++i)
          for (int a = 0; a < 3; ++a) m[i] += mul_q14(cam.rotation[i][a], few.client.decoder().mean_axis_mu(a, f.v[a]) - cam.eye[a]);
        return !NodeProjection::in_view(cam, m);
      };
      for (uint32_t id = 0; id < kFew; ++id) {
        ASSERT_EQ(few.client.put_node(NodeId{id}, record(id), v.record_bytes), ClientStatus::kOk);
        ASSERT_EQ(many.client.put_node(NodeId{id}, record(id), v.record_bytes), ClientStatus::kOk);
      }
      uint32_t hidden = 0;
      for (uint32_t id = kFew; id < n; ++id)
        if (behind(id)) {
          ASSERT_EQ(many.client.put_node(NodeId{id}, record(id), v.record_bytes), ClientStatus::kOk);
          ++hidden;
        }
      FrameStats a, b;
      EXPECT_EQ(draw(few.client, cam, &a), draw(many.client, cam, &b));
      EXPECT_FALSE(a.mean_table);
      EXPECT_TRUE(b.mean_table);
      EXPECT_EQ(a.points, b.points);
      EXPECT_EQ(b.nodes_culled, a.nodes_culled + hidden);
      EXPECT_GT(a.points, 1000u);
    }
}

// The tile pass (RendererConfig::tile_nodes: a node inside one tile has its
// points generated straight into that tile's words) draws exactly the
// picture of the bins, byte for byte and point for point: both pixel
// formats, every point size, every shading, per-point colour, supersampling,
// the resolve, and a tile pass past the rows it owns (lent by the bins). Models: the bunny (every node of its tree held, so large nodes
// spanning many tiles are drawn beside small ones) and the coloured sphere.
TEST(Client, TilePassDrawsTheBinsPicture) {
  struct Case {
    const char* model;
    PixelFormat format;
    uint8_t point_size;
    ShadingMode shading;
    uint8_t supersample;
    bool resolve;
    uint32_t tile_nodes;
    double distance = 3;  // model extents: the sphere's 600 points make large nodes, seen from far to be small
  };
  const Case cases[] = {
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 2, ShadingMode::kSurface, 1, true, 1u << 16},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 1, ShadingMode::kPerPoint, 1, false, 1u << 16},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 3, ShadingMode::kPerNode, 4, true, 1u << 16},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 2, ShadingMode::kNone, 1, false, 300},  // rows lent
      {"tests/data/sphere600_colour.spg", PixelFormat::kRgb888, 2, ShadingMode::kSurface, 1, true, 1u << 16, 12},
      {"tests/data/sphere600_colour.spg", PixelFormat::kRgb565, 1, ShadingMode::kPerPoint, 2, false, 50, 12},
  };
  for (const Case& k : cases) {
    const std::vector<uint8_t> file = test::fixture(k.model);
    SpgView view;
    ASSERT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
    std::vector<uint8_t> frames[2];
    FrameStats stats[2];
    for (int pass = 0; pass < 2; ++pass) {
      ClientConfig c = small_config(view.header.node_count);
      c.raster.format = k.format;
      c.point_size = k.point_size;
      c.shading = k.shading;
      c.supersample = k.supersample;
      c.resolve = k.resolve;
      c.tile_nodes = pass == 0 ? 0 : k.tile_nodes;
      c.raster.max_points = 1u << 21;
      c.quality_q8 = 64;  // every node of the tree at a quarter of its points: none dropped
      Harness h(c);
      ASSERT_EQ(h.client.load_startup(file.data(), spg_startup_bytes(view.header.version, view.header.class_count)),
                ClientStatus::kOk);
      for (uint32_t id = 0; id < view.header.node_count; ++id)
        ASSERT_EQ(h.client.put_node(NodeId{id}, view.records + size_t{id} * view.record_bytes, view.record_bytes),
                  ClientStatus::kOk);
      Camera cam;
      ASSERT_TRUE(orbit_camera(test::orbit(h.client.decoder().extent_mu(), 40, 15, k.distance), 240, 320, &cam));
      frames[pass].assign(240 * 320 * 3, 0xAB);
      ASSERT_EQ(h.client.render(cam, frames[pass].data(), 240 * 3, &stats[pass]), ClientStatus::kOk);
    }
    EXPECT_EQ(frames[0], frames[1]) << k.model << " " << int(k.point_size) << " px, tile_nodes " << k.tile_nodes;
    EXPECT_EQ(stats[0].points, stats[1].points);
    EXPECT_EQ(stats[0].nodes_drawn, stats[1].nodes_drawn);
    EXPECT_EQ(stats[0].points_dropped, 0u);
    EXPECT_EQ(stats[1].points_dropped, 0u);
    EXPECT_GT(stats[0].points, 500u);
    EXPECT_EQ(stats[0].nodes_in_tiles, 0u);
    EXPECT_GT(stats[1].nodes_in_tiles, 0u) << k.model << " " << int(k.supersample);  // the tile pass was taken
    EXPECT_LT(stats[1].nodes_in_tiles, stats[1].nodes_drawn);  // and the bins too
    if (k.tile_nodes < 1000) {  // more than the rows owned: the bins lend the tile nodes their points' share
      EXPECT_GT(stats[1].nodes_in_tiles, k.tile_nodes) << k.model;
    }
  }
}

// The SIMD lanes (PointLanes::kBest: AVX2 where this CPU has it — the
// per-node set-up 8 nodes at a time and the point loop; kBaseline: SSE2 or
// NEON point loops) draw the picture of the scalar loops, byte for byte
// and count for count: every shading, per-point colour, both formats, 1-3
// px, supersampling and the resolve; cameras far, near and inside the
// model (nodes the node lanes leave to the scalar set-up); a tile pass
// that fills, a budget that fills, and the unpacked cache.
// One picture drawn by each of the lanes (scalar, baseline, best) from the
// same startup and records, for the orbit `view` gives for the client.
struct LaneFrames {
  std::vector<uint8_t> frames[3];
  FrameStats stats[3];
};
template <class View>
void draw_in_each_lanes(const std::vector<uint8_t>& file, const SpgView& spg, const uint8_t* records,
                        const ClientConfig& config, View view, LaneFrames* out) {
  const PointLanes lanes[3] = {PointLanes::kScalar, PointLanes::kBaseline, PointLanes::kBest};
  for (int l = 0; l < 3; ++l) {
    ClientConfig c = config;
    c.lanes = lanes[l];
    Harness h(c);
    ASSERT_EQ(h.client.load_startup(file.data(), spg_startup_bytes(spg.header.version, spg.header.class_count)),
              ClientStatus::kOk);
    for (uint32_t id = 0; id < spg.header.node_count; ++id)
      ASSERT_EQ(h.client.put_node(NodeId{id}, records + size_t{id} * spg.record_bytes, spg.record_bytes),
                ClientStatus::kOk);
    Camera cam;
    ASSERT_TRUE(orbit_camera(view(h.client), 240, 320, &cam));
    out->frames[l].assign(240 * 320 * 3, 0xAB);
    ASSERT_EQ(h.client.render(cam, out->frames[l].data(), 240 * 3, &out->stats[l]), ClientStatus::kOk);
  }
  EXPECT_EQ(out->stats[0].nodes_in_lanes, 0u);
  EXPECT_EQ(out->stats[1].nodes_in_lanes, 0u);
  for (int l = 1; l < 3; ++l) {
    EXPECT_EQ(out->frames[0], out->frames[l]) << "lanes " << l;
    const FrameStats &a = out->stats[0], &b = out->stats[l];
    EXPECT_EQ(a.points, b.points) << l;
    EXPECT_EQ(a.points_dropped, b.points_dropped) << l;
    EXPECT_EQ(a.nodes_drawn, b.nodes_drawn) << l;
    EXPECT_EQ(a.nodes_culled, b.nodes_culled) << l;
    EXPECT_EQ(a.nodes_in_tiles, b.nodes_in_tiles) << l;
  }
}

TEST(Client, LanesDrawTheScalarPicture) {
  struct Case {
    const char* model;
    PixelFormat format;
    uint8_t point_size;
    ShadingMode shading;
    uint8_t supersample;
    bool resolve;
    double distance, yaw, pitch;
    uint32_t tile_nodes = 1u << 16, max_points = 1u << 21;
    bool decoded = false;
    uint16_t quality_q8 = 64;
    int32_t near_leaf_mu = 0;  // > 0: the camera this close to the last node's mean (nodes nearer than 2^16 MU)
    uint16_t ambient_q8 = 64;  // the AVX2 lanes compute the diffuse table's entries (diffuse_q8)
  };
  const Case cases[] = {
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kPerPoint, 1, false, 3, 30, 20},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 2, ShadingMode::kSurface, 1, true, 3, 200, -10},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 1, ShadingMode::kPerNode, 1, false, 8, 90, 45},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 3, ShadingMode::kNone, 2, true, 1.2, 10, 5},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kSurface, 4, false, 0.3, 40, 0},  // inside
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kPerPoint, 1, false, 3, 60, 30, 100},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 1, ShadingMode::kSurface, 1, false, 3, 120, 10, 1u << 16, 3000},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kSurface, 1, true, 2, 300, 25, 1u << 16, 1u << 21, true, 256},
      {"tests/data/sphere600_colour.spg", PixelFormat::kRgb888, 2, ShadingMode::kSurface, 1, true, 12, 40, 15},
      {"tests/data/sphere600_normals.spg", PixelFormat::kRgb565, 2, ShadingMode::kPerPoint, 2, false, 4, 10, 70},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kSurface, 1, false, 0, 30, 10, 1u << 16,
       1u << 21, false, 256, 1 << 14},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 1, ShadingMode::kPerPoint, 1, false, 2, 250, 35, 1u << 16,
       1u << 21, false, 256, 0, 0},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb565, 2, ShadingMode::kSurface, 1, false, 3, 70, -20, 1u << 16,
       1u << 21, false, 64, 0, 256},
      {"tests/golden/bunny_v1.spg", PixelFormat::kRgb888, 2, ShadingMode::kPerPoint, 1, false, 3, 160, 5, 1u << 16,
       1u << 21, false, 64, 0, 203},
  };
  uint32_t in_lanes = 0;
  int mixed = 0;
  for (const Case& k : cases) {
    SCOPED_TRACE(testing::Message() << k.model << " at " << k.distance << ", yaw " << k.yaw);
    const std::vector<uint8_t> file = test::fixture(k.model);
    SpgView spg;
    ASSERT_TRUE(spg_parse(file.data(), file.size(), &spg).ok());
    ClientConfig c = small_config(spg.header.node_count);
    c.raster.format = k.format;
    c.raster.max_points = k.max_points;
    c.point_size = k.point_size;
    c.shading = k.shading;
    c.supersample = k.supersample;
    c.resolve = k.resolve;
    c.tile_nodes = k.tile_nodes;
    c.cache_decoded = k.decoded;
    c.quality_q8 = k.quality_q8;
    c.lighting.ambient_q8 = k.ambient_q8;
    LaneFrames out;
    draw_in_each_lanes(file, spg, spg.records, c, [&](const Client& client) {
      OrbitView o = test::orbit(client.decoder().extent_mu(), k.yaw, k.pitch, k.distance > 0 ? k.distance : 1);
      if (k.near_leaf_mu > 0) {
        FixedNode leaf;
        EXPECT_TRUE(client.cache().node_at(client.node_count() - 1, &leaf));
        for (int a = 0; a < 3; ++a) o.target_mu[a] = leaf.mean[a];
        o.distance_mu = k.near_leaf_mu;
      }
      return o;
    }, &out);
    in_lanes += out.stats[2].nodes_in_lanes;
    if (out.stats[2].nodes_in_lanes > 0 && out.stats[2].nodes_in_lanes < out.stats[2].nodes) ++mixed;
    EXPECT_GT(out.stats[0].points, 100u);
  }
  if (avx2::supported()) {  // the node lanes took nodes, and left some to the scalar set-up
    EXPECT_GT(in_lanes, 10000u);
    EXPECT_GE(mixed, 5);
  }
}

// The same on records no encoder writes: every position, angle and class
// field drawn at random within its width (means anywhere in the box, frames
// in any orientation, the largest and smallest classes on any node), from
// far, near and inside — the node lanes' gathers, tables and range checks
// against the scalar set-up's.
TEST(Client, LanesDrawTheScalarPictureOfRandomRecords) {
  const Model& m = bunny();
  const RecordLayout& layout = m.view.header.layout;
  std::mt19937 rng(15);
  std::vector<uint8_t> records(size_t{m.view.header.node_count} * m.view.record_bytes);
  for (uint32_t id = 0; id < m.view.header.node_count; ++id) {
    NodeFields f = unpack_record(layout, record(id));
    for (int i = 0; i < kFieldCount; ++i) {
      const Field field = static_cast<Field>(i);
      uint32_t range = layout.bits[i] == 0 ? 1u : 1u << layout.bits[i];
      if (field == Field::kSigmaP) range = m.view.header.class_count[0];
      if (field == Field::kSigmaN) range = m.view.header.class_count[1];
      if (field == Field::kSigmaC) range = m.view.header.class_count[2];
      if (layout.bits[i] > 0 && (field != Field::kSigmaP || id % 4 == 0)) f.v[i] = static_cast<uint16_t>(rng() % range);
    }
    pack_record(layout, f, records.data() + size_t{id} * m.view.record_bytes);
  }
  const double distances[] = {3, 1.5, 0.4};
  const ShadingMode shadings[] = {ShadingMode::kSurface, ShadingMode::kPerPoint, ShadingMode::kPerNode};
  uint32_t in_lanes = 0;
  for (int v = 0; v < 3; ++v) {
    SCOPED_TRACE(testing::Message() << "distance " << distances[v]);
    ClientConfig c = small_config(m.view.header.node_count);
    c.raster.format = v == 1 ? PixelFormat::kRgb565 : PixelFormat::kRgb888;
    c.raster.max_points = 1u << 21;
    c.shading = shadings[v];
    c.tile_nodes = 1u << 16;
    c.quality_q8 = 64;
    LaneFrames out;
    draw_in_each_lanes(m.file, m.view, records.data(), c, [&](const Client& client) {
      return test::orbit(client.decoder().extent_mu(), 40.0 + 100 * v, 15, distances[v]);
    }, &out);
    in_lanes += out.stats[2].nodes_in_lanes;
    EXPECT_GT(out.stats[0].nodes_in_tiles, 100u);
    EXPECT_LT(out.stats[0].nodes_in_tiles, out.stats[0].nodes_drawn);  // and the bins
  }
  if (avx2::supported()) {
    EXPECT_GT(in_lanes, 1000u);
  }
}

TEST(Client, FrameBudgetDropsPointsAndSaysSo) {
  ClientConfig c = small_config(bunny().view.header.node_count);
  c.raster.max_points = 1000;
  Harness h(c);
  ASSERT_EQ(h.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  for (uint32_t id = 0; id < bunny().view.header.node_count; ++id)
    ASSERT_EQ(h.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes), ClientStatus::kOk);
  FrameStats stats;
  draw(h.client, camera_for(h.client, 0, 0), &stats);
  EXPECT_LE(stats.points, 1000u);
  EXPECT_GT(stats.points, 900u);
  EXPECT_GT(stats.points_dropped, 0u);
}

// The cache alone, as a client without the software renderer (the GL
// client) uses it: every held node decodes to what the decoder makes of its
// record, packed or decoded; ids come back through dense iteration; the
// client's arena is the cache's plus the renderer's.
// Supersampling is exactly the frame drawn at N x N the size with the
// camera scaled, each block averaged (rounded); the arena grows by the
// internal frame and raster, and nothing else changes.
// The point cap: a node draws at most point_cap times the original points
// under it, the count put_node was given (0: unknown, no cap).
TEST(Client, PointCapBoundsEachNodeByItsOriginalPoints) {
  std::vector<uint8_t> points(bunny().view.header.node_count);
  spg_node_points(bunny().view, points.data(), 1);
  uint32_t drawn[3] = {};
  const uint8_t caps[3] = {0, 1, 3};
  for (int k = 0; k < 3; ++k) {
    ClientConfig c = small_config();
    c.point_cap = caps[k];
    c.resolve = false;
    c.close_ups = false;  // the cap alone (a capped frame has no close-ups: the uncapped one would draw more)
    Harness h(c);
    ASSERT_EQ(h.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
    uint64_t bound = 0;
    for (uint32_t id = 3000; id < 6913; ++id) {  // leaves and small nodes: a few points each
      ASSERT_EQ(h.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes, points[id]), ClientStatus::kOk);
      bound += uint64_t{caps[k]} * points[id];
    }
    std::vector<uint8_t> frame(240 * 320 * 2);
    FrameStats stats;
    ASSERT_EQ(h.client.render(camera_for(h.client, 30, 20, 240, 320), frame.data(), 240 * 2, &stats), ClientStatus::kOk);
    drawn[k] = stats.points;
    if (caps[k] > 0) {
      EXPECT_LE(stats.points, bound) << "cap " << int{caps[k]};
    }
  }
  std::printf("points drawn: no cap %u, cap 1 %u, cap 3 %u\n", drawn[0], drawn[1], drawn[2]);
  EXPECT_LT(drawn[1], drawn[2]);
  EXPECT_LT(drawn[2], drawn[0]);
  // Without the counts (put_node's default) nothing is capped.
  ClientConfig c = small_config();
  c.point_cap = 1;
  c.resolve = false;
  c.close_ups = false;
  Harness h(c);
  ASSERT_EQ(h.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
  for (uint32_t id = 3000; id < 6913; ++id)
    ASSERT_EQ(h.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes), ClientStatus::kOk);
  std::vector<uint8_t> frame(240 * 320 * 2);
  FrameStats stats;
  ASSERT_EQ(h.client.render(camera_for(h.client, 30, 20, 240, 320), frame.data(), 240 * 2, &stats), ClientStatus::kOk);
  EXPECT_EQ(stats.points, drawn[0]);
}

TEST(Client, SupersamplingIsTheLargerFrameAveragedBlockByBlock) {
  for (int n : {2, 4}) {
    ClientConfig ss = small_config();
    ss.raster.format = PixelFormat::kRgb888;
    ss.supersample = static_cast<uint8_t>(n);
    ss.resolve = false;  // the mean alone (the resolve follows it: tests/portable/resolve_test.cpp)
    ss.close_ups = false;  // close-ups are sized in the screen's pixels, not the larger frame's
    ClientConfig big = small_config();
    big.raster = RasterConfig{static_cast<uint16_t>(240 * n), static_cast<uint16_t>(320 * n), 5, PixelFormat::kRgb888, 200000};
    big.resolve = false;
    big.close_ups = false;
    EXPECT_GT(client_arena_bytes(ss), client_arena_bytes(small_config()) + size_t{240} * 320 * 3 * n * n);
    Harness a(ss), b(big);
    ASSERT_EQ(a.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
    ASSERT_EQ(b.client.load_startup(bunny().file.data(), bunny().startup_bytes), ClientStatus::kOk);
    for (uint32_t id = 1000; id < 2400; ++id) {
      ASSERT_EQ(a.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes), ClientStatus::kOk);
      ASSERT_EQ(b.client.put_node(NodeId{id}, record(id), bunny().view.record_bytes), ClientStatus::kOk);
    }
    const Camera cam = camera_for(a.client, 30, 20);
    Camera scaled = cam;
    scaled.focal_q4 *= n;
    scaled.center_q4[0] *= n;
    scaled.center_q4[1] *= n;
    std::vector<uint8_t> small(240 * 320 * 3), large(size_t{240} * 320 * 3 * n * n);
    FrameStats sa, sb;
    ASSERT_EQ(a.client.render(cam, small.data(), 240 * 3, &sa), ClientStatus::kOk);
    ASSERT_EQ(b.client.render(scaled, large.data(), size_t{240} * n * 3, &sb), ClientStatus::kOk);
    EXPECT_EQ(sa.points, sb.points);
    size_t mismatches = 0;
    for (int y = 0; y < 320; ++y)
      for (int x = 0; x < 240; ++x)
        for (int c = 0; c < 3; ++c) {
          uint32_t sum = static_cast<uint32_t>(n * n / 2);
          for (int dy = 0; dy < n; ++dy)
            for (int dx = 0; dx < n; ++dx) sum += large[((size_t(y) * n + dy) * 240 * n + size_t(x) * n + dx) * 3 + c];
          mismatches += small[(size_t(y) * 240 + x) * 3 + c] != sum / static_cast<uint32_t>(n * n);
        }
    EXPECT_EQ(mismatches, 0u) << n;
  }
  ClientConfig bad = small_config();
  bad.supersample = 3;
  EXPECT_EQ(client_arena_bytes(bad), 0u);
}

TEST(NodeCache, ServesNodesWithoutARenderer) {
  const SpgView& v = bunny().view;
  for (bool decoded : {false, true}) {
    NodeCacheLimits limits;
    limits.node_capacity = 500;
    limits.decoded = decoded;
    std::vector<uint64_t> storage(node_cache_bytes(limits) / 8 + 1);
    NodeCache cache;
    ASSERT_EQ(cache.init(limits, storage.data(), storage.size() * 8), CacheStatus::kOk);
    ASSERT_EQ(cache.load_startup(bunny().file.data(), bunny().startup_bytes), CacheStatus::kOk);
    for (uint32_t id = 0; id < 1000; id += 2) ASSERT_EQ(cache.put(NodeId{id}, record(id), v.record_bytes), CacheStatus::kOk);
    EXPECT_EQ(cache.put(NodeId{1}, record(1), v.record_bytes), CacheStatus::kFull);
    ASSERT_EQ(cache.drop(NodeId{10}), CacheStatus::kOk);
    EXPECT_EQ(cache.count(), 499u);
    std::vector<bool> seen(1000, false);
    for (uint32_t s = 0; s < cache.count(); ++s) {
      const uint32_t id = index_of(cache.id_at(s));
      ASSERT_TRUE(id % 2 == 0 && id != 10 && !seen[id]) << id;
      seen[id] = true;
      FixedNode got, want;
      ASSERT_TRUE(cache.node_at(s, &got));
      ASSERT_EQ(cache.decoder().decode(record(id), &want), DecodeStatus::kOk);
      // Field by field (padding bytes carry no value).
      EXPECT_TRUE(std::memcmp(got.mean, want.mean, sizeof got.mean) == 0 &&
                  std::memcmp(got.axis, want.axis, sizeof got.axis) == 0 &&
                  std::memcmp(got.normal_frame, want.normal_frame, sizeof got.normal_frame) == 0 &&
                  std::memcmp(got.sigma_n, want.sigma_n, sizeof got.sigma_n) == 0 &&
                  std::memcmp(got.color, want.color, sizeof got.color) == 0 &&
                  std::memcmp(got.color_axis, want.color_axis, sizeof got.color_axis) == 0)
          << id;
    }
    cache.clear();
    EXPECT_EQ(cache.count(), 0u);
    EXPECT_FALSE(cache.has(NodeId{0}));
    EXPECT_TRUE(cache.ready());  // the startup stays
  }
  const ClientConfig c = small_config();
  EXPECT_EQ(client_arena_bytes(c), ((node_cache_bytes(cache_limits(c)) + 7) & ~size_t{7}) +
                                       point_renderer_bytes(renderer_config(c)));
}

// Protocol 4's class tables in pieces: a cache loaded from the header alone
// holds no class and refuses a node whose class has not come
// (kClassMissing); a class beyond its table, of the wrong length or (version
// 1) a NaN is refused with kBadClasses; once a node's classes have come
// (in any order, some twice) it is taken and decodes exactly as from the
// whole startup.
TEST(NodeCache, ClassesOneByOneDecodeAsTheWholeStartup) {
  const Model& m = bunny_v2();
  const SpgView& v = m.view;
  const auto rec = [&](uint32_t id) { return v.records + size_t{id} * v.record_bytes; };
  NodeCacheLimits limits;
  limits.node_capacity = 200;
  std::vector<uint64_t> a(node_cache_bytes(limits) / 8 + 1), b(node_cache_bytes(limits) / 8 + 1);
  NodeCache whole, pieces;
  ASSERT_EQ(whole.init(limits, a.data(), a.size() * 8), CacheStatus::kOk);
  ASSERT_EQ(pieces.init(limits, b.data(), b.size() * 8), CacheStatus::kOk);
  ASSERT_EQ(whole.load_startup(m.file.data(), m.startup_bytes), CacheStatus::kOk);
  const size_t header_bytes = spg_fixed_header_bytes(v.header.version);
  EXPECT_EQ(pieces.load_model(m.file.data(), header_bytes - 1), CacheStatus::kBadStartup);
  ASSERT_EQ(pieces.load_model(m.file.data(), header_bytes), CacheStatus::kOk);
  for (int t = 0; t < 3; ++t) EXPECT_EQ(pieces.classes_held(t), 0u);
  EXPECT_EQ(pieces.put(NodeId{0}, rec(0), v.record_bytes), CacheStatus::kClassMissing);
  const uint8_t* tables[3] = {v.sigma_p, v.sigma_n, v.sigma_c};
  const uint32_t changed = pieces.classes_changed();
  EXPECT_EQ(pieces.add_class(2, 0, v.sigma_p, 6), CacheStatus::kBadClasses);  // a table the model lacks
  EXPECT_EQ(pieces.add_class(0, v.header.class_count[0], v.sigma_p, 6), CacheStatus::kBadClasses);  // beyond
  EXPECT_EQ(pieces.add_class(0, 0, v.sigma_p, 4), CacheStatus::kBadClasses);  // a wrong length
  EXPECT_EQ(pieces.classes_changed(), changed);
  static constexpr Field kField[2] = {Field::kSigmaP, Field::kSigmaN};
  // Nodes 199 down to 0, each after its own classes (sent again if held).
  for (uint32_t k = 0; k < 200; ++k) {
    const uint32_t id = 199 - k;
    const NodeFields f = unpack_record(v.header.layout, rec(id));
    for (int t = 0; t < 2; ++t) {
      const uint32_t c = f[kField[t]];
      const size_t per = pieces.class_value_bytes(t);
      ASSERT_EQ(pieces.add_class(t, c, tables[t] + per * c, per), CacheStatus::kOk);
      EXPECT_TRUE(pieces.class_held(t, c));
    }
    ASSERT_EQ(pieces.put(NodeId{id}, rec(id), v.record_bytes), CacheStatus::kOk);
    FixedNode got, want;
    ASSERT_EQ(whole.decoder().decode(rec(id), &want), DecodeStatus::kOk);
    ASSERT_TRUE(pieces.node_at(pieces.count() - 1, &got));
    EXPECT_TRUE(std::memcmp(got.axis, want.axis, sizeof got.axis) == 0 && std::memcmp(got.mean, want.mean, sizeof got.mean) == 0 &&
                std::memcmp(got.sigma_n, want.sigma_n, sizeof got.sigma_n) == 0)
        << id;
  }
  EXPECT_GT(pieces.classes_held(0), 10u);
  EXPECT_LT(pieces.classes_held(0), v.header.class_count[0]);
  // Version 1's float32 values: a NaN is refused.
  const Model& v1 = bunny();
  NodeCache old;
  std::vector<uint64_t> c(node_cache_bytes(limits) / 8 + 1);
  ASSERT_EQ(old.init(limits, c.data(), c.size() * 8), CacheStatus::kOk);
  ASSERT_EQ(old.load_model(v1.file.data(), spg_fixed_header_bytes(1)), CacheStatus::kOk);
  std::vector<uint8_t> nan(v1.view.sigma_p, v1.view.sigma_p + 12);
  nan[3] = 0x7F, nan[2] = 0xC0;
  EXPECT_EQ(old.add_class(0, 0, nan.data(), 12), CacheStatus::kBadClasses);
  EXPECT_EQ(old.add_class(0, 0, v1.view.sigma_p, 12), CacheStatus::kOk);
}

// The hash's entries are 16 bits up to 65,535 nodes and 32 above: either
// way a cache filled to capacity, half dropped and refilled, finds every
// node it holds and no other, its slots dense.
TEST(NodeCache, HashEntriesNarrowWhereEverySlotFits) {
  const SpgView& v = bunny().view;
  NodeCacheLimits limits;
  limits.node_capacity = 65535;
  const size_t narrow = node_cache_bytes(limits);
  limits.node_capacity = 65536;
  const size_t wide = node_cache_bytes(limits);
  // One more record (17 bytes: colour allowed), id and count, each section
  // 8-aligned, and 2^17 entries either way (load <= 2/3) of 4 bytes, not 2.
  const auto align8 = [](size_t n) { return (n + 7) & ~size_t{7}; };
  EXPECT_EQ(wide - narrow, align8(17 * 65536) - align8(17 * 65535) + align8(4 * 65536) - align8(4 * 65535) +
                               align8(65536) - align8(65535) + (4 - 2) * (size_t{1} << 17));
  for (uint32_t capacity : {65535u, 65536u}) {
    limits.node_capacity = capacity;
    std::vector<uint64_t> storage(node_cache_bytes(limits) / 8 + 1);
    NodeCache cache;
    ASSERT_EQ(cache.init(limits, storage.data(), storage.size() * 8), CacheStatus::kOk);
    ASSERT_EQ(cache.load_startup(bunny().file.data(), bunny().startup_bytes), CacheStatus::kOk);
    // Ids spread over 32 bits, so that probe sequences wrap and collide.
    std::mt19937 rng(capacity);
    std::vector<uint32_t> ids;
    std::set<uint32_t> taken;
    while (ids.size() < 2 * size_t{capacity}) {
      const uint32_t id = static_cast<uint32_t>(rng());
      if (taken.insert(id).second) ids.push_back(id);
    }
    const uint8_t* r = record(3);
    for (uint32_t i = 0; i < capacity; ++i) ASSERT_EQ(cache.put(NodeId{ids[i]}, r, v.record_bytes), CacheStatus::kOk);
    EXPECT_EQ(cache.put(NodeId{ids[capacity]}, r, v.record_bytes), CacheStatus::kFull);
    for (uint32_t i = 0; i < capacity; i += 2) ASSERT_EQ(cache.drop(NodeId{ids[i]}), CacheStatus::kOk);
    for (uint32_t i = capacity; i < capacity + capacity / 2; ++i)
      ASSERT_EQ(cache.put(NodeId{ids[i]}, r, v.record_bytes), CacheStatus::kOk);
    ASSERT_EQ(cache.count(), capacity - (capacity + 1) / 2 + capacity / 2);
    for (uint32_t i = 0; i < 2 * capacity; ++i) {
      const bool held = i < capacity ? i % 2 == 1 : i < capacity + capacity / 2;
      ASSERT_EQ(cache.has(NodeId{ids[i]}), held) << capacity << " " << i;
    }
    std::set<uint32_t> slots;
    for (uint32_t s = 0; s < cache.count(); ++s) ASSERT_TRUE(slots.insert(index_of(cache.id_at(s))).second);
    EXPECT_EQ(cache.drop(NodeId{ids[0]}), CacheStatus::kUnknownNode);
  }
}

}  // namespace
}  // namespace stipple
