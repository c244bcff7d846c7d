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

// Index coordinate (pixel centres at integers) of image coordinate x along an
// axis of `size` pixels, clamped to [0, size - 1]; `clamped` tells whether it
// was (NaN included).
double IndexCoordinate(double x, int size, bool* clamped) {
  const double u = x - 0.5;
  *clamped = true;
  if (!(u >= 0)) return 0;  // also NaN
  if (u > size - 1) return size - 1;
  *clamped = false;
  return u;
}

template <typename T>
double SampleTyped(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  bool clamp_u, clamp_v;
  const double u = IndexCoordinate(x, img.cols, &clamp_u);
  const double v = IndexCoordinate(y, img.rows, &clamp_v);
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

// Catmull-Rom weights of the taps at offsets -1, 0, 1, 2 from the cell's
// first pixel, for the fraction t in [0, 1], and their derivatives in t.
void CubicWeights(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
}

template <typename T>
double SampleCubicTyped(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  bool clamp_u, clamp_v;
  const double u = IndexCoordinate(x, img.cols, &clamp_u);
  const double v = IndexCoordinate(y, img.rows, &clamp_v);
  const int c0 = std::min(static_cast<int>(u), img.cols - 1);
  const int r0 = std::min(static_cast<int>(v), img.rows - 1);
  double wu[4], dwu[4], wv[4], dwv[4];
  CubicWeights(u - c0, wu, dwu);
  CubicWeights(v - r0, wv, dwv);
  int cols[4];
  for (int k = 0; k < 4; ++k) cols[k] = std::clamp(c0 - 1 + k, 0, img.cols - 1);
  double value = 0, du = 0, dv = 0;
  for (int i = 0; i < 4; ++i) {
    const T* row = img.ptr<T>(std::clamp(r0 - 1 + i, 0, img.rows - 1));
    double along = 0, d_along = 0;
    for (int k = 0; k < 4; ++k) {
      const double p = static_cast<double>(row[cols[k]]);
      along += wu[k] * p;
      d_along += dwu[k] * p;
    }
    value += wv[i] * along;
    du += wv[i] * d_along;
    dv += dwv[i] * along;
  }
  if (grad != nullptr) {
    (*grad)(0) = clamp_u ? 0.0 : du;
    (*grad)(1) = clamp_v ? 0.0 : dv;
  }
  return value;
}

// The taps along one axis of `size` pixels of the mean of the cubic
// interpolants at x - sigma and x + sigma (sigma > 0): weights of the pixels
// first .. first + count - 1 (replicated beyond the border) and their
// derivatives in x (0 for a point clamped to the border).
struct AxisTaps {
  static constexpr int kMax = 12;
  int first = 0;
  int count = 0;
  double w[kMax] = {};
  double dw[kMax] = {};
};

AxisTaps BlurredCubicTaps(double x, int size, double sigma, bool with_derivative) {
  const double positions[2] = {x - sigma, x + sigma};
  int c0[2];
  double fraction[2];
  bool clamped[2];
  for (int p = 0; p < 2; ++p) {
    const double u = IndexCoordinate(positions[p], size, &clamped[p]);
    c0[p] = std::min(static_cast<int>(u), size - 1);
    fraction[p] = u - c0[p];
  }
  AxisTaps taps;
  taps.first = c0[0] - 1;
  taps.count = c0[1] + 3 - taps.first;
  MR_CHECK_LE(taps.count, AxisTaps::kMax) << "SampleCubicBlurred: sigma too large";
  for (int p = 0; p < 2; ++p) {
    double w[4], dw[4];
    CubicWeights(fraction[p], w, dw);
    const int offset = c0[p] - 1 - taps.first;
    for (int k = 0; k < 4; ++k) taps.w[offset + k] += 0.5 * w[k];
    if (with_derivative && !clamped[p]) {
      for (int k = 0; k < 4; ++k) taps.dw[offset + k] += 0.5 * dw[k];
    }
  }
  return taps;
}

template <typename T>
double SampleCubicBlurredTyped(const cv::Mat& img, double x, double y, double sigma,
                               Eigen::Vector2d* grad) {
  if (sigma <= 0) return SampleCubicTyped<T>(img, x, y, grad);
  const bool with_derivative = grad != nullptr;
  const AxisTaps tx = BlurredCubicTaps(x, img.cols, sigma, with_derivative);
  const AxisTaps ty = BlurredCubicTaps(y, img.rows, sigma, with_derivative);
  int cols[AxisTaps::kMax];
  for (int k = 0; k < tx.count; ++k) cols[k] = std::clamp(tx.first + k, 0, img.cols - 1);
  double value = 0, du = 0, dv = 0;
  for (int i = 0; i < ty.count; ++i) {
    const T* row = img.ptr<T>(std::clamp(ty.first + i, 0, img.rows - 1));
    double along = 0;
    for (int k = 0; k < tx.count; ++k) along += tx.w[k] * static_cast<double>(row[cols[k]]);
    value += ty.w[i] * along;
    if (!with_derivative) continue;
    double d_along = 0;
    for (int k = 0; k < tx.count; ++k) d_along += tx.dw[k] * static_cast<double>(row[cols[k]]);
    du += ty.w[i] * d_along;
    dv += ty.dw[i] * along;
  }
  if (grad != nullptr) *grad = Eigen::Vector2d(du, dv);
  return value;
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

namespace {

// Checks that `img` is a non-empty single-channel CV_8U, CV_32F or CV_64F
// image and returns sample(T()) with T its pixel type. `name` is the caller's,
// for the messages.
template <typename Sample>
double ByPixelType(const cv::Mat& img, const char* name, const Sample& sample) {
  MR_CHECK(!img.empty() && img.channels() == 1)
      << name << ": expected a non-empty single-channel image";
  switch (img.depth()) {
    case CV_8U:
      return sample(uchar());
    case CV_32F:
      return sample(float());
    case CV_64F:
      return sample(double());
    default:
      MR_CHECK(false) << name << ": image depth must be CV_8U, CV_32F or CV_64F";
  }
  return 0;
}

}  // namespace

double SampleBilinear(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  return ByPixelType(img, "SampleBilinear", [&](auto pixel) {
    return SampleTyped<decltype(pixel)>(img, x, y, grad);
  });
}

double SampleCubic(const cv::Mat& img, double x, double y, Eigen::Vector2d* grad) {
  return ByPixelType(img, "SampleCubic", [&](auto pixel) {
    return SampleCubicTyped<decltype(pixel)>(img, x, y, grad);
  });
}

double SampleCubicBlurred(const cv::Mat& img, double x, double y, double sigma,
                          Eigen::Vector2d* grad) {
  MR_CHECK(sigma >= 0 && sigma <= 3) << "SampleCubicBlurred: sigma " << sigma << " not in [0, 3]";
  return ByPixelType(img, "SampleCubicBlurred", [&](auto pixel) {
    return SampleCubicBlurredTyped<decltype(pixel)>(img, x, y, sigma, grad);
  });
}

}  // namespace mr
