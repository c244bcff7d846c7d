#include "denoise/denoiser.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include <Eigen/SparseCore>
#ifdef MR_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif

#include "denoise/baselines.h"
#include "denoise/lp_model.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/options.h"

namespace mr {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

#define MR_CHECK_OPTION(cond, field, bound)                                            \
  if (!(cond)) {                                                                       \
    MR_THROW_INPUT << "DenoiseOptions::" #field " = " << field                         \
                   << ". Violated constraint: " bound;                                 \
  }

using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The lower triangle of I + 2 beta D^T D with a fixed sparsity pattern; the
// values are refilled when D's weights change or beta changes.
class NormalMatrix {
 public:
  NormalMatrix(const Eigen::MatrixXi& quads, int n) : quads_(quads) {
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

  // Recomputes D^T D from the weights.
  void SetWeights(const Eigen::MatrixXd& W) {
    std::fill(dtd_.begin(), dtd_.end(), 0.0);
    for (int i = 0; i < quads_.rows(); ++i) {
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) {
          const int s = slots_[16 * static_cast<size_t>(i) + 4 * a + b];
          if (s >= 0) dtd_[s] += W(i, a) * W(i, b);
        }
      }
    }
  }

  // Y = A P with A the symmetric matrix whose lower triangle Matrix() last
  // filled; P, Y #V by 3, row-major (one row per vertex). Rows in parallel.
  void Multiply(const Rows3& P, Rows3* Y) const {
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

  // Diagonal of A (for the Jacobi preconditioner).
  Eigen::VectorXd Diagonal() const {
    Eigen::VectorXd d(diag_.size());
    for (size_t v = 0; v < diag_.size(); ++v) d[v] = A_.valuePtr()[diag_[v]];
    return d;
  }

  // A = I + 2 beta D^T D (lower triangle).
  const Eigen::SparseMatrix<double>& Matrix(double beta) {
    double* values = A_.valuePtr();
    for (size_t s = 0; s < dtd_.size(); ++s) values[s] = 2.0 * beta * dtd_[s];
    for (int d : diag_) values[d] += 1.0;
    return A_;
  }

 private:
  int Find(int r, int c) const {
    const int* begin = A_.innerIndexPtr() + A_.outerIndexPtr()[c];
    const int* end = A_.innerIndexPtr() + A_.outerIndexPtr()[c + 1];
    const int* it = std::lower_bound(begin, end, r);
    MR_CHECK(it != end && *it == r) << "pattern entry missing";
    return static_cast<int>(it - A_.innerIndexPtr());
  }

  const Eigen::MatrixXi& quads_;
  Eigen::SparseMatrix<double> A_;
  std::vector<int> slots_;
  std::vector<int> diag_;
  std::vector<double> dtd_;
  std::vector<int> full_outer_, full_col_, full_slot_;
};

#ifdef MR_HAVE_CHOLMOD
using Cholesky = Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
#else
using Cholesky = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
#endif

// Solves A X = B (A from normal.Matrix(beta)) by Jacobi-preconditioned
// conjugate gradients on the three columns at once, warm-started from *X (the
// previous psi/X step's solution, which is close). Stops when the RMS residual
// per vertex and coordinate is below `tolerance` (in the normalised units,
// mean edge = 1; A >= I, so the error is at most the residual), or after
// max_iterations. Returns the iterations used.
int SolveCg(const NormalMatrix& normal, const Eigen::MatrixXd& B_in, double tolerance,
            int max_iterations, Eigen::MatrixXd* X_inout) {
  // CG on the 3n system (A kron I3) x = b: one step length for all three
  // columns, so the iterates commute with a rotation of the coordinates.
  const Rows3 B = B_in;
  Rows3 X = *X_inout;
  const Eigen::VectorXd inv_diag = normal.Diagonal().cwiseInverse();
  Rows3 AX;
  normal.Multiply(X, &AX);
  Rows3 R = B - AX;
  Rows3 Z = R.array().colwise() * inv_diag.array();
  Rows3 P = Z;
  double rz = (R.array() * Z.array()).sum();
  const double target = tolerance * tolerance * static_cast<double>(B.size());
  Rows3 AP;
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

// D^T Psi without forming D.
Eigen::MatrixXd ApplyTranspose(const Eigen::MatrixXi& quads, const Eigen::MatrixXd& W,
                               const Eigen::MatrixXd& Psi, int n) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, 3);
  for (int i = 0; i < quads.rows(); ++i) {
    for (int k = 0; k < 4; ++k) out.row(quads(i, k)) += W(i, k) * Psi.row(i);
  }
  return out;
}

// Robust noise estimate from the rows of D X0 (used where X = X0 makes the
// closed form zero). D only sees the normal component of a displacement, so
// on the (mostly flat) rows |D_i X0| / |w_i| is sigma |N(0, 1)|, sigma the
// standard deviation of the noise along the normal, whose median is 0.6745
// sigma (median absolute deviation).
double RobustSigma(const Eigen::MatrixXd& R, const Eigen::MatrixXd& W) {
  std::vector<double> r;
  r.reserve(R.rows());
  for (int i = 0; i < R.rows(); ++i) {
    const double wn = W.row(i).norm();
    if (wn > 0) r.push_back(R.row(i).norm() / wn);
  }
  if (r.empty()) return 0;
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return r[r.size() / 2] / 0.6745;
}

void DenoiseLp(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F, const DenoiseOptions& o,
               DenoiseResult* result) {
  const double t0 = Now();
  const int n = static_cast<int>(V0.rows());
  EdgeQuads eq = BuildEdgeQuads(F, n);
  result->num_skipped_edges = eq.num_boundary + eq.num_non_manifold;
  if (eq.quads.rows() == 0) {
    result->passed_through = true;
    result->V = V0;
    MR_LOG(INFO) << "Denoise: no interior edge (" << F.rows() << " faces); mesh passed through";
    return;
  }
  // Normalise: centroid at the origin, unit mean edge length (over face edges).
  const Eigen::RowVector3d centre = V0.colwise().mean();
  double h = 0;
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) h += (V0.row(F(f, k)) - V0.row(F(f, (k + 1) % 3))).norm();
  }
  h /= 3.0 * F.rows();
  if (!(h > 0) || !std::isfinite(h)) {
    result->passed_through = true;
    result->V = V0;
    MR_LOG(WARNING) << "Denoise: all edges have zero length; mesh passed through";
    return;
  }
  const Eigen::MatrixXd X0 = (V0.rowwise() - centre) / h;
  Eigen::MatrixXd X = X0;

  int degenerate = 0;
  Eigen::MatrixXd W = EdgeWeights(X0, eq.quads, &degenerate);
  result->num_operator_rows = static_cast<int>(eq.quads.rows()) - degenerate;
  if (eq.num_boundary + eq.num_non_manifold + degenerate > 0) {
    MR_LOG(VERBOSE) << "Denoise: skipped " << eq.num_boundary << " boundary, "
                    << eq.num_non_manifold << " non-manifold and " << degenerate
                    << " degenerate edges";
  }
  NormalMatrix normal(eq.quads, n);
  Cholesky solver;
  const bool direct = o.linear_solver == "cholesky";
  if (direct) solver.analyzePattern(normal.Matrix(1.0));
  result->setup_seconds = Now() - t0;

  const double sigma0 = RobustSigma(ApplyEdgeOperator(eq.quads, W, X0), W);
  for (int k = 0; k < o.max_iterations; ++k) {
    const double tk = Now();
    DenoiseIteration it;
    if (k > 0 && o.update_operator) W = EdgeWeights(X, eq.quads, &degenerate);
    const Eigen::MatrixXd R = ApplyEdgeOperator(eq.quads, W, X);
    std::vector<double> norms;
    norms.reserve(R.rows());
    for (int i = 0; i < R.rows(); ++i) {
      if (W.row(i).squaredNorm() > 0) norms.push_back(R.row(i).norm());
    }
    const Eigen::VectorXd row_norms =
        Eigen::Map<Eigen::VectorXd>(norms.data(), static_cast<int>(norms.size()));
    // sigma: the closed form (eq. ca8), which is 0 at X = X0 and grows past
    // the noise once X is over-smoothed; bounded by the robust estimate of
    // the noise in X0 (documented in docs/denoising.md).
    double sigma2 =
        k == 0 ? sigma0 * sigma0 : std::min(SigmaSquaredClosedForm(X, X0), sigma0 * sigma0);
    double theta = 0, p = 0;
    const bool frozen = k >= o.estimate_iterations && !result->iterations.empty();
    if (frozen) {
      // Parameters frozen after estimate_iterations rounds; only D is re-weighted.
      const DenoiseIteration& prev = result->iterations.back();
      p = prev.p;
      theta = prev.theta * std::pow(h, p);
      sigma2 = prev.sigma * prev.sigma / (h * h);
    } else if (o.fixed_p > 0) {
      p = o.fixed_p;
      theta = ThetaClosedForm(row_norms, p);
    } else {
      p = EstimateP(row_norms, o.p_min, o.p_max, o.p_step, &theta);
    }
    double lambda = o.fixed_lambda > 0 ? o.fixed_lambda / std::pow(h, 2.0 - p)
                                       : 0.5 * theta * sigma2 * o.lambda_scale;
    if (!std::isfinite(lambda)) lambda = 0;
    it.p = p;
    it.theta = theta * std::pow(h, -p);
    it.sigma = std::sqrt(sigma2) * h;
    it.lambda = lambda * std::pow(h, 2.0 - p);
    if (lambda <= 0) {
      it.seconds = Now() - tk;
      result->iterations.push_back(it);
      MR_LOG(VERBOSE) << "Denoise: lambda = 0 (no noise estimated); stopping";
      break;
    }
    normal.SetWeights(W);
    // Every outer iteration runs the full beta continuation (graduated
    // non-convexity) unless warm_iterations > 0: then outer iterations after
    // the first warm-start from X at beta_max (one factorisation,
    // warm_iterations psi/X alternations).
    std::vector<double> betas;
    if (k == 0 || o.warm_iterations == 0) {
      for (double b = o.beta_initial; b <= o.beta_max * (1 + 1e-12); b *= o.beta_factor) {
        for (int j = 0; j < o.inner_iterations; ++j) betas.push_back(b);
      }
    } else {
      betas.assign(o.warm_iterations, o.beta_max);
    }
    Eigen::MatrixXd Xk = X;
    double factored_beta = -1;
    for (double beta : betas) {
      // psi-step: per-row vector GST with threshold lambda / (2 beta).
      Eigen::MatrixXd Psi = ApplyEdgeOperator(eq.quads, W, Xk);
      const double tau = lambda / (2.0 * beta);
#pragma omp parallel for schedule(static) if (Psi.rows() > 50000)
      for (int i = 0; i < Psi.rows(); ++i) {
        Psi.row(i) = GstShrinkVector(Psi.row(i).transpose(), tau, p).transpose();
      }
      // X-step: (I + 2 beta D^T D) X = X0 + 2 beta D^T psi.
      const Eigen::MatrixXd rhs = X0 + 2.0 * beta * ApplyTranspose(eq.quads, W, Psi, n);
      if (!direct) {
        if (beta != factored_beta) {
          normal.Matrix(beta);
          factored_beta = beta;
        }
        const int used = SolveCg(normal, rhs, o.cg_tolerance, o.cg_max_iterations, &Xk);
        it.num_cg_iterations += used;
        if (used >= o.cg_max_iterations) ++it.num_cg_unconverged;
        continue;
      }
      if (beta != factored_beta) {
        solver.factorize(normal.Matrix(beta));
        MR_CHECK(solver.info() == Eigen::Success) << "sparse Cholesky failed";
        factored_beta = beta;
        ++it.num_factorizations;
      }
      Xk = solver.solve(rhs);
    }
    it.change = std::sqrt((Xk - X).squaredNorm() / n);
    X = Xk;
    it.seconds = Now() - tk;
    result->iterations.push_back(it);
    std::ostringstream line;
    line << "Denoise lp: iteration " << k + 1 << ": p = " << it.p << ", theta = " << it.theta
         << ", sigma = " << it.sigma << ", lambda = " << it.lambda << ", change = " << it.change
         << " edge lengths, " << (direct ? it.num_factorizations : it.num_cg_iterations)
         << (direct ? " factorizations, " : " cg iterations, ") << it.seconds
         << " s";
    if (o.verbose) {
      MR_LOG(INFO) << line.str();
    } else {
      MR_LOG(VERBOSE) << line.str();
    }
    if (it.num_cg_unconverged > 0) {
      MR_LOG(WARNING) << "Denoise lp: conjugate gradients hit cg_max_iterations ("
                      << o.cg_max_iterations << ") in " << it.num_cg_unconverged
                      << " X-steps; the result is approximate";
    }
    if (it.change < o.tolerance) break;
  }
  result->V = (X * h).rowwise() + centre;
}

}  // namespace

bool DenoiseOptions::Check() const {
  MR_CHECK_OPTION(method == "lp" || method == "laplacian" || method == "bilateral_normal",
                  method, "method in {lp, laplacian, bilateral_normal}");
  MR_CHECK_OPTION(max_iterations >= 1, max_iterations, "max_iterations >= 1");
  MR_CHECK_OPTION(estimate_iterations >= 1, estimate_iterations, "estimate_iterations >= 1");
  MR_CHECK_OPTION(tolerance >= 0, tolerance, "tolerance >= 0");
  MR_CHECK_OPTION(p_min > 0 && p_min <= 1, p_min, "0 < p_min <= 1");
  MR_CHECK_OPTION(p_max >= p_min && p_max <= 1, p_max, "p_min <= p_max <= 1");
  MR_CHECK_OPTION(p_step > 0, p_step, "p_step > 0");
  MR_CHECK_OPTION(lambda_scale > 0, lambda_scale, "lambda_scale > 0");
  MR_CHECK_OPTION(fixed_lambda >= 0, fixed_lambda, "fixed_lambda >= 0");
  MR_CHECK_OPTION(fixed_p >= 0 && fixed_p <= 1, fixed_p, "0 <= fixed_p <= 1");
  MR_CHECK_OPTION(beta_initial > 0, beta_initial, "beta_initial > 0");
  MR_CHECK_OPTION(beta_max >= beta_initial, beta_max, "beta_max >= beta_initial");
  MR_CHECK_OPTION(beta_factor > 1, beta_factor, "beta_factor > 1");
  MR_CHECK_OPTION(inner_iterations >= 1, inner_iterations, "inner_iterations >= 1");
  MR_CHECK_OPTION(linear_solver == "cg" || linear_solver == "cholesky", linear_solver,
                  "linear_solver in {cg, cholesky}");
  MR_CHECK_OPTION(cg_tolerance > 0, cg_tolerance, "cg_tolerance > 0");
  MR_CHECK_OPTION(cg_max_iterations >= 1, cg_max_iterations, "cg_max_iterations >= 1");
  MR_CHECK_OPTION(warm_iterations >= 0, warm_iterations, "warm_iterations >= 0");
  MR_CHECK_OPTION(laplacian_iterations >= 0, laplacian_iterations, "laplacian_iterations >= 0");
  MR_CHECK_OPTION(laplacian_weight > 0 && laplacian_weight <= 1, laplacian_weight,
                  "0 < laplacian_weight <= 1");
  MR_CHECK_OPTION(bilaplacian_weight >= 0, bilaplacian_weight, "bilaplacian_weight >= 0");
  MR_CHECK_OPTION(2 * laplacian_weight + 4 * bilaplacian_weight < 2, bilaplacian_weight,
                  "2 laplacian_weight + 4 bilaplacian_weight < 2 (stability)");
  MR_CHECK_OPTION(normal_iterations >= 0, normal_iterations, "normal_iterations >= 0");
  MR_CHECK_OPTION(vertex_iterations >= 0, vertex_iterations, "vertex_iterations >= 0");
  MR_CHECK_OPTION(normal_sigma > 0, normal_sigma, "normal_sigma > 0");
  MR_CHECK_OPTION(spatial_sigma > 0, spatial_sigma, "spatial_sigma > 0");
  return true;
}

std::string DenoiseResult::BriefReport() const {
  std::ostringstream s;
  s << "Denoise(" << method << "): " << V.rows() << " vertices";
  if (passed_through) s << ", passed through";
  if (!iterations.empty()) {
    const DenoiseIteration& last = iterations.back();
    s << ", " << iterations.size() << " outer iterations, last p = " << last.p
      << ", theta = " << last.theta << ", sigma = " << last.sigma << ", lambda = " << last.lambda;
  }
  s << ", " << total_seconds << " s";
  return s.str();
}

DenoiseResult Denoise(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F,
                      const DenoiseOptions& options) {
  options.Check();
  const double t0 = Now();
  if (V0.rows() > 0 && V0.cols() != 3) {
    MR_THROW_INPUT << "Denoise: V has " << V0.cols() << " columns (expected 3)";
  }
  if (F.rows() > 0 && F.cols() != 3) {
    MR_THROW_INPUT << "Denoise: F has " << F.cols() << " columns (expected 3)";
  }
  if (!V0.allFinite()) MR_THROW_INPUT << "Denoise: V has non-finite coordinates";
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (F(f, k) < 0 || F(f, k) >= V0.rows()) {
        MR_THROW_INPUT << "Denoise: face " << f << " has vertex index " << F(f, k)
                       << " (expected 0.." << V0.rows() - 1 << ")";
      }
    }
  }
  DenoiseResult result;
  result.method = options.method;
  if (options.method == "lp") {
    DenoiseLp(V0, F, options, &result);
  } else if (options.method == "laplacian") {
    result.V = LaplacianSmooth(V0, F, options.laplacian_iterations, options.laplacian_weight,
                               options.bilaplacian_weight);
  } else {
    result.V = BilateralNormalFilter(V0, F, options.normal_iterations, options.vertex_iterations,
                                     options.normal_sigma, options.spatial_sigma);
  }
  result.total_seconds = Now() - t0;
  result.solve_seconds = result.total_seconds - result.setup_seconds;
  MR_LOG(VERBOSE) << result.BriefReport();
  return result;
}

void RegisterDenoiseOptions(OptionManager* m, DenoiseOptions* o, const std::string& section) {
  auto name = [&](const char* field) { return section + "." + field; };
  m->Add(name("method"), &o->method, "lp | laplacian | bilateral_normal");
  m->Add(name("max_iterations"), &o->max_iterations,
         "lp: outer iterations (parameter estimation + solve), >= 1");
  m->Add(name("tolerance"), &o->tolerance, "lp: stop when RMS change < this (mean edges), >= 0");
  m->Add(name("p_min"), &o->p_min, "lp: smallest p of the search grid, (0, 1]");
  m->Add(name("p_max"), &o->p_max, "lp: largest p of the search grid, [p_min, 1]");
  m->Add(name("p_step"), &o->p_step, "lp: step of the p grid, > 0");
  m->Add(name("lambda_scale"), &o->lambda_scale, "lp: multiplies the estimated lambda, > 0");
  m->Add(name("fixed_lambda"), &o->fixed_lambda,
         "lp: if > 0, lambda in scene units^(2-p) instead of the estimate");
  m->Add(name("fixed_p"), &o->fixed_p, "lp: if in (0, 1], p instead of the search; 0 = search");
  m->Add(name("beta_initial"), &o->beta_initial, "lp: first penalty (mean edge = 1 units), > 0");
  m->Add(name("beta_max"), &o->beta_max, "lp: last penalty, >= beta_initial");
  m->Add(name("beta_factor"), &o->beta_factor, "lp: penalty growth per step, > 1");
  m->Add(name("inner_iterations"), &o->inner_iterations,
         "lp: psi/X alternations per beta (one factorisation each beta), >= 1");
  m->Add(name("linear_solver"), &o->linear_solver,
         "lp: X-step solver: cg (warm-started conjugate gradients) | cholesky (CHOLMOD)");
  m->Add(name("cg_tolerance"), &o->cg_tolerance,
         "lp: cg stops at this RMS residual (mean edge lengths), > 0");
  m->Add(name("cg_max_iterations"), &o->cg_max_iterations,
         "lp: cg iteration cap per X-step, >= 1");
  m->Add(name("estimate_iterations"), &o->estimate_iterations,
         "lp: outer iterations that re-estimate sigma, p, theta, >= 1");
  m->Add(name("warm_iterations"), &o->warm_iterations,
         "lp: 0 = full continuation each outer iteration; > 0 = warm start at beta_max");
  m->Add(name("update_operator"), &o->update_operator,
         "lp: recompute D's weights from X at each outer iteration");
  m->Add(name("laplacian_iterations"), &o->laplacian_iterations, "laplacian: iterations, >= 0");
  m->Add(name("laplacian_weight"), &o->laplacian_weight, "laplacian: first-order weight, (0, 1]");
  m->Add(name("bilaplacian_weight"), &o->bilaplacian_weight,
         "laplacian: second-order weight, >= 0, 2 w1 + 4 w2 < 2");
  m->Add(name("normal_iterations"), &o->normal_iterations,
         "bilateral_normal: normal filtering passes, >= 0");
  m->Add(name("vertex_iterations"), &o->vertex_iterations,
         "bilateral_normal: vertex update passes, >= 0");
  m->Add(name("normal_sigma"), &o->normal_sigma, "bilateral_normal: range sigma on |n_i - n_j|");
  m->Add(name("spatial_sigma"), &o->spatial_sigma,
         "bilateral_normal: spatial sigma in mean centroid distances");
  m->Add(name("verbose"), &o->verbose, "log one line per lp outer iteration");
}

}  // namespace mr
