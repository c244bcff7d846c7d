#include "geometry/primitives.h"

#include <cmath>
#include <map>
#include <vector>

#include "util/error.h"

namespace mr {

void MakeIcosphere(int subdivisions, double radius, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MR_CHECK(subdivisions >= 0 && subdivisions <= 9) << "subdivisions = " << subdivisions;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> vertices = {
      {-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
      {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& v : vertices) v.normalize();
  std::vector<Eigen::Vector3i> faces = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      vertices.push_back((vertices[a] + vertices[b]).normalized());
      const int index = static_cast<int>(vertices.size()) - 1;
      midpoint.emplace(key, index);
      return index;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(faces.size() * 4);
    for (const auto& f : faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.emplace_back(f[0], ab, ca);
      next.emplace_back(f[1], bc, ab);
      next.emplace_back(f[2], ca, bc);
      next.emplace_back(ab, bc, ca);
    }
    faces.swap(next);
  }
  V->resize(static_cast<int>(vertices.size()), 3);
  for (size_t i = 0; i < vertices.size(); ++i) V->row(static_cast<int>(i)) = radius * vertices[i];
  F->resize(static_cast<int>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) F->row(static_cast<int>(i)) = faces[i];
}

void MakeIcosphere(int subdivisions, double radius, const Eigen::Vector3d& center,
                   Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MakeIcosphere(subdivisions, radius, V, F);
  V->rowwise() += center.transpose();
}

void AppendGrid(const Eigen::Vector3d& origin, const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                int cells, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int base = static_cast<int>(V->rows()), first_face = static_cast<int>(F->rows());
  const int n = cells + 1;
  V->conservativeResize(base + n * n, 3);
  F->conservativeResize(first_face + 2 * cells * cells, 3);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      V->row(base + i * n + j) = (origin + (u * j) / cells + (v * i) / cells).transpose();
    }
  }
  int f = first_face;
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      const int a = base + i * n + j, b = a + 1, c = a + n, d = c + 1;
      F->row(f++) << a, b, d;
      F->row(f++) << a, d, c;
    }
  }
}

}  // namespace mr
