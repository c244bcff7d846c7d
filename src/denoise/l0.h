#pragma once

// Mesh denoising via L0 minimization (He & Schaefer, SIGGRAPH 2013): the
// `l0` method of mr::Denoise (denoiser.h), a baseline for the content-aware
// L_p denoiser. Minimises
//   |X - X0|^2 + alpha |R X|^2 + lambda #{e : (D X)_e != 0}
// with D the edge operator of lp_model.h (one 3-vector row per interior
// edge, zero where the two triangles are coplanar; the same area weights as
// He & Schaefer's Eq. 8) and R(e) = x1 + x3 - x2 - x4 their regulariser, by
// their alternation with a growing penalty beta:
//   delta-step: delta_e = (D X)_e if |(D X)_e|^2 >= lambda / beta, else 0;
//   X-step:     (I + alpha R^T R + beta D^T D) X = X0 + beta D^T delta;
//   beta *= l0_beta_factor, alpha *= l0_alpha_decay, until beta > l0_beta_max.
// Works on the mesh normalised to its centroid and unit mean edge length
// (like lp), so the result commutes with rotation, translation and uniform
// scaling. See docs/denoising.md.

#include <Eigen/Core>

#include "denoise/denoiser.h"
#include "denoise/lp_model.h"

namespace mr {

// The start that both edge-operator methods share (lp in denoiser.cc, l0
// here): D's rows, and its weights on the mesh moved to its centroid and
// scaled to unit mean edge length h.
struct EdgeProblem {
  EdgeQuads eq;
  Eigen::RowVector3d centre;
  double h = 0;
  Eigen::MatrixXd X0;  // (V0 - centre) / h
  Eigen::MatrixXd W;   // D's weights at X0
  int degenerate = 0;  // rows of W left zero
};
// Fills result->num_skipped_edges and num_operator_rows. Where there is
// nothing to denoise (no interior edge, or every edge of zero length) it
// returns false with result->V = V0 and passed_through set, and logs why
// under `label`.
bool SetUpEdgeProblem(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F, const char* label,
                      DenoiseResult* result, EdgeProblem* problem);

// Runs the l0 method (options.method is not looked at; options are assumed
// checked, input validated by mr::Denoise). Fills V, l0_lambda,
// l0_mean_dihedral_deg, l0_steps, num_operator_rows, num_skipped_edges,
// passed_through, setup_seconds.
void DenoiseL0(const Eigen::MatrixXd& V0, const Eigen::MatrixXi& F,
               const DenoiseOptions& options, DenoiseResult* result);

// The delta-step: zeroes every row r of `rows` (#rows by 3) with
// |r|^2 < threshold and keeps the others unchanged (the minimiser of
// beta |delta_e - r|^2 + lambda [delta_e != 0] for threshold = lambda / beta;
// a tie keeps the row). Returns the number of non-zero rows kept.
int HardThresholdRows(double threshold, Eigen::MatrixXd* rows);

// Mean over the rows of D (quads with a non-zero weight row) of the angle in
// degrees between the normals of the two triangles (x1, x3, x2) and
// (x1, x4, x3) (0 where they are coplanar, 90 on a cube edge), independent of
// the faces' orientation. 0 if no row.
double MeanDihedralAngleDeg(const Eigen::MatrixXd& V, const Eigen::MatrixXi& quads,
                            const Eigen::MatrixXd& weights);

// R's weights in EdgeWeights' layout (columns v1, v3, v2, v4): (1, 1, -1, -1)
// per row.
Eigen::MatrixXd RegularizerWeights(const Eigen::MatrixXi& quads);

}  // namespace mr
