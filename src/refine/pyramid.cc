#include "refine/pyramid.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace mr {

namespace {

// Binomial [1 5 10 10 5 1] / 32: output pixel c reads input pixels 2c-2..2c+3.
constexpr double kTaps[6] = {1 / 32.0, 5 / 32.0, 10 / 32.0, 10 / 32.0, 5 / 32.0, 1 / 32.0};
constexpr int kPadBefore = 2;
constexpr int kPadAfter = 3;

template <typename T>
cv::Mat DownsampleTyped(const cv::Mat& image) {
  const int cn = image.channels();
  const int wo = (image.cols + 1) / 2, ho = (image.rows + 1) / 2;
  cv::Mat padded;
  cv::copyMakeBorder(image, padded, kPadBefore, kPadAfter, kPadBefore, kPadAfter,
                     cv::BORDER_REFLECT);
  // Horizontal pass: all padded rows, output columns.
  cv::Mat tmp(padded.rows, wo, image.type());
  for (int r = 0; r < padded.rows; ++r) {
    const T* src = padded.ptr<T>(r);
    T* dst = tmp.ptr<T>(r);
    for (int c = 0; c < wo; ++c) {
      // Padded column of input column 2c - 2 is 2c.
      const T* s = src + 2 * c * cn;
      for (int k = 0; k < cn; ++k) {
        double acc = 0;
        for (int i = 0; i < 6; ++i) acc += kTaps[i] * s[i * cn + k];
        dst[c * cn + k] = static_cast<T>(acc);
      }
    }
  }
  // Vertical pass.
  cv::Mat out(ho, wo, image.type());
  const int n = wo * cn;
  for (int r = 0; r < ho; ++r) {
    T* dst = out.ptr<T>(r);
    const T* rows[6];
    for (int i = 0; i < 6; ++i) rows[i] = tmp.ptr<T>(2 * r + i);
    for (int j = 0; j < n; ++j) {
      double acc = 0;
      for (int i = 0; i < 6; ++i) acc += kTaps[i] * rows[i][j];
      dst[j] = static_cast<T>(acc);
    }
  }
  return out;
}

template <typename T>
inline double At(const cv::Mat& img, int r, int c) {
  return static_cast<double>(img.ptr<T>(r)[c]);
}

template <typename T>
double SampleTyped(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  // Index coordinates: pixel centres at integers.
  double u = x - 0.5, v = y - 0.5;
  const double umax = img.cols - 1, vmax = img.rows - 1;
  bool clamp_u = false, clamp_v = false;
  if (!(u >= 0)) {  // also NaN
    u = 0;
    clamp_u = true;
  } else if (u > umax) {
    u = umax;
    clamp_u = true;
  }
  if (!(v >= 0)) {
    v = 0;
    clamp_v = true;
  } else if (v > vmax) {
    v = vmax;
    clamp_v = true;
  }
  int c0 = std::min(static_cast<int>(u), std::max(img.cols - 2, 0));
  int r0 = std::min(static_cast<int>(v), std::max(img.rows - 2, 0));
  const int c1 = std::min(c0 + 1, img.cols - 1);
  const int r1 = std::min(r0 + 1, img.rows - 1);
  const double fu = u - c0, fv = v - r0;
  const double p00 = At<T>(img, r0, c0), p01 = At<T>(img, r0, c1);
  const double p10 = At<T>(img, r1, c0), p11 = At<T>(img, r1, c1);
  const double top = p00 + fu * (p01 - p00);
  const double bottom = p10 + fu * (p11 - p10);
  if (grad != nullptr) {
    // A 1-pixel-wide image has c1 == c0: the difference is 0, as it should.
    (*grad)(0) = clamp_u ? 0.0 : (1 - fv) * (p01 - p00) + fv * (p11 - p10);
    (*grad)(1) = clamp_v ? 0.0 : bottom - top;
  }
  return top + fv * (bottom - top);
}

}  // namespace

cv::Mat DownsampleHalf(const cv::Mat& image) {
  MR_CHECK(!image.empty()) << "DownsampleHalf: empty image";
  MR_CHECK(image.depth() == CV_32F || image.depth() == CV_64F)
      << "DownsampleHalf: image depth must be CV_32F or CV_64F";
  if (image.depth() == CV_32F) return DownsampleTyped<float>(image);
  return DownsampleTyped<double>(image);
}

bool ImagePyramidOptions::Check() const {
  if (num_levels < 1) {
    MR_THROW_INPUT << "ImagePyramidOptions::num_levels = " << num_levels
                   << ". Violated constraint: num_levels >= 1";
  }
  if (min_size < 1) {
    MR_THROW_INPUT << "ImagePyramidOptions::min_size = " << min_size
                   << ". Violated constraint: min_size >= 1";
  }
  return true;
}

std::vector<cv::Mat> BuildImagePyramid(const cv::Mat& image, const ImagePyramidOptions& options) {
  options.Check();
  std::vector<cv::Mat> levels{image};
  while (static_cast<int>(levels.size()) < options.num_levels) {
    const cv::Mat& last = levels.back();
    if (std::min((last.cols + 1) / 2, (last.rows + 1) / 2) < options.min_size) break;
    levels.push_back(DownsampleHalf(last));
  }
  return levels;
}

PinholeView PyramidLevelView(const PinholeView& view, int level) {
  MR_CHECK_GE(level, 0) << "PyramidLevelView";
  PinholeView v = view;
  for (int l = 0; l < level; ++l) {
    v.width = (v.width + 1) / 2;
    v.height = (v.height + 1) / 2;
    v.fx *= 0.5;
    v.fy *= 0.5;
    v.cx *= 0.5;
    v.cy *= 0.5;
  }
  return v;
}

double SampleBilinear(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  MR_CHECK(!img.empty() && img.channels() == 1)
      << "SampleBilinear: expected a non-empty single-channel image";
  switch (img.depth()) {
    case CV_8U:
      return SampleTyped<uchar>(img, x, y, grad);
    case CV_32F:
      return SampleTyped<float>(img, x, y, grad);
    case CV_64F:
      return SampleTyped<double>(img, x, y, grad);
    default:
      MR_CHECK(false) << "SampleBilinear: image depth must be CV_8U, CV_32F or CV_64F";
  }
  return 0;
}

}  // namespace mr
