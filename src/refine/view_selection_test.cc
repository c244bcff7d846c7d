#include "refine/view_selection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <list>
#include <numeric>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "geometry/mesh.h"
#include "geometry/primitives.h"

namespace mr {
namespace {

// Views on the upper half of a sphere (a Fibonacci spiral), each with its k
// nearest views as neighbours, numbered in a random order (as COLMAP's image
// ids can be).
std::vector<std::vector<int>> HemisphereNeighbors(int n, int k, unsigned seed) {
  std::vector<Eigen::Vector3d> p(n);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (i + 0.5) / n;  // (0, 1]
    const double r = std::sqrt(1.0 - z * z);
    p[i] = Eigen::Vector3d(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  std::vector<int> id(n);
  std::iota(id.begin(), id.end(), 0);
  std::shuffle(id.begin(), id.end(), std::mt19937(seed));
  std::vector<std::vector<int>> neighbors(n);
  for (int i = 0; i < n; ++i) {
    std::vector<int> others;
    for (int j = 0; j < n; ++j) {
      if (j != i) others.push_back(j);
    }
    std::partial_sort(others.begin(), others.begin() + k, others.end(), [&](int a, int b) {
      return (p[a] - p[i]).squaredNorm() < (p[b] - p[i]).squaredNorm();
    });
    for (int m = 0; m < k; ++m) neighbors[id[i]].push_back(id[others[m]]);
  }
  return neighbors;
}

// Loads of an LRU cache of `capacity` views over one pass of the data term
// (each pair in both directions needs both views).
int LruLoads(const std::vector<std::pair<int, int>>& pairs, int capacity) {
  std::list<int> cache;  // most recent first
  int loads = 0;
  auto get = [&](int v) {
    const auto it = std::find(cache.begin(), cache.end(), v);
    if (it != cache.end()) {
      cache.erase(it);
    } else {
      ++loads;
      if (static_cast<int>(cache.size()) == capacity) cache.pop_back();
    }
    cache.push_front(v);
  };
  for (const auto& [a, b] : pairs) {
    get(a);
    get(b);
  }
  return loads;
}

TEST(NeighborPairs, EveryPairOnceInAnOrderACacheServes) {
  const int n = 100;
  const auto neighbors = HemisphereNeighbors(n, 3, 7);
  const auto pairs = NeighborPairs(neighbors);
  std::set<std::pair<int, int>> expected;
  for (int i = 0; i < n; ++i) {
    for (int j : neighbors[i]) expected.emplace(std::min(i, j), std::max(i, j));
  }
  const std::set<std::pair<int, int>> got(pairs.begin(), pairs.end());
  EXPECT_EQ(got, expected);
  EXPECT_EQ(pairs.size(), expected.size());  // no pair twice
  for (const auto& [a, b] : pairs) EXPECT_LT(a, b);

  // With a cache of 24 views (the renders of 1280x960 views that half of
  // the default --Refine.cache_mb holds), each view is loaded about once; in
  // the order of the image ids most views are loaded twice.
  const std::vector<std::pair<int, int>> by_id(expected.begin(), expected.end());
  const int ordered = LruLoads(pairs, 24), lexicographic = LruLoads(by_id, 24);
  RecordProperty("loads_ordered", ordered);
  RecordProperty("loads_by_id", lexicographic);
  EXPECT_LE(ordered, n + n / 20) << "lexicographic: " << lexicographic;
  EXPECT_GT(lexicographic, ordered + n / 2);
}

TEST(NeighborPairs, SeveralComponentsAndNoNeighbours) {
  // Two separate triangles of views and a view with no neighbour.
  const std::vector<std::vector<int>> neighbors = {{1, 2}, {0, 2}, {0}, {4}, {5, 3}, {3}, {}};
  const auto pairs = NeighborPairs(neighbors);
  const std::set<std::pair<int, int>> got(pairs.begin(), pairs.end());
  const std::set<std::pair<int, int>> expected = {{0, 1}, {0, 2}, {1, 2}, {3, 4}, {3, 5}, {4, 5}};
  EXPECT_EQ(got, expected);
  EXPECT_EQ(pairs.size(), expected.size());
  EXPECT_TRUE(NeighborPairs({}).empty());
  EXPECT_TRUE(NeighborPairs({{}, {}}).empty());
}

TEST(SplitPairsCoveringViews, TwoHalvesEachCoverEveryView) {
  const int n = 100;
  const auto pairs = NeighborPairs(HemisphereNeighbors(n, 3, 7));
  const auto groups = SplitPairsCoveringViews(pairs, 2);
  ASSERT_EQ(groups.size(), 2u);
  // Every pair in exactly one group, each group in the pairs' own order.
  std::multiset<std::pair<int, int>> all;
  for (const auto& group : groups) {
    all.insert(group.begin(), group.end());
    for (size_t k = 1; k < group.size(); ++k) {
      const auto at = [&](size_t m) {
        return std::find(pairs.begin(), pairs.end(), group[m]) - pairs.begin();
      };
      EXPECT_LT(at(k - 1), at(k));
    }
  }
  const std::multiset<std::pair<int, int>> expected(pairs.begin(), pairs.end());
  EXPECT_EQ(all, expected);
  // Each half holds about half the pairs and every view in 2 or more pairs.
  std::vector<int> pairs_of(n, 0);
  for (const auto& [a, b] : pairs) {
    ++pairs_of[a];
    ++pairs_of[b];
  }
  for (const auto& group : groups) {
    EXPECT_NEAR(static_cast<double>(group.size()), pairs.size() / 2.0, pairs.size() / 10.0);
    std::set<int> covered;
    for (const auto& [a, b] : group) {
      covered.insert(a);
      covered.insert(b);
    }
    for (int v = 0; v < n; ++v) {
      if (pairs_of[v] >= 2) {
        EXPECT_TRUE(covered.count(v)) << "view " << v;
      }
    }
  }
  // One group: the pairs as they were; no pairs: empty groups.
  EXPECT_EQ(SplitPairsCoveringViews(pairs, 1)[0], pairs);
  const auto none = SplitPairsCoveringViews({}, 3);
  ASSERT_EQ(none.size(), 3u);
  EXPECT_TRUE(none[0].empty() && none[1].empty() && none[2].empty());
}

TEST(GroupsCoverEveryView, EveryViewInEnoughPairsIsInEveryGroup) {
  const auto pairs = NeighborPairs(HemisphereNeighbors(100, 3, 7));
  EXPECT_TRUE(GroupsCoverEveryView(pairs, SplitPairsCoveringViews(pairs, 2)));
  // A ring of 4 views: (0,1) (1,2) (2,3) (3,0); view 4 in one pair only.
  const std::vector<std::pair<int, int>> ring = {{0, 1}, {1, 2}, {2, 3}, {0, 3}, {3, 4}};
  EXPECT_TRUE(GroupsCoverEveryView(ring, {{{0, 1}, {2, 3}, {3, 4}}, {{1, 2}, {0, 3}}}));
  // View 3 (in 3 pairs) missing from the second group.
  EXPECT_FALSE(GroupsCoverEveryView(ring, {{{0, 1}, {2, 3}, {0, 3}, {3, 4}}, {{1, 2}}}));
  // A group without pairs, even where no view is in two pairs.
  EXPECT_FALSE(GroupsCoverEveryView({{0, 1}}, SplitPairsCoveringViews({{0, 1}}, 2)));
  EXPECT_TRUE(GroupsCoverEveryView({{0, 1}}, {{{0, 1}}}));
}

// Sparse pair graphs, where a greedy split leaves views out (templeSparseRing:
// 12 views in 17 pairs): every view in two or more pairs is in both halves,
// unless a component is an odd cycle, which no split can serve.
TEST(SplitPairsCoveringViews, SparseGraphsAreCoveredUnlessAnOddCycle) {
  std::mt19937 rng(7);
  int graphs = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 6 + trial % 30;
    const int m = n + n / 2 + static_cast<int>(rng() % (n / 2 + 1));
    std::set<std::pair<int, int>> unique;
    for (int v = 0; v < n; ++v) unique.insert({v, (v + 1) % n});  // a ring: connected
    while (static_cast<int>(unique.size()) < m) {
      int a = static_cast<int>(rng() % n), b = static_cast<int>(rng() % n);
      if (a == b) continue;
      unique.insert({std::min(a, b), std::max(a, b)});
    }
    std::vector<std::pair<int, int>> pairs;
    for (const auto& [a, b] : unique) pairs.push_back({std::min(a, b), std::max(a, b)});
    std::shuffle(pairs.begin(), pairs.end(), rng);
    const auto halves = SplitPairsCoveringViews(pairs, 2);
    EXPECT_TRUE(GroupsCoverEveryView(pairs, halves)) << "trial " << trial;
    EXPECT_EQ(halves[0].size() + halves[1].size(), pairs.size());
    ++graphs;
  }
  EXPECT_EQ(graphs, 300);
  // An even cycle splits; an odd one cannot.
  EXPECT_TRUE(GroupsCoverEveryView({{0, 1}, {1, 2}, {2, 3}, {0, 3}},
                                   SplitPairsCoveringViews({{0, 1}, {1, 2}, {2, 3}, {0, 3}}, 2)));
  EXPECT_FALSE(GroupsCoverEveryView({{0, 1}, {1, 2}, {0, 2}},
                                    SplitPairsCoveringViews({{0, 1}, {1, 2}, {0, 2}}, 2)));
}

// A square of half-side `half` at depth z, facing the origin (-z), as a grid
// of n x n cells appended to (V, F).
void AppendSquareFacingOrigin(double half, double z, int n, Eigen::MatrixXd* V,
                              Eigen::MatrixXi* F) {
  AppendGrid(Eigen::Vector3d(-half, -half, z), Eigen::Vector3d(0, 2 * half, 0),
             Eigen::Vector3d(2 * half, 0, 0), n, V, F);
}

// Two squares at depths 10 and 40 that fill the same part of one image: the
// near one gets edges a quarter as long (four half-octave bands apart), and
// the face count is summed over them.
TEST(EdgeSizing, SurfacesInDepthGetBands) {
  const std::vector<PinholeView> views = {LookAtView(Eigen::Vector3d::Zero(),
                                                     Eigen::Vector3d(0, 0, 1),
                                                     Eigen::Vector3d(0, -1, 0), 640, 480, 500)};
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  AppendSquareFacingOrigin(1, 10, 10, &V, &F);
  AppendSquareFacingOrigin(4, 40, 10, &V, &F);
  const double edge_px = 2.5;
  const EdgeSizing sizing(views, V, F, edge_px, 1000000);
  ASSERT_TRUE(sizing.visible());
  // Equal vertex counts: the median is the far footprint, 40 / 500.
  EXPECT_DOUBLE_EQ(sizing.median_footprint(), 40.0 / 500);
  EXPECT_FALSE(sizing.uniform());
  ASSERT_EQ(sizing.band_edges().size(), 5u);  // half-octaves -4 .. 0, the middle ones empty
  EXPECT_DOUBLE_EQ(sizing.band_edges()[0], edge_px * 10.0 / 500);
  EXPECT_DOUBLE_EQ(sizing.band_edges()[2], edge_px * 20.0 / 500);
  EXPECT_DOUBLE_EQ(sizing.band_edges()[4], edge_px * 40.0 / 500);
  const Eigen::Vector3d towards_camera(0, 0, -1);
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(0.3, 0.2, 10), towards_camera), 0);
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(1.2, -0.8, 40), towards_camera), 4);
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(0, 0, 20), towards_camera), 2);
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(0, 0, 14), towards_camera), 1);  // 10 sqrt(2)
  // Unseen (facing away, or outside the image): the longest edges.
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(0.3, 0.2, 10), -towards_camera), 4);
  EXPECT_EQ(sizing.BandOf(Eigen::Vector3d(500, 0, 10), towards_camera), 4);
  const double equilateral = std::sqrt(3.0) / 4;
  const double e0 = sizing.band_edges()[0], e4 = sizing.band_edges()[4];
  const double faces = 4.0 / (equilateral * e0 * e0) + 64.0 / (equilateral * e4 * e4);
  EXPECT_NEAR(sizing.expected_faces(), faces, 1.0);
  EXPECT_EQ(RemeshedFaceCount(views, V, F, edge_px, 1000000), sizing.expected_faces());
  EXPECT_DOUBLE_EQ(sizing.edge_px(), edge_px);
  // A face budget scales every length alike.
  const EdgeSizing budget(views, V, F, edge_px, 1000);
  EXPECT_NEAR(budget.expected_faces(), 1000, 1);  // truncated after the scaling
  EXPECT_NEAR(budget.band_edges()[4] / budget.band_edges()[0], 4.0, 1e-12);
  EXPECT_NEAR(budget.edge_px(), edge_px * std::sqrt(faces / 1000), 1e-9);
}

// An object seen from around lies within one band: one length, the median
// footprint's, as the uniform remeshing always had.
TEST(EdgeSizing, ObjectSeenFromAroundIsUniform) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, &V, &F);
  std::vector<PinholeView> views;
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * M_PI * i / 12;
    views.push_back(LookAtView(Eigen::Vector3d(4 * std::cos(a), 4 * std::sin(a), 2),
                               Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), 640, 480, 500));
  }
  const EdgeSizing sizing(views, V, F, 2.5, 1000000);
  ASSERT_TRUE(sizing.visible());
  EXPECT_TRUE(sizing.uniform());
  EXPECT_DOUBLE_EQ(sizing.band_edges()[0],
                   2.5 * MedianFootprint(views, V, VertexNormals(V, F)));
  // Every view that sees a vertex counts: the median of all their footprints.
  const Eigen::MatrixXd N = VertexNormals(V, F);
  std::vector<double> footprints;
  for (int v = 0; v < V.rows(); ++v) {
    for (const PinholeView& view : views) {
      const Eigen::Vector3d x = V.row(v), xc = view.WorldToCamera(x);
      if (xc.z() > 0 && N.row(v).dot(view.Center() - x) > 0 &&
          view.InImage(view.CameraToImage(xc))) {
        footprints.push_back(xc.z() / view.fx);
      }
    }
  }
  std::nth_element(footprints.begin(), footprints.begin() + footprints.size() / 2, footprints.end());
  EXPECT_DOUBLE_EQ(MedianFootprint(views, V, N), footprints[footprints.size() / 2]);
  // Not seen at all.
  const std::vector<PinholeView> away = {LookAtView(Eigen::Vector3d(10, 0, 0),
                                                    Eigen::Vector3d(20, 0, 0),
                                                    Eigen::Vector3d(0, 0, 1), 640, 480, 500)};
  EXPECT_FALSE(EdgeSizing(away, V, F, 2.5, 1000000).visible());
  EXPECT_EQ(RemeshedFaceCount(away, V, F, 2.5, 1000000), 0);
}

// A unit sphere seen by three rings of views, every other view of each ring
// at `far_distance` instead of 4: close-ups among overview shots.
struct NearAndFarScene {
  Eigen::MatrixXd V, N;
  Eigen::MatrixXi F;
  std::vector<PinholeView> views;
  double near_footprint = 0, far_footprint = 0;  // the near and far views' medians
};

NearAndFarScene MakeNearAndFarScene(double far_distance) {
  NearAndFarScene scene;
  MakeIcosphere(3, 1.0, &scene.V, &scene.F);
  scene.N = VertexNormals(scene.V, scene.F);
  std::vector<PinholeView> near, far;
  for (int ring = -1; ring <= 1; ++ring) {
    const double elevation = ring * M_PI / 3;
    for (int i = 0; i < 12; ++i) {
      const double a = 2 * M_PI * (i + 0.5 * ring) / 12, distance = i % 2 == 0 ? 4 : far_distance;
      const Eigen::Vector3d direction(std::cos(elevation) * std::cos(a),
                                      std::cos(elevation) * std::sin(a), std::sin(elevation));
      scene.views.push_back(LookAtView(distance * direction, Eigen::Vector3d::Zero(),
                                       Eigen::Vector3d(0, 0, 1), 640, 480, 500));
      (i % 2 == 0 ? near : far).push_back(scene.views.back());
    }
  }
  scene.near_footprint = MedianFootprint(near, scene.V, scene.N);
  scene.far_footprint = MedianFootprint(far, scene.V, scene.N);
  return scene;
}

// The pair term compares a near view with a far one at the far one's
// resolution, but two near views at their own. With the far views about
// twice as far, the mesh is sized by the near views, as if the far ones were
// not there.
TEST(EdgeSizing, ViewsFromNearAndFarSizeByTheNearOnes) {
  const NearAndFarScene s = MakeNearAndFarScene(7.5);
  ASSERT_GT(s.far_footprint, 1.8 * s.near_footprint);
  EXPECT_NEAR(MedianFootprint(s.views, s.V, s.N) / s.near_footprint, 1.0, 0.02);
  const EdgeSizing sizing(s.views, s.V, s.F, 2.5, 1000000);
  ASSERT_TRUE(sizing.visible());
  EXPECT_TRUE(sizing.uniform());
  EXPECT_NEAR(sizing.band_edges()[0] / (2.5 * s.near_footprint), 1.0, 0.02);
}

// Close-ups four times sharper than the rest make the mesh an octave finer
// than the median of all the views, not more: the far views, which the
// close-ups are compared with, would see its faces at a fraction of a pixel.
TEST(EdgeSizing, CloseUpsSharpenTheMeshByAnOctaveAtMost) {
  const NearAndFarScene s = MakeNearAndFarScene(16);
  ASSERT_GT(s.far_footprint, 3.5 * s.near_footprint);
  // Each vertex's upper median is a far view's (as many far views as near
  // ones see it, or more), so the sharp views give half of it.
  EXPECT_NEAR(MedianFootprint(s.views, s.V, s.N) / (0.5 * s.far_footprint), 1.0, 0.03);
  // The surface facing the views gets that length, to the bands' 19 %
  // (the close-ups' own footprint would give half of it).
  const EdgeSizing sizing(s.views, s.V, s.F, 2.5, 1000000);
  ASSERT_TRUE(sizing.visible());
  for (int k = 0; k < 24; ++k) {
    const double a = 2 * M_PI * k / 24;
    const Eigen::Vector3d x(std::cos(a), std::sin(a), 0);
    const double edge = sizing.band_edges()[sizing.BandOf(x, x)];
    EXPECT_NEAR(edge / (2.5 * 0.5 * s.far_footprint), 1.0, 0.19) << k;
  }
}

}  // namespace
}  // namespace mr
