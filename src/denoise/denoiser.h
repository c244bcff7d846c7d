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
//
// Invariance: the lp method works internally on the mesh translated to its
// centroid and scaled to unit mean edge length, so its result commutes with
// rotation, translation and uniform scaling of the input.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace mr {

class OptionManager;

struct DenoiseOptions {
  // "lp" | "laplacian" | "bilateral_normal".
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
  // Grid for the 1-D search of p: p_min, p_min + p_step, ..., p_max; in (0, 1].
  double p_min = 0.1;
  double p_max = 1.0;
  double p_step = 0.05;
  // Multiplies the estimated lambda = theta sigma^2 / 2 (the refiner's
  // proximal step passes its step size eta here), > 0.
  double lambda_scale = 1.0;
  // If > 0, fixes lambda (in the caller's units of length^(2-p)) instead of
  // estimating it; for experiments.
  double fixed_lambda = 0.0;
  // If in (0, 1], fixes p instead of searching it; 0 = search.
  double fixed_p = 0.0;
  // Penalty continuation for the splitting, in units where the mean edge
  // length is 1: beta goes beta_initial, * beta_factor, ... up to beta_max.
  double beta_initial = 2.0;   // > 0
  double beta_max = 100;       // >= beta_initial
  double beta_factor = 2.0;    // > 1
  // X-step solver. "cg": Jacobi-preconditioned conjugate gradients
  // warm-started from the previous step's X (the default: the same result as
  // the direct solver to 0.01 degrees on the benchmark, ~10x faster, half the
  // memory; docs/denoising.md). "cholesky": CHOLMOD supernodal Cholesky, one
  // symbolic analysis per call and one factorisation per beta value.
  std::string linear_solver = "cg";
  // cg: stop at this RMS residual per coordinate, in mean edge lengths
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
  int normal_iterations = 20;          // normal filtering passes, >= 0
  int vertex_iterations = 20;          // vertex update passes, >= 0
  // Range sigma on the normal difference |n_i - n_j|, > 0.
  double normal_sigma = 0.35;
  // Spatial sigma, in mean distances between adjacent face centroids, > 0.
  double spatial_sigma = 1.0;

  // Log one line per outer iteration at INFO (otherwise VERBOSE).
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

struct DenoiseResult {
  Eigen::MatrixXd V;  // #V by 3 denoised positions
  std::string method;
  std::vector<DenoiseIteration> iterations;  // lp only
  int num_operator_rows = 0;     // interior manifold edges used in D
  int num_skipped_edges = 0;     // boundary, non-manifold or degenerate
  bool passed_through = false;   // mesh too small: V returned unchanged
  double setup_seconds = 0;      // topology + symbolic analysis
  double solve_seconds = 0;
  double total_seconds = 0;
  std::string BriefReport() const;
};

// Denoises the mesh (V0 #V by 3, F #F by 3). Throws mr::InputError on bad
// options, out-of-range indices or non-finite coordinates. A mesh with no
// interior edge (empty, one triangle) is passed through unchanged.
DenoiseResult Denoise(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F,
                      const DenoiseOptions& options);

// Registers every DenoiseOptions field as `--<section>.<field>` (e.g.
// `--Denoise.method lp`); used by mesh_denoiser and mesh_refiner.
void RegisterDenoiseOptions(OptionManager* manager, DenoiseOptions* options,
                            const std::string& section = "Denoise");

}  // namespace mr
