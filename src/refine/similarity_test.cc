#include "refine/similarity.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <omp.h>
#include <opencv2/imgproc.hpp>

#include "util/error.h"

namespace mr {
namespace {

// A smooth random texture in [0, 1] (CV_64F): random values blurred a little.
cv::Mat RandomImage(int cols, int rows, unsigned seed, double blur = 0.7) {
  cv::Mat img(rows, cols, CV_64F);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) img.at<double>(r, c) = u(rng);
  if (blur > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), blur);
  return img;
}

// A non-trivial mask: a disc touching the image border, minus a hole and a
// few isolated pixels, plus an isolated valid pixel.
cv::Mat TestMask(int cols, int rows) {
  cv::Mat mask(rows, cols, CV_8U, cv::Scalar(0));
  cv::circle(mask, cv::Point(cols / 2 - 2, rows / 2 + 1), std::min(cols, rows) / 2 + 2,
             cv::Scalar(255), -1);
  cv::circle(mask, cv::Point(cols / 2 + 1, rows / 2 - 1), 2, cv::Scalar(0), -1);
  mask.at<uchar>(2, 3) = 0;
  mask.at<uchar>(rows - 3, 4) = 0;
  mask.at<uchar>(0, cols - 1) = 255;  // an isolated valid pixel in a corner
  return mask;
}

SimilarityOptions DoubleOptions(const std::string& method, double sigma, double kappa) {
  SimilarityOptions o;
  o.method = method;
  o.sigma = sigma;
  o.kappa = kappa;
  o.double_precision = true;
  return o;
}

// Brute-force reference of the local statistics (double, explicit 2-D sums
// with the same truncated kernel, zero outside the image).
struct Reference {
  cv::Mat omega, mu1, mu2, v1, v2, v12, m;
};

cv::Mat Kernel2D(double sigma) {
  const int radius = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  const cv::Mat k = cv::getGaussianKernel(2 * radius + 1, sigma, CV_64F);
  return k * k.t();
}

// G*f at every pixel by explicit summation.
cv::Mat BruteBlur(const cv::Mat& f, double sigma) {
  const cv::Mat K = Kernel2D(sigma);
  const int R = K.rows / 2;
  cv::Mat out(f.size(), CV_64F, cv::Scalar(0));
  for (int r = 0; r < f.rows; ++r)
    for (int c = 0; c < f.cols; ++c) {
      double s = 0;
      for (int dr = -R; dr <= R; ++dr)
        for (int dc = -R; dc <= R; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if (rr < 0 || cc < 0 || rr >= f.rows || cc >= f.cols) continue;
          s += K.at<double>(dr + R, dc + R) * f.at<double>(rr, cc);
        }
      out.at<double>(r, c) = s;
    }
  return out;
}

Reference BruteStatistics(const cv::Mat& I1, const cv::Mat& I2, const cv::Mat& mask8,
                          double sigma, double eps) {
  cv::Mat M;
  mask8.convertTo(M, CV_64F, 1.0 / 255);
  Reference ref;
  ref.omega = BruteBlur(M, sigma);
  const cv::Mat s1 = BruteBlur(M.mul(I1), sigma), s2 = BruteBlur(M.mul(I2), sigma);
  const cv::Mat s11 = BruteBlur(M.mul(I1.mul(I1)), sigma);
  const cv::Mat s22 = BruteBlur(M.mul(I2.mul(I2)), sigma);
  const cv::Mat s12 = BruteBlur(M.mul(I1.mul(I2)), sigma);
  ref.mu1 = s1 / ref.omega;
  ref.mu2 = s2 / ref.omega;
  ref.v1 = s11 / ref.omega - ref.mu1.mul(ref.mu1) + eps;
  ref.v2 = s22 / ref.omega - ref.mu2.mul(ref.mu2) + eps;
  ref.v12 = s12 / ref.omega - ref.mu1.mul(ref.mu2);
  cv::Mat s;
  cv::sqrt(ref.v1.mul(ref.v2), s);
  ref.m = ref.v12 / s;
  return ref;
}

TEST(SimilarityOptions, DefaultsAreValid) { EXPECT_TRUE(SimilarityOptions().Check()); }

TEST(SimilarityOptions, RejectsInvalid) {
  SimilarityOptions o;
  o.method = "ssd";
  EXPECT_THROW(o.Check(), InputError);
  o = SimilarityOptions();
  o.sigma = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = SimilarityOptions();
  o.epsilon = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = SimilarityOptions();
  o.kappa = -1;
  EXPECT_THROW(o.Check(), InputError);
  o = SimilarityOptions();
  o.min_support = 1;
  EXPECT_THROW(o.Check(), InputError);
  o = SimilarityOptions();
  o.epsilon = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(o.Check(), InputError);
  try {
    o = SimilarityOptions();
    o.kappa = -2;
    o.Check();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("kappa = -2"), std::string::npos) << e.what();
  }
}

TEST(Similarity, MatchesBruteForce) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 1), I2 = RandomImage(cols, rows, 2);
  const cv::Mat mask = TestMask(cols, rows);
  const SimilarityOptions o = DoubleOptions("zncc", 1.5, 0);
  const SimilarityResult res = ComputeSimilarity(I1, I2, mask, o);
  const Reference ref = BruteStatistics(I1, I2, mask, o.sigma, o.epsilon);
  double cost = 0, wsum = 0;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      if (mask.at<uchar>(r, c) == 0) {
        EXPECT_EQ(res.zncc.at<double>(r, c), 0.0);
        continue;
      }
      EXPECT_NEAR(res.zncc.at<double>(r, c), ref.m.at<double>(r, c), 1e-10) << r << " " << c;
      cost += 1 - ref.m.at<double>(r, c);
      wsum += 1;
    }
  EXPECT_NEAR(res.cost, cost, 1e-9);
  EXPECT_NEAR(res.weight_sum, wsum, 1e-12);
  EXPECT_NEAR(res.zncc_sum + res.cost, res.weight_sum, 1e-9);
}

TEST(Similarity, AffineInvariantAndMaximalForIdenticalImages) {
  const int cols = 40, rows = 32;
  const cv::Mat I1 = RandomImage(cols, rows, 3);
  const cv::Mat I2 = 0.5 * I1 + 0.2;
  SimilarityOptions o = DoubleOptions("zncc", 2.0, 0);
  o.epsilon = 1e-14;  // (almost) no regularisation: m = 1 exactly up to eps
  cv::Mat mask = TestMask(cols, rows);
  mask.at<uchar>(0, cols - 1) = 0;  // no isolated pixel (it has m = 0)
  const SimilarityResult res = ComputeSimilarity(I1, I2, mask, o);
  ASSERT_GT(res.weight_sum, 100);
  EXPECT_NEAR(res.MeanZncc(), 1.0, 1e-6);
  // At the maximum of m the derivative vanishes; compare with a generic pair.
  const SimilarityResult other = ComputeSimilarity(I1, RandomImage(cols, rows, 4), mask, o);
  double gmax = 0, gother = 0;
  cv::minMaxLoc(cv::abs(res.gradient), nullptr, &gmax);
  cv::minMaxLoc(cv::abs(other.gradient), nullptr, &gother);
  EXPECT_LT(gmax, 1e-4 * gother) << gmax << " vs " << gother;
}

// dC/dI2 against central differences of C, at every pixel.
void CheckGradientByFiniteDifferences(const cv::Mat& I1, const cv::Mat& I2, const cv::Mat& mask,
                                      const SimilarityOptions& o, double* max_rel_err) {
  const SimilarityResult res = ComputeSimilarity(I1, I2, mask, o);
  double gscale = 0;
  cv::minMaxLoc(cv::abs(res.gradient), nullptr, &gscale);
  ASSERT_GT(gscale, 0);
  const double h = 1e-6;
  *max_rel_err = 0;
  for (int r = 0; r < I2.rows; ++r)
    for (int c = 0; c < I2.cols; ++c) {
      cv::Mat plus = I2.clone(), minus = I2.clone();
      plus.at<double>(r, c) += h;
      minus.at<double>(r, c) -= h;
      const double fd = (ComputeSimilarity(I1, plus, mask, o, false).cost -
                         ComputeSimilarity(I1, minus, mask, o, false).cost) /
                        (2 * h);
      const double g = res.gradient.at<double>(r, c);
      // Relative error, with a floor of 1e-3 of the largest entry for
      // entries near zero.
      const double denom = std::max({std::abs(g), std::abs(fd), 1e-3 * gscale});
      const double err = std::abs(g - fd) / denom;
      *max_rel_err = std::max(*max_rel_err, err);
      EXPECT_LT(err, 1e-4) << "pixel (" << c << ", " << r << "): analytic " << g << " fd " << fd;
    }
}

TEST(Similarity, WindowLargerThanImage) {
  const int cols = 9, rows = 7;  // kernel 31x31 for sigma = 5
  const cv::Mat I1 = RandomImage(cols, rows, 34), I2 = RandomImage(cols, rows, 35);
  const cv::Mat mask = TestMask(cols, rows);
  const SimilarityOptions o = DoubleOptions("zncc", 5.0, 0);
  const SimilarityResult res = ComputeSimilarity(I1, I2, mask, o);
  const Reference ref = BruteStatistics(I1, I2, mask, o.sigma, o.epsilon);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      if (mask.at<uchar>(r, c) == 0) continue;
      EXPECT_NEAR(res.zncc.at<double>(r, c), ref.m.at<double>(r, c), 1e-10) << r << " " << c;
    }
  double err = 0;
  CheckGradientByFiniteDifferences(I1, I2, mask, o, &err);
}

TEST(Similarity, GradientMatchesFiniteDifferences) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 5), I2 = RandomImage(cols, rows, 6);
  const cv::Mat mask = TestMask(cols, rows);
  for (const double sigma : {1.0, 2.0}) {
    double err = 0;
    CheckGradientByFiniteDifferences(I1, I2, mask, DoubleOptions("zncc", sigma, 0), &err);
    std::printf("sigma %.1f: max relative error of dC/dI2 vs central differences: %.3g\n", sigma,
                err);
  }
}

TEST(Similarity, GradientMatchesFiniteDifferencesSoftMaskMinSupport) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 7), I2 = RandomImage(cols, rows, 8);
  cv::Mat soft;
  TestMask(cols, rows).convertTo(soft, CV_64F, 1.0 / 255);
  cv::GaussianBlur(soft, soft, cv::Size(0, 0), 1.0);
  cv::threshold(soft, soft, 0.2, 0, cv::THRESH_TOZERO);  // exact zeros outside
  SimilarityOptions o = DoubleOptions("zncc", 1.5, 0);
  o.min_support = 0.4;
  const SimilarityResult res = ComputeSimilarity(I1, I2, soft, o);
  double full = 0;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) full += soft.at<double>(r, c);
  EXPECT_LT(res.weight_sum, full - 0.5);  // min_support excluded some pixels
  double err = 0;
  CheckGradientByFiniteDifferences(I1, I2, soft, o, &err);
  std::printf("soft mask, min_support 0.4: max relative error: %.3g\n", err);
}

TEST(Similarity, ZeroGradientOutsideMask) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 9), I2 = RandomImage(cols, rows, 10);
  const cv::Mat mask = TestMask(cols, rows);
  for (const std::string method : {"zncc", "dcv"}) {
    const SimilarityResult res = ComputeSimilarity(I1, I2, mask, DoubleOptions(method, 2, 1));
    int nonzero_inside = 0;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        if (mask.at<uchar>(r, c) == 0) {
          EXPECT_EQ(res.gradient.at<double>(r, c), 0.0);
        } else if (res.gradient.at<double>(r, c) != 0) {
          ++nonzero_inside;
        }
      }
    EXPECT_GT(nonzero_inside, 300);
  }
}

TEST(Similarity, DcvWithZeroKappaEqualsZncc) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 11), I2 = RandomImage(cols, rows, 12);
  const cv::Mat mask = TestMask(cols, rows);
  for (const bool dbl : {false, true}) {
    SimilarityOptions z = DoubleOptions("zncc", 2, 0.7), d = DoubleOptions("dcv", 2, 0);
    z.double_precision = d.double_precision = dbl;
    cv::Mat i1, i2;
    I1.convertTo(i1, dbl ? CV_64F : CV_32F);
    I2.convertTo(i2, dbl ? CV_64F : CV_32F);
    const SimilarityResult a = ComputeSimilarity(i1, i2, mask, z);
    const SimilarityResult b = ComputeSimilarity(i1, i2, mask, d);
    EXPECT_EQ(a.cost, b.cost);
    EXPECT_EQ(cv::norm(a.gradient, b.gradient, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.zncc, b.zncc, cv::NORM_INF), 0.0);
  }
}

TEST(Similarity, DcvTermMatchesIndependentComputation) {
  const int cols = 24, rows = 20;
  const cv::Mat I1 = RandomImage(cols, rows, 13), I2 = RandomImage(cols, rows, 14);
  const cv::Mat mask = TestMask(cols, rows);
  const double kappa = 0.8, sigma = 1.5;
  const SimilarityResult z = ComputeSimilarity(I1, I2, mask, DoubleOptions("zncc", sigma, 0));
  const SimilarityResult d = ComputeSimilarity(I1, I2, mask, DoubleOptions("dcv", sigma, kappa));
  EXPECT_EQ(z.cost, d.cost);
  const Reference ref = BruteStatistics(I1, I2, mask, sigma, SimilarityOptions().epsilon);
  cv::Mat M;
  mask.convertTo(M, CV_64F, 1.0 / 255);
  const cv::Mat ratio = M.mul((ref.v2 - ref.v1) / ref.v2);
  const cv::Mat expected = kappa * M.mul(BruteBlur(ratio, sigma));
  const cv::Mat term = d.gradient - z.gradient;
  double emax = 0;
  cv::minMaxLoc(cv::abs(expected), nullptr, &emax);
  ASSERT_GT(emax, 0.1);
  EXPECT_LT(cv::norm(term, expected, cv::NORM_INF), 1e-10 * emax);
}

TEST(Similarity, DcvTermVanishesWhenVariancesAgree) {
  const int cols = 32, rows = 24;
  const cv::Mat I1 = RandomImage(cols, rows, 15);
  const cv::Mat mask = TestMask(cols, rows);
  const cv::Mat I2 = I1 + 0.15;  // a = 1: v2 = v1
  const SimilarityResult z = ComputeSimilarity(I1, I2, mask, DoubleOptions("zncc", 2, 0));
  const SimilarityResult d = ComputeSimilarity(I1, I2, mask, DoubleOptions("dcv", 2, 5.0));
  EXPECT_LT(cv::norm(d.gradient - z.gradient, cv::NORM_INF), 1e-10);
}

// The sign of the added term: where the predicted image has more local
// variance than the observed one (v2 > v1) the term is positive, so a descent
// step I2 -= step * gradient lowers I2 there; where v2 < v1 it is negative.
TEST(Similarity, DcvTermSignFollowsVarianceExcess) {
  const int cols = 32, rows = 24;
  const cv::Mat I1 = RandomImage(cols, rows, 16);
  const cv::Mat mask = TestMask(cols, rows);
  for (const double a : {2.0, 0.5}) {
    const cv::Mat I2 = a * (I1 - 0.5) + 0.5;  // v2 - eps = a^2 (v1 - eps)
    const SimilarityResult z = ComputeSimilarity(I1, I2, mask, DoubleOptions("zncc", 2, 0));
    const SimilarityResult d = ComputeSimilarity(I1, I2, mask, DoubleOptions("dcv", 2, 1.0));
    const cv::Mat term = d.gradient - z.gradient;
    int checked = 0;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) {
        if (mask.at<uchar>(r, c) == 0) continue;
        ++checked;
        if (a > 1) {
          EXPECT_GT(term.at<double>(r, c), 0) << c << " " << r;
        } else {
          EXPECT_LT(term.at<double>(r, c), 0) << c << " " << r;
        }
      }
    EXPECT_GT(checked, 300);
  }
}

// What the added term does NOT do: in image space it is close to a local
// brightness offset (a Gaussian-smoothed field), to which local variances are
// blind: a step I2 -= eta K changes v2 only through the local covariance of I2
// and K, with no definite sign. Compared with a step of the same amplitude
// (<= 0.1) along a direction that does target the variances, P(q) =
// (v2 - v1)(q) (I2(q) - mu2(q)), it changes the variance gap
// sum_p |v2 - v1| by far less (see docs/similarity.md).
TEST(Similarity, DcvTermIsNearlyABrightnessOffsetInImageSpace) {
  const int cols = 48, rows = 40;
  const cv::Mat I1 = RandomImage(cols, rows, 33);
  cv::Mat mask(rows, cols, CV_8U, cv::Scalar(0));
  cv::circle(mask, cv::Point(24, 20), 17, cv::Scalar(255), -1);
  cv::Mat M;
  mask.convertTo(M, CV_64F, 1.0 / 255);
  cv::Mat noise(rows, cols, CV_64F);
  cv::randn(noise, 0, 0.02);
  const double sigma = 2;
  auto gap = [&](const cv::Mat& I2) {
    const Reference ref = BruteStatistics(I1, I2, mask, sigma, 1e-4);
    double g = 0;
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        if (mask.at<uchar>(r, c)) g += std::abs(ref.v2.at<double>(r, c) - ref.v1.at<double>(r, c));
    return g;
  };
  for (const double a : {2.0, 0.5}) {
    const cv::Mat I2 = a * (I1 - 0.5) + 0.5 + noise;
    const SimilarityResult z = ComputeSimilarity(I1, I2, mask, DoubleOptions("zncc", sigma, 0));
    const SimilarityResult d = ComputeSimilarity(I1, I2, mask, DoubleOptions("dcv", sigma, 1.0));
    const cv::Mat K = d.gradient - z.gradient;
    const Reference ref = BruteStatistics(I1, I2, mask, sigma, 1e-4);
    const cv::Mat P = M.mul((ref.v2 - ref.v1).mul(I2 - ref.mu2));
    const double before = gap(I2);
    const double after_k = gap(I2 - 0.1 / cv::norm(K, cv::NORM_INF) * K);
    const double after_p = gap(I2 - 0.1 / cv::norm(P, cv::NORM_INF) * P);
    std::printf("a = %.1f: variance gap %.4f -> %.4f (kappa term), %.4f (variance direction)\n", a,
                before, after_k, after_p);
    EXPECT_LT(after_p, before);
    EXPECT_LT(std::abs(after_k - before), 0.1 * (before - after_p));
  }
}

TEST(Similarity, FloatMatchesDouble) {
  const int cols = 64, rows = 48;
  const cv::Mat I1 = RandomImage(cols, rows, 17), I2 = RandomImage(cols, rows, 18);
  cv::Mat mask = TestMask(cols, rows);
  cv::Mat f1, f2;
  I1.convertTo(f1, CV_32F);
  I2.convertTo(f2, CV_32F);
  SimilarityOptions o = DoubleOptions("dcv", 2, 0.5);
  const SimilarityResult d = ComputeSimilarity(f1, f2, mask, o);
  o.double_precision = false;
  const SimilarityResult f = ComputeSimilarity(f1, f2, mask, o);
  ASSERT_EQ(f.gradient.type(), CV_32F);
  EXPECT_NEAR(f.cost, d.cost, 1e-5 * d.weight_sum);
  cv::Mat fg;
  f.gradient.convertTo(fg, CV_64F);
  const double gscale = cv::norm(d.gradient, cv::NORM_INF);
  EXPECT_LT(cv::norm(fg, d.gradient, cv::NORM_INF), 1e-4 * gscale);
}

// The maps are filtered in row bands, one per thread, and the per-pixel
// loops share the rows: every map and sum must be the same bits as on one
// thread (which filters the whole image at once), for both precisions.
TEST(Similarity, SameBitsOnAnyNumberOfThreads) {
  const int cols = 203, rows = 157;  // bands of unequal height
  const cv::Mat I1 = RandomImage(cols, rows, 21), I2 = RandomImage(cols, rows, 22);
  const cv::Mat mask = TestMask(cols, rows);
  cv::Mat f1, f2;
  I1.convertTo(f1, CV_32F);
  I2.convertTo(f2, CV_32F);
  auto same_bits = [](const cv::Mat& a, const cv::Mat& b) {
    if (a.size() != b.size() || a.type() != b.type()) return false;
    for (int r = 0; r < a.rows; ++r) {
      if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
    }
    return true;
  };
  for (const bool double_precision : {true, false}) {
    SimilarityOptions o = DoubleOptions("dcv", 2, 0.5);
    o.double_precision = double_precision;
    o.min_support = 0.2;
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const SimilarityResult one = ComputeSimilarity(f1, f2, mask, o);
    omp_set_num_threads(5);
    const SimilarityResult five = ComputeSimilarity(f1, f2, mask, o);
    omp_set_num_threads(threads);
    EXPECT_EQ(one.cost, five.cost) << double_precision;
    EXPECT_EQ(one.zncc_sum, five.zncc_sum);
    EXPECT_EQ(one.weight_sum, five.weight_sum);
    EXPECT_TRUE(same_bits(one.zncc, five.zncc));
    EXPECT_TRUE(same_bits(one.gradient, five.gradient));
    EXPECT_TRUE(same_bits(one.variance_predicted, five.variance_predicted));
    EXPECT_GT(cv::norm(one.gradient, cv::NORM_INF), 0);
  }
}

TEST(Similarity, ColorIsSumOfChannels) {
  const int cols = 24, rows = 20;
  std::vector<cv::Mat> a{RandomImage(cols, rows, 19), RandomImage(cols, rows, 20),
                         RandomImage(cols, rows, 21)};
  std::vector<cv::Mat> b{RandomImage(cols, rows, 22), RandomImage(cols, rows, 23),
                         RandomImage(cols, rows, 24)};
  cv::Mat A, B;
  cv::merge(a, A);
  cv::merge(b, B);
  const cv::Mat mask = TestMask(cols, rows);
  const SimilarityOptions o = DoubleOptions("dcv", 1.5, 0.3);
  const SimilarityResult color = ComputeSimilarity(A, B, mask, o);
  ASSERT_EQ(color.gradient.channels(), 3);
  std::vector<cv::Mat> g;
  cv::split(color.gradient, g);
  double cost = 0;
  for (int k = 0; k < 3; ++k) {
    const SimilarityResult single = ComputeSimilarity(a[k], b[k], mask, o);
    cost += single.cost;
    EXPECT_LT(cv::norm(single.gradient, g[k], cv::NORM_INF), 1e-12);
  }
  EXPECT_NEAR(color.cost, cost, 1e-9);
}

TEST(Similarity, EmptyMask) {
  const cv::Mat I1 = RandomImage(16, 12, 25), I2 = RandomImage(16, 12, 26);
  const cv::Mat mask(12, 16, CV_8U, cv::Scalar(0));
  const SimilarityResult res = ComputeSimilarity(I1, I2, mask, DoubleOptions("dcv", 2, 1));
  EXPECT_EQ(res.cost, 0.0);
  EXPECT_EQ(res.weight_sum, 0.0);
  EXPECT_EQ(res.MeanZncc(), 0.0);
  EXPECT_EQ(cv::norm(res.gradient, cv::NORM_INF), 0.0);
}

TEST(Similarity, NoMaskMeansAllValid) {
  const cv::Mat I1 = RandomImage(16, 12, 27), I2 = RandomImage(16, 12, 28);
  const cv::Mat ones(12, 16, CV_8U, cv::Scalar(1));
  const SimilarityOptions o = DoubleOptions("dcv", 2, 1);
  const SimilarityResult a = ComputeSimilarity(I1, I2, cv::Mat(), o);
  const SimilarityResult b = ComputeSimilarity(I1, I2, ones, o);
  EXPECT_EQ(a.weight_sum, 16 * 12);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(cv::norm(a.gradient, b.gradient, cv::NORM_INF), 0.0);
}

TEST(Similarity, NonFinitePixelsAreInvalid) {
  const int cols = 24, rows = 20;
  cv::Mat I1 = RandomImage(cols, rows, 29), I2 = RandomImage(cols, rows, 30);
  cv::Mat mask = TestMask(cols, rows);
  // NaN outside the mask changes nothing; NaN inside acts as a mask hole.
  const SimilarityOptions o = DoubleOptions("dcv", 2, 1);
  const SimilarityResult ref = ComputeSimilarity(I1, I2, mask, o);
  cv::Mat I2nan = I2.clone();
  I2nan.at<double>(0, 0) = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(mask.at<uchar>(0, 0), 0);
  const SimilarityResult outside = ComputeSimilarity(I1, I2nan, mask, o);
  EXPECT_EQ(outside.cost, ref.cost);
  EXPECT_EQ(cv::norm(outside.gradient, ref.gradient, cv::NORM_INF), 0.0);
  const int r = rows / 2 + 5, c = cols / 2 - 4;
  ASSERT_NE(mask.at<uchar>(r, c), 0);
  I2nan.at<double>(r, c) = std::numeric_limits<double>::infinity();
  cv::Mat holed = mask.clone();
  holed.at<uchar>(r, c) = 0;
  const SimilarityResult inside = ComputeSimilarity(I1, I2nan, mask, o);
  const SimilarityResult expected = ComputeSimilarity(I1, I2, holed, o);
  EXPECT_EQ(inside.cost, expected.cost);
  EXPECT_TRUE(std::isfinite(inside.cost));
  cv::Mat g = inside.gradient.clone();
  EXPECT_EQ(cv::norm(g, expected.gradient, cv::NORM_INF), 0.0);
}

TEST(Similarity, Textureless) {
  // Constant images: v = eps, m = 0, finite everything.
  const cv::Mat I1(12, 16, CV_64F, cv::Scalar(0.3)), I2(12, 16, CV_64F, cv::Scalar(0.6));
  const SimilarityResult res = ComputeSimilarity(I1, I2, cv::Mat(), DoubleOptions("dcv", 2, 1));
  EXPECT_NEAR(res.MeanZncc(), 0.0, 1e-9);
  EXPECT_TRUE(cv::checkRange(res.gradient));
}

TEST(Similarity, MismatchedInputsThrow) {
  const cv::Mat I1 = RandomImage(16, 12, 31), I2 = RandomImage(15, 12, 32);
  EXPECT_THROW(ComputeSimilarity(I1, I2, cv::Mat(), SimilarityOptions()), InternalError);
  cv::Mat f;
  I1.convertTo(f, CV_32F);
  EXPECT_THROW(ComputeSimilarity(I1, f, cv::Mat(), SimilarityOptions()), InternalError);
  cv::Mat bad_mask(12, 16, CV_32F, cv::Scalar(2.0f));
  EXPECT_THROW(ComputeSimilarity(I1, I1, bad_mask, SimilarityOptions()), InternalError);
  SimilarityOptions o;
  o.method = "ncc";
  EXPECT_THROW(ComputeSimilarity(I1, I1, cv::Mat(), o), InputError);
}

}  // namespace
}  // namespace mr
