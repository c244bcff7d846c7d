#include "refine/pyramid.h"

#include <cmath>
#include <random>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "util/error.h"

namespace mr {
namespace {

// f(x, y) = a + b x + c y sampled at pixel centres (COLMAP coordinates).
cv::Mat Ramp(int cols, int rows, int type, double a, double b, double c) {
  cv::Mat img(rows, cols, type);
  for (int r = 0; r < rows; ++r)
    for (int col = 0; col < cols; ++col) {
      const double v = a + b * (col + 0.5) + c * (r + 0.5);
      if (type == CV_32F) {
        img.at<float>(r, col) = static_cast<float>(v);
      } else {
        img.at<double>(r, col) = v;
      }
    }
  return img;
}

TEST(ImagePyramidOptions, DefaultsAreValid) { EXPECT_TRUE(ImagePyramidOptions().Check()); }

TEST(ImagePyramidOptions, RejectsInvalid) {
  ImagePyramidOptions o;
  o.num_levels = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = ImagePyramidOptions();
  o.min_size = 0;
  EXPECT_THROW(o.Check(), InputError);
}

TEST(Pyramid, SizesMatchScaledView) {
  for (const int w : {1, 2, 5, 8, 33, 640}) {
    const cv::Mat img(7, w, CV_32F, cv::Scalar(0.5f));
    const cv::Mat half = DownsampleHalf(img);
    PinholeView view;
    view.width = w;
    view.height = 7;
    const PinholeView scaled = view.Scaled(0.5);
    EXPECT_EQ(half.cols, scaled.width) << w;
    EXPECT_EQ(half.rows, scaled.height);
    EXPECT_EQ(half.cols, PyramidLevelView(view, 1).width);
    EXPECT_EQ(half.rows, PyramidLevelView(view, 1).height);
    // A constant stays constant, borders included.
    for (int r = 0; r < half.rows; ++r)
      for (int c = 0; c < half.cols; ++c) EXPECT_NEAR(half.at<float>(r, c), 0.5f, 1e-6f);
  }
}

// A linear ramp sampled at the same continuous image point agrees across
// levels (x at level l is x / 2 at level l + 1), away from the mirrored border.
TEST(Pyramid, RampIsConsistentAcrossLevels) {
  for (const int type : {CV_32F, CV_64F}) {
    const cv::Mat img = Ramp(67, 50, type, 0.1, 0.01, -0.004);
    ImagePyramidOptions o;
    o.num_levels = 3;
    o.min_size = 4;
    const std::vector<cv::Mat> pyr = BuildImagePyramid(img, o);
    ASSERT_EQ(pyr.size(), 3u);
    EXPECT_EQ(pyr[1].cols, 34);
    EXPECT_EQ(pyr[2].cols, 17);
    const double tol = type == CV_32F ? 1e-5 : 1e-12;
    std::mt19937 rng(1);
    // Level 2 is exact for pixels whose support (+-12 level-0 pixels) is inside.
    std::uniform_real_distribution<double> ux(14, 67 - 14), uy(14, 50 - 14);
    for (int i = 0; i < 50; ++i) {
      const double x = ux(rng), y = uy(rng);
      const double f0 = SampleBilinear(pyr[0], x, y);
      EXPECT_NEAR(f0, 0.1 + 0.01 * x - 0.004 * y, tol);
      EXPECT_NEAR(SampleBilinear(pyr[1], x / 2, y / 2), f0, tol) << x << " " << y;
      EXPECT_NEAR(SampleBilinear(pyr[2], x / 4, y / 4), f0, tol) << x << " " << y;
    }
    // The centre of pixel (c, r) at level 1 is level-0 point (2c + 1, 2r + 1).
    EXPECT_NEAR(pyr[1].type() == CV_32F ? pyr[1].at<float>(10, 12) : pyr[1].at<double>(10, 12),
                0.1 + 0.01 * 25 - 0.004 * 21, tol);
  }
}

// cv::pyrDown's output pixel c is centred on input pixel 2c: a half-pixel
// shift against the exact 0.5 scaling. Our levels do not have it.
TEST(Pyramid, DiffersFromPyrDownByHalfPixelShift) {
  const cv::Mat img = Ramp(64, 48, CV_64F, 0, 0.01, 0);
  const cv::Mat ours = DownsampleHalf(img);
  cv::Mat theirs;
  cv::pyrDown(img, theirs);
  EXPECT_NEAR(ours.at<double>(10, 10), 0.01 * 21, 1e-12);     // f at x = 2 * 10.5
  EXPECT_NEAR(theirs.at<double>(10, 10), 0.01 * 20.5, 1e-12);  // f at x = 2 * 10 + 0.5
}

TEST(Pyramid, StopsAtMinSize) {
  const cv::Mat img(40, 100, CV_32F, cv::Scalar(0));
  ImagePyramidOptions o;
  o.num_levels = 10;
  o.min_size = 8;
  const std::vector<cv::Mat> pyr = BuildImagePyramid(img, o);
  ASSERT_EQ(pyr.size(), 3u);  // 40 -> 20 -> 10 (-> 5 < 8)
  EXPECT_EQ(pyr[2].rows, 10);
  EXPECT_EQ(pyr[2].cols, 25);
}

TEST(Pyramid, ColorImage) {
  std::vector<cv::Mat> ch{Ramp(20, 16, CV_32F, 0.1, 0.01, 0), Ramp(20, 16, CV_32F, 0.2, 0, 0.01),
                          Ramp(20, 16, CV_32F, 0.3, 0.01, 0.01)};
  cv::Mat color;
  cv::merge(ch, color);
  const cv::Mat half = DownsampleHalf(color);
  ASSERT_EQ(half.type(), CV_32FC3);
  std::vector<cv::Mat> split;
  cv::split(half, split);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(cv::norm(split[k], DownsampleHalf(ch[k]), cv::NORM_INF), 0.0);
  }
}

TEST(Pyramid, LevelViewScalesProjectionExactly) {
  PinholeView view;
  view.width = 641;
  view.height = 481;
  view.fx = 700;
  view.fy = 710;
  view.cx = 320.3;
  view.cy = 240.7;
  const Eigen::Vector3d X(0.3, -0.2, 4.0);
  const Eigen::Vector2d p0 = view.Project(X);
  for (int level = 1; level <= 3; ++level) {
    const PinholeView v = PyramidLevelView(view, level);
    EXPECT_LT((v.Project(X) - p0 / std::pow(2.0, level)).norm(), 1e-12);
  }
  EXPECT_EQ(PyramidLevelView(view, 1).width, 321);
  EXPECT_EQ(PyramidLevelView(view, 2).height, 121);
  // For even sizes it agrees with Scaled(0.5).
  view.width = 640;
  view.height = 480;
  const PinholeView a = PyramidLevelView(view, 1), b = view.Scaled(0.5);
  EXPECT_EQ(a.width, b.width);
  EXPECT_DOUBLE_EQ(a.fx, b.fx);
  EXPECT_DOUBLE_EQ(a.cy, b.cy);
}

TEST(SampleBilinear, ExactAtPixelCentres) {
  cv::Mat img(5, 7, CV_64F);
  cv::randu(img, 0.0, 1.0);
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 7; ++c) {
      EXPECT_DOUBLE_EQ(SampleBilinear(img, c + 0.5, r + 0.5), img.at<double>(r, c));
    }
  cv::Mat u8(3, 3, CV_8U, cv::Scalar(0));
  u8.at<uchar>(1, 1) = 200;
  EXPECT_DOUBLE_EQ(SampleBilinear(u8, 1.5, 1.5), 200.0);
  EXPECT_DOUBLE_EQ(SampleBilinear(u8, 1.0, 1.5), 100.0);
}

// A random image in [0, 1), as CV_64F and as CV_32F.
std::pair<cv::Mat, cv::Mat> RandomImage(int rows, int cols) {
  cv::Mat img(rows, cols, CV_64F);
  cv::randu(img, 0.0, 1.0);
  cv::Mat f;
  img.convertTo(f, CV_32F);
  return {img, f};
}

TEST(SampleBilinear, GradientMatchesFiniteDifferences) {
  const auto [img, f] = RandomImage(9, 11);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ux(0.5, 10.5), uy(0.5, 8.5);
  const double h = 1e-6;
  int tested = 0;
  for (int i = 0; i < 200; ++i) {
    const double x = ux(rng), y = uy(rng);
    // Stay off the cell borders (the interpolant has kinks there).
    const double fx = x - 0.5 - std::floor(x - 0.5), fy = y - 0.5 - std::floor(y - 0.5);
    if (fx < 1e-3 || fx > 1 - 1e-3 || fy < 1e-3 || fy > 1 - 1e-3) continue;
    ++tested;
    for (const cv::Mat* m : {&img, &f}) {
      Eigen::Vector2d g;
      const double v = SampleBilinear(*m, x, y, &g);
      EXPECT_DOUBLE_EQ(v, SampleBilinear(*m, x, y));
      const double gx = (SampleBilinear(*m, x + h, y) - SampleBilinear(*m, x - h, y)) / (2 * h);
      const double gy = (SampleBilinear(*m, x, y + h) - SampleBilinear(*m, x, y - h)) / (2 * h);
      EXPECT_NEAR(g.x(), gx, 1e-6 * std::max(1.0, std::abs(gx)));
      EXPECT_NEAR(g.y(), gy, 1e-6 * std::max(1.0, std::abs(gy)));
    }
  }
  EXPECT_GT(tested, 150);
}

TEST(SampleBilinear, ImageBorder) {
  const cv::Mat img = Ramp(6, 4, CV_64F, 0.0, 1.0, 10.0);  // f = x + 10 y
  Eigen::Vector2d g;
  // Within the square of pixel centres: exact ramp and gradient.
  EXPECT_NEAR(SampleBilinear(img, 5.5, 3.5, &g), 5.5 + 35, 1e-12);
  EXPECT_NEAR(g.x(), 1.0, 1e-12);
  EXPECT_NEAR(g.y(), 10.0, 1e-12);
  EXPECT_NEAR(SampleBilinear(img, 0.5, 0.5, &g), 5.5, 1e-12);
  EXPECT_NEAR(g.x(), 1.0, 1e-12);  // on the border: one-sided, from inside
  EXPECT_NEAR(g.y(), 10.0, 1e-12);
  // Between the last pixel centre and the image edge: clamped to the centre.
  EXPECT_NEAR(SampleBilinear(img, 5.9, 2.0, &g), 5.5 + 20, 1e-12);
  EXPECT_EQ(g.x(), 0.0);
  EXPECT_NEAR(g.y(), 10.0, 1e-12);
  EXPECT_NEAR(SampleBilinear(img, 0.1, 2.0, &g), 0.5 + 20, 1e-12);
  EXPECT_EQ(g.x(), 0.0);
  // Far outside: the nearest border pixel.
  EXPECT_NEAR(SampleBilinear(img, -100, 100, &g), 0.5 + 35, 1e-12);
  EXPECT_EQ(g.norm(), 0.0);
  // Degenerate 1-pixel images.
  const cv::Mat one(1, 1, CV_32F, cv::Scalar(0.25f));
  EXPECT_EQ(SampleBilinear(one, 0.7, 0.2, &g), 0.25);
  EXPECT_EQ(g.norm(), 0.0);
  const cv::Mat row = Ramp(4, 1, CV_64F, 0.0, 1.0, 0.0);
  EXPECT_NEAR(SampleBilinear(row, 2.25, 0.5, &g), 2.25, 1e-12);
  EXPECT_NEAR(g.x(), 1.0, 1e-12);
}

TEST(SampleBilinear, RejectsMultiChannel) {
  const cv::Mat img(4, 4, CV_32FC3, cv::Scalar(0, 0, 0));
  EXPECT_THROW(SampleBilinear(img, 1, 1), InternalError);
}

TEST(SampleCubic, ExactAtPixelCentresAndOnQuadratics) {
  cv::Mat img(5, 7, CV_64F);
  cv::randu(img, 0.0, 1.0);
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 7; ++c) {
      EXPECT_NEAR(SampleCubic(img, c + 0.5, r + 0.5), img.at<double>(r, c), 1e-15);
    }
  // f = (x - 3)^2 - 2 x y + 0.5 y^2 at the pixel centres; the interpolant and
  // its gradient are exact wherever the 4x4 stencil is inside the image.
  auto f = [](double x, double y) { return (x - 3) * (x - 3) - 2 * x * y + 0.5 * y * y; };
  cv::Mat quad(8, 9, CV_64F);
  for (int r = 0; r < quad.rows; ++r)
    for (int c = 0; c < quad.cols; ++c) quad.at<double>(r, c) = f(c + 0.5, r + 0.5);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(1.5, 7.5), uy(1.5, 6.5);
  for (int i = 0; i < 100; ++i) {
    const double x = ux(rng), y = uy(rng);
    Eigen::Vector2d g;
    EXPECT_NEAR(SampleCubic(quad, x, y, &g), f(x, y), 1e-11) << x << " " << y;
    EXPECT_NEAR(g.x(), 2 * (x - 3) - 2 * y, 1e-11);
    EXPECT_NEAR(g.y(), -2 * x + y, 1e-11);
  }
}

TEST(SampleCubic, GradientMatchesFiniteDifferencesAndIsContinuous) {
  const auto [img, f] = RandomImage(9, 11);
  cv::Mat u8_image;
  img.convertTo(u8_image, CV_8U, 255.0);
  const cv::Mat& u8 = u8_image;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> ux(0.5, 10.5), uy(0.5, 8.5);
  const double h = 1e-6;
  for (int i = 0; i < 200; ++i) {
    const double x = ux(rng), y = uy(rng);
    for (const cv::Mat* m : {&img, &f, &u8}) {
      Eigen::Vector2d g;
      const double v = SampleCubic(*m, x, y, &g);
      EXPECT_DOUBLE_EQ(v, SampleCubic(*m, x, y));
      const double gx = (SampleCubic(*m, x + h, y) - SampleCubic(*m, x - h, y)) / (2 * h);
      const double gy = (SampleCubic(*m, x, y + h) - SampleCubic(*m, x, y - h)) / (2 * h);
      const double scale = m == &u8 ? 255.0 : 1.0;
      EXPECT_NEAR(g.x(), gx, 1e-5 * scale);
      EXPECT_NEAR(g.y(), gy, 1e-5 * scale);
    }
  }
  // Across a cell border the gradient has no jump (the bilinear one does).
  for (int c = 1; c < 10; ++c) {
    Eigen::Vector2d left, right, bl, br;
    SampleCubic(img, c + 0.5 - 1e-9, 4.3, &left);
    SampleCubic(img, c + 0.5 + 1e-9, 4.3, &right);
    EXPECT_NEAR(left.x(), right.x(), 1e-6) << c;
    SampleBilinear(img, c + 0.5 - 1e-9, 4.3, &bl);
    SampleBilinear(img, c + 0.5 + 1e-9, 4.3, &br);
    EXPECT_GT(std::abs(bl.x() - br.x()), 1e-3) << c;  // the test can tell a jump
  }
}

TEST(SampleCubic, KeepsFineTextureThatBilinearBlurs) {
  // A cosine of period 3 pixels along x, sampled half way between pixel
  // centres. The interpolants' gains there are those of their taps at that
  // frequency (w = 2 pi / 3): bilinear (1/2, 1/2): cos(w / 2) = 0.5; cubic
  // (-1/16, 9/16, 9/16, -1/16): 9/8 cos(w / 2) - 1/8 cos(3 w / 2) = 0.6875.
  const double period = 3.0;
  cv::Mat img(4, 40, CV_64F);
  for (int c = 0; c < img.cols; ++c) img.col(c).setTo(std::cos(2 * M_PI * (c + 0.5) / period));
  double cubic = 0, bilinear = 0, truth = 0;
  for (int c = 5; c < 35; ++c) {
    const double x = c + 1.0;  // half way between the centres c + 0.5 and c + 1.5
    const double t = std::cos(2 * M_PI * x / period);
    truth += t * t;
    cubic += SampleCubic(img, x, 2.0) * t;
    bilinear += SampleBilinear(img, x, 2.0) * t;
  }
  EXPECT_NEAR(bilinear / truth, 0.5, 1e-9);
  EXPECT_NEAR(cubic / truth, 0.6875, 1e-9);
}

TEST(SampleCubic, ImageBorder) {
  const cv::Mat img = Ramp(6, 4, CV_64F, 0.0, 1.0, 10.0);  // f = x + 10 y
  Eigen::Vector2d g;
  // Between the last pixel centre and the image edge: clamped to the centre,
  // no gradient across the border; the replicated stencil bends the ramp
  // only in the outermost cells.
  EXPECT_NEAR(SampleCubic(img, 5.9, 2.0, &g), 5.5 + 20, 1e-12);
  EXPECT_EQ(g.x(), 0.0);
  EXPECT_NEAR(g.y(), 10.0, 1e-12);
  EXPECT_NEAR(SampleCubic(img, -100, 100, &g), 0.5 + 35, 1e-12);
  EXPECT_EQ(g.norm(), 0.0);
  EXPECT_NEAR(SampleCubic(img, 3.2, 2.0), 3.2 + 20, 1e-12);
  const cv::Mat one(1, 1, CV_32F, cv::Scalar(0.25f));
  EXPECT_EQ(SampleCubic(one, 0.7, 0.2, &g), 0.25);
  EXPECT_EQ(g.norm(), 0.0);
  const cv::Mat multi(4, 4, CV_32FC3, cv::Scalar(0, 0, 0));
  EXPECT_THROW(SampleCubic(multi, 1, 1), InternalError);
}

TEST(SampleCubicBlurred, IsTheMeanOfFourCubicSamples) {
  const auto [img, f] = RandomImage(12, 15);
  std::mt19937 rng(5);
  // Points across the whole image and beyond its border, where some of the
  // four points are clamped and others not.
  std::uniform_real_distribution<double> ux(-1.0, 16.0), uy(-1.0, 13.0), us(0.0, 3.0);
  for (int i = 0; i < 300; ++i) {
    const double x = ux(rng), y = uy(rng), sigma = i % 10 == 0 ? 0.0 : us(rng);
    for (const cv::Mat* m : {&img, &f}) {
      double mean = 0;
      Eigen::Vector2d mean_grad = Eigen::Vector2d::Zero(), g;
      for (const double dy : {-sigma, sigma}) {
        for (const double dx : {-sigma, sigma}) {
          mean += 0.25 * SampleCubic(*m, x + dx, y + dy, &g);
          mean_grad += 0.25 * g;
        }
      }
      Eigen::Vector2d grad;
      EXPECT_NEAR(SampleCubicBlurred(*m, x, y, sigma, &grad), mean, 1e-12) << x << " " << y;
      EXPECT_NEAR(grad.x(), mean_grad.x(), 1e-12) << x << " " << y << " " << sigma;
      EXPECT_NEAR(grad.y(), mean_grad.y(), 1e-12) << x << " " << y << " " << sigma;
    }
  }
  EXPECT_THROW(SampleCubicBlurred(img, 3, 3, 3.5), InternalError);
}

}  // namespace
}  // namespace mr
