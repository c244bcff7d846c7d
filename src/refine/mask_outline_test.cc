#include "refine/mask_outline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "util/error.h"

namespace mr {
namespace {

// Views of a textured, shaded ellipse (radii 70 x 50, drawn antialiased at
// 4x and averaged down, as a renderer or a camera would) on a dark, noisy
// background, each view's ellipse turned by another angle. `truth` gets the
// ellipse's pixels (centre inside).
InMemoryViewSource EllipseViews(int num_views, std::vector<cv::Mat>* truth,
                                double background_noise = 0.01) {
  InMemoryViewSource source;
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0, background_noise);
  const int width = 320, height = 240, scale = 4;
  for (int v = 0; v < num_views; ++v) {
    const double angle = 23.0 * v;
    cv::Mat big = cv::Mat::zeros(height * scale, width * scale, CV_8U);
    cv::ellipse(big, cv::Point(160 * scale, 120 * scale), cv::Size(70 * scale, 50 * scale), angle,
                0, 360, 255, cv::FILLED);
    cv::Mat coverage;
    cv::resize(big, coverage, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    cv::Mat gray(height, width, CV_32F);
    cv::Mat inside(height, width, CV_8U);
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const double object = 0.45 + 0.15 * std::sin(0.35 * c + 0.2 * r) + 0.1 * std::cos(0.5 * r);
        const double a = coverage.at<uchar>(r, c) / 255.0;
        gray.at<float>(r, c) =
            static_cast<float>(a * object + (1 - a) * (0.05 + gauss(rng)));
        inside.at<uchar>(r, c) = a >= 0.5 ? 255 : 0;
      }
    }
    truth->push_back(inside);
    PinholeView view;
    view.width = width;
    view.height = height;
    source.Add("view" + std::to_string(v), view, gray, inside);
  }
  return source;
}

// The same views with every mask replaced by `masks[i]`.
InMemoryViewSource WithMasks(const InMemoryViewSource& source, const std::vector<cv::Mat>& masks) {
  InMemoryViewSource out;
  for (int i = 0; i < source.NumViews(); ++i) {
    out.Add(source.Name(i), source.View(i), source.LoadGray(i), masks[i]);
  }
  return out;
}

cv::Mat Grown(const cv::Mat& mask, int px) {
  const cv::Mat disc =
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * std::abs(px) + 1, 2 * std::abs(px) + 1));
  cv::Mat out;
  if (px >= 0) {
    cv::dilate(mask, out, disc);
  } else {
    cv::erode(mask, out, disc);
  }
  return out;
}

double IntersectionOverUnion(const cv::Mat& a, const cv::Mat& b) {
  return static_cast<double>(cv::countNonZero((a > 0) & (b > 0))) /
         cv::countNonZero((a > 0) | (b > 0));
}

TEST(MaskOutlineTest, ExactMasksMeasureOnTheOutlineAndStay) {
  std::vector<cv::Mat> truth;
  const InMemoryViewSource source = EllipseViews(4, &truth);
  const MaskOutlineReport report = MeasureMaskOutline(source, MaskOutlineOptions());
  EXPECT_EQ(report.views_measured, 4);
  EXPECT_LT(std::abs(report.edge_offset_px), 0.5) << report.BriefReport();
  EXPECT_FALSE(report.move) << report.BriefReport();
}

TEST(MaskOutlineTest, GrownAndShrunkMasksAreMovedBackOntoTheEdge) {
  std::vector<cv::Mat> truth;
  const InMemoryViewSource source = EllipseViews(4, &truth);
  for (const int px : {3, 5, -2}) {
    std::vector<cv::Mat> masks;
    for (const cv::Mat& t : truth) masks.push_back(Grown(t, px));
    const InMemoryViewSource off = WithMasks(source, masks);
    const MaskOutlineReport report = MeasureMaskOutline(off, MaskOutlineOptions());
    EXPECT_NEAR(report.edge_offset_px, px, 0.5) << px << " px: " << report.BriefReport();
    EXPECT_TRUE(report.move) << px << " px: " << report.BriefReport();
    const MovedMaskViewSource moved(off, report.edge_offset_px);
    for (int i = 0; i < off.NumViews(); ++i) {
      const double before = IntersectionOverUnion(masks[i], truth[i]);
      const double after = IntersectionOverUnion(moved.LoadMask(i), truth[i]);
      EXPECT_GT(after, 0.985) << px << " px, view " << i << " (as given: " << before << ")";
      EXPECT_GT(after, before) << px << " px, view " << i;
    }
  }
}

TEST(MaskOutlineTest, NoEdgeNoMove) {
  // A uniform image: no edge anywhere, so nothing can say the masks are off.
  InMemoryViewSource flat;
  std::vector<cv::Mat> truth;
  const InMemoryViewSource source = EllipseViews(2, &truth);
  for (int i = 0; i < source.NumViews(); ++i) {
    flat.Add(source.Name(i), source.View(i), cv::Mat(240, 320, CV_32F, cv::Scalar(0.4)),
             Grown(truth[i], 4));
  }
  const MaskOutlineReport report = MeasureMaskOutline(flat, MaskOutlineOptions());
  EXPECT_FALSE(report.move) << report.BriefReport();
  // Views without masks are not measured.
  InMemoryViewSource unmasked;
  unmasked.Add("a", source.View(0), source.LoadGray(0));
  EXPECT_EQ(MeasureMaskOutline(unmasked, MaskOutlineOptions()).views_measured, 0);
  EXPECT_FALSE(MeasureMaskOutline(unmasked, MaskOutlineOptions()).move);
}

TEST(MaskOutlineTest, MoveMaskOutlineShiftsByWholePixels) {
  cv::Mat mask = cv::Mat::zeros(50, 60, CV_8U);
  mask(cv::Rect(10, 10, 30, 20)) = 255;
  EXPECT_EQ(cv::countNonZero(MoveMaskOutline(mask, 0) != mask), 0);
  EXPECT_EQ(cv::countNonZero(MoveMaskOutline(mask, 2) != (Grown(mask, -2) > 0)), 0);
  const cv::Mat out = MoveMaskOutline(mask, -2);
  EXPECT_EQ(cv::countNonZero(out(cv::Rect(8, 8, 34, 24))), 34 * 24 - 4);  // rounded corners
  EXPECT_EQ(cv::countNonZero(out), 34 * 24 - 4);
}

TEST(MaskOutlineTest, BadOptionsAreRejected) {
  MaskOutlineOptions options;
  options.band_px = 1;
  EXPECT_THROW(options.Check(), InputError);
  options = MaskOutlineOptions();
  options.min_offset_px = -1;
  EXPECT_THROW(options.Check(), InputError);
  options = MaskOutlineOptions();
  options.min_peak_ratio = 1;
  EXPECT_THROW(options.Check(), InputError);
  options = MaskOutlineOptions();
  options.max_images = 0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace mr
