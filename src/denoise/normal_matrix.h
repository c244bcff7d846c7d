#pragma once

// The linear algebra shared by the lp and l0 denoisers (denoiser.cc, l0.cc):
// both alternate a per-row shrinkage of D X with an X-step
//   (I + c_D D^T D + c_R R^T R) X = B,
// D (and the optional regulariser R of l0) one row per interior edge quad
// (EdgeQuads::quads, lp_model.h). The matrix has the fixed sparsity pattern of
// the quads; only its values change with the weights and the coefficients.
//
//   NormalMatrix normal(quads, n);
//   normal.SetWeights(W);                     // D's weights (EdgeWeights)
//   normal.Matrix(2 * beta);                  // fill I + 2 beta D^T D
//   SolveCg(normal, B, 1e-3, 1000, &X);       // warm-started from X
// or the direct path: SparseCholesky::Analyze once, Factorize per matrix.

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mr {

using RowMatrix3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The lower triangle of I + c_D D^T D + c_R R^T R with a fixed sparsity
// pattern; the values are refilled when the weights or coefficients change.
// `quads` (#rows by 4 vertex indices) must outlive this object.
class NormalMatrix {
 public:
  NormalMatrix(const Eigen::MatrixXi& quads, int num_vertices);

  // Recomputes D^T D from D's #rows by 4 weights (row i of D X is
  // sum_k W(i, k) X(quads(i, k))).
  void SetWeights(const Eigen::MatrixXd& W);
  // Recomputes R^T R from the weights of a second operator on the same quads
  // (l0's regulariser); until called, R = 0.
  void SetRegularizerWeights(const Eigen::MatrixXd& W);

  // Fills and returns A = I + d_coefficient D^T D + r_coefficient R^T R
  // (lower triangle, compressed column storage).
  const Eigen::SparseMatrix<double>& Matrix(double d_coefficient, double r_coefficient = 0);

  // Y = A P with A the symmetric matrix that Matrix() last filled; P, Y #V by
  // 3, one row per vertex. Rows in parallel.
  void Multiply(const RowMatrix3& P, RowMatrix3* Y) const;
  // Diagonal of A (for the Jacobi preconditioner).
  Eigen::VectorXd Diagonal() const;

 private:
  int Find(int r, int c) const;
  void Accumulate(const Eigen::MatrixXd& W, std::vector<double>* out) const;

  const Eigen::MatrixXi& quads_;
  Eigen::SparseMatrix<double> A_;
  std::vector<int> slots_;
  std::vector<int> diag_;
  std::vector<double> dtd_, rtr_;
  std::vector<int> full_outer_, full_col_, full_slot_;
};

// Solves A X = B (A from normal.Matrix(...)) by Jacobi-preconditioned
// conjugate gradients on the three columns at once (one step length for all
// three, so the iterates commute with a rotation of the coordinates),
// warm-started from *X_inout. Stops when the RMS residual per vertex and
// coordinate is below `tolerance` (A >= I, so the error is at most the
// residual), or after max_iterations. Returns the iterations used.
int SolveCg(const NormalMatrix& normal, const Eigen::MatrixXd& B, double tolerance,
            int max_iterations, Eigen::MatrixXd* X_inout);

// Sparse Cholesky of the lower triangle: CHOLMOD supernodal when found at
// configure time (MR_HAVE_CHOLMOD), else Eigen's SimplicialLDLT.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  // Symbolic analysis (once per pattern).
  void Analyze(const Eigen::SparseMatrix<double>& A);
  // Numeric factorisation; throws (MR_CHECK) if A is not positive definite.
  void Factorize(const Eigen::SparseMatrix<double>& A);
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& B) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// D^T Psi (#V by 3) without forming D; Psi #rows by 3.
Eigen::MatrixXd ApplyEdgeOperatorTranspose(const Eigen::MatrixXi& quads,
                                           const Eigen::MatrixXd& W, const Eigen::MatrixXd& Psi,
                                           int num_vertices);

// The normalisation both methods work in: X = (V - centre) / scale with the
// centroid of the vertices and the mean length of the face edges (each
// interior edge counted twice). Returns false if the scale is not a positive
// finite number (all edges of zero length, or no face).
bool NormalizationOf(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                     Eigen::RowVector3d* centre, double* scale);

}  // namespace mr
