// The point formula's loops (raster/point_kernel.h): the SIMD lanes of this
// target — SSE2 or NEON, AVX2 where the CPU has it — draw exactly the tile
// words of the scalar loop, for random nodes and nodes at every bound the
// formula states (slopes and depth terms at 16 bits, the depth word's ends,
// sigma_n at 4 rad, the surface and colour terms at their ends, squares clipped
// at the tile's edges), in both word formats, every point size and shading.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "raster/point_kernel.h"
#include "raster/point_kernel_avx2.h"

namespace stipple {
namespace {

constexpr int kTileLog2 = 6, kTile = 1 << kTileLog2;
constexpr int kPx0 = 128, kPy0 = 64;  // the tile's first pixel
constexpr uint32_t kSamples = 256;

struct Tables {
  std::vector<Gaussian3Q12> position, color;
  std::vector<Gaussian2Q12> normal;
  ShadingTables shading;
  std::vector<uint64_t> lanes;
  PointTables t;
  Tables() : position(kSamples), color(kSamples), normal(kSamples), lanes(point_lane_bytes(kSamples) / 8 + 1) {
    build_gaussian3_table(GaussianSource::kSobol, position.data(), kSamples);
    build_gaussian3_table(GaussianSource::kSobol, color.data(), kSamples, kColorSobolDim);
    build_gaussian2_table(GaussianSource::kSobol, normal.data(), kSamples);
    EXPECT_TRUE(build_shading_tables(Lighting{}, &shading));
    t = PointTables{position.data(), normal.data(), color.data(), &shading};
    build_point_lanes(position.data(), normal.data(), color.data(), kSamples, lanes.data(), &t);
  }
};

int16_t bounded(std::mt19937& rng, int32_t limit) {  // uniform in [-limit, limit]
  return static_cast<int16_t>(static_cast<int32_t>(rng() % (2u * static_cast<uint32_t>(limit) + 1)) - limit);
}

// Three values whose magnitudes sum below 2^15 (the tile pass's slopes).
void slopes(std::mt19937& rng, int16_t m[4], bool extreme) {
  int32_t left = extreme ? 32767 : static_cast<int32_t>(rng() % 32768);
  for (int k = 0; k < 3; ++k) {
    const int32_t v = k == 2 ? left : static_cast<int32_t>(rng() % static_cast<uint32_t>(left + 1));
    m[k] = static_cast<int16_t>(rng() & 1 ? -v : v);
    left -= v;
  }
  m[3] = 0;
}

// A node as PointRenderer::draw_node files it: the span from the slopes,
// the depths inside the word.
TileNode random_node(std::mt19937& rng, int size, bool extreme) {
  TileNode n;
  slopes(rng, n.mx, extreme && rng() % 2);
  slopes(rng, n.my, extreme && rng() % 2);
  for (int k = 0; k < 3; ++k) n.dz[k] = extreme && rng() % 2 ? (rng() & 1 ? 32767 : -32768) : bounded(rng, 32767);
  n.dshift = static_cast<uint8_t>(extreme && rng() % 2 ? (rng() & 1 ? 0 : 12) : rng() % 13);
  const int64_t reach = ((int64_t{std::abs(n.dz[0])} + std::abs(n.dz[1]) + std::abs(n.dz[2])) * kGaussianClip) >> n.dshift;
  const int64_t lo = reach + 1, hi = int64_t{0xFFFFFFFE} - reach;
  const int64_t pick = extreme && rng() % 2 ? (rng() & 1 ? lo : hi) : lo + static_cast<int64_t>(rng() % static_cast<uint64_t>(hi - lo + 1));
  n.depth0 = static_cast<uint32_t>(pick);
  // The mean anywhere the node still touches the tile or its neighbours.
  n.x0_q4 = (kPx0 - 24) * 16 + static_cast<int32_t>(rng() % ((kTile + 48) * 16));
  n.y0_q4 = (kPy0 - 24) * 16 + static_cast<int32_t>(rng() % ((kTile + 48) * 16));
  const auto span = [&](int32_t p0, const int16_t m[4], int16_t* out) {
    const int64_t d = ((int64_t{std::abs(m[0])} + std::abs(m[1]) + std::abs(m[2])) * kGaussianClip) >> 16;
    out[0] = static_cast<int16_t>((p0 - d - 1) >> 4);
    out[1] = static_cast<int16_t>(((p0 + d) >> 4) + size - 1);
  };
  span(n.x0_q4, n.mx, n.span);
  span(n.y0_q4, n.my, n.span + 2);
  n.count = static_cast<uint16_t>(extreme && rng() % 2 ? kSamples : 1 + rng() % 40);
  PointShade& s = n.shade;
  // A third of the nodes turn their normals gently, as nearly every real one
  // does: no angle needs its clamp (angles_in_range), up to that bound exactly.
  const bool gentle = rng() % 3 == 0;
  constexpr int32_t kGentle = (int32_t{1} << 26) / kGaussianClip;
  for (int k = 0; k < 2; ++k)
    s.sn[k] = static_cast<int16_t>(gentle ? (extreme && rng() % 2 ? kGentle : rng() % (kGentle + 1))
                                          : extreme && rng() % 2 ? 16384 : rng() % 16385);
  // (L.t1, L.t2, L.n0) and (H.t1, H.t2, H.n0): a unit vector in the
  // node's frame, as light_terms gives (Q14 tangents, Q12 normal), all
  // tangential or all normal at the extremes. (The scalar loops index the
  // intensity tables unclamped for such vectors: lit_entry_q26.)
  for (auto [t, n0] : {std::pair{s.lt, &s.l0}, std::pair{s.ht, &s.h0}}) {
    const double a = static_cast<double>(rng() % 6283) / 1000.0;
    const double r = extreme && rng() % 2 ? (rng() & 1 ? 1.0 : 0.0) : static_cast<double>(rng() % 1001) / 1000.0;
    t[0] = static_cast<int16_t>(std::lround(16384 * r * std::cos(a) * 0.9999));
    t[1] = static_cast<int16_t>(std::lround(16384 * r * std::sin(a) * 0.9999));
    *n0 = static_cast<int16_t>(std::lround((rng() & 1 ? 4096 : -4096) * std::sqrt(1 - r * r) * 0.9999));
  }
  for (auto& row : s.surface) {
    if (gentle) {  // |row| summing to at most kGentle: slopes() scaled
      int32_t left = extreme && rng() % 2 ? kGentle : static_cast<int32_t>(rng() % (kGentle + 1));
      for (int k = 0; k < 3; ++k) {
        const int32_t v = k == 2 ? left : static_cast<int32_t>(rng() % static_cast<uint32_t>(left + 1));
        row[k] = static_cast<int16_t>(rng() & 1 ? -v : v);
        left -= v;
      }
    } else {
      for (int16_t& v : row) v = extreme && rng() % 2 ? (rng() & 1 ? 16416 : -16416) : bounded(rng, 16416);
    }
  }
  for (auto& row : s.ca)
    for (int16_t& v : row) v = extreme && rng() % 2 ? (rng() & 1 ? 32767 : -32767) : bounded(rng, 32767);
  s.base_rgb = rng() & 0xFFFFFF;
  s.intensity = static_cast<uint16_t>(64 + rng() % 193);
  s.specular = static_cast<uint16_t>(rng() % 256);
  s.node_rgb = rng() & 0xFFFFFF;
  return n;
}

template <class Word>
std::vector<Word> fresh_tile(uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Word> words(kTile * kTile);
  for (Word& w : words) w = static_cast<Word>((uint64_t{rng()} << 32 | rng()) | (sizeof(Word) == 8 ? uint64_t{1} << 63 : 0));
  return words;
}

template <PointNormals kNormals, bool kColor, bool kSpecular, class Word>
void compare(const Tables& tables, const std::vector<TileNode>& nodes, int size, const char* what) {
  const std::vector<Word> start = fresh_tile<Word>(static_cast<uint32_t>(nodes.size()));
  std::vector<uint64_t> storage(TileNodes::bytes(static_cast<uint32_t>(nodes.size())) / 8 + 1);
  TileNodes rows;
  rows.init(storage.data(), static_cast<uint32_t>(nodes.size()));
  std::vector<uint32_t> list(nodes.size());
  for (uint32_t i = 0; i < nodes.size(); ++i) {
    rows.store(i, nodes[i]);
    list[i] = i;
  }
  std::vector<Word> scalar = start, lanes = start;
  for (uint32_t i = 0; i < nodes.size(); ++i) {
    const TileRow n(rows.row(i));
    draw_tile_node_scalar<kNormals, kColor, kSpecular>(n, tables.t, size, scalar.data(), kTileLog2, kPx0, kPy0);
    draw_tile_node<kNormals, kColor, kSpecular>(n, tables.t, size, lanes.data(), kTileLog2, kPx0, kPy0);
  }
  ASSERT_NE(scalar, start) << what << ": no point drew";
  EXPECT_EQ(scalar, lanes) << what << ", " << size << " px: the baseline lanes differ from the scalar loop";
  if constexpr (avx2::kBuilt) {
    if (!avx2::supported()) return;
    std::vector<Word> wide = start;
    avx2::draw_tile<kNormals, kColor, kSpecular>(rows, list.data(), static_cast<uint32_t>(list.size()), tables.t, size,
                                                 wide.data(), kTileLog2, kPx0, kPy0);
    EXPECT_EQ(scalar, wide) << what << ", " << size << " px: the AVX2 lanes differ from the scalar loop";
  }
}

template <class Word>
void every_mode(const Tables& tables, const std::vector<TileNode>& nodes, int size) {
  compare<PointNormals::kNode, false, false, Word>(tables, nodes, size, "per node");
  compare<PointNormals::kNode, true, true, Word>(tables, nodes, size, "per node, colour");
  compare<PointNormals::kSampled, false, true, Word>(tables, nodes, size, "sampled");
  compare<PointNormals::kSampled, true, false, Word>(tables, nodes, size, "sampled, colour, no specular");
  compare<PointNormals::kSurface, false, true, Word>(tables, nodes, size, "surface");
  compare<PointNormals::kSurface, true, true, Word>(tables, nodes, size, "surface, colour");
}

TEST(PointKernel, LanesDrawTheScalarWordsForRandomAndExtremeNodes) {
  const Tables tables;
  for (int size = 1; size <= 3; ++size) {
    for (bool extreme : {false, true}) {
      std::mt19937 rng(static_cast<uint32_t>(size * 7 + extreme));
      std::vector<TileNode> nodes;
      for (int i = 0; i < 400; ++i) nodes.push_back(random_node(rng, size, extreme));
      every_mode<uint32_t>(tables, nodes, size);
      every_mode<uint64_t>(tables, nodes, size);
    }
  }
}

TEST(PointKernel, AnglesInRangeNeedNoClampUpToTheirBound) {
  // At the bound every sample's angles stay within +-4 rad, so the colours
  // are the clamped formula's; one step past it the clamp is kept.
  const Tables tables;
  constexpr int16_t kBound = (int32_t{1} << 26) / kGaussianClip;
  PointShade s;
  s.lt[0] = 9000;
  s.lt[1] = -7000;
  s.ht[0] = -5000;
  s.ht[1] = 12000;
  s.l0 = 3000;
  s.h0 = -1000;
  s.base_rgb = 0x806040;
  for (int sign : {1, -1}) {
    s.sn[0] = s.sn[1] = static_cast<int16_t>(sign * kBound);
    s.surface[0][0] = static_cast<int16_t>(sign * kBound);
    s.surface[0][1] = s.surface[0][2] = 0;
    s.surface[1][0] = static_cast<int16_t>(-sign * (kBound - 1000));
    s.surface[1][1] = static_cast<int16_t>(sign * 600);
    s.surface[1][2] = static_cast<int16_t>(-sign * 400);
    const PackedShade p(s);
    ASSERT_TRUE(angles_in_range<PointNormals::kSampled>(p));
    ASSERT_TRUE(angles_in_range<PointNormals::kSurface>(p));
    for (uint32_t j = 0; j < kSamples; ++j) {
      const uint32_t g01 = tables.t.g01[j], g2 = tables.t.g2[j];
      EXPECT_EQ((point_color<PointNormals::kSampled, true, true, false, true>(p, tables.t, j, g01, g2)),
                (point_color<PointNormals::kSampled, true, true, false, false>(p, tables.t, j, g01, g2)))
          << "sample " << j;
      EXPECT_EQ((point_color<PointNormals::kSurface, true, true, false, true>(p, tables.t, j, g01, g2)),
                (point_color<PointNormals::kSurface, true, true, false, false>(p, tables.t, j, g01, g2)))
          << "sample " << j;
    }
    s.sn[1] = static_cast<int16_t>(sign * (kBound + 1));
    EXPECT_FALSE(angles_in_range<PointNormals::kSampled>(PackedShade(s)));
    s.surface[1][2] = static_cast<int16_t>(-sign * 401);
    EXPECT_FALSE(angles_in_range<PointNormals::kSurface>(PackedShade(s)));
  }
}

// Both loops keep every point within the span its node was filed with: a
// point outside would be drawn into the wrong tile's words (the checked
// build traps on it in the scalar loop).
TEST(PointKernel, EveryPointFallsWithinItsNodesSpan) {
  const Tables tables;
  std::mt19937 rng(5);
  for (int i = 0; i < 2000; ++i) {
    const int size = 1 + i % 3;
    const TileNode n = random_node(rng, size, i % 2 == 0);
    for (uint32_t j = 0; j < n.count; ++j) {
      const Gaussian3Q12 g = tables.position[j];
      const int32_t x = (n.x0_q4 + ((n.mx[0] * g.v[0] + n.mx[1] * g.v[1] + n.mx[2] * g.v[2]) >> 16)) >> 4;
      const int32_t y = (n.y0_q4 + ((n.my[0] * g.v[0] + n.my[1] * g.v[1] + n.my[2] * g.v[2]) >> 16)) >> 4;
      ASSERT_GE(x, n.span[0]);
      ASSERT_LE(x + size - 1, n.span[1]);
      ASSERT_GE(y, n.span[2]);
      ASSERT_LE(y + size - 1, n.span[3]);
    }
  }
}

// Every field store writes is where the loops' view of a row (TileRow,
// PackedShade) reads it back.
TEST(PointKernel, TileNodesStoreEveryFieldWhereTheLoopsReadIt) {
  std::mt19937 rng(9);
  std::vector<uint64_t> storage(TileNodes::bytes(16) / 8 + 1);
  TileNodes rows;
  rows.init(storage.data(), 16);
  for (uint32_t i = 0; i < 16; ++i) {
    const TileNode n = random_node(rng, 2, i % 2 == 1);
    rows.store(i, n);
    const TileRow r(rows.row(i));
    const TileField pairs[3][2] = {{TileField::kMx01, TileField::kMx2},
                                   {TileField::kMy01, TileField::kMy2},
                                   {TileField::kDz01, TileField::kDz2}};
    const int16_t* terms[3] = {n.mx, n.my, n.dz};
    for (int v = 0; v < 3; ++v) {
      EXPECT_EQ(r.lo(pairs[v][0]), terms[v][0]);
      EXPECT_EQ(r.hi(pairs[v][0]), terms[v][1]);
      EXPECT_EQ(r.lo(pairs[v][1]), terms[v][2]);
      EXPECT_EQ(r.hi(pairs[v][1]), terms[v][3]);
    }
    EXPECT_EQ(r.lo(TileField::kSpanX), n.span[0]);
    EXPECT_EQ(r.hi(TileField::kSpanX), n.span[1]);
    EXPECT_EQ(r.lo(TileField::kSpanY), n.span[2]);
    EXPECT_EQ(r.hi(TileField::kSpanY), n.span[3]);
    EXPECT_EQ(r.x0_q4(), n.x0_q4);
    EXPECT_EQ(r.y0_q4(), n.y0_q4);
    EXPECT_EQ(r.depth0(), n.depth0);
    EXPECT_EQ(r.count(), n.count);
    EXPECT_EQ(r.dshift(), n.dshift);
    for (int px0 : {n.span[0] - 1, static_cast<int>(n.span[0])})
      for (int py0 : {n.span[2] - 1, static_cast<int>(n.span[2])})
        EXPECT_EQ(r.inside_tile(px0, py0, 64),
                  n.span[0] >= px0 && n.span[1] < px0 + 64 && n.span[2] >= py0 && n.span[3] < py0 + 64);
    // The shading terms: the same packed terms as the binned path's from
    // the node's PointShade (every field of it, in pairs), and the colours whole.
    const PointShade& s = n.shade;
    const PackedShade from_row(r), from_shade(s);
    EXPECT_EQ(0, std::memcmp(&from_row, &from_shade, sizeof(PackedShade)));
    EXPECT_EQ(r[TileField::kBaseRgb], s.base_rgb);
    EXPECT_EQ(r[TileField::kNodeRgb], s.node_rgb);
    EXPECT_EQ(r[TileField::kLighting], s.intensity | uint32_t{s.specular} << 16);
  }
}

}  // namespace
}  // namespace stipple
