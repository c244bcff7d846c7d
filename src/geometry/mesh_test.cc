#include <gtest/gtest.h>

#include "geometry/mesh.h"
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
