#include "denoise/denoiser.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "denoise/baselines.h"
#include "denoise/l0.h"
#include "denoise/lp_model.h"
#include "denoise/normal_matrix.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/statistics.h"

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
  return Median(&r) / 0.6745;
}

void DenoiseLp(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F, const DenoiseOptions& o,
               const Eigen::MatrixXd* noise_reference, DenoiseResult* result) {
  const double t0 = Now();
  const int n = static_cast<int>(V0.rows());
  EdgeProblem problem;
  if (!SetUpEdgeProblem(V0, F, "Denoise", result, &problem)) return;
  auto [eq, centre, h, X0, W, degenerate] = std::move(problem);
  Eigen::MatrixXd X = X0;
  NormalMatrix normal(eq.quads, n);
  SparseCholesky solver;
  const bool direct = o.linear_solver == "cholesky";
  if (direct) solver.Analyze(normal.Matrix(1.0));
  result->setup_seconds = Now() - t0;

  // The noise to remove: all of X0's roughness, or only what was added to
  // the reference (D is linear in X for fixed weights).
  const double sigma0 =
      noise_reference == nullptr
          ? RobustSigma(ApplyEdgeOperator(eq.quads, W, X0), W)
          : RobustSigma(ApplyEdgeOperator(eq.quads, W, (V0 - *noise_reference) / h), W);
  Eigen::VectorXd row_scale = Eigen::VectorXd::Ones(eq.quads.rows());
  for (int k = 0; k < o.max_iterations; ++k) {
    const double tk = Now();
    DenoiseIteration it;
    if (k > 0 && o.update_operator) W = EdgeWeights(X, eq.quads, &degenerate);
    // Row weights s_e = l_e^a (l_e the edge's length in the current X, unit mean
    // edge): the prior acts on s_e |(D X)_e| (docs/denoising.md, "Row weights").
    if (k == 0 || o.update_operator) {
      for (int i = 0; i < eq.quads.rows(); ++i) {
        row_scale(i) = o.edge_length_exponent == 0
                           ? 1.0
                           : std::pow((X.row(eq.quads(i, 1)) - X.row(eq.quads(i, 0))).norm(),
                                      o.edge_length_exponent);
      }
    }
    const Eigen::MatrixXd R = ApplyEdgeOperator(eq.quads, W, X);
    std::vector<double> norms;
    norms.reserve(R.rows());
    for (int i = 0; i < R.rows(); ++i) {
      if (W.row(i).squaredNorm() > 0) norms.push_back(row_scale(i) * R.row(i).norm());
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
    // s_e^p, the factor of the shrinkage parameter of row e in this round.
    Eigen::VectorXd shrink_scale = row_scale;
    if (o.edge_length_exponent != 0) {
      for (int i = 0; i < shrink_scale.size(); ++i) shrink_scale(i) = std::pow(row_scale(i), p);
    }
    Eigen::MatrixXd Xk = X;
    double factored_beta = -1;
    for (double beta : betas) {
      // psi-step: per-row vector GST of min beta |psi - D X|^2 + lambda
      // (s_e |psi|)^p, i.e. with parameter lambda s_e^p / (2 beta).
      Eigen::MatrixXd Psi = ApplyEdgeOperator(eq.quads, W, Xk);
      const double tau = lambda / (2.0 * beta);
#pragma omp parallel for schedule(static) if (Psi.rows() > 50000)
      for (int i = 0; i < Psi.rows(); ++i) {
        Psi.row(i) = GstShrinkVector(Psi.row(i).transpose(), tau * shrink_scale(i), p).transpose();
      }
      // X-step: (I + 2 beta D^T D) X = X0 + 2 beta D^T psi.
      const Eigen::MatrixXd rhs = X0 + 2.0 * beta * ApplyEdgeOperatorTranspose(eq.quads, W, Psi, n);
      if (!direct) {
        if (beta != factored_beta) {
          normal.Matrix(2.0 * beta);
          factored_beta = beta;
        }
        const int used = SolveCg(normal, rhs, o.cg_tolerance, o.cg_max_iterations, &Xk);
        it.num_cg_iterations += used;
        if (used >= o.cg_max_iterations) ++it.num_cg_unconverged;
        continue;
      }
      if (beta != factored_beta) {
        solver.Factorize(normal.Matrix(2.0 * beta));
        factored_beta = beta;
        ++it.num_factorizations;
      }
      Xk = solver.Solve(rhs);
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
  MR_CHECK_OPTION(method == "lp" || method == "laplacian" || method == "bilateral_normal" ||
                      method == "l0",
                  method, "method in {lp, laplacian, bilateral_normal, l0}");
  MR_CHECK_OPTION(max_iterations >= 1, max_iterations, "max_iterations >= 1");
  MR_CHECK_OPTION(estimate_iterations >= 1, estimate_iterations, "estimate_iterations >= 1");
  MR_CHECK_OPTION(tolerance >= 0, tolerance, "tolerance >= 0");
  MR_CHECK_OPTION(p_min > 0 && p_min <= 2, p_min, "0 < p_min <= 2");
  MR_CHECK_OPTION(p_max >= p_min && p_max <= 2, p_max, "p_min <= p_max <= 2");
  MR_CHECK_OPTION(p_step > 0, p_step, "p_step > 0");
  MR_CHECK_OPTION(lambda_scale > 0, lambda_scale, "lambda_scale > 0");
  MR_CHECK_OPTION(fixed_lambda >= 0, fixed_lambda, "fixed_lambda >= 0");
  MR_CHECK_OPTION(fixed_p >= 0 && fixed_p <= 2, fixed_p, "0 <= fixed_p <= 2");
  MR_CHECK_OPTION(edge_length_exponent >= 0 && edge_length_exponent <= 4, edge_length_exponent,
                  "0 <= edge_length_exponent <= 4");
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
  MR_CHECK_OPTION(outer_iterations >= 1, outer_iterations, "outer_iterations >= 1");
  MR_CHECK_OPTION(normal_iterations >= 0, normal_iterations, "normal_iterations >= 0");
  MR_CHECK_OPTION(vertex_iterations >= 0, vertex_iterations, "vertex_iterations >= 0");
  MR_CHECK_OPTION(normal_sigma > 0, normal_sigma, "normal_sigma > 0");
  MR_CHECK_OPTION(spatial_sigma > 0, spatial_sigma, "spatial_sigma > 0");
  MR_CHECK_OPTION(fairing_weight >= 0 && fairing_weight < 0.5, fairing_weight,
                  "0 <= fairing_weight < 0.5 (stability)");
  MR_CHECK_OPTION(l0_lambda_factor > 0 && std::isfinite(l0_lambda_factor), l0_lambda_factor,
                  "l0_lambda_factor > 0");
  MR_CHECK_OPTION(l0_lambda >= 0 && std::isfinite(l0_lambda), l0_lambda, "l0_lambda >= 0");
  MR_CHECK_OPTION(l0_beta_initial > 0, l0_beta_initial, "l0_beta_initial > 0");
  MR_CHECK_OPTION(l0_beta_max >= l0_beta_initial && std::isfinite(l0_beta_max), l0_beta_max,
                  "l0_beta_initial <= l0_beta_max < inf");
  MR_CHECK_OPTION(l0_beta_factor > 1, l0_beta_factor, "l0_beta_factor > 1");
  MR_CHECK_OPTION(l0_alpha_factor >= 0 && std::isfinite(l0_alpha_factor), l0_alpha_factor,
                  "l0_alpha_factor >= 0");
  MR_CHECK_OPTION(l0_alpha_decay >= 0 && l0_alpha_decay <= 1, l0_alpha_decay,
                  "0 <= l0_alpha_decay <= 1");
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
  if (!l0_steps.empty()) {
    s << ", " << l0_steps.size() << " beta steps, lambda = " << l0_lambda
      << ", mean dihedral angle = " << l0_mean_dihedral_deg
      << " deg, non-zero rows at the end = " << l0_steps.back().num_nonzero_rows;
  }
  s << ", " << total_seconds << " s";
  return s.str();
}

DenoiseResult Denoise(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F,
                      const DenoiseOptions& options, const Eigen::MatrixXd* noise_reference) {
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
    if (noise_reference != nullptr) {
      MR_CHECK(noise_reference->rows() == V0.rows() && noise_reference->cols() == 3)
          << "noise_reference must be #V by 3";
    }
    DenoiseLp(V0, F, options, noise_reference, &result);
  } else if (options.method == "l0") {
    DenoiseL0(V0, F, options, &result);
  } else if (options.method == "laplacian") {
    result.V = LaplacianSmooth(V0, F, options.laplacian_iterations, options.laplacian_weight,
                               options.bilaplacian_weight);
  } else {
    result.V = BilateralNormalFilter(V0, F, options.normal_iterations, options.vertex_iterations,
                                     options.normal_sigma, options.spatial_sigma,
                                     options.outer_iterations, options.fairing_weight);
  }
  result.total_seconds = Now() - t0;
  result.solve_seconds = result.total_seconds - result.setup_seconds;
  MR_LOG(VERBOSE) << result.BriefReport();
  return result;
}

void RegisterDenoiseOptions(OptionManager* m, DenoiseOptions* o, const std::string& section) {
  auto name = [&](const char* field) { return section + "." + field; };
  m->Add(name("method"), &o->method, "lp | laplacian | bilateral_normal | l0");
  m->Add(name("max_iterations"), &o->max_iterations,
         "lp: outer iterations (parameter estimation + solve), >= 1");
  m->Add(name("tolerance"), &o->tolerance, "lp: stop when RMS change < this (mean edges), >= 0");
  m->Add(name("p_min"), &o->p_min, "lp: smallest p of the search grid, (0, 2]");
  m->Add(name("p_max"), &o->p_max, "lp: largest p of the search grid, [p_min, 2]");
  m->Add(name("p_step"), &o->p_step, "lp: step of the p grid, > 0");
  m->Add(name("lambda_scale"), &o->lambda_scale, "lp: multiplies the estimated lambda, > 0");
  m->Add(name("fixed_lambda"), &o->fixed_lambda,
         "lp: if > 0, lambda in scene units^(2-p) instead of the estimate");
  m->Add(name("fixed_p"), &o->fixed_p, "lp: if in (0, 2], p instead of the search; 0 = search");
  m->Add(name("edge_length_exponent"), &o->edge_length_exponent,
         "lp: prior on l_e^a |(D X)_e|, l_e the edge length in mean edges; 0 = unweighted, "
         "[0, 4]");
  m->Add(name("beta_initial"), &o->beta_initial, "lp: first penalty (mean edge = 1 units), > 0");
  m->Add(name("beta_max"), &o->beta_max, "lp: last penalty, >= beta_initial");
  m->Add(name("beta_factor"), &o->beta_factor, "lp: penalty growth per step, > 1");
  m->Add(name("inner_iterations"), &o->inner_iterations,
         "lp: psi/X alternations per beta (one factorisation each beta), >= 1");
  m->Add(name("linear_solver"), &o->linear_solver,
         "lp, l0: X-step solver: cg (warm-started conjugate gradients) | cholesky (CHOLMOD)");
  m->Add(name("cg_tolerance"), &o->cg_tolerance,
         "lp, l0: cg stops at this RMS residual (mean edge lengths), > 0");
  m->Add(name("cg_max_iterations"), &o->cg_max_iterations,
         "lp, l0: cg iteration cap per X-step, >= 1");
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
  m->Add(name("outer_iterations"), &o->outer_iterations,
         "bilateral_normal: rounds of normal filtering then vertex fitting, the normals "
         "recomputed from the vertices each round, >= 1");
  m->Add(name("normal_iterations"), &o->normal_iterations,
         "bilateral_normal: normal filtering passes per round, >= 0");
  m->Add(name("vertex_iterations"), &o->vertex_iterations,
         "bilateral_normal: vertex update passes per round, >= 0");
  m->Add(name("normal_sigma"), &o->normal_sigma, "bilateral_normal: range sigma on |n_i - n_j|");
  m->Add(name("spatial_sigma"), &o->spatial_sigma,
         "bilateral_normal: spatial sigma in mean centroid distances");
  m->Add(name("fairing_weight"), &o->fairing_weight,
         "bilateral_normal: each round ends with one second-order fairing step of this "
         "weight where the filter leaves faces unfiltered (features a few edges round), "
         "[0, 0.5)");
  m->Add(name("l0_lambda_factor"), &o->l0_lambda_factor,
         "l0: lambda = this * mean edge^2 * mean dihedral angle (degrees), > 0");
  m->Add(name("l0_lambda"), &o->l0_lambda,
         "l0: if > 0, lambda in scene units^2 instead of the default");
  m->Add(name("l0_beta_initial"), &o->l0_beta_initial, "l0: first penalty beta, > 0");
  m->Add(name("l0_beta_max"), &o->l0_beta_max, "l0: last penalty, >= l0_beta_initial");
  m->Add(name("l0_beta_factor"), &o->l0_beta_factor, "l0: penalty growth per step, > 1");
  m->Add(name("l0_alpha_factor"), &o->l0_alpha_factor,
         "l0: regulariser weight = this * mean dihedral angle (degrees) at the first step, >= 0");
  m->Add(name("l0_alpha_decay"), &o->l0_alpha_decay,
         "l0: regulariser weight factor per step, [0, 1]");
  m->Add(name("l0_update_operator"), &o->l0_update_operator,
         "l0: recompute D's weights from X at every beta step");
  m->Add(name("verbose"), &o->verbose, "log one line per lp outer iteration / l0 beta step");
}

}  // namespace mr
