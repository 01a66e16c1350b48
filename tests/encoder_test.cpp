// Hierarchy invariants, determinism, golden bitstream, reference decoding and
// metrics on synthetic and real scans.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include <filesystem>
#include <fstream>

#include "platform/file_io.h"
#include "test_util.h"
#include "tools/encoder/encoder.h"
#include "tools/reference/metrics.h"
#include "tools/embedded/embedded.h"
#include "tools/scan/las_io.h"
#include "tools/scan/ply_io.h"
#include "tools/reference/sampler.h"
#include "tools/reference/spg_model.h"

namespace stipple {
namespace {

void check_invariants(const Tree& tree, size_t points, const TreeOptions& o) {
  ASSERT_FALSE(tree.nodes.empty());
  EXPECT_EQ(tree.nodes[0].count(), points);
  // Every point in exactly one leaf.
  std::vector<int> seen(points, 0);
  for (const TreeNode& n : tree.nodes)
    if (n.leaf())
      for (uint32_t i = n.begin; i < n.end; ++i) ++seen[tree.order[i]];
  for (size_t i = 0; i < points; ++i) ASSERT_EQ(seen[i], 1) << "point " << i;
  uint64_t unbalanced = 0;
  for (size_t id = 0; id < tree.nodes.size(); ++id) {
    const TreeNode& n = tree.nodes[id];
    EXPECT_EQ(n.stats.count, n.count());
    if (n.leaf()) {
      // A leaf is small, flat at the floor, or a failed split.
      continue;
    }
    EXPECT_GE(n.count(), o.leaf_size);
    EXPECT_GT(n.first_child, id);  // breadth-first: children after the parent
    uint32_t sum = 0, smallest = n.count();
    uint32_t at = n.begin;
    for (uint32_t c = n.first_child; c < n.first_child + n.child_count; ++c) {
      const TreeNode& child = tree.nodes[c];
      EXPECT_EQ(child.begin, at);  // siblings adjacent, ranges contiguous
      EXPECT_EQ(child.depth, n.depth + 1);
      at = child.end;
      sum += child.count();
      smallest = std::min(smallest, child.count());
    }
    EXPECT_EQ(sum, n.count());  // counts add up
    if (!o.octree) {
      EXPECT_EQ(n.child_count, 2);
      if (static_cast<double>(smallest) < o.balance * n.count()) ++unbalanced;
    }
  }
  // Out-of-band splits exist only as the counted Euclidean fallback.
  EXPECT_EQ(unbalanced, tree.report.unbalanced);
  EXPECT_LE(tree.report.unbalanced, tree.report.euclidean_fallbacks);
}

TEST(Hierarchy, InvariantsOnTwoDisjointSheets) {
  // Two parallel planes 0.05 apart: Mahalanobis keeps them apart.
  PointCloud c;
  for (int s = 0; s < 2; ++s)
    for (int i = 0; i < 60; ++i)
      for (int j = 0; j < 60; ++j) {
        c.positions.push_back(Vec3(i / 60.0, j / 60.0, s * 0.05));
        c.normals.push_back(Vec3(0, 0, s ? 1 : -1));
      }
  TreeOptions o;
  o.leaf_size = 10;
  const Tree tree = build_tree(c, o);
  check_invariants(tree, c.size(), o);
  // No leaf mixes the two sheets.
  for (const TreeNode& n : tree.nodes) {
    if (!n.leaf()) continue;
    const double z0 = c.positions[tree.order[n.begin]].z();
    for (uint32_t i = n.begin; i < n.end; ++i) ASSERT_EQ(c.positions[tree.order[i]].z(), z0);
  }
  EXPECT_LT(tree.nodes.size(), 2 * c.size() / 5);
}

TEST(Hierarchy, OctreeInvariantsAndPartitionRatios) {
  PointCloud c = test::sphere_cloud(5000);
  TreeOptions o;
  o.leaf_size = 12;
  const Tree binary = build_tree(c, o);
  o.octree = true;
  const Tree octree = build_tree(c, o);
  check_invariants(octree, c.size(), o);
  const PartitionRatios rb = partition_ratios(binary), ro = partition_ratios(octree);
  EXPECT_LT(rb.apr, 1.6);    // 2-means with a 30-70 band: at most 2.33, typically ~1.2
  EXPECT_GT(ro.apr, rb.apr);  // the octree is far less balanced (TOG05 Table II)
}

TEST(Hierarchy, CoincidentPointsBecomeOneLeaf) {
  PointCloud c;
  c.positions.assign(100, Vec3(0.5, 0.5, 0.5));
  c.normals.assign(100, Vec3::UnitZ());
  TreeOptions o;
  o.stats.sigma_floor = 1e-15;
  const Tree tree = build_tree(c, o);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(tree.nodes[0].count(), 100u);
}

TEST(Encoder, SameInputSameBytesAnyThreadCount) {
  const PointCloud cloud = test::sphere_cloud(4000);
  EncodeOptions o1, o2;
  o1.tree.threads = 1;
  o2.tree.threads = 2;
  EXPECT_EQ(test::encode(cloud, o1), test::encode(cloud, o2));
}

// Above 65,536 points a node's sums run in chunks; with every node "wide"
// the chunks of one node go to several threads. The bytes stay the same, and
// so do the bare scan's estimated normals (its k-NN fits run in threads too).
TEST(Encoder, LargeNodesSameBytesAnyThreadCount) {
  PointCloud cloud = test::sphere_cloud(140000, 1.0, false);
  EncodeOptions o1, o3;
  o1.tree.threads = 1;
  o3.tree.threads = 3;
  o3.tree.wide_node = 1000;
  EncodeReport report;
  const std::vector<uint8_t> one = test::encode(cloud, o1, &report);
  EXPECT_EQ(report.normals_source, "k-NN");
  EXPECT_EQ(one, test::encode(cloud, o3));
}

// Taking the scan's positions and normals instead of copying them changes
// nothing in the file; the cloud is left without them, its colours kept.
TEST(Encoder, ConsumingTheScanGivesTheSameBytes) {
  PointCloud cloud = test::sphere_cloud(3000);
  for (size_t i = 0; i < cloud.size(); ++i) cloud.colors.push_back(Vec3(0.2, 0.5, static_cast<double>(i % 7) / 7.0));
  const std::vector<uint8_t> copied = test::encode(cloud);
  EncodeOptions o;
  o.consume_scan = true;
  std::vector<uint8_t> consumed;
  EncodeReport report;
  std::string error;
  ASSERT_TRUE(encode_cloud(cloud, o, consumed, report, error)) << error;
  EXPECT_EQ(consumed, copied);
  EXPECT_TRUE(cloud.positions.empty());
  EXPECT_TRUE(cloud.normals.empty());
  EXPECT_EQ(cloud.colors.size(), 3000u);
}

TEST(Encoder, RejectsBadOptionsByName) {
  PointCloud c = test::sphere_cloud(100);
  EncodeOptions o;
  o.classes_p = 5000;
  std::vector<uint8_t> spg;
  EncodeReport r;
  std::string error;
  EXPECT_FALSE(encode_cloud(c, o, spg, r, error));
  EXPECT_NE(error.find("--classes"), std::string::npos) << error;
}

TEST(Encoder, DecodedNodesMatchTheEncoderWithinQuantization) {
  const PointCloud c = test::sphere_cloud(3000);
  EncodeOptions o;
  o.tree.leaf_size = 10;
  EncodeReport r;
  const DecodedModel m = test::decode(test::encode(c, o, &r));
  ASSERT_EQ(m.nodes.size(), r.nodes);
  // Positions: every leaf mean lies within half a grid cell of a leaf's true mean
  // (checked through the root, whose mean is the centroid).
  Vec3 cell;
  for (int k = 0; k < 3; ++k) cell[k] = (m.bbox_max[k] - m.bbox_min[k]) / std::ldexp(1.0, m.header.layout.bits[k]);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : c.positions) centroid += p;
  centroid /= static_cast<double>(c.size());
  for (int k = 0; k < 3; ++k) EXPECT_LE(std::abs(m.nodes[0].position.mean[k] - centroid[k]), cell[k] / 2 + 1e-12);
  // Point counts rebuilt from the leaf table.
  EXPECT_EQ(m.nodes[0].point_count, 3000u);
  uint64_t leaf_sum = 0;
  for (const DecodedNode& n : m.nodes) leaf_sum += n.leaf() ? n.point_count : 0;
  EXPECT_EQ(leaf_sum, 3000u);
}

// The variance floor is a length for positions only: a scan 1e15 units
// across keeps the normal spreads it has at unit size (they were floored
// at 1e-15 of the diagonal, which above ~4e12 units turned every sigma_n
// into radians of noise and destroyed the shading).
TEST(Encoder, NormalSpreadsDoNotGrowWithTheScansSize) {
  std::vector<double> sigma_n[2];
  for (int k = 0; k < 2; ++k) {
    PointCloud c = test::sphere_cloud(2000);
    if (k == 1)
      for (Vec3& p : c.positions) p *= 1e15;  // the old floor: 3.5 rad
    const DecodedModel m = test::decode(test::encode(c));
    for (const Vec2& s : m.sigma_n) sigma_n[k].push_back(s[0]);
  }
  ASSERT_EQ(sigma_n[0].size(), sigma_n[1].size());
  for (size_t i = 0; i < sigma_n[0].size(); ++i) EXPECT_NEAR(sigma_n[1][i], sigma_n[0][i], 1e-3) << "class " << i;
}

TEST(Encoder, SampledLeavesReproduceTheSurface) {
  const PointCloud original = test::sphere_cloud(20000);
  const DecodedModel m = test::decode(test::encode(original));
  const PointCloud leaves = sample_cut(m, leaf_cut(m), 0);
  ASSERT_EQ(leaves.size(), original.size());
  const CloudMetrics leaf_metrics = compare_clouds(original, leaves);
  // Measured 50.6 dB one-sided, 48.0 dB symmetric: the sphere's own sample
  // spacing (~0.025 on a 3.46 diagonal) bounds what any resampling can reach.
  EXPECT_GT(leaf_metrics.psnr_one_sided, 49.5);
  EXPECT_GT(leaf_metrics.psnr_symmetric, 47.0);
  EXPECT_LT(leaf_metrics.generated_to_original.normal_rms_deg, 10.0);
  // Coarser cuts are worse: PSNR falls with the level.
  const CloudMetrics coarse = compare_clouds(original, sample_cut(m, level_cut(m, 4), 0));
  EXPECT_LT(coarse.psnr_one_sided, leaf_metrics.psnr_one_sided);
}

// An error bound (encode --tolerance): the leaves' points regenerated lie
// within it (RMS, both ways, of the bounding box's diagonal), the variance
// stop makes every leaf of two points or more at most that wide, and the
// position fields are narrowed to cells of half of it — a coarser bound, a
// smaller file.
TEST(Encoder, ToleranceBoundsTheErrorAndFitsTheWidths) {
  const PointCloud original = test::sphere_cloud(20000);
  size_t bytes_before = ~size_t{0};
  for (double share : {0.002, 0.01, 0.03}) {
    EncodeOptions o;
    o.tolerance = share;
    o.tolerance_relative = true;
    o.tree.leaf_size = 2;
    const std::vector<uint8_t> file = test::encode(original, o);
    const DecodedModel m = test::decode(file);
    const CloudMetrics leaves = compare_clouds(original, sample_cut(m, leaf_cut(m), 0));
    const double diagonal = leaves.diagonal;
    EXPECT_LE(leaves.original_to_generated.rms, share * diagonal) << share;
    EXPECT_LE(leaves.generated_to_original.rms, share * diagonal) << share;
    SpgView view;
    ASSERT_TRUE(spg_parse(file.data(), file.size(), &view).ok());
    for (int a = 0; a < 3; ++a) {
      float lo, hi;
      std::memcpy(&lo, &view.header.bbox_bits[a], 4);
      std::memcpy(&hi, &view.header.bbox_bits[3 + a], 4);
      const double extent = double(hi) - lo;
      const int bits = view.header.layout.bits[a];
      EXPECT_LE(extent / std::ldexp(1.0, bits), share * diagonal / 2 * 1.01) << share;  // a cell at most half the bound
      EXPECT_GT(extent / std::ldexp(1.0, bits - 1), share * diagonal / 2 * 0.99) << share;  // and no finer than that needs
    }
    EXPECT_LT(file.size(), bytes_before) << share;
    bytes_before = file.size();
    std::printf("tolerance %.1f %% of the diagonal: %u nodes, %zu bytes, position %u/%u/%u bits, RMS %.4f / %.4f\n",
                100 * share, view.header.node_count, file.size(), view.header.layout.bits[0], view.header.layout.bits[1],
                view.header.layout.bits[2], leaves.original_to_generated.rms, leaves.generated_to_original.rms);
  }
}

// Colour modes end to end (encode --color-by classification | intensity):
// a synthetic LAS of a flat 60 x 60 m square, ground (class 2, intensity 40)
// on its left half, a roof (class 6, intensity 200) on its right, without
// RGB (point format 0). Encoded with its classes as the colour and drawn
// unlit from above, the left half is the ground's brown, the right the
// building's red; by intensity, dark grey and light grey.
TEST(Encoder, LasClassesAndIntensityBecomeTheNodeColour) {
  std::vector<uint8_t> las(227, 0);
  std::memcpy(las.data(), "LASF", 4);
  las[24] = 1, las[25] = 2;
  const uint16_t header = 227, record = 20;
  const uint32_t offset = 227, count = 120 * 120;
  std::memcpy(&las[94], &header, 2);
  std::memcpy(&las[96], &offset, 4);
  std::memcpy(&las[105], &record, 2);
  std::memcpy(&las[107], &count, 4);
  const double scale[3] = {0.001, 0.001, 0.001}, shift[3] = {0, 0, 0};
  std::memcpy(&las[131], scale, 24);
  std::memcpy(&las[155], shift, 24);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 120; ++x) {
      uint8_t r[20] = {};
      const int32_t xyz[3] = {x * 500, y * 500, ((x * 7 + y * 13) % 5) * 2};  // 0.5 m apart, 1 cm of relief
      std::memcpy(r, xyz, 12);
      const uint16_t intensity = x < 60 ? 40 : 200;
      std::memcpy(&r[12], &intensity, 2);
      r[15] = x < 60 ? 2 : 6;
      las.insert(las.end(), r, r + 20);
    }
  for (LasColor by : {LasColor::kClassification, LasColor::kIntensity}) {
    PointCloud cloud;
    std::string error;
    ScanOptions scan;
    scan.color_by = by;
    ASSERT_TRUE(parse_point_cloud("site.las", las.data(), las.size(), cloud, error, scan)) << error;
    std::vector<uint8_t> spg;
    EncodeReport report;
    ASSERT_TRUE(encode_cloud(cloud, EncodeOptions{}, spg, report, error)) << error;
    SpgView view;
    ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &view).ok());
    ASSERT_TRUE(view.header.has_color());
    ClientConfig c;
    c.raster = RasterConfig{240, 240, 5, PixelFormat::kRgb888, 1u << 20};
    c.shading = ShadingMode::kNone;
    c.sample_color = false;
    ViewSpec spec;
    ASSERT_TRUE(parse_view("0,90,1.2", spec, error)) << error;
    FixedRender out;
    ASSERT_TRUE(render_fixed(view, spg.data(), c, CutRule{CutRule::kProjectedSize, 0, 32}, spec, out, error)) << error;
    // Seen from above, the square fills the screen, its halves the top and
    // the bottom (which is which is the view's yaw's); their middles are the
    // two colours, one each.
    const auto at = [&](int x, int y) {
      const uint8_t* p = &out.image.rgb[(static_cast<size_t>(y) * 240 + x) * 3];
      return uint32_t{p[0]} << 16 | uint32_t{p[1]} << 8 | p[2];
    };
    const uint32_t a = at(120, 60), b = at(120, 180);
    const uint32_t want[2] = {by == LasColor::kClassification ? las_class_rgb(2) : 0x333333u,
                              by == LasColor::kClassification ? las_class_rgb(6) : 0xFFFFFFu};
    const auto near = [](uint32_t x, uint32_t y) {
      for (int k : {16, 8, 0})
        if (std::abs(static_cast<int>((x >> k) & 255) - static_cast<int>((y >> k) & 255)) > 12) return false;
      return true;
    };
    EXPECT_TRUE((near(a, want[0]) && near(b, want[1])) || (near(a, want[1]) && near(b, want[0])))
        << std::hex << a << " " << b << " want " << want[0] << " and " << want[1];
  }
}

TEST(Metrics, KnownDistances) {
  PointCloud a, b;
  for (int i = 0; i < 100; ++i) {
    a.positions.push_back(Vec3(i, 0, 0));
    b.positions.push_back(Vec3(i, 0.5, 0));
  }
  const CloudMetrics m = compare_clouds(a, b);
  EXPECT_DOUBLE_EQ(m.generated_to_original.rms, 0.5);
  EXPECT_DOUBLE_EQ(m.hausdorff, 0.5);
  EXPECT_NEAR(m.psnr_one_sided, 20 * std::log10(99.0 / 0.5), 1e-9);
  // A hole: generated covers half the original. One-sided cannot see it.
  b.positions.resize(50);
  const CloudMetrics hole = compare_clouds(a, b);
  EXPECT_DOUBLE_EQ(hole.generated_to_original.rms, 0.5);
  EXPECT_GT(hole.original_to_generated.max, 49.0);
  EXPECT_LT(hole.psnr_symmetric, hole.psnr_one_sided - 20);
  EXPECT_TRUE(std::isinf(compare_clouds(a, a).psnr_one_sided));
  EXPECT_EQ(hole.generated_to_original.color_rms, -1);  // no colours: not measured
  a.colors.assign(a.size(), Vec3(1, 0, 0));
  b.colors.assign(b.size(), Vec3(1, 0.3, 0.4));
  EXPECT_NEAR(compare_clouds(a, b).generated_to_original.color_rms, 0.5, 1e-12);
}

// The bundled bunny, encoded with the defaults, must reproduce
// tests/golden/bunny_v2.spg (and bunny_v1.spg) bit for bit. Regenerate only on purpose, with
// tests/golden/regenerate.sh; on failure the actual bytes are written beside
// the test binary.
TEST(Golden, BundledBunnyBitstream) {
  PointCloud cloud;
  std::string error;
  ASSERT_TRUE(read_point_cloud(test::source_path("data/bunny.ply"), cloud, error)) << error;
  // Both versions the encoder writes: the default (16-bit class tables) and
  // --format-version 1 (float32 tables; the file every golden image is drawn
  // from, and the proof that version 1 is still read everywhere).
  for (const int version : {2, 1}) {
    const std::string name = "bunny_v" + std::to_string(version) + ".spg";
    std::vector<uint8_t> spg;
    EncodeReport r;
    EncodeOptions o;
    o.format_version = version;
    ASSERT_TRUE(encode_cloud(cloud, o, spg, r, error)) << error;
    std::vector<uint8_t> golden;
    ASSERT_TRUE(read_file(test::source_path("tests/golden/" + name), golden, error))
        << error << " (a missing golden file fails; run tests/golden/regenerate.sh on purpose)";
    if (spg != golden) {
      const std::string actual = name + ".actual";
      write_file_atomic(actual, spg, error);
      size_t first = 0;
      while (first < std::min(spg.size(), golden.size()) && spg[first] == golden[first]) ++first;
      ADD_FAILURE() << "bitstream differs from tests/golden/" << name << " at byte " << first << " (sizes " << spg.size()
                    << " vs " << golden.size() << "); actual written to " << std::filesystem::absolute(actual);
    }
  }
}

// Automatic class counts fitted to what the picture needs (docs/encoder.md
// "Classes"), numbered by size: σ1 (|σn1|) never falls along the table (σn's
// within each of its sign patterns, ++, -+, +-, -- in turn), so a view's
// class pieces go as small steps (docs/protocol.md "Coded batches").
TEST(Encoder, ClassesAreCountedForTheSceneAndNumberedBySize) {
  std::vector<uint8_t> spg;
  std::string error;
  ASSERT_TRUE(read_file(test::source_path("tests/golden/bunny_v2.spg"), spg, error)) << error;
  SpgView v;
  ASSERT_TRUE(spg_parse(spg.data(), spg.size(), &v).ok());
  const uint32_t nodes = v.header.node_count;
  EXPECT_EQ(v.header.class_count[0], std::clamp(nodes / 16, 64u, 2048u));  // 432
  EXPECT_EQ(v.header.class_count[1], std::clamp(nodes / 64, 64u, 1024u));  // 108
  ASSERT_TRUE(v.header.has_curvature_sign());
  for (uint32_t c = 1; c < v.header.class_count[0]; ++c)
    ASSERT_LE(load_u16le(v.sigma_p + 6 * (c - 1)), load_u16le(v.sigma_p + 6 * c)) << "sigma_p class " << c;
  // sigma_n: (pattern, |sigma_n1|) ascending, and every pattern there.
  const auto key = [&](uint32_t c) {
    const int32_t a = spg_sigma_n_q12(load_u16le(v.sigma_n + 4 * c), true), b = spg_sigma_n_q12(load_u16le(v.sigma_n + 4 * c + 2), true);
    return std::make_pair((a < 0 ? 1 : 0) | (b < 0 ? 2 : 0), a < 0 ? -a : a);
  };
  for (uint32_t c = 1; c < v.header.class_count[1]; ++c) ASSERT_LE(key(c - 1), key(c)) << "sigma_n class " << c;
  EXPECT_EQ(key(0).first, 0);
  EXPECT_EQ(key(v.header.class_count[1] - 1u).first, 3);
}

TEST(RealScans, SharedBunnyAndDragonEncode) {
  for (const char* name : {"bunny.ply", "dragon.ply"}) {
    const std::string path = test::shared_data(name);
    if (!std::filesystem::exists(path)) {
      GTEST_SKIP() << path << " not present (../shared/data is optional for tests)";
    }
    PointCloud cloud;
    std::string error;
    ASSERT_TRUE(read_point_cloud(path, cloud, error)) << error;
    const size_t points = cloud.size();
    EXPECT_FALSE(cloud.triangles.empty());
    std::vector<uint8_t> spg;
    EncodeReport r;
    ASSERT_TRUE(encode_cloud(cloud, EncodeOptions{}, spg, r, error)) << error;
    EXPECT_EQ(r.normals_source, "faces");
    EXPECT_EQ(r.record_bytes, 13u);
    EXPECT_LT(r.ratios.apr, 1.6) << name;
    DecodedModel m;
    ASSERT_TRUE(decode_spg(name, spg.data(), spg.size(), m, error)) << error;
    EXPECT_EQ(m.header.point_count, points);
  }
}

}  // namespace
}  // namespace stipple
