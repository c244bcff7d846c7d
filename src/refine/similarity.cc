#include "refine/similarity.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "util/error.h"

namespace mr {

bool SimilarityOptions::Check() const {
  if (method != "dcv" && method != "zncc") {
    MR_THROW_INPUT << "SimilarityOptions::method = " << method
                   << ". Violated constraint: method is one of dcv, zncc";
  }
  if (!(sigma > 0) || !std::isfinite(sigma)) {
    MR_THROW_INPUT << "SimilarityOptions::sigma = " << sigma << ". Violated constraint: sigma > 0";
  }
  if (sigma > 100) {
    MR_THROW_INPUT << "SimilarityOptions::sigma = " << sigma
                   << ". Violated constraint: sigma <= 100";
  }
  if (!(epsilon > 0) || !std::isfinite(epsilon)) {
    MR_THROW_INPUT << "SimilarityOptions::epsilon = " << epsilon
                   << ". Violated constraint: epsilon > 0";
  }
  if (!(kappa >= 0) || !std::isfinite(kappa)) {
    MR_THROW_INPUT << "SimilarityOptions::kappa = " << kappa << ". Violated constraint: kappa >= 0";
  }
  if (!(min_support >= 0 && min_support < 1)) {
    MR_THROW_INPUT << "SimilarityOptions::min_support = " << min_support
                   << ". Violated constraint: 0 <= min_support < 1";
  }
  return true;
}

namespace {

// The threads a filter may split into bands here: 1 inside a parallel region
// (the caller's threads are taken), else OpenMP's maximum.
int ThreadsForBands() {
#ifdef _OPENMP
  return omp_in_parallel() ? 1 : std::max(1, omp_get_max_threads());
#else
  return 1;
#endif
}

// Fewer rows per thread than this are filtered on one thread.
constexpr int kMinBandRows = 32;

// Normalised Gaussian G* with zero padding (self-adjoint), on every channel.
class GaussianFilter {
 public:
  GaussianFilter(double sigma, int depth) {
    const int radius = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
    kernel_ = cv::getGaussianKernel(2 * radius + 1, sigma, depth);
    depth_ = depth;
  }
  // In row bands, one per thread: each band is filtered as a view of `src`,
  // whose neighbouring rows OpenCV reads for the kernel's reach (only the
  // image's own border is padded with zeros), so every pixel gets the same
  // value as when the whole image is filtered at once.
  void Apply(const cv::Mat& src, cv::Mat* dst) const {
    dst->create(src.size(), CV_MAKETYPE(depth_, src.channels()));
    const int bands = std::max(1, std::min(ThreadsForBands(), src.rows / kMinBandRows));
#pragma omp parallel for schedule(static) if (bands > 1)
    for (int b = 0; b < bands; ++b) {
      const cv::Range rows(src.rows * b / bands, src.rows * (b + 1) / bands);
      cv::Mat band = (*dst)(rows, cv::Range::all());
      cv::sepFilter2D(src(rows, cv::Range::all()), band, depth_, kernel_, kernel_,
                      cv::Point(-1, -1), 0.0, cv::BORDER_CONSTANT);
    }
  }

 private:
  cv::Mat kernel_;
  int depth_;
};

// Effective validity weight M (type T): the user's mask, zeroed where either
// channel value of either image is not finite.
template <typename T>
cv::Mat EffectiveMask(const cv::Mat& I1, const cv::Mat& I2, const cv::Mat& mask) {
  const int rows = I1.rows, cols = I1.cols, n = cols * I1.channels(), cn = I1.channels();
  cv::Mat M(rows, cols, cv::DataType<T>::type);
  for (int r = 0; r < rows; ++r) {
    T* m = M.ptr<T>(r);
    if (mask.empty()) {
      std::fill(m, m + cols, T(1));
    } else if (mask.depth() == CV_8U) {
      const uchar* k = mask.ptr<uchar>(r);
      for (int c = 0; c < cols; ++c) m[c] = k[c] != 0 ? T(1) : T(0);
    } else {
      for (int c = 0; c < cols; ++c) {
        double w = mask.depth() == CV_32F ? mask.ptr<float>(r)[c] : mask.ptr<double>(r)[c];
        // Tolerate rounding (a blurred binary mask overshoots 1 by ~1e-16).
        MR_CHECK(w >= -1e-6 && w <= 1 + 1e-6)
            << "ComputeSimilarity: mask value " << w << " at (" << c << ", " << r
            << "), expected in [0, 1]";
        m[c] = static_cast<T>(std::min(std::max(w, 0.0), 1.0));
      }
    }
    // Non-finite pixels are invalid. (x - x is 0 for finite x, NaN otherwise.)
    const T* a = I1.ptr<T>(r);
    const T* b = I2.ptr<T>(r);
    bool all_finite = true;
    for (int j = 0; j < n; ++j) all_finite &= (a[j] - a[j] == 0) & (b[j] - b[j] == 0);
    if (all_finite) continue;
    for (int c = 0; c < cols; ++c) {
      for (int k = 0; k < cn; ++k) {
        if (!std::isfinite(a[c * cn + k]) || !std::isfinite(b[c * cn + k])) m[c] = 0;
      }
    }
  }
  return M;
}

template <typename T>
void SimilarityOneChannel(const cv::Mat& I1, const cv::Mat& I2, const cv::Mat& M,
                          const GaussianFilter& G, const SimilarityOptions& options,
                          bool compute_gradient, SimilarityResult* result, cv::Mat* zncc,
                          cv::Mat* gradient, cv::Mat* variance2) {
  const int rows = I1.rows, cols = I1.cols;
  const int type6 = CV_MAKETYPE(cv::DataType<T>::depth, 6);
  const T eps = static_cast<T>(options.epsilon);
  const T min_support = static_cast<T>(options.min_support);
  const bool with_kappa = options.method == "dcv" && options.kappa > 0;

  // Centre both images on their masked means (m and dC/dI2 are invariant to
  // it; it keeps v = E[I^2] - E[I]^2 accurate in float).
  double sum_m = 0, sum_1 = 0, sum_2 = 0;
  for (int r = 0; r < rows; ++r) {
    const T* m = M.ptr<T>(r);
    const T* a = I1.ptr<T>(r);
    const T* b = I2.ptr<T>(r);
    for (int c = 0; c < cols; ++c) {
      if (m[c] > 0) {
        sum_m += m[c];
        sum_1 += m[c] * a[c];
        sum_2 += m[c] * b[c];
      }
    }
  }
  const T c1 = static_cast<T>(sum_m > 0 ? sum_1 / sum_m : 0.0);
  const T c2 = static_cast<T>(sum_m > 0 ? sum_2 / sum_m : 0.0);

  // Forward: the six masked moments, filtered in one pass.
  cv::Mat F(rows, cols, type6), Fs;
#pragma omp parallel for schedule(static)
  for (int r = 0; r < rows; ++r) {
    const T* m = M.ptr<T>(r);
    const T* a = I1.ptr<T>(r);
    const T* b = I2.ptr<T>(r);
    T* f = F.ptr<T>(r);
    for (int c = 0; c < cols; ++c, f += 6) {
      const T w = m[c];
      const T x = w > 0 ? a[c] - c1 : T(0);
      const T y = w > 0 ? b[c] - c2 : T(0);
      f[0] = w;
      f[1] = w * x;
      f[2] = w * y;
      f[3] = w * x * x;
      f[4] = w * y * y;
      f[5] = w * x * y;
    }
  }
  G.Apply(F, &Fs);

  // Per pixel: m, the cost, and the three backward maps A, B and
  // A mu1 - B mu2 (+ kappa K for dcv), so that alpha = -G*A, beta = G*B and
  // gamma = G*(A mu1 - B mu2) (+ the De17 term, by linearity of G*).
  const T kappa = static_cast<T>(options.kappa);
  constexpr int nb = 3;
  cv::Mat R;
  if (compute_gradient) R.create(rows, cols, CV_MAKETYPE(cv::DataType<T>::depth, nb));
  // Whether pixel (m, omega) has a ZNCC; the cost sums over these pixels.
  auto supported = [&](T W, T omega) { return W > 0 && omega > 0 && !(omega < min_support); };
#pragma omp parallel for schedule(static)
  for (int r = 0; r < rows; ++r) {
    const T* m = M.ptr<T>(r);
    const T* fs = Fs.ptr<T>(r);
    T* z = zncc->ptr<T>(r);
    T* v2out = variance2->ptr<T>(r);
    T* b = compute_gradient ? R.ptr<T>(r) : nullptr;
    for (int c = 0; c < cols; ++c, fs += 6) {
      const T omega = fs[0];
      const T W = m[c];
      if (!supported(W, omega)) {
        z[c] = 0;
        v2out[c] = eps;
        if (b) std::fill(b + c * nb, b + (c + 1) * nb, T(0));
        continue;
      }
      const T inv_omega = T(1) / omega;
      const T mu1 = fs[1] * inv_omega, mu2 = fs[2] * inv_omega;
      // v_k >= eps in exact arithmetic (Cauchy-Schwarz); clamp rounding only.
      const T v1 = std::max(fs[3] * inv_omega - mu1 * mu1 + eps, eps);
      const T v2 = std::max(fs[4] * inv_omega - mu2 * mu2 + eps, eps);
      const T v12 = fs[5] * inv_omega - mu1 * mu2;
      const T inv_s = T(1) / std::sqrt(v1 * v2);
      const T zn = v12 * inv_s;
      z[c] = zn;
      v2out[c] = v2;
      if (b) {
        const T inv_v2 = T(1) / v2;
        const T A = W * inv_omega * inv_s;
        const T B = W * zn * inv_omega * inv_v2;
        T* o = b + c * nb;
        o[0] = A;
        o[1] = B;
        o[2] = A * mu1 - B * mu2;
        if (with_kappa) o[2] += kappa * (W * (v2 - v1) * inv_v2);
      }
    }
  }
  // The sums on one thread, pixel by pixel, so that they do not depend on
  // the number of threads.
  double cost = 0, zsum = 0, wsum = 0;
  for (int r = 0; r < rows; ++r) {
    const T* m = M.ptr<T>(r);
    const T* fs = Fs.ptr<T>(r);
    const T* z = zncc->ptr<T>(r);
    for (int c = 0; c < cols; ++c, fs += 6) {
      const T W = m[c];
      if (!supported(W, fs[0])) continue;
      cost += static_cast<double>(W) * (1.0 - static_cast<double>(z[c]));
      zsum += static_cast<double>(W) * z[c];
      wsum += W;
    }
  }
  result->cost += cost;
  result->zncc_sum += zsum;
  result->weight_sum += wsum;
  if (!compute_gradient) return;

  // Backward: dC/dI2(q) = M(q) [-x(q) G*A + y(q) G*B + G*(A mu1 - B mu2)]
  // (+ kappa M(q) G*K for dcv, inside the last map), in centred coordinates
  // x = I1 - c1, y = I2 - c2 (mu1, mu2 are centred the same way).
  cv::Mat Rs;
  G.Apply(R, &Rs);
#pragma omp parallel for schedule(static)
  for (int r = 0; r < rows; ++r) {
    const T* m = M.ptr<T>(r);
    const T* a = I1.ptr<T>(r);
    const T* bb = I2.ptr<T>(r);
    const T* rs = Rs.ptr<T>(r);
    T* g = gradient->ptr<T>(r);
    for (int c = 0; c < cols; ++c, rs += nb) {
      const T w = m[c];
      g[c] = w > 0 ? w * (-(a[c] - c1) * rs[0] + (bb[c] - c2) * rs[1] + rs[2]) : T(0);
    }
  }
}

template <typename T>
SimilarityResult ComputeTyped(const cv::Mat& observed, const cv::Mat& predicted,
                              const cv::Mat& mask, const SimilarityOptions& options,
                              bool compute_gradient) {
  const int depth = cv::DataType<T>::depth;
  cv::Mat I1 = observed, I2 = predicted;
  if (I1.depth() != depth) observed.convertTo(I1, CV_MAKETYPE(depth, observed.channels()));
  if (I2.depth() != depth) predicted.convertTo(I2, CV_MAKETYPE(depth, predicted.channels()));
  const cv::Mat M = EffectiveMask<T>(I1, I2, mask);
  const GaussianFilter G(options.sigma, depth);

  std::vector<cv::Mat> ch1{I1}, ch2{I2};
  if (I1.channels() > 1) {
    cv::split(I1, ch1);
    cv::split(I2, ch2);
  }
  const int cn = static_cast<int>(ch1.size());
  std::vector<cv::Mat> z(cn), g(cn), v(cn);
  SimilarityResult result;
  for (int k = 0; k < cn; ++k) {
    z[k].create(I1.size(), depth);
    v[k].create(I1.size(), depth);
    if (compute_gradient) g[k].create(I1.size(), depth);
    SimilarityOneChannel<T>(ch1[k], ch2[k], M, G, options, compute_gradient, &result, &z[k],
                            &g[k], &v[k]);
  }
  if (cn == 1) {
    result.zncc = z[0];
    result.variance_predicted = v[0];
    if (compute_gradient) result.gradient = g[0];
  } else {
    cv::merge(z, result.zncc);
    cv::merge(v, result.variance_predicted);
    if (compute_gradient) cv::merge(g, result.gradient);
  }
  return result;
}

}  // namespace

SimilarityResult ComputeSimilarity(const cv::Mat& observed, const cv::Mat& predicted,
                                   const cv::Mat& mask, const SimilarityOptions& options,
                                   bool compute_gradient) {
  options.Check();
  MR_CHECK(!observed.empty()) << "ComputeSimilarity: empty observed image";
  MR_CHECK(observed.size() == predicted.size())
      << "ComputeSimilarity: observed " << observed.cols << "x" << observed.rows
      << " vs predicted " << predicted.cols << "x" << predicted.rows;
  MR_CHECK(observed.type() == predicted.type())
      << "ComputeSimilarity: observed and predicted image types differ";
  MR_CHECK(observed.depth() == CV_32F || observed.depth() == CV_64F)
      << "ComputeSimilarity: images must be CV_32F or CV_64F";
  MR_CHECK(observed.channels() >= 1 && observed.channels() <= 4)
      << "ComputeSimilarity: " << observed.channels() << " channels, expected 1 to 4";
  if (!mask.empty()) {
    MR_CHECK(mask.size() == observed.size())
        << "ComputeSimilarity: mask " << mask.cols << "x" << mask.rows << " vs image "
        << observed.cols << "x" << observed.rows;
    MR_CHECK(mask.type() == CV_8UC1 || mask.type() == CV_32FC1 || mask.type() == CV_64FC1)
        << "ComputeSimilarity: mask must be CV_8UC1, CV_32FC1 or CV_64FC1";
  }
  if (options.double_precision) {
    return ComputeTyped<double>(observed, predicted, mask, options, compute_gradient);
  }
  return ComputeTyped<float>(observed, predicted, mask, options, compute_gradient);
}

}  // namespace mr
