#pragma once

// Gaussian image pyramids and bilinear and cubic sampling, in COLMAP's image
// coordinates: the centre of pixel (column c, row r) is the image point
// (c + 0.5, r + 0.5), so the image covers [0, width] x [0, height].
//
// Level l + 1 halves level l exactly: its pixel (c, r) covers the level-l
// pixels (2c..2c+1, 2r..2r+1), and an image point x at level l is the point
// x / 2 at level l + 1 (no half-pixel shift, unlike cv::pyrDown, whose output
// pixel c is centred on input pixel 2c). The smoothing kernel is the
// separable binomial [1 5 10 10 5 1] / 32 centred between input pixels 2c and
// 2c+1 (= the 2x2 box average of pyrDown's [1 4 6 4 1] / 16 Gaussian; std dev
// 1.12 input pixels), with mirrored borders (BORDER_REFLECT). A level of odd
// size n gives ceil(n / 2) pixels (the last one mirrors the missing pixel),
// the same size as PinholeView::Scaled(0.5).

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "geometry/view.h"

namespace mr {

// Half-resolution image, see above. `image`: CV_32F or CV_64F, any number of
// channels, at least 1x1; the result has the same type.
cv::Mat DownsampleHalf(const cv::Mat& image);

struct ImagePyramidOptions {
  // Number of levels including the full-resolution level 0, >= 1.
  int num_levels = 4;
  // Stop early (fewer levels) rather than make a level whose smaller side is
  // below this many pixels, >= 1.
  int min_size = 16;

  bool Check() const;
};

// levels[0] = image (shared, not copied), levels[l + 1] = DownsampleHalf(levels[l]).
// Always returns at least level 0.
std::vector<cv::Mat> BuildImagePyramid(const cv::Mat& image, const ImagePyramidOptions& options);

// The view of pyramid level `level` (>= 0): intrinsics scaled by exactly
// 0.5^level (so that Project() at level l is 0.5^l times Project() at level 0)
// and width, height halved `level` times rounding up, matching the pyramid's
// image sizes. Equals view.Scaled(0.5) applied `level` times while the sizes
// stay even; for odd sizes Scaled() rescales by the size ratio instead, which
// is not the pyramid's geometry.
PinholeView PyramidLevelView(const PinholeView& view, int level);

// Bilinear interpolation of a single-channel CV_8U, CV_32F or CV_64F image at
// the image point (x, y) in COLMAP coordinates. Points outside the square of
// pixel centres [0.5, width - 0.5] x [0.5, height - 0.5] (NaN included) are
// clamped to it (replicated border): the value is that of the nearest point
// of the square and the gradient component across its border is 0. `grad`
// (optional) receives (d/dx, d/dy) of the interpolant; on cell borders it is
// one-sided (from the cell to the right / below, or the last cell).
double SampleBilinear(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad = nullptr);

// Cubic convolution (Keys, a = -0.5: Catmull-Rom) of the same images at the
// same points, with the same clamping. The 4x4 stencil replicates the border
// pixels. Unlike the bilinear interpolant, this one is C1 (its gradient is
// continuous) and reproduces quadratics, so it blurs fine texture less and
// less unevenly: the bilinear interpolant averages two pixels half way
// between them and none at a pixel centre.
double SampleCubic(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad = nullptr);

// The mean of SampleCubic at the four points (x ± sigma, y ± sigma) (each
// clamped as SampleCubic clamps it), a blur of variance sigma² per axis on
// top of the interpolation, and its gradient; computed as one separable
// stencil of up to 4 + 2 sigma + 1 taps per axis. 0 <= sigma <= 3.
double SampleCubicBlurred(const cv::Mat& img, double x, double y, double sigma,
                          Eigen::Vector2d* grad = nullptr);

}  // namespace mr
