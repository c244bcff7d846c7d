#pragma once

// The refiner's detail-preserving proximal step: instead of smoothing the
// surface (which flattens the relief that the data put there), smooth the
// gradient step, with each vertex's own data confidence as its weight.
//
//   x = argmin_x  Σ_v c_v |x_v - d_v|² + w Σ_{(i,j) ∈ E} |x_i - x_j|²,
//
// d_v = -g_v / c_v the Gauss-Newton step of vertex v, c_v its Gauss-Newton
// curvature (0 where no pixel sees it), E the mesh edges. In normal-equation
// form (diag(c) + w L) x = -g, L the graph Laplacian: no division by small
// c_v. The filter removes what the surface cannot hold, the step's
// triangle-scale disagreement between neighbours, where the data are weak,
// and keeps the surface's relief and creases untouched: they are in V, not
// in the step. Vertices that no pixel sees move with their neighbours.
//
// The strength w is measured, not set: w = smoothing * median(c_v) over the
// seen vertices, so that a vertex of median confidence weighs its own
// measurement like that of one neighbour (smoothing = 1); it follows the data
// from scene to scene, level to level and iteration to iteration.

#include <Eigen/Core>

namespace mr {

struct StepFilterOptions {
  // Edge weight relative to the median confidence (dimensionless, > 0).
  double smoothing = 1.0;
  // Conjugate-gradient tolerance (relative residual, > 0) and cap (>= 1).
  double tolerance = 1e-4;
  int max_iterations = 200;
};

struct StepFilterSummary {
  double edge_weight = 0;       // w
  double median_confidence = 0;
  int cg_iterations = 0;
  // RMS over seen vertices of the neighbour disagreement |d_v - mean of the
  // one-ring's d| before and after filtering (scene units): the jitter.
  double jitter_before = 0, jitter_after = 0;
};

// Solves (diag(confidence) + w L + w 1e-6 I) X = -gradient for X (#V by 3).
// `gradient` #V by 3, `confidence` #V (>= 0; 0 = no data), F #F by 3.
// Vertices with no data and no path to one get X = 0.
Eigen::MatrixXd FilterStep(const Eigen::MatrixXd& gradient, const Eigen::VectorXd& confidence,
                           const Eigen::MatrixXi& F, const StepFilterOptions& options,
                           StepFilterSummary* summary = nullptr);

}  // namespace mr
