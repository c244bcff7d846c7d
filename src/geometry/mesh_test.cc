#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/LU>

#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "geometry/view.h"

namespace mr {
namespace {

// A unit square split into two triangles, plus a folded third triangle.
void TwoTriangles(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  V->resize(4, 3);
  *V << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  F->resize(2, 3);
  *F << 0, 1, 2, 0, 2, 3;
}

TEST(Mesh, NormalsAndAreas) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  TwoTriangles(&V, &F);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  EXPECT_NEAR(N(0, 2), 1.0, 1e-12);
  EXPECT_NEAR(N(1, 2), 1.0, 1e-12);
  EXPECT_NEAR(FaceAreas(V, F).sum(), 1.0, 1e-12);
  EXPECT_NEAR(VertexNormals(V, F)(3, 2), 1.0, 1e-12);
  EXPECT_NEAR(MeanEdgeLength(V, F), (4 + std::sqrt(2.0)) / 5, 1e-12);
}

TEST(Mesh, EdgeTopology) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  TwoTriangles(&V, &F);
  const EdgeTopology topo = ComputeEdgeTopology(F, 4);
  EXPECT_EQ(topo.E.rows(), 5);
  EXPECT_EQ(topo.NumBoundaryEdges(), 4);
  EXPECT_EQ(topo.NumNonManifoldEdges(), 0);
  // Face 0 corner 1 (vertex 1) is opposite edge (0, 2), shared with face 1.
  EXPECT_EQ(topo.edge_faces[topo.face_edges(0, 1)].size(), 2u);
}

// The sorted construction against the definition: edges numbered by first
// appearance (face by face, corner k = the edge opposite corner k), each
// edge's faces in increasing order, on a random soup of 400 triangles over
// 12 vertices (every edge non-manifold, faces repeated).
TEST(Mesh, EdgeTopologyMatchesTheDefinition) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> vertex(0, 11);
  Eigen::MatrixXi F(400, 3);
  for (int f = 0; f < F.rows(); ++f) {
    do {
      F.row(f) << vertex(rng), vertex(rng), vertex(rng);
    } while (F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 0) == F(f, 2));
  }
  std::map<std::pair<int, int>, int> index;
  std::vector<std::pair<int, int>> edges;
  std::vector<std::vector<int>> faces;
  Eigen::MatrixXi face_edges(F.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
      const auto key = std::minmax(a, b);
      auto [it, inserted] = index.emplace(key, static_cast<int>(edges.size()));
      if (inserted) {
        edges.push_back(key);
        faces.emplace_back();
      }
      faces[it->second].push_back(f);
      face_edges(f, k) = it->second;
    }
  }
  const EdgeTopology topo = ComputeEdgeTopology(F, 12);
  ASSERT_EQ(topo.E.rows(), static_cast<int>(edges.size()));
  ASSERT_EQ(topo.edge_faces.size(), edges.size());
  int non_manifold = 0;
  for (size_t e = 0; e < edges.size(); ++e) {
    EXPECT_EQ(topo.E(e, 0), edges[e].first);
    EXPECT_EQ(topo.E(e, 1), edges[e].second);
    const IndexLists::List list = topo.edge_faces[e];
    EXPECT_EQ(std::vector<int>(list.begin(), list.end()), faces[e]) << "edge " << e;
    non_manifold += faces[e].size() > 2 ? 1 : 0;
  }
  EXPECT_EQ(topo.face_edges, face_edges);
  EXPECT_EQ(topo.NumNonManifoldEdges(), non_manifold);
  EXPECT_GT(non_manifold, 10);  // lists longer than 2
}

TEST(Mesh, EmptyMesh) {
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  EXPECT_EQ(MeanEdgeLength(V, F), 0.0);
  EXPECT_EQ(BoundingBoxDiagonal(V), 0.0);
  EXPECT_EQ(ComputeEdgeTopology(F, 0).E.rows(), 0);
}

TEST(Mesh, RemoveUnreferencedVertices) {
  Eigen::MatrixXd V(5, 3);
  V.setRandom();
  Eigen::MatrixXi F(1, 3);
  F << 4, 2, 0;
  const Eigen::MatrixXd V0 = V;
  RemoveUnreferencedVertices(&V, &F);
  EXPECT_EQ(V.rows(), 3);
  EXPECT_EQ(V.row(F(0, 0)), V0.row(4));
}

TEST(PinholeView, LookAt) {
  const PinholeView v = LookAtView(Eigen::Vector3d(0, -5, 0), Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d(0, 0, 1), 64, 48, 50);
  EXPECT_NEAR(v.R.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((v.Center() - Eigen::Vector3d(0, -5, 0)).norm() < 1e-12);
  EXPECT_TRUE((v.Project(Eigen::Vector3d::Zero()) - Eigen::Vector2d(32, 24)).norm() < 1e-12);
  // World up appears at smaller image y; world +x appears to the right.
  EXPECT_LT(v.Project(Eigen::Vector3d(0, 0, 1)).y(), 24);
  EXPECT_GT(v.Project(Eigen::Vector3d(1, 0, 0)).x(), 32);
}

TEST(PinholeView, ProjectAndScale) {
  PinholeView v;
  v.width = 640;
  v.height = 480;
  v.fx = v.fy = 500;
  v.cx = 320;
  v.cy = 240;
  const Eigen::Vector3d X(0.1, -0.2, 2.0);
  const Eigen::Vector2d p = v.Project(X);
  EXPECT_NEAR(p.x(), 345, 1e-12);
  EXPECT_NEAR(p.y(), 190, 1e-12);
  // The ray through p at depth 2 hits X.
  EXPECT_TRUE((v.Center() + 2.0 * v.RayDirection(p.x(), p.y()) - X).norm() < 1e-12);
  const PinholeView h = v.Scaled(0.5);
  EXPECT_EQ(h.width, 320);
  EXPECT_TRUE((h.Project(X) - 0.5 * p).norm() < 1e-12);
}

}  // namespace
}  // namespace mr

#include "geometry/primitives.h"

namespace mr {
namespace {

TEST(Primitives, IcosphereIsClosedAndOutward) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(2, 2.0, &V, &F);
  EXPECT_EQ(F.rows(), 320);
  const EdgeTopology topo = ComputeEdgeTopology(F, static_cast<int>(V.rows()));
  EXPECT_EQ(topo.NumBoundaryEdges(), 0);
  EXPECT_EQ(topo.NumNonManifoldEdges(), 0);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    EXPECT_GT(N.row(f).dot(c), 0) << "face " << f << " points inward";
  }
  EXPECT_NEAR(V.rowwise().norm().maxCoeff(), 2.0, 1e-12);
}

// Each triangle as its three corner positions, rotated to start at the
// smallest, so that the same triangle with the same winding compares equal.
std::vector<std::array<double, 9>> Triangles(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  std::vector<std::array<double, 9>> out;
  for (int f = 0; f < F.rows(); ++f) {
    std::array<std::array<double, 3>, 3> corners;
    for (int k = 0; k < 3; ++k) corners[k] = {V(F(f, k), 0), V(F(f, k), 1), V(F(f, k), 2)};
    const int first = static_cast<int>(std::min_element(corners.begin(), corners.end()) - corners.begin());
    std::array<double, 9> t;
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) t[3 * k + a] = corners[(first + k) % 3][a];
    }
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Mean distance in memory (index difference) between the vertices of each
// edge: what the spatial order makes small.
double MeanIndexSpread(const Eigen::MatrixXi& F) {
  double sum = 0;
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) sum += std::abs(F(f, k) - F(f, (k + 1) % 3));
  }
  return sum / (3.0 * F.rows());
}

TEST(Mesh, OrderSpatiallyKeepsTheSurfaceAndGathersNeighbours) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(5, 1.0, &V, &F);
  // Shuffled, as a remesher's output can be.
  std::mt19937 rng(3);
  std::vector<int> perm(V.rows());
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  Eigen::MatrixXd shuffled(V.rows(), 3);
  for (int v = 0; v < V.rows(); ++v) shuffled.row(perm[v]) = V.row(v);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) F(f, k) = perm[F(f, k)];
  }
  std::vector<int> rows(F.rows());
  std::iota(rows.begin(), rows.end(), 0);
  std::shuffle(rows.begin(), rows.end(), rng);
  Eigen::MatrixXi shuffled_F(F.rows(), 3);
  for (int f = 0; f < F.rows(); ++f) shuffled_F.row(f) = F.row(rows[f]);
  // And a vertex no face uses.
  shuffled.conservativeResize(shuffled.rows() + 1, 3);
  shuffled.row(shuffled.rows() - 1) << 5, 5, 5;

  Eigen::MatrixXd W = shuffled;
  Eigen::MatrixXi G = shuffled_F;
  const std::vector<int> map = OrderSpatially(&W, &G);
  ASSERT_EQ(G.rows(), shuffled_F.rows());
  ASSERT_EQ(W.rows(), shuffled.rows() - 1);  // the unused vertex is gone
  EXPECT_EQ(map.back(), -1);
  for (int v = 0; v + 1 < shuffled.rows(); ++v) {
    ASSERT_GE(map[v], 0);
    EXPECT_EQ(W.row(map[v]), shuffled.row(v));
  }
  EXPECT_EQ(Triangles(W, G), Triangles(shuffled, shuffled_F));
  const double before = MeanIndexSpread(shuffled_F), after = MeanIndexSpread(G);
  std::printf("mean index spread of an edge: %.0f shuffled, %.0f ordered (%d vertices)\n", before,
              after, static_cast<int>(W.rows()));
  EXPECT_LT(after, 0.05 * before);
  // An empty mesh stays empty.
  Eigen::MatrixXd E(0, 3);
  Eigen::MatrixXi EF(0, 3);
  EXPECT_TRUE(OrderSpatially(&E, &EF).empty());
}

// A flat n x n grid in z = 0 over [0, 1]^2: its border is the square's outline.
void FlatGrid(int cells, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  *V = Eigen::MatrixXd(0, 3);
  *F = Eigen::MatrixXi(0, 3);
  AppendGrid(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), cells, V,
             F);
}

// Edge rings from the grid's outline: 1 on it, k + 1 on the k-th square inside.
int GridRing(const Eigen::RowVector3d& p, int cells) {
  const double d = std::min({p.x(), p.y(), 1 - p.x(), 1 - p.y()});
  return static_cast<int>(std::lround(d * cells)) + 1;
}

TEST(OpenBorderBand, HoldsTheRingsOfTheBorderOfAnOpenMeshAndNothingOfAClosedOne) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(2, 1.0, &V, &F);
  EXPECT_TRUE(OpenBorderBand(F, static_cast<int>(V.rows()), 3).vertices.empty());

  constexpr int kCells = 10;
  FlatGrid(kCells, &V, &F);
  EXPECT_TRUE(OpenBorderBand(F, static_cast<int>(V.rows()), 0).vertices.empty());
  for (int rings = 1; rings <= 3; ++rings) {
    const VertexBand band = OpenBorderBand(F, static_cast<int>(V.rows()), rings);
    EXPECT_EQ(band.num_border, 4 * kCells);
    // The vertices within `rings` rings, and only those, each with its
    // one-ring neighbours (the triangulated grid's 3 to 6).
    int expected = 0;
    for (int v = 0; v < V.rows(); ++v) expected += GridRing(V.row(v), kCells) <= rings ? 1 : 0;
    ASSERT_EQ(static_cast<int>(band.vertices.size()), expected);
    ASSERT_EQ(band.neighbours.size(), band.vertices.size());
    for (size_t i = 0; i < band.vertices.size(); ++i) {
      const int v = band.vertices[i];
      EXPECT_LE(GridRing(V.row(v), kCells), rings);
      EXPECT_EQ(GridRing(V.row(v), kCells) == 1, static_cast<int>(i) < band.num_border);
      EXPECT_GE(band.neighbours[i].size(), 2u);
      EXPECT_LE(band.neighbours[i].size(), 6u);
      for (const int w : band.neighbours[i]) {
        EXPECT_NEAR((V.row(w) - V.row(v)).norm(), 1.0 / kCells, 1.0 / kCells * 0.5)
            << "not a one-ring neighbour";
      }
    }
  }
}

TEST(MembraneStep, PullsAFlaredSkirtInAndLeavesTheInsideAlone) {
  // A flat grid whose outermost ring is bent down and out, as the skirt
  // COLMAP's trimmed Poisson surface often ends in.
  constexpr int kCells = 12;
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  FlatGrid(kCells, &V, &F);
  for (int v = 0; v < V.rows(); ++v) {
    if (GridRing(V.row(v), kCells) == 1) {
      const Eigen::RowVector3d outward(V(v, 0) - 0.5, V(v, 1) - 0.5, 0);
      V.row(v) += 0.3 * outward + Eigen::RowVector3d(0, 0, -0.2);
    }
  }
  const Eigen::MatrixXd V0 = V;
  const VertexBand band = OpenBorderBand(F, static_cast<int>(V.rows()), 3);
  auto border_sag = [&](const Eigen::MatrixXd& X) {
    double sag = 0;
    for (int i = 0; i < band.num_border; ++i) sag = std::max(sag, -X(band.vertices[i], 2));
    return sag;
  };
  auto border_reach = [&](const Eigen::MatrixXd& X) {
    double reach = 0;
    for (int i = 0; i < band.num_border; ++i) {
      const int v = band.vertices[i];
      reach = std::max(reach, std::max(std::abs(X(v, 0) - 0.5), std::abs(X(v, 1) - 0.5)));
    }
    return reach;
  };
  for (int step = 0; step < 10; ++step) MembraneStep(band, 0.5, &V);
  // The skirt comes up and in: its sag down by more than a third (it spreads
  // into the band, which the fixed inside then lifts), its reach back to
  // within the square.
  EXPECT_LT(border_sag(V), 0.65 * border_sag(V0));
  EXPECT_LT(border_reach(V), 0.5);
  EXPECT_GT(border_reach(V0), 0.6);
  // Beyond the band nothing moves.
  std::vector<char> in_band(V.rows(), 0);
  for (const int v : band.vertices) in_band[v] = 1;
  for (int v = 0; v < V.rows(); ++v) {
    if (!in_band[v]) {
      EXPECT_EQ(V.row(v), V0.row(v)) << v;
    }
  }

  // A flat band stays in its plane.
  FlatGrid(kCells, &V, &F);
  MembraneStep(band, 0.5, &V);
  EXPECT_LT(V.col(2).cwiseAbs().maxCoeff(), 1e-15);

  // With weights, a band vertex of weight 0 stays, one of weight w moves w
  // times as far as without them.
  V = V0;
  Eigen::MatrixXd V_full = V0;
  MembraneStep(band, 0.5, &V_full);
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(band.vertices.size());
  weights(0) = 0;
  weights(1) = 0.25;
  MembraneStep(band, 0.5, &V, &weights);
  const int held = band.vertices[0], quarter = band.vertices[1], free = band.vertices[2];
  EXPECT_EQ(V.row(held), V0.row(held));
  EXPECT_GT((V_full.row(quarter) - V0.row(quarter)).norm(), 1e-3);
  EXPECT_LT((V.row(quarter) - V0.row(quarter) - 0.25 * (V_full.row(quarter) - V0.row(quarter)))
                .norm(),
            1e-15);
  EXPECT_EQ(V.row(free), V_full.row(free));
}

}  // namespace
}  // namespace mr
