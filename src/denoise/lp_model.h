#pragma once

// Building blocks of the content-aware L_p denoiser (DCV Sec. IV-B):
// the edge-based operator D of He & Schaefer 2013, the GST shrinkage of
// Zuo et al. 2013, and the closed-form / 1-D-search parameter estimates.
// Exposed for tests and for callers that want the pieces.

#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace mr {

// One row of D per interior manifold edge (v1, v3) with opposite vertices v2
// (in the face that has v1 -> v3 ... either orientation) and v4.
struct EdgeQuads {
  Eigen::MatrixXi quads;  // #rows by 4: (v1, v3, v2, v4), edge ends first
  int num_boundary = 0;     // edges with one incident face (skipped)
  int num_non_manifold = 0; // edges with > 2 incident faces (skipped)
};
// Throws mr::InputError on an index out of [0, num_vertices).
EdgeQuads BuildEdgeQuads(const Eigen::MatrixXi& F, int num_vertices);

// #rows by 4 weights w such that row i of D X is sum_k w(i,k) X(quads(i,k)):
//   (A134 x2 + A123 x4) / (A123 + A134) - ((1 - t) x1 + t x3),
// i.e. the point where segment x2 x4 crosses the edge's line, minus that
// point's projection on the edge: exactly He & Schaefer's area-based edge
// operator, Eq. 8 (test EdgeWeights.AreHeSchaefersAreaBasedOperator). It is
// zero whenever the two triangles are coplanar. Degenerate rows (zero areas or edge length,
// or a foot point far outside the edge) get all-zero weights; their count is
// returned in `num_degenerate` if non-null.
Eigen::MatrixXd EdgeWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& quads,
                            int* num_degenerate = nullptr);

// Sparse D (#rows by num_vertices) from quads and weights.
Eigen::SparseMatrix<double> AssembleEdgeOperator(const Eigen::MatrixXi& quads,
                                                 const Eigen::MatrixXd& weights,
                                                 int num_vertices);
// Rows of D X (#rows by 3) without forming D.
Eigen::MatrixXd ApplyEdgeOperator(const Eigen::MatrixXi& quads,
                                  const Eigen::MatrixXd& weights,
                                  const Eigen::MatrixXd& X);

// GST (Zuo et al. ICCV 2013): argmin_x 0.5 (x - y)^2 + lambda |x|^p for
// p in (0, 1], lambda >= 0. Also p in (1, 2] (convex, no threshold: the root
// of x + lambda p x^(p-1) = |y| by safeguarded Newton; p = 2 is y / (1 + 2 lambda)).
double GstShrink(double y, double lambda, double p);
// The GST threshold: the result is 0 iff |y| <= GstThreshold(lambda, p) (0 for p > 1).
double GstThreshold(double lambda, double p);
// Vector GST: argmin_x 0.5 |x - y|^2 + lambda |x|_2^p (x, y in R^3). The
// minimiser is parallel to y, so this is rotation invariant.
Eigen::Vector3d GstShrinkVector(const Eigen::Vector3d& y, double lambda, double p);

// The likelihood model (documented in docs/denoising.md). D annihilates
// tangential motion on flat regions, so a row of D X is, to first order, a
// scalar along the surface normal: the prior is the paper's hyper-Laplacian
// (eq. ca1) on the row's vector length r_i = |(D X)_i|,
//   q(r) = p/2 (theta/2)^(1/p) / Gamma(1/p) exp(-theta/2 r^p),
// one factor per row (m rows, not 3m coordinates), and the noise is the
// paper's eq. ca2, one Gaussian factor per vertex displacement |x_i - x0_i|.
// Negative log-likelihood of the m rows for (p, theta):
double HyperLaplacianNll(const Eigen::VectorXd& row_norms, double p, double theta);
// Closed-form argmin over theta: theta = 2 m / (p sum r_i^p).
double ThetaClosedForm(const Eigen::VectorXd& row_norms, double p);
// Closed form for sigma^2 = |X - X0|_F^2 / n (eq. ca8; n vertices).
double SigmaSquaredClosedForm(const Eigen::MatrixXd& X, const Eigen::MatrixXd& X0);
// 1-D exhaustive search of p over p_min, p_min + p_step, ..., p_max with
// theta(p) in closed form. Returns p and sets *theta.
double EstimateP(const Eigen::VectorXd& row_norms, double p_min, double p_max, double p_step,
                 double* theta);

}  // namespace mr
