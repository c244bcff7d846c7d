#include "denoise/normal_matrix.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "denoise/l0.h"
#include "denoise/lp_model.h"
#include "denoise/synthetic_meshes.h"

namespace mr {
namespace {

struct Fixture {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  EdgeQuads eq;
  Eigen::MatrixXd W, Wr;
  Eigen::MatrixXd D, R;  // dense operators
  int n = 0;
};

Fixture MakeFixture() {
  Fixture f;
  SubdividedCube(3, &f.V, &f.F);
  f.V = AddNormalNoise(f.V, f.F, 0.05, 3);
  f.n = static_cast<int>(f.V.rows());
  f.eq = BuildEdgeQuads(f.F, f.n);
  f.W = EdgeWeights(f.V, f.eq.quads);
  f.Wr = RegularizerWeights(f.eq.quads);
  f.D = Eigen::MatrixXd(AssembleEdgeOperator(f.eq.quads, f.W, f.n));
  f.R = Eigen::MatrixXd(AssembleEdgeOperator(f.eq.quads, f.Wr, f.n));
  return f;
}

TEST(NormalMatrix, MatchesDenseAssembly) {
  const Fixture f = MakeFixture();
  NormalMatrix normal(f.eq.quads, f.n);
  normal.SetWeights(f.W);
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(f.n, f.n);
  // Without a regulariser, the R coefficient is ignored.
  Eigen::MatrixXd lower = Eigen::MatrixXd(normal.Matrix(3.0, 5.0));
  Eigen::MatrixXd expected = I + 3.0 * f.D.transpose() * f.D;
  EXPECT_LT((lower - Eigen::MatrixXd(expected.triangularView<Eigen::Lower>())).norm(), 1e-12);
  normal.SetRegularizerWeights(f.Wr);
  lower = Eigen::MatrixXd(normal.Matrix(3.0, 0.25));
  expected = I + 3.0 * f.D.transpose() * f.D + 0.25 * f.R.transpose() * f.R;
  EXPECT_LT((lower - Eigen::MatrixXd(expected.triangularView<Eigen::Lower>())).norm(), 1e-12);
  EXPECT_LT((normal.Diagonal() - expected.diagonal()).norm(), 1e-12);
  // The row-parallel product uses both triangles.
  const RowMatrix3 P = Eigen::MatrixXd::Random(f.n, 3);
  RowMatrix3 Y;
  normal.Multiply(P, &Y);
  EXPECT_LT((Eigen::MatrixXd(Y) - expected * Eigen::MatrixXd(P)).norm(), 1e-10);
}

TEST(NormalMatrix, CgAndCholeskySolve) {
  const Fixture f = MakeFixture();
  NormalMatrix normal(f.eq.quads, f.n);
  normal.SetWeights(f.W);
  normal.SetRegularizerWeights(f.Wr);
  const Eigen::SparseMatrix<double>& A = normal.Matrix(50.0, 0.5);
  const Eigen::MatrixXd full = Eigen::MatrixXd(
      Eigen::MatrixXd(A).selfadjointView<Eigen::Lower>());
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(f.n, 3);
  const Eigen::MatrixXd exact = full.ldlt().solve(B);
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(f.n, 3);
  const int used = SolveCg(normal, B, 1e-8, 1000, &X);
  EXPECT_GT(used, 0);
  EXPECT_LT(used, 1000);
  EXPECT_LT((X - exact).cwiseAbs().maxCoeff(), 1e-6);
  // Warm-started at the solution: no iteration.
  EXPECT_EQ(SolveCg(normal, B, 1e-6, 1000, &X), 0);
  SparseCholesky chol;
  chol.Analyze(A);
  chol.Factorize(A);
  EXPECT_LT((chol.Solve(B) - exact).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(NormalMatrix, TransposeAndNormalization) {
  const Fixture f = MakeFixture();
  const Eigen::MatrixXd Psi = Eigen::MatrixXd::Random(f.eq.quads.rows(), 3);
  EXPECT_LT(
      (ApplyEdgeOperatorTranspose(f.eq.quads, f.W, Psi, f.n) - f.D.transpose() * Psi).norm(),
      1e-12);
  Eigen::RowVector3d centre;
  double scale = 0;
  ASSERT_TRUE(NormalizationOf(f.V, f.F, &centre, &scale));
  EXPECT_LT((centre - f.V.colwise().mean()).norm(), 1e-15);
  double sum = 0;
  for (int i = 0; i < f.F.rows(); ++i) {
    for (int k = 0; k < 3; ++k) sum += (f.V.row(f.F(i, k)) - f.V.row(f.F(i, (k + 1) % 3))).norm();
  }
  EXPECT_NEAR(scale, sum / (3.0 * f.F.rows()), 1e-15);
  // Degenerate: no face, or all vertices at one point.
  EXPECT_FALSE(NormalizationOf(Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3), &centre, &scale));
  EXPECT_FALSE(NormalizationOf(Eigen::MatrixXd::Zero(f.n, 3), f.F, &centre, &scale));
}

}  // namespace
}  // namespace mr
