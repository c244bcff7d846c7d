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

}  // namespace
}  // namespace mr
