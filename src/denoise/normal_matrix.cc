#include "denoise/normal_matrix.h"

#include <algorithm>
#include <cmath>

#ifdef MR_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif

#include "util/error.h"

namespace mr {

NormalMatrix::NormalMatrix(const Eigen::MatrixXi& quads, int n) : quads_(quads) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(quads.rows()) * 10 + n);
  for (int v = 0; v < n; ++v) t.emplace_back(v, v, 1.0);
  for (int i = 0; i < quads.rows(); ++i) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int r = quads(i, a), c = quads(i, b);
        if (r >= c) t.emplace_back(r, c, 1.0);
      }
    }
  }
  A_.resize(n, n);
  A_.setFromTriplets(t.begin(), t.end());
  A_.makeCompressed();
  // Position of each (row, a, b) product in A_'s value array (lower part).
  slots_.resize(static_cast<size_t>(quads.rows()) * 16);
  for (int i = 0; i < quads.rows(); ++i) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int r = quads(i, a), c = quads(i, b);
        slots_[16 * static_cast<size_t>(i) + 4 * a + b] = r >= c ? Find(r, c) : -1;
      }
    }
  }
  diag_.resize(n);
  for (int v = 0; v < n; ++v) diag_[v] = Find(v, v);
  dtd_.assign(A_.nonZeros(), 0.0);
  // Both triangles, row by row, pointing into the lower triangle's values
  // (for the row-parallel product of the conjugate-gradient solver).
  const int* outer = A_.outerIndexPtr();
  const int* inner = A_.innerIndexPtr();
  full_outer_.assign(n + 1, 0);
  for (int c = 0; c < n; ++c) {
    for (int s = outer[c]; s < outer[c + 1]; ++s) {
      ++full_outer_[inner[s] + 1];
      if (inner[s] != c) ++full_outer_[c + 1];
    }
  }
  for (int r = 0; r < n; ++r) full_outer_[r + 1] += full_outer_[r];
  full_col_.resize(full_outer_[n]);
  full_slot_.resize(full_outer_[n]);
  std::vector<int> next(full_outer_.begin(), full_outer_.end() - 1);
  for (int c = 0; c < n; ++c) {
    for (int s = outer[c]; s < outer[c + 1]; ++s) {
      const int r = inner[s];
      full_col_[next[r]] = c;
      full_slot_[next[r]++] = s;
      if (r != c) {
        full_col_[next[c]] = r;
        full_slot_[next[c]++] = s;
      }
    }
  }
}

void NormalMatrix::Accumulate(const Eigen::MatrixXd& W, std::vector<double>* out) const {
  MR_CHECK(W.rows() == quads_.rows() && W.cols() == 4) << "weights do not match the quads";
  out->assign(A_.nonZeros(), 0.0);
  for (int i = 0; i < quads_.rows(); ++i) {
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int s = slots_[16 * static_cast<size_t>(i) + 4 * a + b];
        if (s >= 0) (*out)[s] += W(i, a) * W(i, b);
      }
    }
  }
}

void NormalMatrix::SetWeights(const Eigen::MatrixXd& W) { Accumulate(W, &dtd_); }

void NormalMatrix::SetRegularizerWeights(const Eigen::MatrixXd& W) { Accumulate(W, &rtr_); }

const Eigen::SparseMatrix<double>& NormalMatrix::Matrix(double d_coefficient,
                                                        double r_coefficient) {
  double* values = A_.valuePtr();
  for (size_t s = 0; s < dtd_.size(); ++s) values[s] = d_coefficient * dtd_[s];
  if (r_coefficient != 0 && !rtr_.empty()) {
    for (size_t s = 0; s < rtr_.size(); ++s) values[s] += r_coefficient * rtr_[s];
  }
  for (int d : diag_) values[d] += 1.0;
  return A_;
}

void NormalMatrix::Multiply(const RowMatrix3& P, RowMatrix3* Y) const {
  Y->resize(P.rows(), 3);
  const double* values = A_.valuePtr();
#pragma omp parallel for schedule(static) if (P.rows() > 20000)
  for (int r = 0; r < static_cast<int>(P.rows()); ++r) {
    Eigen::RowVector3d y = Eigen::RowVector3d::Zero();
    for (int s = full_outer_[r]; s < full_outer_[r + 1]; ++s) {
      y += values[full_slot_[s]] * P.row(full_col_[s]);
    }
    Y->row(r) = y;
  }
}

Eigen::VectorXd NormalMatrix::Diagonal() const {
  Eigen::VectorXd d(diag_.size());
  for (size_t v = 0; v < diag_.size(); ++v) d[v] = A_.valuePtr()[diag_[v]];
  return d;
}

int NormalMatrix::Find(int r, int c) const {
  const int* begin = A_.innerIndexPtr() + A_.outerIndexPtr()[c];
  const int* end = A_.innerIndexPtr() + A_.outerIndexPtr()[c + 1];
  const int* it = std::lower_bound(begin, end, r);
  MR_CHECK(it != end && *it == r) << "pattern entry missing";
  return static_cast<int>(it - A_.innerIndexPtr());
}

int SolveCg(const NormalMatrix& normal, const Eigen::MatrixXd& B_in, double tolerance,
            int max_iterations, Eigen::MatrixXd* X_inout) {
  // CG on the 3n system (A kron I3) x = b.
  const RowMatrix3 B = B_in;
  RowMatrix3 X = *X_inout;
  const Eigen::VectorXd inv_diag = normal.Diagonal().cwiseInverse();
  RowMatrix3 AX;
  normal.Multiply(X, &AX);
  RowMatrix3 R = B - AX;
  RowMatrix3 Z = R.array().colwise() * inv_diag.array();
  RowMatrix3 P = Z;
  double rz = (R.array() * Z.array()).sum();
  const double target = tolerance * tolerance * static_cast<double>(B.size());
  RowMatrix3 AP;
  int k = 0;
  for (; k < max_iterations; ++k) {
    if (R.squaredNorm() <= target) break;
    normal.Multiply(P, &AP);
    const double pap = (P.array() * AP.array()).sum();
    if (!(pap > 0)) break;
    const double alpha = rz / pap;
    X += alpha * P;
    R -= alpha * AP;
    Z = R.array().colwise() * inv_diag.array();
    const double rz_new = (R.array() * Z.array()).sum();
    P = Z + (rz_new / rz) * P;
    rz = rz_new;
  }
  *X_inout = X;
  return k;
}

struct SparseCholesky::Impl {
#ifdef MR_HAVE_CHOLMOD
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
#else
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
#endif
};

SparseCholesky::SparseCholesky() : impl_(new Impl) {}
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::Analyze(const Eigen::SparseMatrix<double>& A) {
  impl_->solver.analyzePattern(A);
}

void SparseCholesky::Factorize(const Eigen::SparseMatrix<double>& A) {
  impl_->solver.factorize(A);
  MR_CHECK(impl_->solver.info() == Eigen::Success) << "sparse Cholesky failed";
}

Eigen::MatrixXd SparseCholesky::Solve(const Eigen::MatrixXd& B) const {
  return impl_->solver.solve(B);
}

Eigen::MatrixXd ApplyEdgeOperatorTranspose(const Eigen::MatrixXi& quads,
                                           const Eigen::MatrixXd& W, const Eigen::MatrixXd& Psi,
                                           int n) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, 3);
  for (int i = 0; i < quads.rows(); ++i) {
    for (int k = 0; k < 4; ++k) out.row(quads(i, k)) += W(i, k) * Psi.row(i);
  }
  return out;
}

bool NormalizationOf(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                     Eigen::RowVector3d* centre, double* scale) {
  *centre = V.rows() > 0 ? Eigen::RowVector3d(V.colwise().mean()) : Eigen::RowVector3d::Zero();
  double h = 0;
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) h += (V.row(F(f, k)) - V.row(F(f, (k + 1) % 3))).norm();
  }
  if (F.rows() > 0) h /= 3.0 * F.rows();
  *scale = h;
  return h > 0 && std::isfinite(h);
}

}  // namespace mr
