#pragma once

// Image-space photometric similarity of DCV (Li et al., TIP 2016, Sec. IV-A):
// local ZNCC with Gaussian windows restricted to a valid domain, its exact
// derivative with respect to the predicted image, and the paper's
// detail-preserving modification of that derivative (eq. De17).
//
// Notation (all sums over pixels; G = the normalised, truncated 2-D Gaussian
// kernel of standard deviation `sigma`, applied with zero padding outside the
// image, so that G* is self-adjoint):
//   M(q)   validity weight in [0, 1] (the valid domain pi_i o S_ij; 0 outside).
//          Pixels where I1 or I2 is not finite get M = 0.
//   omega  = G*M                               (Gaussian mass in the domain)
//   mu_k   = G*(M I_k) / omega                 (eq. De4)
//   v_k    = G*(M I_k^2) / omega - mu_k^2 + eps  (eq. De2)
//   v_12   = G*(M I1 I2) / omega - mu_1 mu_2   (eq. De3)
//   m      = v_12 / sqrt(v_1 v_2)              (eq. De1, in [-1, 1])
//   W(p)   = M(p) if omega(p) >= min_support, else 0  (the pixels counted)
// The cost (a reprojection error, to be minimised) is
//   C = sum_p W(p) (1 - m(p)),
// and its exact derivative with respect to the predicted image I2 at pixel q is
//   dC/dI2(q) = M(q) [ alpha(q) I1(q) + beta(q) I2(q) + gamma(q) ]   (eq. De5)
//   alpha = -G*A,  beta = G*B,  gamma = G*(A mu_1 - B mu_2)          (De6-De7a)
//   A = W / (omega sqrt(v_1 v_2)),   B = W m / (omega v_2).
// With W = M = 1 this is exactly the paper's formula; the paper's d_2 m is the
// derivative of the error sum_p (-m(p)) (note its sign), i.e. of C.
//
// method "dcv" adds the paper's variance term (eq. De17) to that derivative:
//   D(q) = dC/dI2(q) + kappa M(q) (G*(W (v_2 - v_1) / v_2))(q).
// The added term is NOT the derivative of any cost returned here: for "dcv"
// `gradient` is the paper's modified descent direction (descend with
// I2 -= step * gradient, or chain it to the surface as the derivative of C).
// See docs/similarity.md for the derivation and what the added term does.

#include <string>

#include <opencv2/core.hpp>

namespace mr {

struct SimilarityOptions {
  // "zncc": the isotropic ZNCC baseline; "dcv": ZNCC plus the detail-preserving
  // variance term of eq. De17 (weighted by `kappa`).
  std::string method = "dcv";
  // Standard deviation of the Gaussian window G, in pixels, > 0. 2.0 has the
  // same second moment as a 7x7 box window (sqrt((7^2 - 1) / 12) = 2); the
  // kernel is truncated at radius ceil(3 sigma) (13x13 for sigma = 2).
  double sigma = 2.0;
  // Variance regulariser eps of eq. De2, in intensity^2 for images in [0, 1],
  // > 0. 1e-4 = (0.01)^2, i.e. about 2.5 grey levels of 255: windows with a
  // smaller standard deviation count as textureless.
  double epsilon = 1e-4;
  // Weight kappa of the variance term of eq. De17 (used by "dcv" only), >= 0,
  // dimensionless (the term is kappa times a ratio of variances; the ZNCC
  // derivative is of the order of 1 / (local standard deviation) per pixel).
  // The paper starts it small and increases it over the iterations; the caller
  // schedules it.
  double kappa = 0.5;
  // A pixel p counts in the cost only if omega(p) = (G*M)(p) >= min_support,
  // in [0, 1): the fraction of the Gaussian window that lies in the valid
  // domain. 0 counts every valid pixel (0.5 is a straight domain border).
  double min_support = 0.0;
  // Compute in double (slower; for tests and diagnostics) instead of float.
  // Float computations centre both images on their masked mean first, so
  // they lose little to cancellation.
  bool double_precision = false;

  bool Check() const;
};

struct SimilarityResult {
  double cost = 0;        // C = sum_p W(p) (1 - m(p)), summed over channels
  double zncc_sum = 0;    // sum_p W(p) m(p), summed over channels
  double weight_sum = 0;  // sum_p W(p), summed over channels
  // Per-pixel m(p) (0 where W(p) = 0), same size and channel count as the
  // images, CV_32F (CV_64F with double_precision).
  cv::Mat zncc;
  // Per-pixel local variance v_2 of the predicted image (eq. De2, including
  // eps; eps where W(p) = 0), same size, channels and depth as `zncc`. The
  // refiner's Gauss-Newton curvature uses 1 / v_2.
  cv::Mat variance_predicted;
  // Per-pixel dC/dI2 ("zncc") or the paper's modified direction ("dcv"), same
  // size, channels and depth as `zncc`; 0 where M = 0. Empty unless
  // compute_gradient.
  cv::Mat gradient;

  // Weighted mean ZNCC in [-1, 1]; 0 when no pixel counts.
  double MeanZncc() const { return weight_sum > 0 ? zncc_sum / weight_sum : 0.0; }
};

// observed = I1 (the observed image I_i), predicted = I2 (the predicted image
// I_ij): CV_32F or CV_64F, 1 to 4 channels, same size and type; intensities
// are expected in [0, 1] (the defaults of epsilon assume so). Each channel is
// compared separately and the costs are summed.
// mask = the validity weight M: empty (all valid), CV_8UC1 (non-zero = valid)
// or CV_32FC1 / CV_64FC1 with values in [0, 1]; same size as the images.
// Throws InputError on invalid options; InternalError (MR_CHECK) on
// mismatched sizes or types, or mask values outside [0, 1].
SimilarityResult ComputeSimilarity(const cv::Mat& observed, const cv::Mat& predicted,
                                   const cv::Mat& mask, const SimilarityOptions& options,
                                   bool compute_gradient = true);

}  // namespace mr
