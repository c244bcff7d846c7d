#include "denoise/baselines.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "geometry/mesh.h"

namespace mr {
namespace {

Eigen::MatrixXd Umbrella(const IndexLists& nb, const Eigen::MatrixXd& X) {
  const int n = static_cast<int>(X.rows());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, 3);
#pragma omp parallel for schedule(static) if (n > 50000)
  for (int i = 0; i < n; ++i) {
    const IndexLists::List neighbours = nb[i];
    if (neighbours.size() == 0) continue;
    Eigen::RowVector3d s = Eigen::RowVector3d::Zero();
    for (const int j : neighbours) s += X.row(j);
    L.row(i) = s / static_cast<double>(neighbours.size()) - X.row(i);
  }
  return L;
}

// The faces sharing a vertex with each face, itself excluded (Zheng et al.'s
// local neighbourhood).
std::vector<std::vector<int>> FaceRings(const Eigen::MatrixXi& F, const IndexLists& vf) {
  const int nf = static_cast<int>(F.rows());
  std::vector<std::vector<int>> ring(nf);
#pragma omp parallel for schedule(dynamic, 256) if (nf > 50000)
  for (int f = 0; f < nf; ++f) {
    std::vector<int>& r = ring[f];
    for (int k = 0; k < 3; ++k) {
      for (const int g : vf[F(f, k)]) {
        if (g != f) r.push_back(g);
      }
    }
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  return ring;
}

}  // namespace

Eigen::MatrixXd LaplacianSmooth(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                int iterations, double w1, double w2) {
  const IndexLists nb = VertexAdjacency(F, static_cast<int>(V.rows()));
  Eigen::MatrixXd X = V;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::MatrixXd L = Umbrella(nb, X);
    if (w2 > 0) {
      X += w1 * L - w2 * Umbrella(nb, L);
    } else {
      X += w1 * L;
    }
  }
  return X;
}

namespace {

// One round of BilateralNormalFilter on X: normals, centroids, areas and the
// spatial sigma from X, then the normal filtering and the vertex fitting.
// `vf` are the faces of each vertex, `ring` the faces sharing a vertex with
// each face.
void BilateralNormalRound(const Eigen::MatrixXi& F, const IndexLists& vf,
                          const std::vector<std::vector<int>>& ring, int normal_iterations,
                          int vertex_iterations, double normal_sigma, double spatial_sigma,
                          Eigen::MatrixXd* X_in_out) {
  Eigen::MatrixXd& X = *X_in_out;
  const int n = static_cast<int>(X.rows()), nf = static_cast<int>(F.rows());
  auto centroids_normals_areas = [&](Eigen::MatrixXd* C, Eigen::MatrixXd* N, Eigen::VectorXd* A) {
    C->resize(nf, 3);
    N->resize(nf, 3);
    A->resize(nf);
#pragma omp parallel for schedule(static) if (n > 50000)
    for (int f = 0; f < nf; ++f) {
      const Eigen::Vector3d a = X.row(F(f, 0)), b = X.row(F(f, 1)), c = X.row(F(f, 2));
      const Eigen::Vector3d cr = (b - a).cross(c - a);
      const double len = cr.norm();
      C->row(f) = (a + b + c).transpose() / 3.0;
      N->row(f) = len > 0 ? Eigen::RowVector3d(cr.transpose() / len) : Eigen::RowVector3d::Zero();
      (*A)(f) = 0.5 * len;
    }
  };
  Eigen::MatrixXd C, N;
  Eigen::VectorXd A;
  centroids_normals_areas(&C, &N, &A);
  // Spatial sigma: mean distance between centroids of faces sharing a vertex.
  double dsum = 0;
  long dcount = 0;
  for (int f = 0; f < nf; ++f) {
    for (int g : ring[f]) {
      dsum += (C.row(f) - C.row(g)).norm();
      ++dcount;
    }
  }
  const double ss = spatial_sigma * (dcount > 0 ? dsum / dcount : 1.0);
  const double inv_ss2 = 1.0 / (2 * ss * ss), inv_sr2 = 1.0 / (2 * normal_sigma * normal_sigma);
  for (int it = 0; it < normal_iterations; ++it) {
    Eigen::MatrixXd Nn(nf, 3);
#pragma omp parallel for schedule(static) if (n > 50000)
    for (int f = 0; f < nf; ++f) {
      Eigen::RowVector3d s = A(f) * N.row(f);
      for (int g : ring[f]) {
        const double w = A(g) * std::exp(-(C.row(f) - C.row(g)).squaredNorm() * inv_ss2 -
                                         (N.row(f) - N.row(g)).squaredNorm() * inv_sr2);
        s += w * N.row(g);
      }
      const double len = s.norm();
      Nn.row(f) = len > 0 ? Eigen::RowVector3d(s / len) : N.row(f);
    }
    N = Nn;
  }
  // Vertex update (Sun et al. 2007): x_i += 1/|F_i| sum_f n_f (n_f . (c_f - x_i)).
  for (int it = 0; it < vertex_iterations; ++it) {
    Eigen::MatrixXd Xn = X;
#pragma omp parallel for schedule(static) if (n > 50000)
    for (int v = 0; v < n; ++v) {
      const IndexLists::List faces = vf[v];
      if (faces.size() == 0) continue;
      Eigen::RowVector3d d = Eigen::RowVector3d::Zero();
      for (const int f : faces) d += N.row(f) * N.row(f).dot(C.row(f) - X.row(v));
      Xn.row(v) += d / static_cast<double>(faces.size());
    }
    X = Xn;
#pragma omp parallel for schedule(static) if (n > 50000)
    for (int f = 0; f < nf; ++f) {
      C.row(f) = FaceCentroid(X, F, f).transpose();
    }
  }
}

// How well two groups explain the normals of the faces around vertex v (its
// faces' rings, about two rings of faces): the normals are ordered along
// their main direction of spread and split in two where the scatter left
// within the two groups is least; the result is that scatter over the
// normals' whole scatter. 0 beside a noise-free crease (two flat sides);
// 0.25 or more where the normals spread evenly, around a finger or a tube.
double TwoGroupResidual(const Eigen::MatrixXd& N, const IndexLists& vf,
                        const std::vector<std::vector<int>>& ring, int v) {
  std::vector<int> patch;
  for (const int f : vf[v]) {
    patch.push_back(f);
    patch.insert(patch.end(), ring[f].begin(), ring[f].end());
  }
  std::sort(patch.begin(), patch.end());
  patch.erase(std::unique(patch.begin(), patch.end()), patch.end());
  const int k = static_cast<int>(patch.size());
  if (k < 4) return 1.0;
  Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
  for (const int f : patch) mean += N.row(f);
  mean /= k;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const int f : patch) {
    const Eigen::Vector3d d = (N.row(f) - mean).transpose();
    cov += d * d.transpose();
  }
  const double total = cov.trace();
  if (!(total > 0)) return 1.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);
  std::vector<std::pair<double, int>> along(k);
  for (int i = 0; i < k; ++i) along[i] = {(N.row(patch[i]) - mean).dot(axis.transpose()), patch[i]};
  std::sort(along.begin(), along.end());
  // Within-group scatter of every split point, from prefix sums.
  std::vector<Eigen::RowVector3d> sum(k + 1, Eigen::RowVector3d::Zero());
  std::vector<double> sq(k + 1, 0.0);
  for (int i = 0; i < k; ++i) {
    sum[i + 1] = sum[i] + N.row(along[i].second);
    sq[i + 1] = sq[i] + N.row(along[i].second).squaredNorm();
  }
  double best = total;
  for (int s = 1; s < k; ++s) {
    const double left = sq[s] - sum[s].squaredNorm() / s;
    const Eigen::RowVector3d rs = sum[k] - sum[s];
    const double right = (sq[k] - sq[s]) - rs.squaredNorm() / (k - s);
    best = std::min(best, left + right);
  }
  return std::max(0.0, best) / total;
}

// SecondOrderFairing on neighbourhoods already built: `nb` the neighbours of
// each vertex, `vf` its faces, `ring` the faces sharing a vertex with each
// face.
Eigen::MatrixXd FairingStep(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                            const IndexLists& nb, const IndexLists& vf,
                            const std::vector<std::vector<int>>& ring, double weight,
                            double normal_sigma) {
  const int n = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  const Eigen::MatrixXd LL = Umbrella(nb, Umbrella(nb, V));
  if (!(normal_sigma > 0)) return V - weight * LL;
  // Each face's share of its ring that the range weight leaves out.
  const Eigen::MatrixXd N = FaceNormals(V, F);
  const double inv_2s2 = 1.0 / (2.0 * normal_sigma * normal_sigma);
  Eigen::VectorXd left_out(nf);
#pragma omp parallel for schedule(static) if (nf > 50000)
  for (int f = 0; f < nf; ++f) {
    double kept = 0;
    for (const int g : ring[f]) kept += std::exp(-(N.row(f) - N.row(g)).squaredNorm() * inv_2s2);
    left_out(f) = ring[f].empty() ? 0.0 : 1.0 - kept / static_cast<double>(ring[f].size());
  }
  // The vertex's weight ramps from 0 to 1 as its faces' mean share goes
  // from kFairingFrom to kFairingFull, and back to 0 as its neighbourhood's
  // normals fall into two groups, a crease's two sides (TwoGroupResidual
  // from kCreaseFull down to kCreaseFrom).
  constexpr double kFairingFrom = 0.15, kFairingFull = 0.4;
  constexpr double kCreaseFrom = 0.02, kCreaseFull = 0.06;
  Eigen::MatrixXd X = V;
#pragma omp parallel for schedule(static) if (n > 50000)
  for (int v = 0; v < n; ++v) {
    const IndexLists::List faces = vf[v];
    if (faces.size() == 0) continue;
    double share = 0;
    for (const int f : faces) share += left_out(f);
    share /= static_cast<double>(faces.size());
    double m = std::clamp((share - kFairingFrom) / (kFairingFull - kFairingFrom), 0.0, 1.0);
    if (m > 0) {
      const double r = TwoGroupResidual(N, vf, ring, v);
      m *= std::clamp((r - kCreaseFrom) / (kCreaseFull - kCreaseFrom), 0.0, 1.0);
    }
    X.row(v) -= weight * m * LL.row(v);
  }
  return X;
}

}  // namespace

Eigen::MatrixXd BilateralNormalFilter(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      int normal_iterations, int vertex_iterations,
                                      double normal_sigma, double spatial_sigma,
                                      int outer_iterations, double fairing_weight) {
  const int n = static_cast<int>(V.rows()), nf = static_cast<int>(F.rows());
  if (nf == 0) return V;
  const IndexLists vf = VertexFaces(F, n);
  const std::vector<std::vector<int>> ring = FaceRings(F, vf);
  const IndexLists nb = fairing_weight > 0 ? VertexAdjacency(F, n) : IndexLists();
  Eigen::MatrixXd X = V;
  for (int round = 0; round < outer_iterations; ++round) {
    BilateralNormalRound(F, vf, ring, normal_iterations, vertex_iterations, normal_sigma,
                         spatial_sigma, &X);
    if (fairing_weight > 0) X = FairingStep(X, F, nb, vf, ring, fairing_weight, normal_sigma);
  }
  return X;
}

Eigen::MatrixXd SecondOrderFairing(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                   double weight, double normal_sigma) {
  const int n = static_cast<int>(V.rows());
  if (F.rows() == 0 || !(weight > 0)) return V;
  const IndexLists vf = VertexFaces(F, n);
  return FairingStep(V, F, VertexAdjacency(F, n), vf, FaceRings(F, vf), weight, normal_sigma);
}

}  // namespace mr
