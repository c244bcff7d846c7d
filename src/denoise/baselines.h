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
// from the input; `normal_sigma` acts on |n_i - n_j|. With a
// `fairing_weight` > 0 each outer iteration ends with one SecondOrderFairing
// step of that weight and normal_sigma, on the neighbourhoods the filter
// built.
Eigen::MatrixXd BilateralNormalFilter(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      int normal_iterations, int vertex_iterations,
                                      double normal_sigma, double spatial_sigma,
                                      int outer_iterations = 1, double fairing_weight = 0);

// One second-order fairing step X <- X - weight m L(L X), L the umbrella
// operator (L X = mean of the one-ring - X). A surface of constant
// curvature moves far less than under an umbrella step of the same weight (a
// tube 8 edges round shrinks by a seventh as much); a bump a few edges wide
// is rounded. With normal_sigma <= 0, m = 1 everywhere. Otherwise m is, per
// vertex, how much of its faces' rings a bilateral normal filter of that
// range sigma leaves out (the mean over its faces of 1 - the mean range
// weight exp(-|n_f - n_g|^2 / (2 normal_sigma^2)) over the faces g sharing a
// vertex with f), ramped from 0 at 0.15 to 1 at 0.4: 0 on a surface whose
// neighbouring faces turn by less than the sigma, so that the filter
// already smooths it, and up to 1 on a feature a few edges round, a finger or
// an ear, whose faces differ by more and are left unfiltered. A crease's
// faces differ by more too, but the normals around it fall into two groups,
// one per side, where a finger's spread around it; m goes back to 0 as the
// scatter left within the best split of the normals of a vertex's two rings
// of faces in two falls from 0.06 to 0.02 of their whole scatter (a sharp
// crease: 0; a tube: 0.25 or more). Stable for weight < 0.5.
Eigen::MatrixXd SecondOrderFairing(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                   double weight, double normal_sigma);

}  // namespace mr
