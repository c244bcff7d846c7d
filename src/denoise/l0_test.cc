#include "denoise/l0.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "denoise/lp_model.h"
#include "denoise/synthetic_meshes.h"

namespace mr {
namespace {

// Two triangles hinged on the edge (0, 1) along x, the second folded by
// `fold_deg` out of the plane of the first.
void Hinge(double fold_deg, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const double a = fold_deg * M_PI / 180.0;
  V->resize(4, 3);
  *V << 0, 0, 0,  //
      1, 0, 0,    //
      0.4, 0.8, 0,  //
      0.6, -0.7 * std::cos(a), 0.7 * std::sin(a);
  F->resize(2, 3);
  *F << 0, 1, 2, 1, 0, 3;
}

// lp_model's EdgeWeights are He & Schaefer's area-based edge operator: the
// weights of the opposite vertices are S134 / (S123 + S134), S123 / (S123 +
// S134), and those of the edge ends their dot-product forms, e.g. for x1
//   (S123 (x4 - x3).(x3 - x1) + S134 (x1 - x3).(x3 - x2)) / (l13^2 (S123 + S134)).
TEST(EdgeWeights, AreHeSchaefersAreaBasedOperator) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  SubdividedCube(3, &V, &F);
  V = AddNormalNoise(V, F, 0.1, 5);
  const EdgeQuads eq = BuildEdgeQuads(F, static_cast<int>(V.rows()));
  const Eigen::MatrixXd W = EdgeWeights(V, eq.quads);
  for (int i = 0; i < eq.quads.rows(); ++i) {
    const Eigen::Vector3d p1 = V.row(eq.quads(i, 0)), p3 = V.row(eq.quads(i, 1));
    const Eigen::Vector3d p2 = V.row(eq.quads(i, 2)), p4 = V.row(eq.quads(i, 3));
    const double s123 = 0.5 * (p2 - p1).cross(p3 - p1).norm();
    const double s134 = 0.5 * (p4 - p1).cross(p3 - p1).norm();
    const double l2 = (p3 - p1).squaredNorm(), s = s123 + s134;
    const double c1 = (s123 * (p4 - p3).dot(p3 - p1) + s134 * (p1 - p3).dot(p3 - p2)) / (l2 * s);
    const double c3 = (s123 * (p3 - p1).dot(p1 - p4) + s134 * (p2 - p1).dot(p1 - p3)) / (l2 * s);
    EXPECT_NEAR(W(i, 0), c1, 1e-12) << i;
    EXPECT_NEAR(W(i, 1), c3, 1e-12) << i;
    EXPECT_NEAR(W(i, 2), s134 / s, 1e-12) << i;
    EXPECT_NEAR(W(i, 3), s123 / s, 1e-12) << i;
  }
}

TEST(HardThresholdRows, KeepsRowsAtOrAboveTheThreshold) {
  Eigen::MatrixXd rows(5, 3);
  rows << 0.1, 0, 0,  // |r|^2 = 0.01 < 0.04: zeroed
      0, 0.2, 0,      // 0.04 = threshold: kept (tie)
      0.3, 0.3, 0,    // 0.18: kept
      0, 0, 0,        // zero row: stays zero, not counted
      0.1, 0.1, 0.1;  // 0.03: zeroed
  const Eigen::MatrixXd in = rows;
  EXPECT_EQ(HardThresholdRows(0.04, &rows), 2);
  EXPECT_EQ(rows.row(0).squaredNorm(), 0);
  EXPECT_EQ(rows.row(1), in.row(1));
  EXPECT_EQ(rows.row(2), in.row(2));
  EXPECT_EQ(rows.row(3).squaredNorm(), 0);
  EXPECT_EQ(rows.row(4).squaredNorm(), 0);
  Eigen::MatrixXd all = in;
  EXPECT_EQ(HardThresholdRows(0.0, &all), 4);
  EXPECT_EQ(all, in);
  Eigen::MatrixXd empty(0, 3);
  EXPECT_EQ(HardThresholdRows(1.0, &empty), 0);
}

// The delta-step minimises beta |delta - r|^2 + lambda [delta != 0] per row:
// compare with the two candidates (0 and r; any other delta != 0 is worse
// than r) over a sweep of row lengths and directions.
TEST(HardThresholdRows, MinimisesTheRowEnergy) {
  const double lambda = 0.3, beta = 2.0;
  for (int k = 0; k < 50; ++k) {
    const double len = 0.02 * k;
    Eigen::MatrixXd r(1, 3);
    r.row(0) = len * Eigen::RowVector3d(std::cos(k), std::sin(k), 0.5).normalized();
    Eigen::MatrixXd delta = r;
    HardThresholdRows(lambda / beta, &delta);
    auto energy = [&](const Eigen::MatrixXd& d) {
      return beta * (d - r).squaredNorm() + (d.squaredNorm() > 0 ? lambda : 0.0);
    };
    const double best = std::min(energy(Eigen::MatrixXd::Zero(1, 3)), energy(r));
    EXPECT_LE(energy(delta), best + 1e-15) << "len " << len;
  }
}

TEST(MeanDihedralAngleDeg, HingeAngles) {
  for (double fold : {0.0, 10.0, 30.0, 90.0, 150.0}) {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    Hinge(fold, &V, &F);
    const EdgeQuads eq = BuildEdgeQuads(F, 4);
    ASSERT_EQ(eq.quads.rows(), 1);
    const Eigen::MatrixXd W = EdgeWeights(V, eq.quads);
    EXPECT_NEAR(MeanDihedralAngleDeg(V, eq.quads, W), fold, 1e-9) << fold;
    // Independent of the faces' orientation.
    const Eigen::MatrixXi flipped = F.rowwise().reverse();
    const EdgeQuads ef = BuildEdgeQuads(flipped, 4);
    EXPECT_NEAR(MeanDihedralAngleDeg(V, ef.quads, EdgeWeights(V, ef.quads)), fold, 1e-9);
  }
}

TEST(MeanDihedralAngleDeg, CubeAndEmpty) {
  // n x n grid per face: 18 n^2 edges, 12 n of them on the cube's edges at 90
  // degrees, the others flat: mean = 90 * 12 n / (18 n^2) = 60 / n.
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  SubdividedCube(4, &V, &F);
  const EdgeQuads eq = BuildEdgeQuads(F, static_cast<int>(V.rows()));
  EXPECT_NEAR(MeanDihedralAngleDeg(V, eq.quads, EdgeWeights(V, eq.quads)), 15.0, 1e-9);
  EXPECT_EQ(MeanDihedralAngleDeg(V, Eigen::MatrixXi(0, 4), Eigen::MatrixXd(0, 4)), 0.0);
  // Rows with zero weights (degenerate) are not counted.
  Eigen::MatrixXd W = EdgeWeights(V, eq.quads);
  W.setZero();
  EXPECT_EQ(MeanDihedralAngleDeg(V, eq.quads, W), 0.0);
}

TEST(RegularizerWeights, EdgeEndsMinusOppositeVertices) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Hinge(40, &V, &F);
  const EdgeQuads eq = BuildEdgeQuads(F, 4);
  const Eigen::MatrixXd RX = ApplyEdgeOperator(eq.quads, RegularizerWeights(eq.quads), V);
  const Eigen::RowVector3d expected = V.row(0) + V.row(1) - V.row(2) - V.row(3);
  EXPECT_LT((RX.row(0) - expected).norm(), 1e-15);
  // Zero on a parallelogram (a flat regular grid: the subdivided cube's faces).
  SubdividedCube(3, &V, &F);
  const EdgeQuads ec = BuildEdgeQuads(F, static_cast<int>(V.rows()));
  const Eigen::MatrixXd RC = ApplyEdgeOperator(ec.quads, RegularizerWeights(ec.quads), V);
  const Eigen::MatrixXd DC = ApplyEdgeOperator(ec.quads, EdgeWeights(V, ec.quads), V);
  int flat = 0;
  for (int i = 0; i < RC.rows(); ++i) {
    if (DC.row(i).norm() < 1e-12) {
      ++flat;
      EXPECT_LT(RC.row(i).norm(), 1e-12) << i;
    }
  }
  EXPECT_EQ(flat, 18 * 9 - 12 * 3);
}

}  // namespace
}  // namespace mr
