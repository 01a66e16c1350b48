// The encoder in partitions (tools/encoder/partition.h, merge.h): the same
// bytes whoever runs the jobs, normals at the borders as an in-core run
// gives them, upper nodes whose normal spread is never understated, and
// faults named by their file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "core/spg_format.h"
#include "platform/file_io.h"
#include "tests/test_util.h"
#include "tools/encoder/merge.h"
#include "tools/encoder/normals.h"
#include "tools/encoder/partition.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

namespace fs = std::filesystem;

// Rolling terrain, bare: x, y in [0, 40), z a few waves and a sensor's
// noise of +-3 cm (so a normal depends on which neighbours it had).
PointCloud terrain(size_t n, uint64_t seed = 7) {
  PointCloud c;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 40.0), noise(-0.03, 0.03);
  for (size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng);
    c.positions.emplace_back(x, y, 0.6 * std::sin(0.5 * x) * std::cos(0.4 * y) + noise(rng));
  }
  return c;
}

// A fresh folder for one test's files.
std::string folder(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("partition_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// The plan, routed into `dir`, written.
PartitionPlan plan_into(PointCloud cloud, const EncodeOptions& o, const std::string& dir) {
  PartitionPlan plan;
  std::string error;
  EXPECT_TRUE(make_plan(cloud, o, plan, error)) << error;
  EXPECT_TRUE(route_points(cloud, plan, dir, error)) << error;
  EXPECT_TRUE(write_plan(plan, dir, error)) << error;
  return plan;
}

std::vector<uint8_t> merge_dir(const std::string& dir, std::string& error, int threads = 2) {
  PartitionPlan plan;
  if (!read_plan(dir, plan, error)) return {};
  std::vector<std::unique_ptr<PartNodes>> parts;
  for (uint32_t i = 0; i < plan.partitions(); ++i) {
    parts.push_back(open_part_file(dir, plan, i, error));
    if (!parts.back()) return {};
  }
  std::vector<uint8_t> out;
  const ByteSink sink = [&](const uint8_t* d, size_t n, std::string&) {
    out.insert(out.end(), d, d + n);
    return true;
  };
  EncodeReport report;
  if (!merge_parts(plan, parts, threads, sink, report, error)) return {};
  return out;
}

TEST(Partition, AScanThatFitsIsOnePartitionAndTheInCoreTree) {
  const PointCloud cloud = terrain(20000);
  EncodeOptions o;
  EncodeReport whole, fits;
  const std::vector<uint8_t> a = test::encode(cloud, o, &whole);
  o.partition_points = 20000;
  const std::vector<uint8_t> b = test::encode(cloud, o, &fits);
  EXPECT_EQ(fits.partitions, 1u);
  EXPECT_EQ(a, b);
}

TEST(Partition, ManyPartitionsMakeOneValidTreeWhateverTheThreadCount) {
  const PointCloud cloud = terrain(40000);
  EncodeOptions o;
  o.partition_points = 5000;
  EncodeReport r1, r2;
  o.tree.threads = 1;
  const std::vector<uint8_t> one = test::encode(cloud, o, &r1);
  o.tree.threads = 2;
  const std::vector<uint8_t> two = test::encode(cloud, o, &r2);
  EXPECT_GE(r1.partitions, 8u);
  EXPECT_EQ(one, two);
  const DecodedModel m = test::decode(one);
  EXPECT_EQ(m.header.point_count, 40000u);
  EXPECT_EQ(m.header.node_count, r1.nodes);
  // The root holds every point; its mean is the scan's.
  EXPECT_EQ(m.nodes[0].point_count, 40000u);
  EXPECT_NEAR(m.nodes[0].position.mean.x(), 20.0, 0.5);
  EXPECT_NEAR(m.nodes[0].position.mean.y(), 20.0, 0.5);
  // Every node's count is its children's sum, down to the leaves.
  for (const DecodedNode& n : m.nodes) {
    if (n.leaf()) continue;
    EXPECT_EQ(n.point_count, m.nodes[n.first_child].point_count + m.nodes[n.first_child + 1].point_count);
  }
}

TEST(Partition, JobsRunApartGiveTheBytesOfOneProcess) {
  const PointCloud cloud = terrain(30000);
  EncodeOptions o;
  o.partition_points = 4000;
  const std::vector<uint8_t> local = test::encode(cloud, o);
  const std::string dir = folder("apart");
  const PartitionPlan plan = plan_into(cloud, o, dir);
  ASSERT_GE(plan.partitions(), 8u);
  std::string error;
  PartitionPlan read;
  ASSERT_TRUE(read_plan(dir, read, error)) << error;
  // In reverse, one thread each: order and threads change nothing.
  for (uint32_t i = read.partitions(); i-- > 0;) ASSERT_TRUE(run_part_file(dir, read, i, 1, error)) << error;
  EXPECT_EQ(merge_dir(dir, error, 1), local) << error;
  // A job run twice writes the same part.
  std::vector<uint8_t> first, second;
  ASSERT_TRUE(read_file(part_path(dir, 3, "nodes"), first, error));
  ASSERT_TRUE(run_part_file(dir, read, 3, 2, error)) << error;
  ASSERT_TRUE(read_file(part_path(dir, 3, "nodes"), second, error));
  EXPECT_EQ(first, second);
}

// The share of border points whose job's normal differs by more than 10
// degrees from the in-core one, with and without the halo.
TEST(Partition, NormalsAtBordersMatchTheInCoreRun) {
  const PointCloud cloud = terrain(60000);
  EncodeOptions o;
  o.partition_points = 6000;
  for (const bool halo : {true, false}) {
    const std::string dir = folder(halo ? "halo" : "nohalo");
    PartitionPlan plan;
    std::string error;
    PointCloud copy = cloud;
    ASSERT_TRUE(make_plan(copy, o, plan, error)) << error;
    ASSERT_TRUE(plan.estimate);
    ASSERT_GT(plan.halo, 0.0);
    if (!halo) plan.halo = 0;
    ASSERT_TRUE(route_points(copy, plan, dir, error)) << error;
    PointCloud whole = cloud;
    estimate_normals(whole, plan.normal_neighbours, plan.frame);
    // In-core normals by position (the terrain's positions are distinct).
    std::map<std::array<double, 3>, Vec3> truth;
    for (size_t i = 0; i < whole.size(); ++i) truth[{whole.positions[i].x(), whole.positions[i].y(), whole.positions[i].z()}] = whole.normals[i];
    size_t compared = 0, off = 0, border = 0, border_off = 0, border_moved = 0;
    for (uint32_t p = 0; p < plan.partitions(); ++p) {
      PointCloud part;
      size_t own = 0;
      ASSERT_TRUE(load_part_points(dir, plan, p, part, own, error)) << error;
      // Border: within 0.4 m (about two k-NN radii) of a plane the point
      // went by.
      std::vector<bool> near(own, false);
      for (size_t i = 0; i < own; ++i)
        for (uint32_t t = 0; !plan.top[t].leaf();) {
          const TopNode& node = plan.top[t];
          const double s = node.normal.dot(part.positions[i]) - node.offset;
          near[i] = near[i] || std::abs(s) < 0.4;
          t = node.first_child + (s > 0);
        }
      estimate_part_normals(part, own, plan, 2);
      for (size_t i = 0; i < own; ++i) {
        const Vec3& q = part.positions[i];
        const Vec3 want = truth.at({q.x(), q.y(), q.z()});
        const bool bad = part.normals[i].dot(want) < std::cos(10 * M_PI / 180);
        border_moved += near[i] && part.normals[i].dot(want) < std::cos(1e-6);  // other neighbours
        ++compared;
        off += bad;
        border += near[i];
        border_off += near[i] && bad;
      }
    }
    ASSERT_EQ(compared, cloud.size());
    ASSERT_GT(border, 2000u);
    const double share = static_cast<double>(border_off) / static_cast<double>(border);
    const double moved = static_cast<double>(border_moved) / static_cast<double>(border);
    std::printf("halo %s: of %zu border points %.3f %% off by more than 10 degrees, %.2f %% moved at all; %zu of all off\n",
                halo ? "on" : "off", border, 100 * share, 100 * moved, off);
    if (halo) {
      EXPECT_LE(share, 0.005);  // the bound
      EXPECT_LE(moved, 0.001);  // the same neighbours, the same normal
    } else {
      EXPECT_GT(moved, 0.05);  // the halo is what holds the border
    }
  }
}

// Normals scattered about `axis` by up to `spread` radians.
std::vector<Vec3> normals_about(const Vec3& axis, double spread, size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> out;
  const Vec3 t1 = any_perpendicular(axis), t2 = axis.cross(t1);
  for (size_t i = 0; i < n; ++i) {
    const double a = spread * u(rng), b = 0.4 * spread * u(rng);
    out.push_back((axis + std::tan(a) * t1 + std::tan(b) * t2).normalized());
  }
  return out;
}

// An upper node's turn from its children's (their own and their means'
// offsets) keeps the sign a whole bowl or dome has, near its size.
TEST(Partition, UpperNodesKeepTheCurvaturesSign) {
  for (const double k : {0.4, -0.4}) {
    const PointCloud patch = quadric_patch(41, k, 0.5 * k);
    std::vector<uint32_t> left, right, all(patch.size());
    for (uint32_t i = 0; i < patch.size(); ++i) {
      (patch.positions[i].x() < 0 ? left : right).push_back(i);
      all[i] = i;
    }
    NodeStats children[2] = {node_stats(patch, left.data(), left.size(), StatsOptions{}),
                             node_stats(patch, right.data(), right.size(), StatsOptions{})};
    const NodeStats whole = node_stats(patch, all.data(), all.size(), StatsOptions{});
    Vec3 sum = Vec3::Zero();
    for (const Vec3& n : patch.normals) sum += n;
    const double counts[2] = {static_cast<double>(left.size()), static_cast<double>(right.size())};
    const NormalSpread merged = combine_normal_spreads(children, counts, 2, sum, Vec3::UnitZ());
    for (int a = 0; a < 2; ++a) {
      EXPECT_EQ(merged.turn[a] > 0, k < 0) << k << " axis " << a;  // a dome (k < 0) is convex
      EXPECT_NEAR(merged.turn[a], whole.turn[a], 0.25 * std::abs(whole.turn[a])) << k << " axis " << a;
    }
  }
}

TEST(Partition, UpperNodesNeverUnderstateTheirNormalSpread) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 axis_a = Vec3(u(rng), u(rng), u(rng)).normalized();
    const Vec3 axis_b = (axis_a + 0.8 * Vec3(u(rng), u(rng), u(rng))).normalized();
    const double spread_a = 0.02 + 0.6 * (u(rng) + 1), spread_b = 0.02 + 0.3 * (u(rng) + 1);
    const std::vector<Vec3> a = normals_about(axis_a, spread_a, 300, 10 + trial);
    const std::vector<Vec3> b = normals_about(axis_b, spread_b, 100 + trial, 1000 + trial);
    std::vector<Vec3> all = a;
    all.insert(all.end(), b.begin(), b.end());
    Vec3 sum_a = Vec3::Zero(), sum_b = Vec3::Zero();
    for (const Vec3& v : a) sum_a += v;
    for (const Vec3& v : b) sum_b += v;
    const NormalSpread sa = normal_spread(a.data(), a.size(), Vec3::UnitZ());
    const NormalSpread sb = normal_spread(b.data(), b.size(), Vec3::UnitZ());
    const NormalSpread truth = normal_spread(all.data(), all.size(), Vec3::UnitZ());
    NodeStats children[2];
    children[0].normal_frame = sa.frame;
    children[0].sigma_n = sa.sigma;
    children[1].normal_frame = sb.frame;
    children[1].sigma_n = sb.sigma;
    const double counts[2] = {static_cast<double>(a.size()), static_cast<double>(b.size())};
    const NormalSpread merged = combine_normal_spreads(children, counts, 2, sum_a + sum_b, Vec3::UnitZ());
    ASSERT_NEAR(merged.frame.col(2).dot(truth.frame.col(2)), 1.0, 1e-12);
    // The RMS angle bounds the truth's; and stays near it (within 2x).
    EXPECT_GE(merged.sigma.norm(), truth.sigma.norm() * (1 - 1e-9)) << "trial " << trial;
    EXPECT_LE(merged.sigma.norm(), 2 * truth.sigma.norm() + 0.05) << "trial " << trial;
  }
}

TEST(Partition, ACorruptMissingOrForeignPartIsNamed) {
  const PointCloud cloud = terrain(20000);
  EncodeOptions o;
  o.partition_points = 4000;
  const std::string dir = folder("faults");
  const PartitionPlan plan = plan_into(cloud, o, dir);
  std::string error;
  for (uint32_t i = 0; i < plan.partitions(); ++i) ASSERT_TRUE(run_part_file(dir, plan, i, 2, error)) << error;
  ASSERT_FALSE(merge_dir(dir, error).empty()) << error;

  // One byte changed in the middle of a part.
  const std::string part1 = part_path(dir, 1, "nodes");
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(read_file(part1, bytes, error));
  bytes[bytes.size() / 2] ^= 0x10;
  ASSERT_TRUE(write_file_atomic(part1, bytes, error));
  EXPECT_TRUE(merge_dir(dir, error).empty());
  EXPECT_NE(error.find("part-00001.nodes: CRC-32 mismatch"), std::string::npos) << error;

  // Cut short (a job killed while writing leaves no part: the write is
  // atomic; a copy cut short is refused the same way).
  bytes[bytes.size() / 2] ^= 0x10;
  bytes.resize(bytes.size() - 100);
  ASSERT_TRUE(write_file_atomic(part1, bytes, error));
  EXPECT_TRUE(merge_dir(dir, error).empty());
  EXPECT_NE(error.find("part-00001.nodes"), std::string::npos) << error;

  // Missing: the message says which job to run.
  fs::remove(part1);
  EXPECT_TRUE(merge_dir(dir, error).empty());
  EXPECT_NE(error.find("part-00001.nodes: No such file or directory (has its job run? stipple encode-part"),
            std::string::npos) << error;

  // Another partition's result under this name.
  fs::copy_file(part_path(dir, 2, "nodes"), part1);
  EXPECT_TRUE(merge_dir(dir, error).empty());
  EXPECT_NE(error.find("part-00001.nodes: is another partition's result"), std::string::npos) << error;

  // The points of a job cut in the middle of a point.
  const std::string pts = part_path(dir, 0, "pts");
  ASSERT_TRUE(read_file(pts, bytes, error));
  bytes.resize(bytes.size() - 10);
  ASSERT_TRUE(write_file_atomic(pts, bytes, error));
  EXPECT_FALSE(run_part_file(dir, plan, 0, 2, error));
  EXPECT_NE(error.find("part-00000.pts: "), std::string::npos) << error;
  EXPECT_NE(error.find("cut short, or from another plan"), std::string::npos) << error;

  // A plan changed on disk.
  const std::string plan_file = (fs::path(dir) / "plan.bin").string();
  ASSERT_TRUE(read_file(plan_file, bytes, error));
  bytes[40] ^= 1;
  ASSERT_TRUE(write_file_atomic(plan_file, bytes, error));
  PartitionPlan broken;
  EXPECT_FALSE(read_plan(dir, broken, error));
  EXPECT_NE(error.find("plan.bin: CRC-32 mismatch"), std::string::npos) << error;

  // A plan an older stipple made (before the tolerance's fields).
  bytes[40] ^= 1;
  bytes[7] = '1';
  ASSERT_TRUE(write_file_atomic(plan_file, bytes, error));
  EXPECT_FALSE(read_plan(dir, broken, error));
  EXPECT_NE(error.find("plan.bin: a plan of an older stipple (SPGPLAN1; this one reads SPGPLAN2): plan the scan again"),
            std::string::npos)
      << error;
}

TEST(Partition, TheTemporaryFolderGoesAwayOnSuccessAndOnFailure) {
  const std::string dir = folder("tmp");
  const PointCloud cloud = terrain(20000);
  EncodeOptions o;
  o.partition_points = 4000;
  o.tmp_dir = dir;
  EncodeReport report;
  std::string error;
  PointCloud copy = cloud;
  ASSERT_TRUE(encode_to_file(copy, o, dir + "/out.spg", report, error)) << error;
  EXPECT_GT(report.partitions, 1u);
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.path().filename() != "out.spg";
  EXPECT_EQ(entries, 0u);
  // A failure (the output's folder does not exist) leaves nothing either.
  copy = cloud;
  EXPECT_FALSE(encode_to_file(copy, o, dir + "/missing/out.spg", report, error));
  EXPECT_NE(error.find("missing/out.spg"), std::string::npos) << error;
  entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) entries += e.path().filename() != "out.spg";
  EXPECT_EQ(entries, 0u);
}

TEST(Partition, ACountPast32BitsIsRefusedBeforeAnyJob) {
  // What a reader's pass over 2^32 points leaves (the sample is all it keeps).
  PlanSampler sampler;
  sampler.add(terrain(1000));
  sampler.count = uint64_t{1} << 32;
  PartitionPlan plan;
  std::string error;
  EXPECT_FALSE(finish_plan(sampler, ScanFacts{}, EncodeOptions{}, plan, error));
  EXPECT_EQ(error, "the scan has 4294967296 points; a .spg counts them in 32 bits (at most 4,294,967,295)");
  sampler.count = 0xFFFFFFFFu;  // the most a .spg holds: planned
  EncodeOptions o;
  o.partition_points = uint64_t{1} << 28;
  EXPECT_TRUE(finish_plan(sampler, ScanFacts{}, o, plan, error)) << error;
  EXPECT_GT(plan.partitions(), 8u);
}

TEST(Partition, TheMemoryBudgetSetsThePartitionSize) {
  EXPECT_GE(partition_points_for(EncodeOptions{}), uint64_t{1} << 16);
  EncodeOptions o;
  o.memory = uint64_t{1} << 30;
  EXPECT_EQ(partition_points_for(o), (uint64_t{1} << 30) / 256);
  o.partition_points = 5000;
  EXPECT_EQ(partition_points_for(o), 5000u);
}

// A LAS 1.2 file of point format 2 (RGB): positions at 1 mm, 8-bit colours
// stored in 16 bits (as many writers do).
void write_las(const std::string& path, const PointCloud& cloud) {
  std::vector<uint8_t> out(227, 0);
  std::memcpy(out.data(), "LASF", 4);
  out[24] = 1;
  out[25] = 2;
  const uint16_t header = 227, record = 26;
  std::memcpy(&out[94], &header, 2);
  const uint32_t offset = 227, count = static_cast<uint32_t>(cloud.size());
  std::memcpy(&out[96], &offset, 4);
  out[104] = 2;
  std::memcpy(&out[105], &record, 2);
  std::memcpy(&out[107], &count, 4);
  const double scale[3] = {0.001, 0.001, 0.001}, shift[3] = {500000, 5000000, 100};
  std::memcpy(&out[131], scale, 24);
  std::memcpy(&out[155], shift, 24);
  for (size_t i = 0; i < cloud.size(); ++i) {
    uint8_t r[26] = {};
    for (int a = 0; a < 3; ++a) {
      const int32_t v = static_cast<int32_t>(std::lround(cloud.positions[i][a] * 1000));
      std::memcpy(r + 4 * a, &v, 4);
    }
    for (int c = 0; c < 3; ++c) {
      const uint16_t v = static_cast<uint16_t>((i * (c + 3)) % 256);
      std::memcpy(r + 20 + 2 * c, &v, 2);
    }
    out.insert(out.end(), r, r + 26);
  }
  std::string error;
  ASSERT_TRUE(write_file_atomic(path, out, error)) << error;
}

// A PLY (double positions, normals, colours) and a LAS of 150,000 points:
// three chunks and a bit.
std::vector<std::string> big_scans(const std::string& dir) {
  PointCloud c = terrain(150000);
  for (size_t i = 0; i < c.size(); ++i) {
    c.normals.push_back(Vec3(0.1, 0.2, 1).normalized());
    c.colors.push_back(Vec3(static_cast<double>(i % 256) / 255, 0.5, 1.0));
  }
  std::string error;
  const std::string ply = dir + "/big.ply", las = dir + "/big.las";
  EXPECT_TRUE(write_ply(ply, c, error)) << error;
  write_las(las, c);
  // Text whose columns 4-6 only the whole file tells apart (colours here,
  // normals there), and an ascii PCD.
  std::ofstream rgb(dir + "/big_rgb.txt"), nrm(dir + "/big_normals.xyz"), pcd(dir + "/big.pcd");
  pcd << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << c.size()
      << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << c.size() << "\nDATA ascii\n";
  char line[160];
  for (size_t i = 0; i < c.size(); ++i) {
    const Vec3& p = c.positions[i];
    std::snprintf(line, sizeof line, "%.4f %.4f %.4f", p.x(), p.y(), p.z());
    rgb << line << " " << i % 256 << " 128 7\n";
    nrm << line << " 0.1 0.2 0.97\n";
    pcd << line << "\n";
  }
  return {ply, las, dir + "/big_rgb.txt", dir + "/big_normals.xyz", dir + "/big.pcd"};
}

TEST(ScanStream, ChunksAreTheWholeReadInPieces) {
  for (const std::string& path : big_scans(folder("chunks"))) {
    PointCloud whole, rest, joined;
    std::string error;
    ASSERT_TRUE(read_point_cloud(path, whole, error)) << error;
    ScanStream stream;
    std::vector<uint64_t> firsts;
    uint64_t last_bytes = 0;
    stream.deliver = [&](PointCloud& chunk, uint64_t first, uint64_t bytes, std::string&) {
      EXPECT_LE(chunk.size(), kScanChunk);
      EXPECT_EQ(first, joined.size());
      EXPECT_GT(bytes, last_bytes);
      last_bytes = bytes;
      firsts.push_back(first);
      joined.positions.insert(joined.positions.end(), chunk.positions.begin(), chunk.positions.end());
      joined.normals.insert(joined.normals.end(), chunk.normals.begin(), chunk.normals.end());
      joined.colors.insert(joined.colors.end(), chunk.colors.begin(), chunk.colors.end());
      return true;
    };
    ASSERT_TRUE(stream_point_cloud(path, stream, rest, error)) << error;
    EXPECT_EQ(firsts.size(), 3u) << path;  // 65,536 + 65,536 + 18,928
    EXPECT_EQ(stream.delivered, whole.size());
    EXPECT_EQ(joined.positions, whole.positions) << path;
    EXPECT_EQ(rest.warnings, whole.warnings) << path;
    if (stream.text_columns.empty()) {
      EXPECT_EQ(joined.normals, whole.normals) << path;
    }
    // LAS colours come unscaled, then the divisor the whole file decides
    // (8-bit here); PLY's are scaled already.
    EXPECT_EQ(stream.color_divisor, path.ends_with(".las") ? 255.0 : 1.0) << path;
    for (Vec3& c : joined.colors) c /= stream.color_divisor;
    if (path.ends_with(".txt") || path.ends_with(".xyz")) {
      // Columns 4-6 come only once the whole file has told them apart.
      EXPECT_EQ(stream.text_columns, path.ends_with(".txt") ? "x,y,z,r,g,b" : "x,y,z,nx,ny,nz");
      continue;
    }
    EXPECT_EQ(joined.colors, whole.colors) << path;
  }
}

TEST(ScanStream, AFaultInALaterChunkGetsTheWholeReadsMessage) {
  const std::vector<std::string> scans = big_scans(folder("faults_stream"));
  std::string error;
  // Cut in the middle of the second chunk; a coordinate past float32's
  // range at point 100,000.
  std::vector<uint8_t> bytes;
  ASSERT_TRUE(read_file(scans[0], bytes, error));
  const std::string cut = scans[0] + ".cut.ply", wide = scans[0] + ".wide.ply";
  std::vector<uint8_t> part(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() / 2));
  ASSERT_TRUE(write_file_atomic(cut, part, error));
  PointCloud c, rest;
  ASSERT_TRUE(read_point_cloud(scans[0], c, error)) << error;
  c.positions[100000].x() = 1e39;
  ASSERT_TRUE(write_ply(wide, c, error)) << error;
  for (const std::string& path : {cut, wide}) {
    std::string whole_error, stream_error;
    EXPECT_FALSE(read_point_cloud(path, c, whole_error));
    ScanStream stream;
    stream.deliver = [](PointCloud&, uint64_t, uint64_t, std::string&) { return true; };
    EXPECT_FALSE(stream_point_cloud(path, stream, rest, stream_error));
    EXPECT_EQ(stream_error, whole_error);
    EXPECT_NE(stream_error.find(path), std::string::npos) << stream_error;
  }
}

TEST(Partition, AScanReadInChunksGivesTheBytesOfOneReadWhole) {
  const std::string dir = folder("streamed");
  for (const std::string& path : big_scans(dir))
    for (const uint64_t partition : {uint64_t{0}, uint64_t{30000}}) {
      if (partition == 0 && !path.ends_with(".ply") && !path.ends_with(".las")) continue;  // (the time a test may take)
      EncodeOptions o;
      o.partition_points = partition;
      PointCloud cloud;
      std::string error;
      ASSERT_TRUE(read_point_cloud(path, cloud, error)) << error;
      const std::vector<uint8_t> whole = test::encode(cloud, o);
      EncodeReport report;
      std::vector<std::string> warnings;
      ASSERT_TRUE(encode_scan_file(path, ScanOptions{}, o, dir + "/streamed.spg", report, error, nullptr,
                                   [&](const std::vector<std::string>& w) { warnings.insert(warnings.end(), w.begin(), w.end()); }))
          << error;
      EXPECT_EQ(report.partitions > 1, partition > 0);
      std::vector<uint8_t> streamed;
      ASSERT_TRUE(read_file(dir + "/streamed.spg", streamed, error));
      EXPECT_EQ(streamed, whole) << path << " in partitions of " << partition;
      EXPECT_EQ(warnings, cloud.warnings);
    }
}

}  // namespace
}  // namespace stipple
