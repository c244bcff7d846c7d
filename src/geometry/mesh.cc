#include "geometry/mesh.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>

#include <Eigen/Geometry>

#include "util/error.h"

namespace mr {

Eigen::MatrixXd FaceNormals(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Eigen::MatrixXd N(F.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    N.row(f) = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  }
  return N;
}

Eigen::VectorXd FaceAreas(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Eigen::VectorXd A(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    A(f) = 0.5 * (b - a).cross(c - a).norm();
  }
  return A;
}

Eigen::MatrixXd VertexNormals(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(V.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);  // length = 2 * area
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (int v = 0; v < N.rows(); ++v) {
    const double len = N.row(v).norm();
    if (len > 0) N.row(v) /= len;
  }
  return N;
}

double MeanEdgeLength(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  if (F.rows() == 0) return 0.0;
  const EdgeTopology topo = ComputeEdgeTopology(F, static_cast<int>(V.rows()));
  double sum = 0;
  for (int e = 0; e < topo.E.rows(); ++e) sum += (V.row(topo.E(e, 0)) - V.row(topo.E(e, 1))).norm();
  return sum / topo.E.rows();
}

double BoundingBoxDiagonal(const Eigen::MatrixXd& V) {
  if (V.rows() == 0) return 0.0;
  return (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
}

int EdgeTopology::NumBoundaryEdges() const {
  return static_cast<int>(std::count_if(edge_faces.begin(), edge_faces.end(),
                                        [](const auto& f) { return f.size() == 1; }));
}

int EdgeTopology::NumNonManifoldEdges() const {
  return static_cast<int>(std::count_if(edge_faces.begin(), edge_faces.end(),
                                        [](const auto& f) { return f.size() > 2; }));
}

EdgeTopology ComputeEdgeTopology(const Eigen::MatrixXi& F, int num_vertices) {
  EdgeTopology topo;
  topo.face_edges.resize(F.rows(), 3);
  std::unordered_map<int64_t, int> index;
  index.reserve(static_cast<size_t>(F.rows()) * 2);
  std::vector<Eigen::Vector2i> edges;
  edges.reserve(static_cast<size_t>(F.rows()) * 3 / 2 + 1);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      int a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
      MR_CHECK(a >= 0 && a < num_vertices && b >= 0 && b < num_vertices)
          << "face " << f << " has an out-of-range vertex index";
      if (a > b) std::swap(a, b);
      const int64_t key = static_cast<int64_t>(a) * num_vertices + b;
      auto [it, inserted] = index.emplace(key, static_cast<int>(edges.size()));
      if (inserted) {
        edges.emplace_back(a, b);
        topo.edge_faces.emplace_back();
      }
      topo.edge_faces[it->second].push_back(f);
      topo.face_edges(f, k) = it->second;
    }
  }
  topo.E.resize(static_cast<int>(edges.size()), 2);
  for (size_t e = 0; e < edges.size(); ++e) topo.E.row(static_cast<int>(e)) = edges[e];
  return topo;
}

std::vector<std::vector<int>> VertexAdjacency(const Eigen::MatrixXi& F, int num_vertices) {
  std::vector<std::vector<int>> adj(num_vertices);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      adj[F(f, k)].push_back(F(f, (k + 1) % 3));
      adj[F(f, k)].push_back(F(f, (k + 2) % 3));
    }
  }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return adj;
}

std::vector<int> RemoveUnreferencedVertices(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  std::vector<int> map(V->rows(), -1);
  int next = 0;
  for (int f = 0; f < F->rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      int& v = (*F)(f, k);
      if (map[v] < 0) map[v] = next++;
      v = map[v];
    }
  }
  Eigen::MatrixXd W(next, V->cols());
  for (int v = 0; v < V->rows(); ++v) {
    if (map[v] >= 0) W.row(map[v]) = V->row(v);
  }
  *V = std::move(W);
  return map;
}

namespace {

// The bits of a 21-bit integer spread to every third bit.
uint64_t SpreadBits(uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::vector<int> OrderSpatially(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int num_faces = static_cast<int>(F->rows());
  if (num_faces == 0) return RemoveUnreferencedVertices(V, F);
  const Eigen::RowVector3d lo = V->colwise().minCoeff(), hi = V->colwise().maxCoeff();
  const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
  const double cells = (1 << 21) - 1;
  std::vector<std::pair<uint64_t, int>> keyed(num_faces);
  for (int f = 0; f < num_faces; ++f) {
    const Eigen::RowVector3d c =
        (V->row((*F)(f, 0)) + V->row((*F)(f, 1)) + V->row((*F)(f, 2))) / 3.0;
    uint64_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const double t = std::clamp((c(a) - lo(a)) / extent, 0.0, 1.0);
      code |= SpreadBits(static_cast<uint64_t>(t * cells)) << a;
    }
    keyed[f] = {code, f};
  }
  std::sort(keyed.begin(), keyed.end());
  Eigen::MatrixXi sorted(num_faces, 3);
  for (int f = 0; f < num_faces; ++f) sorted.row(f) = F->row(keyed[f].second);
  *F = std::move(sorted);
  return RemoveUnreferencedVertices(V, F);
}

}  // namespace mr
