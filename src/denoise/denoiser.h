#pragma once

// Mesh denoising that only moves vertices (connectivity is never changed).
//
//   mr::DenoiseOptions options;               // defaults: content-aware L_p
//   mr::DenoiseResult r = mr::Denoise(V0, F, options);
//   // r.V: denoised #V by 3 positions; r.iterations: p, theta, sigma, lambda
//
// Methods (DenoiseOptions::method):
//  - "lp": the content-aware L_p denoiser of DCV (Li et al., TIP 2016,
//    Sec. IV-B): hyper-Laplacian prior on the rows of D X, D the edge-based
//    operator of He & Schaefer 2013; sigma, theta, p and lambda estimated from
//    the data at every outer iteration; the X-problem solved by variable
//    splitting with GST shrinkage and a warm-started conjugate-gradient (or
//    sparse Cholesky) X-step. See docs/denoising.md.
//  - "laplacian": first + second order umbrella Laplacian smoothing (the
//    paper's isotropic baseline), fixed iteration count.
//  - "bilateral_normal": bilateral normal filtering (Zheng et al. 2011) with
//    the iterative vertex update of Sun et al. 2007.
//  - "l0": He & Schaefer 2013 (mesh denoising via L0 minimization): the
//    number of non-zero rows of D X penalised, solved by hard thresholding
//    and a beta continuation (denoise/l0.h).
//
// Invariance: the lp and l0 methods work internally on the mesh translated
// to its centroid and scaled to unit mean edge length, so their results
// commute with rotation, translation and uniform scaling of the input.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace mr {

class OptionManager;

struct DenoiseOptions {
  // "lp" | "laplacian" | "bilateral_normal" | "l0".
  std::string method = "lp";

  // ---- lp (content-aware L_p) ----
  // Outer iterations (D re-weighting + X-solve), >= 1. Default 3: round 1
  // fits p, theta on the noisy input with sigma from its robust noise
  // estimate; round 2 re-fits sigma, p, theta on round 1's result; round 3
  // keeps them (see estimate_iterations) and re-weights D. See
  // docs/denoising.md for why the estimation stops after 2 rounds.
  int max_iterations = 3;
  // Outer iterations that re-estimate sigma, p and theta; later ones keep
  // the last estimate and only re-weight D and re-solve, >= 1.
  int estimate_iterations = 2;
  // Stop the outer loop when the relative change of X (RMS, in mean edge
  // lengths) falls below this, >= 0.
  double tolerance = 1e-3;
  // Grid for the 1-D search of p: p_min, p_min + p_step, ..., p_max; in (0, 2]
  // (p > 1 is the convex range; the default grid stops at 1: extending it made
  // round 1 pick p = 1.65-1.9 on the noisy inputs and was worse everywhere,
  // docs/denoising.md).
  double p_min = 0.1;
  double p_max = 1.0;
  double p_step = 0.05;
  // Multiplies the estimated lambda = theta sigma^2 / 2 (the refiner's
  // proximal step passes its step size eta here), > 0.
  double lambda_scale = 1.0;
  // Row weights of the prior: it acts on s_e |(D X)_e| with s_e = l_e^a, l_e
  // the length of row e's edge in the current X in mean edge lengths (so
  // scale-free), a = edge_length_exponent, recomputed with D's weights. a = 1
  // weighs each row by its edge's length (the measure of a dihedral angle's
  // edge: s_e |(D X)_e| ~ angle x area for a fold); 0 = the unweighted prior
  // (the default before; 0.1-0.4 deg worse on every benchmark model,
  // docs/denoising.md). In [0, 4].
  double edge_length_exponent = 1.0;
  // If > 0, fixes lambda (in the caller's units of length^(2-p)) instead of
  // estimating it; for experiments.
  double fixed_lambda = 0.0;
  // If in (0, 2], fixes p instead of searching it; 0 = search.
  double fixed_p = 0.0;
  // Penalty continuation for the splitting, in units where the mean edge
  // length is 1: beta goes beta_initial, * beta_factor, ... up to beta_max.
  double beta_initial = 2.0;   // > 0
  double beta_max = 100;       // >= beta_initial
  double beta_factor = 2.0;    // > 1
  // X-step solver of lp and l0. "cg": Jacobi-preconditioned conjugate gradients
  // warm-started from the previous step's X (the default: the same result as
  // the direct solver to 0.01 degrees on the benchmark, ~10x faster, half the
  // memory; docs/denoising.md). "cholesky": CHOLMOD supernodal Cholesky, one
  // symbolic analysis per call and one factorisation per beta value.
  std::string linear_solver = "cg";
  // cg (lp and l0): stop at this RMS residual per coordinate, in mean edge lengths
  // (the matrix is >= I, so the error is at most the residual), > 0.
  double cg_tolerance = 1e-3;
  // cg: iteration cap per X-step (a warning is logged when hit), >= 1.
  int cg_max_iterations = 1000;
  // psi/X alternations per beta value (the factorisation is reused), >= 1.
  int inner_iterations = 3;
  // 0: every outer iteration runs the full beta continuation from X0 (the
  // default). > 0: outer iterations after the first warm-start from X at
  // beta_max and run this many psi/X alternations (one factorisation);
  // cheaper, but stays in the first iteration's local minimum. >= 0.
  int warm_iterations = 0;
  // Recompute the weights of D from the current X at every outer iteration
  // (its sparsity pattern never changes).
  bool update_operator = true;

  // ---- laplacian ----
  int laplacian_iterations = 10;       // >= 0
  double laplacian_weight = 0.4;       // first-order weight, in (0, 1]
  double bilaplacian_weight = 0.1;     // second-order weight, >= 0

  // ---- bilateral_normal ----
  // Zheng et al.'s iterative scheme: outer_iterations times, the face normals
  // (recomputed from the current vertices) are filtered normal_iterations
  // times and the vertices then fitted to them in vertex_iterations passes.
  // The defaults (10 x (1 + 2), range sigma 0.6, fairing 0.45) were chosen on
  // the denoising benchmark's four organic models over three noise seeds by
  // the worst ratio to Laplacian smoothing at its oracle-best iteration count
  // (docs/denoising.md): 0.987 (beast, igea), below it on every model and
  // seed; 5 x (1 + 10) at 1.25, the defaults until 7 December 2026, were
  // 1.039 (beast). Piecewise-flat CAD shapes lose their creases (use lp).
  // mesh_refiner's proximal step sets its own (refiner.h).
  int outer_iterations = 10;           // >= 1
  int normal_iterations = 1;           // normal filtering passes, >= 0
  int vertex_iterations = 2;           // vertex update passes, >= 0
  // Range sigma on the normal difference |n_i - n_j|, > 0.
  double normal_sigma = 0.6;
  // Spatial sigma, in mean distances between adjacent face centroids, > 0.
  double spatial_sigma = 1.0;
  // At the end of each round, one second-order fairing step of this weight
  // (SecondOrderFairing in baselines.h, [0, 0.5)) where the filter leaves
  // faces unfiltered because they differ by more than normal_sigma: features
  // a few edges round, which the filter cannot smooth. 0: none. 0.45 chosen
  // on the denoising benchmark by the worst ratio to the Laplacian oracle
  // (docs/denoising.md); with the rounds above it takes beast from 19.25 to
  // 13.66 degrees. mesh_refiner's proximal step uses 0.3 (refiner.h).
  double fairing_weight = 0.45;

  // ---- l0 (He & Schaefer 2013; also uses linear_solver, cg_tolerance,
  // cg_max_iterations) ----
  // min |X - X0|^2 + alpha |R X|^2 + lambda #{e : (D X)_e != 0}, by
  // alternating delta_e = (D X)_e if |(D X)_e|^2 >= lambda / beta else 0 and
  // (I + alpha R^T R + beta D^T D) X = X0 + beta D^T delta.
  // lambda = l0_lambda_factor * l_e^2 * gamma, l_e the mean edge length and
  // gamma the mean dihedral angle (between adjacent face normals) of the
  // input in DEGREES (He & Schaefer's default 0.02; docs/denoising.md for why
  // degrees), > 0.
  double l0_lambda_factor = 0.02;
  // If > 0, lambda in the caller's units (length^2) instead, >= 0.
  double l0_lambda = 0.0;
  // beta continuation (dimensionless: D's weights are): l0_beta_initial,
  // * l0_beta_factor, ... while <= l0_beta_max. Paper: 1e-3, sqrt(2), 1e3.
  double l0_beta_initial = 1e-3;             // > 0
  double l0_beta_max = 1e3;                  // >= l0_beta_initial
  double l0_beta_factor = 1.4142135623730951;  // > 1
  // Regulariser alpha |R X|^2, R(e) = x1 + x3 - x2 - x4 (edge ends minus
  // opposite vertices: zero on a parallelogram), alpha = l0_alpha_factor *
  // gamma (degrees) at the first beta step, times l0_alpha_decay at each next
  // one. Paper: 0.1 and 0.5. l0_alpha_factor >= 0 (0: no regulariser),
  // l0_alpha_decay in [0, 1].
  double l0_alpha_factor = 0.1;
  double l0_alpha_decay = 0.5;
  // Recompute D's weights from the current X at every beta step (else keep
  // the weights of the input).
  bool l0_update_operator = true;

  // Log one line per lp outer iteration / l0 beta step at INFO (otherwise VERBOSE).
  bool verbose = false;

  // Throws mr::InputError naming the field, its value and the violated bound.
  bool Check() const;
};

// What the lp method chose at one outer iteration (in the caller's units).
struct DenoiseIteration {
  double p = 0;
  double theta = 0;   // width of the hyper-Laplacian (units length^-p)
  double sigma = 0;   // noise standard deviation per vertex, sqrt(|X - X0|^2 / n) (length)
  double lambda = 0;  // theta sigma^2 / 2 * lambda_scale
  double change = 0;  // RMS vertex displacement of this iteration / mean edge
  int num_factorizations = 0;  // linear_solver = cholesky
  int num_cg_iterations = 0;   // linear_solver = cg, summed over X-steps
  int num_cg_unconverged = 0;  // X-steps that hit cg_max_iterations
  double seconds = 0;
};

// One beta step of the l0 method.
struct L0Step {
  double beta = 0;
  double alpha = 0;
  int num_nonzero_rows = 0;    // rows of delta kept by the hard threshold
  double change = 0;           // RMS vertex displacement of this step / mean edge
  int num_cg_iterations = 0;   // linear_solver = cg
  bool cg_unconverged = false; // hit cg_max_iterations
  double seconds = 0;
};

struct DenoiseResult {
  Eigen::MatrixXd V;  // #V by 3 denoised positions
  std::string method;
  std::vector<DenoiseIteration> iterations;  // lp only
  int num_operator_rows = 0;     // interior manifold edges used in D
  int num_skipped_edges = 0;     // boundary, non-manifold or degenerate
  bool passed_through = false;   // mesh too small: V returned unchanged
  // l0 only: lambda in the caller's units (length^2), the input's mean
  // dihedral angle gamma (degrees), one entry per beta step.
  double l0_lambda = 0;
  double l0_mean_dihedral_deg = 0;
  std::vector<L0Step> l0_steps;
  double setup_seconds = 0;      // topology + symbolic analysis
  double solve_seconds = 0;
  double total_seconds = 0;
  std::string BriefReport() const;
};

// Denoises the mesh (V0 #V by 3, F #F by 3). Throws mr::InputError on bad
// options, out-of-range indices or non-finite coordinates. A mesh with no
// interior edge (empty, one triangle) is passed through unchanged.
//
// lp only: `noise_reference` (optional, #V by 3) is the mesh before the
// operation that made V0 noisy, for instance a refiner's gradient step. The
// noise sigma of the first round is then estimated from D (V0 - reference),
// the roughness that operation added, instead of from D V0, which also counts
// the surface's own relief and would smooth it away.
DenoiseResult Denoise(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F,
                      const DenoiseOptions& options,
                      const Eigen::MatrixXd* noise_reference = nullptr);

// Registers every DenoiseOptions field as `--<section>.<field>` (e.g.
// `--Denoise.method lp`); used by mesh_denoiser and mesh_refiner.
void RegisterDenoiseOptions(OptionManager* manager, DenoiseOptions* options,
                            const std::string& section = "Denoise");

}  // namespace mr
