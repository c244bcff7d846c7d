#include "init/isosurface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/mesh.h"

namespace mr {
namespace {

// A grid of n^3 nodes over [-1, 1]^3 filled with f(X).
template <typename Fn>
ScalarGrid MakeGrid(int n, Fn f) {
  const double h = 2.0 / (n - 1);
  ScalarGrid grid(n, n, n, Eigen::Vector3d(-1, -1, -1), h);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) grid.At(i, j, k) = static_cast<float>(f(grid.Position(i, j, k)));
    }
  }
  return grid;
}

int EulerCharacteristic(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const EdgeTopology topo = ComputeEdgeTopology(F, static_cast<int>(V.rows()));
  return static_cast<int>(V.rows() - topo.E.rows() + F.rows());
}

TEST(ExtractIsosurface, SphereSdfIsWatertightOrientedAndAccurate) {
  const double r = 0.7;
  const ScalarGrid grid = MakeGrid(33, [&](const Eigen::Vector3d& X) { return r - X.norm(); });
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(grid, 0.0, &V, &F);
  ASSERT_GT(F.rows(), 100);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  // Every edge is shared by exactly two faces.
  const EdgeTopology topo = ComputeEdgeTopology(F, static_cast<int>(V.rows()));
  EXPECT_EQ(topo.NumBoundaryEdges(), 0);
  EXPECT_EQ(topo.NumNonManifoldEdges(), 0);
  EXPECT_EQ(EulerCharacteristic(V, F), 2);
  // Vertices lie on the sphere up to the linear interpolation error of the
  // SDF along a grid edge (second order in the spacing).
  const double h = grid.spacing;
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    ASSERT_NEAR(V.row(v).norm(), r, 0.1 * h) << "vertex " << v;
  }
  const double volume = SignedVolume(V, F);
  EXPECT_GT(volume, 0);  // outward orientation
  EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI * r * r * r, 0.03 * 4.0 / 3.0 * M_PI * r * r * r);
  // Face normals point away from the centre.
  const Eigen::MatrixXd N = FaceNormals(V, F);
  int inward = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    inward += N.row(f).dot(c.normalized()) < 0;
  }
  EXPECT_EQ(inward, 0);
}

TEST(ExtractIsosurface, TorusHasGenusOne) {
  const ScalarGrid grid = MakeGrid(41, [](const Eigen::Vector3d& X) {
    const double q = std::hypot(X.x(), X.y()) - 0.6;
    return 0.25 - std::hypot(q, X.z());
  });
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(grid, 0.0, &V, &F);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  EXPECT_EQ(EulerCharacteristic(V, F), 0);
  EXPECT_GT(SignedVolume(V, F), 0);
}

TEST(ExtractIsosurface, RandomFieldIsStillManifold) {
  // Many ambiguous configurations and values exactly at the iso level.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> dist(-2, 2);
  const ScalarGrid grid = MakeGrid(14, [&](const Eigen::Vector3d&) { return dist(rng) * 0.5; });
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(grid, 0.0, &V, &F);
  ASSERT_GT(F.rows(), 100);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  EXPECT_GT(SignedVolume(V, F), 0);
}

TEST(ExtractIsosurface, AllInsideIsClosedByTheGridBoundary) {
  const ScalarGrid grid = MakeGrid(6, [](const Eigen::Vector3d&) { return 1.0; });
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(grid, 0.0, &V, &F);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  EXPECT_EQ(EulerCharacteristic(V, F), 2);
  EXPECT_GT(SignedVolume(V, F), 0);
}

TEST(ExtractIsosurface, EmptyAndDegenerateGrids) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(MakeGrid(5, [](const Eigen::Vector3d&) { return -1.0; }), 0.0, &V, &F);
  EXPECT_EQ(F.rows(), 0);
  EXPECT_EQ(V.rows(), 0);
  ExtractIsosurface(ScalarGrid(1, 5, 5, Eigen::Vector3d::Zero(), 1.0, 1.f), 0.0, &V, &F);
  EXPECT_EQ(F.rows(), 0);
}

TEST(KeepLargestComponent, TwoSpheres) {
  const ScalarGrid grid = MakeGrid(41, [](const Eigen::Vector3d& X) {
    const double a = 0.45 - (X - Eigen::Vector3d(-0.45, 0, 0)).norm();
    const double b = 0.3 - (X - Eigen::Vector3d(0.6, 0, 0)).norm();
    return std::max(a, b);
  });
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ExtractIsosurface(grid, 0.0, &V, &F);
  EXPECT_EQ(KeepLargestComponent(&V, &F), 2);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  // Only the large sphere is left.
  for (Eigen::Index v = 0; v < V.rows(); ++v) ASSERT_LT(V(v, 0), 0.05);
  EXPECT_NEAR(SignedVolume(V, F), 4.0 / 3.0 * M_PI * std::pow(0.45, 3), 0.05);
}

TEST(IsClosedAndOriented, DetectsHolesAndFlips) {
  // A tetrahedron, outward.
  Eigen::MatrixXi F(4, 3);
  F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  Eigen::MatrixXd V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  EXPECT_TRUE(IsClosedAndOriented(F));
  EXPECT_GT(SignedVolume(V, F), 0);
  Eigen::MatrixXi open = F.topRows(3);
  std::string why;
  EXPECT_FALSE(IsClosedAndOriented(open, &why));
  EXPECT_FALSE(why.empty());
  Eigen::MatrixXi flipped = F;
  std::swap(flipped(0, 1), flipped(0, 2));
  EXPECT_FALSE(IsClosedAndOriented(flipped));
}

}  // namespace
}  // namespace mr
