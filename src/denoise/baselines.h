#pragma once

// Baseline denoisers behind mr::Denoise (method "laplacian" and
// "bilateral_normal"); exposed for tests and benchmarks.

#include <Eigen/Core>

namespace mr {

// First + second order umbrella-Laplacian smoothing (the isotropic baseline
// of DCV, as in PMVS/OpenMVS): per iteration
//   X <- X + w1 L X - w2 L (L X),   L X = mean of one-ring neighbours - X.
// Stable for 2 w1 + 4 w2 < 2.
Eigen::MatrixXd LaplacianSmooth(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                int iterations, double w1, double w2);

// Bilateral normal filtering (Zheng et al., TVCG 2011, local iterative
// scheme) over the faces sharing a vertex, followed by the iterative vertex
// update of Sun et al. 2007; `outer_iterations` times, the face normals,
// centroids and areas recomputed from the updated vertices each time (so
// that two outer iterations are the filter applied twice). `spatial_sigma`
// is in mean distances between the centroids of faces sharing a vertex, taken
// from the input; `normal_sigma` acts on |n_i - n_j|.
Eigen::MatrixXd BilateralNormalFilter(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      int normal_iterations, int vertex_iterations,
                                      double normal_sigma, double spatial_sigma,
                                      int outer_iterations = 1);

}  // namespace mr
