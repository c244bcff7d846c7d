#include "refine/view_selection.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <set>

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "util/error.h"
#include "util/statistics.h"

namespace mr {

bool ViewSelectionOptions::Check() const {
  if (num_neighbors < 1 || num_neighbors > 16) {
    MR_THROW_INPUT << "ViewSelectionOptions::num_neighbors = " << num_neighbors
                   << ". Violated constraint: 1 <= num_neighbors <= 16";
  }
  if (!(0 < min_angle_deg && min_angle_deg < ideal_angle_deg && ideal_angle_deg < max_angle_deg &&
        max_angle_deg < 90)) {
    MR_THROW_INPUT << "ViewSelectionOptions angles = " << min_angle_deg << ", " << ideal_angle_deg
                   << ", " << max_angle_deg
                   << ". Violated constraint: 0 < min_angle_deg < ideal_angle_deg < "
                      "max_angle_deg < 90";
  }
  if (!(min_overlap >= 0 && min_overlap <= 1)) {
    MR_THROW_INPUT << "ViewSelectionOptions::min_overlap = " << min_overlap
                   << ". Violated constraint: 0 <= min_overlap <= 1";
  }
  return true;
}

std::vector<std::vector<int>> SelectNeighbors(const std::vector<PinholeView>& views,
                                              const Eigen::MatrixXd& V,
                                              const Eigen::MatrixXd& N,
                                              const ViewSelectionOptions& options) {
  options.Check();
  const int num_views = static_cast<int>(views.size());
  // Up to ~4000 evenly strided vertex samples keep this cheap for any mesh.
  const int stride = std::max<int>(1, static_cast<int>(V.rows() / 4000));
  std::vector<int> samples;
  for (int v = 0; v < V.rows(); v += stride) samples.push_back(v);

  // seen[i][s]: sample s faces camera i and projects inside image i.
  std::vector<std::vector<char>> seen(num_views, std::vector<char>(samples.size(), 0));
  for (int i = 0; i < num_views; ++i) {
    const Eigen::Vector3d c = views[i].Center();
    for (size_t s = 0; s < samples.size(); ++s) {
      const Eigen::Vector3d x = V.row(samples[s]);
      const Eigen::Vector3d xc = views[i].WorldToCamera(x);
      if (xc.z() <= 0) continue;
      if (N.rows() == V.rows() && N.row(samples[s]).dot(c - x) <= 0) continue;
      if (views[i].InImage(views[i].CameraToImage(xc))) seen[i][s] = 1;
    }
  }

  const double deg = M_PI / 180.0;
  std::vector<std::vector<int>> neighbors(num_views);
  for (int i = 0; i < num_views; ++i) {
    const long num_seen = std::count(seen[i].begin(), seen[i].end(), 1);
    if (num_seen == 0) continue;
    std::vector<std::pair<double, int>> scored;
    for (int j = 0; j < num_views; ++j) {
      if (j == i) continue;
      double score = 0;
      long shared = 0;
      for (size_t s = 0; s < samples.size(); ++s) {
        if (!seen[i][s] || !seen[j][s]) continue;
        ++shared;
        const Eigen::Vector3d x = V.row(samples[s]);
        const Eigen::Vector3d a = (views[i].Center() - x).normalized();
        const Eigen::Vector3d b = (views[j].Center() - x).normalized();
        const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0)) / deg;
        if (angle < options.min_angle_deg || angle > options.max_angle_deg) continue;
        // A Gaussian preference around the ideal angle, wider on the large side.
        const double width = angle < options.ideal_angle_deg
                                 ? options.ideal_angle_deg - options.min_angle_deg
                                 : options.max_angle_deg - options.ideal_angle_deg;
        const double d = (angle - options.ideal_angle_deg) / width;
        score += std::exp(-2.0 * d * d);
      }
      if (shared < options.min_overlap * num_seen || score <= 0) continue;
      scored.emplace_back(score, j);
    }
    std::sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    for (int k = 0; k < std::min<int>(options.num_neighbors, static_cast<int>(scored.size())); ++k) {
      neighbors[i].push_back(scored[k].second);
    }
  }
  return neighbors;
}

namespace {

// Appends the pixel footprint (depth / fx) of point x (normal n) in each of
// `views` that sees it: in front, facing it, inside the image.
void AppendFootprints(const std::vector<PinholeView>& views, const Eigen::Vector3d& x,
                      const Eigen::Vector3d& n, std::vector<double>* footprints) {
  for (const PinholeView& view : views) {
    const Eigen::Vector3d xc = view.WorldToCamera(x);
    if (xc.z() <= 0 || n.dot(view.Center() - x) <= 0) continue;
    if (!view.InImage(view.CameraToImage(xc))) continue;
    footprints->push_back(xc.z() / view.fx);
  }
}

// The upper median of the values (reorders them); 0 if none.
double UpperMedian(std::vector<double>* values) { return values->empty() ? 0 : Median(values); }

// A point's footprints in the views that see it, less those of the views
// that see it coarser than its sharpest pair by more than kSharpSpread: the
// pair term compares such a view with a sharper one at its own, coarser,
// resolution, so it cannot tell the mesh anything finer. Views taken from
// near and far (close-ups among overview shots) leave the far ones out; an
// object seen from around at one distance, whose views see a point over less
// than a factor 1.6 in depth up to 75 degrees off its normal, keeps them all.
// The sharp views make the point's footprint at most an octave finer than
// the upper median of all (the kept values are scaled up to it): close-ups
// three times sharper than the rest, sized by their own footprint, left a
// mesh whose faces the far views see at under a pixel, and the flow flipped
// 13 times as many of them (builtin with alternate_fill_fraction 1.4: normal
// error 0.68x -> 0.94x the input). Sorts the values.
void KeepSharpFootprints(std::vector<double>* footprints) {
  constexpr double kSharpSpread = 1.6817928305074290;    // 2^(3/4)
  constexpr double kMaxSharpening = 2;                   // an octave
  if (footprints->size() < 3) return;
  std::sort(footprints->begin(), footprints->end());
  const double median = (*footprints)[footprints->size() / 2];
  const double limit = kSharpSpread * (*footprints)[1];
  footprints->erase(std::upper_bound(footprints->begin(), footprints->end(), limit),
                    footprints->end());
  const double sharp = (*footprints)[footprints->size() / 2];
  if (sharp * kMaxSharpening < median) {
    for (double& footprint : *footprints) footprint *= median / (kMaxSharpening * sharp);
  }
}

}  // namespace

EdgeSizing::EdgeSizing(std::vector<PinholeView> views, const Eigen::MatrixXd& V,
                       const Eigen::MatrixXi& F, double edge_px, int max_faces)
    : views_(std::move(views)) {
  median_footprint_ = MedianFootprint(views_, V, VertexNormals(V, F));
  if (!(median_footprint_ > 0)) return;
  const Eigen::VectorXd areas = FaceAreas(V, F);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  // Each face's footprint. The bands are centred on the footprint that the
  // most area shares (within half an octave: e.g. the object, where a ground
  // recedes behind it), so that it gets its own length exactly: the
  // area-weighted median of log2(footprint / m) in the half-octave window
  // that holds the most area.
  std::vector<double> footprint(F.rows());
  std::vector<std::pair<double, double>> logs;  // (log2(footprint / m), area)
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    footprint[f] = Footprint(c, N.row(f));
    if (footprint[f] > 0) logs.emplace_back(std::log2(footprint[f] / median_footprint_), areas(f));
  }
  std::sort(logs.begin(), logs.end());
  size_t best_begin = 0, best_end = 0;
  double best_area = -1, window_area = 0;
  for (size_t begin = 0, end = 0; begin < logs.size(); ++begin) {
    for (; end < logs.size() && logs[end].first <= logs[begin].first + kBandWidth; ++end) {
      window_area += logs[end].second;
    }
    if (window_area > best_area) {
      best_area = window_area;
      best_begin = begin;
      best_end = end;
    }
    window_area -= logs[begin].second;
  }
  anchor_ = 0;
  double sum = 0;
  for (size_t i = best_begin; i < best_end; ++i) {
    sum += logs[i].second;
    if (sum >= 0.5 * best_area) {
      anchor_ = logs[i].first;
      break;
    }
  }
  // The bands in use lie between the 1st and the 99th percentile of the
  // seen area (a few faces at the edge of a view's frustum do not add a band
  // to an object).
  std::vector<std::pair<int, double>> seen;  // (band step, area)
  double seen_area = 0;
  for (int f = 0; f < F.rows(); ++f) {
    if (!(footprint[f] > 0)) continue;
    seen.emplace_back(BandStepOf(footprint[f]), areas(f));
    seen_area += areas(f);
  }
  std::sort(seen.begin(), seen.end());
  min_step_ = max_step_ = 0;  // when only vertices are seen
  double below = 0;
  bool found_min = false;
  for (const auto& [k, area] : seen) {
    below += area;
    if (!found_min && below > 0.01 * seen_area) {
      min_step_ = k;
      found_min = true;
    }
    if (below - area < 0.99 * seen_area) max_step_ = k;
  }
  const int num_bands = max_step_ - min_step_ + 1;
  // Each band's area and footprint: m x 2^(anchor + k/2) for band k (one
  // band: m and the whole area, as the uniform remeshing always had).
  std::vector<double> band_area(num_bands, 0.0);
  std::vector<double> band_footprint(num_bands, median_footprint_);
  if (num_bands == 1) {
    band_area[0] = areas.sum();
  } else {
    for (int f = 0; f < F.rows(); ++f) band_area[BandOfFootprint(footprint[f])] += areas(f);
    for (int b = 0; b < num_bands; ++b) {
      band_footprint[b] = median_footprint_ * std::exp2(anchor_ + kBandWidth * (b + min_step_));
    }
  }
  const double equilateral = std::sqrt(3.0) / 4.0;
  for (int b = 0; b < num_bands; ++b) band_edges_.push_back(edge_px * band_footprint[b]);
  auto expected = [&] {
    double faces = 0;
    for (int b = 0; b < num_bands; ++b) {
      faces += band_area[b] / (equilateral * band_edges_[b] * band_edges_[b]);
    }
    return faces;
  };
  // The face budget lengthens every band alike.
  const double faces = expected();
  if (faces > max_faces) {
    for (double& edge : band_edges_) edge *= std::sqrt(faces / max_faces);
  }
  edge_px_ = band_edges_[0] / band_footprint[0];
  expected_faces_ = static_cast<int>(std::min<double>(expected(), max_faces));
}

double EdgeSizing::Footprint(const Eigen::Vector3d& x, const Eigen::Vector3d& n) const {
  std::vector<double> footprints;
  footprints.reserve(views_.size());
  AppendFootprints(views_, x, n, &footprints);
  KeepSharpFootprints(&footprints);
  return UpperMedian(&footprints);
}

int EdgeSizing::BandStepOf(double footprint) const {
  constexpr int kMaxSteps = 20;  // a factor of 1000 either way
  const double steps = std::round((std::log2(footprint / median_footprint_) - anchor_) / kBandWidth);
  return static_cast<int>(std::clamp(steps, -double(kMaxSteps), double(kMaxSteps)));
}

int EdgeSizing::BandOfFootprint(double footprint) const {
  const int step = footprint > 0 ? BandStepOf(footprint) : max_step_;
  return std::clamp(step, min_step_, max_step_) - min_step_;
}

int EdgeSizing::BandOf(const Eigen::Vector3d& x, const Eigen::Vector3d& n) const {
  return BandOfFootprint(Footprint(x, n));
}

int RemeshedFaceCount(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                      const Eigen::MatrixXi& F, double edge_px, int max_faces) {
  const EdgeSizing sizing(views, V, F, edge_px, max_faces);
  return sizing.visible() ? sizing.expected_faces() : 0;
}

bool GroupsCoverEveryView(const std::vector<std::pair<int, int>>& pairs,
                          const std::vector<std::vector<std::pair<int, int>>>& groups) {
  std::map<int, int> pairs_of_view;
  for (const auto& [a, b] : pairs) ++pairs_of_view[a], ++pairs_of_view[b];
  for (const auto& group : groups) {
    if (group.empty()) return false;
    std::set<int> covered;
    for (const auto& [a, b] : group) covered.insert({a, b});
    for (const auto& [view, count] : pairs_of_view) {
      if (count >= static_cast<int>(groups.size()) && covered.count(view) == 0) return false;
    }
  }
  return true;
}

double MedianFootprint(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                       const Eigen::MatrixXd& N) {
  std::vector<double> footprints, point;
  const int stride = std::max<int>(1, static_cast<int>(V.rows() / 5000));
  for (int v = 0; v < V.rows(); v += stride) {
    point.clear();
    AppendFootprints(views, V.row(v), N.row(v), &point);
    KeepSharpFootprints(&point);
    footprints.insert(footprints.end(), point.begin(), point.end());
  }
  return UpperMedian(&footprints);
}

double BestViewCoverage(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                        const Eigen::MatrixXi& F) {
  double best = 0;
  for (const PinholeView& view : views) {
    double area = 0;
    const Eigen::Vector3d center = view.Center();
    for (int f = 0; f < F.rows(); ++f) {
      const Eigen::Vector3d x0 = V.row(F(f, 0)), x1 = V.row(F(f, 1)), x2 = V.row(F(f, 2));
      if ((x1 - x0).cross(x2 - x0).dot(center - x0) <= 0) continue;  // faces away
      Eigen::Vector2d p[3];
      bool in_front = true;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d xc = view.WorldToCamera(V.row(F(f, k)).transpose());
        in_front = in_front && xc.z() > 0;
        p[k] = view.CameraToImage(xc);
      }
      if (!in_front) continue;
      const Eigen::Vector2d lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]);
      const Eigen::Vector2d hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
      if (hi.x() < 0 || hi.y() < 0 || lo.x() > view.width || lo.y() > view.height) continue;
      const Eigen::Vector2d a = p[1] - p[0], b = p[2] - p[0];
      area += 0.5 * std::abs(a.x() * b.y() - a.y() * b.x());
    }
    best = std::max(best, std::min(1.0, area / (double(view.width) * view.height)));
  }
  return best;
}

std::vector<std::pair<int, int>> NeighborPairs(const std::vector<std::vector<int>>& neighbors) {
  const int n = static_cast<int>(neighbors.size());
  std::set<std::pair<int, int>> unique;
  for (int i = 0; i < n; ++i) {
    for (int j : neighbors[i]) {
      if (j != i) unique.emplace(std::min(i, j), std::max(i, j));
    }
  }
  std::vector<std::vector<int>> adjacent(n);
  for (const auto& [a, b] : unique) {
    adjacent[a].push_back(b);
    adjacent[b].push_back(a);
  }
  // Cuthill-McKee: breadth first from a view of least degree, each view's
  // unnumbered neighbours in order of degree, one component after another.
  // Neighbouring views get nearby numbers whatever the input's numbering.
  std::vector<int> position(n, -1);
  int next = 0;
  auto by_degree = [&](int a, int b) {
    return adjacent[a].size() != adjacent[b].size() ? adjacent[a].size() < adjacent[b].size()
                                                    : a < b;
  };
  while (next < n) {
    int start = -1;
    for (int v = 0; v < n; ++v) {
      if (position[v] < 0 && (start < 0 || by_degree(v, start))) start = v;
    }
    std::deque<int> queue = {start};
    position[start] = next++;
    while (!queue.empty()) {
      const int v = queue.front();
      queue.pop_front();
      std::vector<int> fresh;
      for (int w : adjacent[v]) {
        if (position[w] < 0) fresh.push_back(w);
      }
      std::sort(fresh.begin(), fresh.end(), by_degree);
      for (int w : fresh) {
        position[w] = next++;
        queue.push_back(w);
      }
    }
  }
  // By the later view's number, then the earlier's: a view's pairs come
  // while its neighbours, numbered shortly before it, are still cached.
  std::vector<std::pair<int, int>> pairs(unique.begin(), unique.end());
  auto key = [&](const std::pair<int, int>& p) {
    const int a = position[p.first], b = position[p.second];
    return std::make_pair(std::max(a, b), std::min(a, b));
  };
  std::sort(pairs.begin(), pairs.end(),
            [&](const auto& x, const auto& y) { return key(x) < key(y); });
  return pairs;
}

namespace {

// The pairs in two groups by colouring the edges of the pair graph in turn
// along Euler circuits: each visit of a view enters and leaves it by pairs
// of different groups, so every view in two or more pairs is in both,
// except on a component that is an odd cycle. Odd-degree views are first
// joined to one extra vertex, where each circuit of their component starts;
// a component with none starts at a view in the most pairs. Groups in the
// pairs' order.
std::vector<std::vector<std::pair<int, int>>> SplitPairsAlongEulerCircuits(
    const std::vector<std::pair<int, int>>& pairs) {
  int num_views = 0;
  for (const auto& [a, b] : pairs) num_views = std::max({num_views, a + 1, b + 1});
  const int extra = num_views;  // the extra vertex
  std::vector<std::pair<int, int>> edges(pairs.begin(), pairs.end());
  std::vector<std::vector<int>> incident(num_views + 1);
  for (size_t e = 0; e < edges.size(); ++e) {
    incident[edges[e].first].push_back(static_cast<int>(e));
    incident[edges[e].second].push_back(static_cast<int>(e));
  }
  for (int v = 0; v < num_views; ++v) {
    if (incident[v].size() % 2 == 1) {
      incident[v].push_back(static_cast<int>(edges.size()));
      incident[extra].push_back(static_cast<int>(edges.size()));
      edges.emplace_back(v, extra);
    }
  }
  std::vector<char> used(edges.size(), 0);
  std::vector<size_t> next(num_views + 1, 0);  // first incident edge not yet tried
  std::vector<int> group_of(pairs.size(), 0);
  auto other = [&](int e, int v) { return edges[e].first == v ? edges[e].second : edges[e].first; };
  // Hierholzer's algorithm from `start`; the circuit's edges in order.
  auto circuit_from = [&](int start) {
    std::vector<int> circuit, stack_edges;
    std::vector<int> stack_vertices = {start};
    while (!stack_vertices.empty()) {
      const int v = stack_vertices.back();
      while (next[v] < incident[v].size() && used[incident[v][next[v]]]) ++next[v];
      if (next[v] < incident[v].size()) {
        const int e = incident[v][next[v]];
        used[e] = 1;
        stack_vertices.push_back(other(e, v));
        stack_edges.push_back(e);
      } else {
        stack_vertices.pop_back();
        if (!stack_edges.empty()) {
          circuit.push_back(stack_edges.back());
          stack_edges.pop_back();
        }
      }
    }
    return circuit;
  };
  auto colour = [&](const std::vector<int>& circuit) {
    for (size_t k = 0; k < circuit.size(); ++k) {
      if (circuit[k] < static_cast<int>(pairs.size())) group_of[circuit[k]] = k % 2;
    }
  };
  colour(circuit_from(extra));  // every component with an odd-degree view
  // The rest: components of even degrees, each from a view in the most pairs.
  std::vector<int> order(num_views);
  for (int v = 0; v < num_views; ++v) order[v] = v;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return incident[a].size() > incident[b].size();
  });
  for (const int v : order) colour(circuit_from(v));
  std::vector<std::vector<std::pair<int, int>>> groups(2);
  for (size_t k = 0; k < pairs.size(); ++k) groups[group_of[k]].push_back(pairs[k]);
  return groups;
}

}  // namespace

std::vector<std::vector<std::pair<int, int>>> SplitPairsCoveringViews(
    const std::vector<std::pair<int, int>>& pairs, int num_groups) {
  MR_CHECK(num_groups >= 1);
  int num_views = 0;
  for (const auto& [a, b] : pairs) num_views = std::max({num_views, a + 1, b + 1});
  // count[g][v]: pairs of view v in group g.
  std::vector<std::vector<int>> count(num_groups, std::vector<int>(num_views, 0));
  std::vector<std::vector<int>> pairs_of(num_views);
  std::vector<int> group_of(pairs.size()), group_size(num_groups, 0);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    pairs_of[a].push_back(static_cast<int>(k));
    pairs_of[b].push_back(static_cast<int>(k));
    // The group that gains the most views from the pair, then the smallest.
    int best = 0, best_gain = -1;
    for (int g = 0; g < num_groups; ++g) {
      const int gain = (count[g][a] == 0) + (count[g][b] == 0);
      if (gain > best_gain || (gain == best_gain && group_size[g] < group_size[best])) {
        best = g;
        best_gain = gain;
      }
    }
    group_of[k] = best;
    ++group_size[best];
    ++count[best][a];
    ++count[best][b];
  }
  // Repair what the greedy pass left: a view missing from group g takes one
  // of its pairs from a group where both of that pair's views have another.
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool moved = false;
    for (int v = 0; v < num_views; ++v) {
      for (int g = 0; g < num_groups; ++g) {
        if (count[g][v] > 0 || static_cast<int>(pairs_of[v].size()) < num_groups) continue;
        for (const int k : pairs_of[v]) {
          const int h = group_of[k];
          const auto [a, b] = pairs[k];
          if (count[h][a] < 2 || count[h][b] < 2) continue;
          --count[h][a];
          --count[h][b];
          ++count[g][a];
          ++count[g][b];
          group_of[k] = g;
          moved = true;
          break;
        }
      }
    }
    if (!moved) break;
  }
  std::vector<std::vector<std::pair<int, int>>> groups(num_groups);
  for (size_t k = 0; k < pairs.size(); ++k) groups[group_of[k]].push_back(pairs[k]);
  // Two groups that leave a view out (a sparse ring: templeSparseRing's 12
  // views in 17 pairs, or 40 hemisphere views in 70): the Euler split.
  if (num_groups == 2 && !GroupsCoverEveryView(pairs, groups)) {
    auto euler = SplitPairsAlongEulerCircuits(pairs);
    if (GroupsCoverEveryView(pairs, euler)) return euler;
  }
  return groups;
}

}  // namespace mr
