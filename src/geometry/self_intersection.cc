#include "geometry/self_intersection.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <CGAL/Bbox_3.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include "util/error.h"
#include "util/threads.h"

namespace mr {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;

// Whether faces a and b (both non-degenerate) intersect other than in what
// they share: the cases of CGAL's do_faces_intersect, on rows of F.
bool FacesIntersectAt(const Point* p, const int va[3], const int vb[3]) {
  int shared = 0, ia[3], ib[3];  // positions of the shared vertices in a and in b
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (va[i] == vb[j]) {
        ia[shared] = i;
        ib[shared] = j;
        ++shared;
      }
    }
  }
  // p holds a's corners, then b's.
  const Point* pa = p;
  const Point* pb = p + 3;
  if (shared >= 3) return true;  // the same triangle twice
  if (shared == 2) {
    // A shared edge (u, w): they intersect when the four points are coplanar
    // and the apexes lie on the same side of the edge (the faces overlap).
    const Point& u = pa[ia[0]];
    const Point& w = pa[ia[1]];
    const Point& apex_a = pa[3 - ia[0] - ia[1]];
    const Point& apex_b = pb[3 - ib[0] - ib[1]];
    return CGAL::coplanar(u, w, apex_a, apex_b) &&
           CGAL::coplanar_orientation(u, w, apex_a, apex_b) == CGAL::POSITIVE;
  }
  const Triangle ta(pa[0], pa[1], pa[2]);
  const Triangle tb(pb[0], pb[1], pb[2]);
  if (shared == 1) {
    // A shared vertex: the edge of each face opposite it against the other.
    const Segment sa(pa[(ia[0] + 1) % 3], pa[(ia[0] + 2) % 3]);
    const Segment sb(pb[(ib[0] + 1) % 3], pb[(ib[0] + 2) % 3]);
    return CGAL::do_intersect(ta, sb) || CGAL::do_intersect(tb, sa);
  }
  return CGAL::do_intersect(ta, tb);
}

Point Corner(const Eigen::MatrixXd& V, int v) { return Point(V(v, 0), V(v, 1), V(v, 2)); }

// Sorts (cell, box) entries by cell, stably (a cell's boxes stay in the order
// given), cells in [0, num_cells): least significant digit first, 11 bits a
// pass, as many passes as the cells need (two for the example's 159k faces,
// where std::sort took 30-70 ms).
void SortByCell(uint64_t num_cells, std::vector<std::pair<uint64_t, int>>* entries) {
  constexpr int kBits = 11;
  constexpr size_t kDigits = size_t{1} << kBits;
  std::vector<std::pair<uint64_t, int>> buffer(entries->size());
  for (int shift = 0; shift < 64 && (num_cells - 1) >> shift != 0; shift += kBits) {
    std::vector<size_t> count(kDigits + 1, 0);
    for (const auto& e : *entries) ++count[((e.first >> shift) & (kDigits - 1)) + 1];
    for (size_t d = 0; d < kDigits; ++d) count[d + 1] += count[d];
    for (const auto& e : *entries) buffer[count[(e.first >> shift) & (kDigits - 1)]++] = e;
    entries->swap(buffer);
  }
}

// The candidates by CGAL's box_intersection_d (sorting).
std::vector<std::pair<int, int>> OverlappingBySorting(const Boxes& boxes,
                                                      const std::vector<int>& ids) {
  using CgalBox = CGAL::Box_intersection_d::Box_with_info_d<double, 3, int>;
  std::vector<CgalBox> cgal_boxes;
  cgal_boxes.reserve(ids.size());
  for (const int i : ids) {
    cgal_boxes.emplace_back(CGAL::Bbox_3(boxes.lo(i, 0), boxes.lo(i, 1), boxes.lo(i, 2),
                                         boxes.hi(i, 0), boxes.hi(i, 1), boxes.hi(i, 2)),
                            i);
  }
  std::vector<std::pair<int, int>> pairs;
  CGAL::box_self_intersection_d(cgal_boxes.begin(), cgal_boxes.end(),
                                [&](const CgalBox& x, const CgalBox& y) {
                                  const int a = x.info(), b = y.info();
                                  pairs.emplace_back(std::min(a, b), std::max(a, b));
                                });
  return pairs;
}

// The same by the uniform grid; false (and nothing) when the boxes crowd the
// cells (more pairs to look at in the cells than kMaxPerBox a box).
bool OverlappingByGrid(const Boxes& boxes, const std::vector<int>& ids,
                       std::vector<std::pair<int, int>>* out) {
  constexpr double kMaxCellsPerBox = 8;
  constexpr double kMaxPerBox = 64;
  double origin[3], extent[3], size_sum = 0;
  for (int k = 0; k < 3; ++k) {
    origin[k] = std::numeric_limits<double>::infinity();
    extent[k] = -std::numeric_limits<double>::infinity();
  }
  for (const int i : ids) {
    double size = 0;
    for (int k = 0; k < 3; ++k) {
      origin[k] = std::min(origin[k], boxes.lo(i, k));
      extent[k] = std::max(extent[k], boxes.hi(i, k));
      size = std::max(size, boxes.hi(i, k) - boxes.lo(i, k));
    }
    size_sum += size;
  }
  // Cells twice as large as a box on average (measured on a 159k-face mesh:
  // 1x 0.22 s, 2x 0.16 s, 3x 0.16 s), at most 2^20 along an axis (so that a
  // cell's index fits 60 bits), and larger while the boxes would fill more
  // than kMaxCellsPerBox cells each.
  double cell = 2 * size_sum / ids.size();
  for (int k = 0; k < 3; ++k) {
    extent[k] -= origin[k];
    cell = std::max(cell, extent[k] / (1 << 20));
  }
  if (!(cell > 0) || !std::isfinite(cell)) return false;
  auto index = [&](double x, int k) {
    return static_cast<uint64_t>(std::floor((x - origin[k]) / cell));
  };
  uint64_t dims[3];
  for (;;) {
    for (int k = 0; k < 3; ++k) dims[k] = index(origin[k] + extent[k], k) + 1;
    double cells = 0;
    for (const int i : ids) {
      double n = 1;
      for (int k = 0; k < 3; ++k) n *= index(boxes.hi(i, k), k) - index(boxes.lo(i, k), k) + 1;
      cells += n;
    }
    if (cells <= kMaxCellsPerBox * ids.size()) break;
    cell *= 2;
  }
  auto key = [&](uint64_t x, uint64_t y, uint64_t z) { return (x * dims[1] + y) * dims[2] + z; };

  std::vector<std::pair<uint64_t, int>> entries;  // (cell, box)
  entries.reserve(4 * ids.size());
  for (const int i : ids) {
    const uint64_t x0 = index(boxes.lo(i, 0), 0), x1 = index(boxes.hi(i, 0), 0);
    const uint64_t y0 = index(boxes.lo(i, 1), 1), y1 = index(boxes.hi(i, 1), 1);
    const uint64_t z0 = index(boxes.lo(i, 2), 2), z1 = index(boxes.hi(i, 2), 2);
    for (uint64_t x = x0; x <= x1; ++x) {
      for (uint64_t y = y0; y <= y1; ++y) {
        for (uint64_t z = z0; z <= z1; ++z) entries.emplace_back(key(x, y, z), i);
      }
    }
  }
  SortByCell(dims[0] * dims[1] * dims[2], &entries);
  std::vector<size_t> starts;  // of each cell's run of entries, then the end
  double pairs_in_cells = 0;
  for (size_t begin = 0, end = 0; begin < entries.size(); begin = end) {
    while (end < entries.size() && entries[end].first == entries[begin].first) ++end;
    starts.push_back(begin);
    pairs_in_cells += 0.5 * (end - begin) * (end - begin - 1.0);
  }
  starts.push_back(entries.size());
  if (pairs_in_cells > kMaxPerBox * ids.size()) return false;

  // The cells in equal shares per thread (static: the same pairs in the same
  // order on every run with as many threads).
  const long num_cells = static_cast<long>(starts.size()) - 1;
  std::vector<std::vector<std::pair<int, int>>> found(NumThreads());
#pragma omp parallel for schedule(static)
  for (long c = 0; c < num_cells; ++c) {
    std::vector<std::pair<int, int>>& mine = found[ThreadIndex()];
    const uint64_t cell_key = entries[starts[c]].first;
    for (size_t i = starts[c]; i < starts[c + 1]; ++i) {
      const int a = entries[i].second;
      for (size_t j = i + 1; j < starts[c + 1]; ++j) {
        const int b = entries[j].second;
        if (!BoxesOverlap(boxes, a, boxes, b)) continue;
        const uint64_t corner = key(index(std::max(boxes.lo(a, 0), boxes.lo(b, 0)), 0),
                                    index(std::max(boxes.lo(a, 1), boxes.lo(b, 1)), 1),
                                    index(std::max(boxes.lo(a, 2), boxes.lo(b, 2)), 2));
        if (corner == cell_key) mine.emplace_back(std::min(a, b), std::max(a, b));
      }
    }
  }
  out->clear();
  for (const auto& mine : found) out->insert(out->end(), mine.begin(), mine.end());
  return true;
}

}  // namespace

bool FaceIsDegenerate(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f) {
  return CGAL::collinear(Corner(V, F(f, 0)), Corner(V, F(f, 1)), Corner(V, F(f, 2)));
}

bool FacesIntersect(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int a, int b) {
  const int va[3] = {F(a, 0), F(a, 1), F(a, 2)};
  const int vb[3] = {F(b, 0), F(b, 1), F(b, 2)};
  const Point p[6] = {Corner(V, va[0]), Corner(V, va[1]), Corner(V, va[2]),
                      Corner(V, vb[0]), Corner(V, vb[1]), Corner(V, vb[2])};
  return FacesIntersectAt(p, va, vb);
}

std::vector<char> DegenerateFaces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const int num_faces = static_cast<int>(F.rows());
  std::vector<char> degenerate(num_faces, 0);
#pragma omp parallel for schedule(static)
  for (int f = 0; f < num_faces; ++f) degenerate[f] = FaceIsDegenerate(V, F, f) ? 1 : 0;
  return degenerate;
}

void SetFaceBox(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f, Boxes* boxes) {
  for (int k = 0; k < 3; ++k) {
    const double x = V(F(f, 0), k), y = V(F(f, 1), k), z = V(F(f, 2), k);
    boxes->lo(f, k) = std::min({x, y, z});
    boxes->hi(f, k) = std::max({x, y, z});
  }
}

Boxes FaceBoxes(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Boxes boxes;
  boxes.lo.resize(F.rows(), 3);
  boxes.hi.resize(F.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) SetFaceBox(V, F, f, &boxes);
  return boxes;
}

void GrowFaceBoxes(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Boxes* boxes) {
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        boxes->lo(f, k) = std::min(boxes->lo(f, k), V(F(f, c), k));
        boxes->hi(f, k) = std::max(boxes->hi(f, k), V(F(f, c), k));
      }
    }
  }
}

bool BoxesOverlap(const Boxes& x, int a, const Boxes& y, int b) {
  for (int k = 0; k < 3; ++k) {
    if (x.hi(a, k) < y.lo(b, k) || y.hi(b, k) < x.lo(a, k)) return false;
  }
  return true;
}

std::vector<std::pair<int, int>> OverlappingBoxes(const Boxes& boxes,
                                                  const std::vector<int>& ids) {
  std::vector<std::pair<int, int>> pairs;
  if (ids.size() < 2) return pairs;
  if (!OverlappingByGrid(boxes, ids, &pairs)) pairs = OverlappingBySorting(boxes, ids);
  return pairs;
}

std::vector<std::pair<int, int>> IntersectingCandidates(
    const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const Boxes& boxes,
    const std::vector<char>& degenerate, const std::vector<std::pair<int, int>>& candidates,
    const std::vector<int>* which) {
  const long n = static_cast<long>(which != nullptr ? which->size() : candidates.size());
  auto candidate = [&](long i) -> const std::pair<int, int>& {
    return candidates[which != nullptr ? (*which)[i] : i];
  };
  std::vector<char> hit(n, 0);
#pragma omp parallel for schedule(dynamic, 1024)
  for (long i = 0; i < n; ++i) {
    const auto [a, b] = candidate(i);
    hit[i] = !degenerate[a] && !degenerate[b] && BoxesOverlap(boxes, a, boxes, b) &&
             FacesIntersect(V, F, a, b);
  }
  std::vector<std::pair<int, int>> pairs;
  for (long i = 0; i < n; ++i) {
    if (hit[i]) pairs.push_back(candidate(i));
  }
  return pairs;
}

std::vector<std::pair<int, int>> IntersectingFacePairs(const Eigen::MatrixXd& V,
                                                       const Eigen::MatrixXi& F) {
  const std::vector<char> degenerate = DegenerateFaces(V, F);
  std::vector<std::pair<int, int>> pairs;
  std::vector<int> boxed;  // the non-degenerate faces
  boxed.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    if (degenerate[f]) {
      pairs.emplace_back(f, f);
    } else {
      boxed.push_back(f);
    }
  }
  const Boxes boxes = FaceBoxes(V, F);
  const std::vector<std::pair<int, int>> found =
      IntersectingCandidates(V, F, boxes, degenerate, OverlappingBoxes(boxes, boxed));
  pairs.insert(pairs.end(), found.begin(), found.end());
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace mr
