#include "render/icosphere.h"

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "util/error.h"

namespace mr {

void MakeIcosphere(int subdivisions, double radius, const Eigen::Vector3d& center,
                   Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MR_CHECK(subdivisions >= 0 && subdivisions <= 10) << "subdivisions = " << subdivisions;
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> verts = {
      {-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
      {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  for (auto& v : verts) v.normalize();
  std::vector<Eigen::Vector3i> faces = {
      {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
      {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      verts.push_back((verts[a] + verts[b]).normalized());
      const int id = static_cast<int>(verts.size()) - 1;
      midpoint[key] = id;
      return id;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(faces.size() * 4);
    for (const auto& f : faces) {
      const int a = mid(f[0], f[1]), b = mid(f[1], f[2]), c = mid(f[2], f[0]);
      next.emplace_back(f[0], a, c);
      next.emplace_back(f[1], b, a);
      next.emplace_back(f[2], c, b);
      next.emplace_back(a, b, c);
    }
    faces.swap(next);
  }
  V->resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) V->row(i) = (center + radius * verts[i]).transpose();
  F->resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) F->row(i) = faces[i].transpose();
}

}  // namespace mr
