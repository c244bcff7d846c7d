#include "denoise/synthetic_meshes.h"

#include <algorithm>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>

#include "geometry/mesh.h"

namespace mr {

void SubdividedCube(int n, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  std::map<std::tuple<int, int, int>, int> index;  // integer lattice coords
  std::vector<Eigen::Vector3d> verts;
  std::vector<Eigen::Vector3i> faces;
  auto vid = [&](const Eigen::Vector3i& q) {
    const auto key = std::make_tuple(q.x(), q.y(), q.z());
    auto it = index.find(key);
    if (it != index.end()) return it->second;
    const int id = static_cast<int>(verts.size());
    verts.push_back(q.cast<double>() * (2.0 / n) - Eigen::Vector3d::Ones());
    index[key] = id;
    return id;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          Eigen::Vector3i q[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            q[k][axis] = side * n;
            q[k][u] = i + di[k];
            q[k][w] = j + dj[k];
          }
          int id[4];
          for (int k = 0; k < 4; ++k) id[k] = vid(q[k]);
          // (u, w, axis) is right-handed: ccw in (u, w) faces +axis.
          if (side == 1) {
            faces.emplace_back(id[0], id[1], id[2]);
            faces.emplace_back(id[0], id[2], id[3]);
          } else {
            faces.emplace_back(id[0], id[2], id[1]);
            faces.emplace_back(id[0], id[3], id[2]);
          }
        }
      }
    }
  }
  V->resize(static_cast<int>(verts.size()), 3);
  for (size_t i = 0; i < verts.size(); ++i) V->row(i) = verts[i].transpose();
  F->resize(static_cast<int>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) F->row(i) = faces[i].transpose();
}

void MidpointSubdivide(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int n = static_cast<int>(V->rows()), nf = static_cast<int>(F->rows());
  std::vector<std::pair<int64_t, int>> keys;
  keys.reserve(static_cast<size_t>(nf) * 3);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = (*F)(f, k), b = (*F)(f, (k + 1) % 3);
      keys.emplace_back((static_cast<int64_t>(std::min(a, b)) << 32) | std::max(a, b), 3 * f + k);
    }
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> mid(static_cast<size_t>(nf) * 3);
  std::vector<Eigen::RowVector3d> extra;
  for (size_t i = 0; i < keys.size();) {
    size_t j = i;
    const int a = static_cast<int>(keys[i].first >> 32);
    const int b = static_cast<int>(keys[i].first & 0xffffffff);
    const int id = n + static_cast<int>(extra.size());
    extra.push_back(0.5 * (V->row(a) + V->row(b)));
    while (j < keys.size() && keys[j].first == keys[i].first) mid[keys[j++].second] = id;
    i = j;
  }
  Eigen::MatrixXd V2(n + static_cast<int>(extra.size()), 3);
  V2.topRows(n) = *V;
  for (size_t i = 0; i < extra.size(); ++i) V2.row(n + i) = extra[i];
  Eigen::MatrixXi F2(4 * nf, 3);
  for (int f = 0; f < nf; ++f) {
    const int a = (*F)(f, 0), b = (*F)(f, 1), c = (*F)(f, 2);
    const int ab = mid[3 * f], bc = mid[3 * f + 1], ca = mid[3 * f + 2];
    F2.row(4 * f) << a, ab, ca;
    F2.row(4 * f + 1) << ab, b, bc;
    F2.row(4 * f + 2) << ca, bc, c;
    F2.row(4 * f + 3) << ab, bc, ca;
  }
  *V = V2;
  *F = F2;
}

void SubdividedOctahedron(int levels, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  V->resize(6, 3);
  *V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  F->resize(8, 3);
  *F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  for (int l = 0; l < levels; ++l) MidpointSubdivide(V, F);
}

Eigen::MatrixXd AddNormalNoise(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, double sigma,
                               uint64_t seed) {
  const Eigen::MatrixXd N = VertexNormals(V, F);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0.0, sigma);
  Eigen::MatrixXd out = V;
  for (int v = 0; v < V.rows(); ++v) out.row(v) += gauss(rng) * N.row(v);
  return out;
}

}  // namespace mr
