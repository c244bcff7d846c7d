#include "denoise/l0.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include <Eigen/Geometry>

#include "denoise/lp_model.h"
#include "denoise/normal_matrix.h"
#include "util/logging.h"

namespace mr {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int HardThresholdRows(double threshold, Eigen::MatrixXd* rows) {
  int kept = 0;
  for (int i = 0; i < rows->rows(); ++i) {
    const double sq = rows->row(i).squaredNorm();
    if (sq >= threshold) {
      if (sq > 0) ++kept;
    } else {
      rows->row(i).setZero();
    }
  }
  return kept;
}

double MeanDihedralAngleDeg(const Eigen::MatrixXd& V, const Eigen::MatrixXi& quads,
                            const Eigen::MatrixXd& weights) {
  double sum = 0;
  int count = 0;
  for (int i = 0; i < quads.rows(); ++i) {
    if (weights.row(i).squaredNorm() == 0) continue;
    const Eigen::Vector3d x1 = V.row(quads(i, 0)), x3 = V.row(quads(i, 1));
    const Eigen::Vector3d x2 = V.row(quads(i, 2)), x4 = V.row(quads(i, 3));
    const Eigen::Vector3d e = x3 - x1;
    const Eigen::Vector3d n1 = e.cross(x2 - x1), n2 = (x4 - x1).cross(e);
    sum += std::atan2(n1.cross(n2).norm(), n1.dot(n2)) * 180.0 / M_PI;
    ++count;
  }
  return count > 0 ? sum / count : 0.0;
}

Eigen::MatrixXd RegularizerWeights(const Eigen::MatrixXi& quads) {
  Eigen::MatrixXd W(quads.rows(), 4);
  W.col(0).setOnes();
  W.col(1).setOnes();
  W.col(2).setConstant(-1.0);
  W.col(3).setConstant(-1.0);
  return W;
}

bool SetUpEdgeProblem(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F, const char* label,
                      DenoiseResult* result, EdgeProblem* problem) {
  EdgeProblem& p = *problem;
  p.eq = BuildEdgeQuads(F, static_cast<int>(V0.rows()));
  result->num_skipped_edges = p.eq.num_boundary + p.eq.num_non_manifold;
  if (p.eq.quads.rows() == 0) {
    result->passed_through = true;
    result->V = V0;
    MR_LOG(INFO) << label << ": no interior edge (" << F.rows() << " faces); mesh passed through";
    return false;
  }
  if (!NormalizationOf(V0, F, &p.centre, &p.h)) {
    result->passed_through = true;
    result->V = V0;
    MR_LOG(WARNING) << label << ": all edges have zero length; mesh passed through";
    return false;
  }
  p.X0 = (V0.rowwise() - p.centre) / p.h;
  p.W = EdgeWeights(p.X0, p.eq.quads, &p.degenerate);
  result->num_operator_rows = static_cast<int>(p.eq.quads.rows()) - p.degenerate;
  if (p.eq.num_boundary + p.eq.num_non_manifold + p.degenerate > 0) {
    MR_LOG(VERBOSE) << label << ": skipped " << p.eq.num_boundary << " boundary, "
                    << p.eq.num_non_manifold << " non-manifold and " << p.degenerate
                    << " degenerate edges";
  }
  return true;
}

void DenoiseL0(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F, const DenoiseOptions& o,
               DenoiseResult* result) {
  const double t0 = Now();
  const int n = static_cast<int>(V0.rows());
  EdgeProblem problem;
  if (!SetUpEdgeProblem(V0, F, "Denoise l0", result, &problem)) return;
  // In units of h, lambda = l0_lambda_factor * gamma, and beta and alpha
  // (which weigh squared lengths against squared lengths through
  // dimensionless weights) need no conversion.
  auto [eq, centre, h, X0, W, degenerate] = std::move(problem);
  Eigen::MatrixXd X = X0;
  const double gamma = MeanDihedralAngleDeg(X0, eq.quads, W);
  const double lambda = o.l0_lambda > 0 ? o.l0_lambda / (h * h) : o.l0_lambda_factor * gamma;
  result->l0_mean_dihedral_deg = gamma;
  result->l0_lambda = lambda * h * h;

  NormalMatrix normal(eq.quads, n);
  double alpha = o.l0_alpha_factor * gamma;
  if (alpha > 0) normal.SetRegularizerWeights(RegularizerWeights(eq.quads));
  SparseCholesky solver;
  const bool direct = o.linear_solver == "cholesky";
  if (direct) solver.Analyze(normal.Matrix(1.0, 1.0));
  result->setup_seconds = Now() - t0;
  MR_LOG(VERBOSE) << "Denoise l0: " << result->num_operator_rows << " rows, mean dihedral angle "
                  << gamma << " deg, lambda = " << result->l0_lambda << " (" << lambda
                  << " mean edges^2)";

  int unconverged = 0;
  for (double beta = o.l0_beta_initial; beta <= o.l0_beta_max * (1 + 1e-12);
       beta *= o.l0_beta_factor, alpha *= o.l0_alpha_decay) {
    const double tk = Now();
    L0Step step;
    step.beta = beta;
    step.alpha = alpha;
    if (o.l0_update_operator && !result->l0_steps.empty()) {
      W = EdgeWeights(X, eq.quads, &degenerate);
    }
    // delta-step: hard threshold of the rows of D X.
    Eigen::MatrixXd delta = ApplyEdgeOperator(eq.quads, W, X);
    step.num_nonzero_rows = HardThresholdRows(lambda / beta, &delta);
    // X-step: (I + alpha R^T R + beta D^T D) X = X0 + beta D^T delta.
    normal.SetWeights(W);
    const Eigen::SparseMatrix<double>& A = normal.Matrix(beta, alpha);
    const Eigen::MatrixXd rhs = X0 + beta * ApplyEdgeOperatorTranspose(eq.quads, W, delta, n);
    Eigen::MatrixXd Xk = X;
    if (direct) {
      solver.Factorize(A);
      Xk = solver.Solve(rhs);
    } else {
      step.num_cg_iterations = SolveCg(normal, rhs, o.cg_tolerance, o.cg_max_iterations, &Xk);
      step.cg_unconverged = step.num_cg_iterations >= o.cg_max_iterations;
      if (step.cg_unconverged) ++unconverged;
    }
    step.change = std::sqrt((Xk - X).squaredNorm() / n);
    X = Xk;
    step.seconds = Now() - tk;
    result->l0_steps.push_back(step);
    std::ostringstream line;
    line << "Denoise l0: step " << result->l0_steps.size() << ": beta = " << beta
         << ", alpha = " << alpha << ", non-zero rows = " << step.num_nonzero_rows << " / "
         << eq.quads.rows() << ", change = " << step.change << " edge lengths";
    if (!direct) line << ", " << step.num_cg_iterations << " cg iterations";
    line << ", " << step.seconds << " s";
    if (o.verbose) {
      MR_LOG(INFO) << line.str();
    } else {
      MR_LOG(VERBOSE) << line.str();
    }
  }
  if (unconverged > 0) {
    MR_LOG(WARNING) << "Denoise l0: conjugate gradients hit cg_max_iterations ("
                    << o.cg_max_iterations << ") in " << unconverged
                    << " X-steps; the result is approximate";
  }
  result->V = (X * h).rowwise() + centre;
}

}  // namespace mr
