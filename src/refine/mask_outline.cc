#include "refine/mask_outline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "util/error.h"
#include "util/mask_distance.h"

namespace mr {

bool MaskOutlineOptions::Check() const {
  if (!(band_px > 1) || !std::isfinite(band_px)) {
    MR_THROW_INPUT << "MaskOutlineOptions::band_px = " << band_px
                   << ". Violated constraint: band_px > 1";
  }
  if (!(min_offset_px >= 0) || !std::isfinite(min_offset_px)) {
    MR_THROW_INPUT << "MaskOutlineOptions::min_offset_px = " << min_offset_px
                   << ". Violated constraint: min_offset_px >= 0";
  }
  if (!(min_peak_ratio > 1) || !std::isfinite(min_peak_ratio)) {
    MR_THROW_INPUT << "MaskOutlineOptions::min_peak_ratio = " << min_peak_ratio
                   << ". Violated constraint: min_peak_ratio > 1";
  }
  if (max_images < 1) {
    MR_THROW_INPUT << "MaskOutlineOptions::max_images = " << max_images
                   << ". Violated constraint: max_images >= 1";
  }
  return true;
}

std::string MaskOutlineReport::Measured() const {
  std::ostringstream s;
  if (views_measured == 0) return "no view has a mask";
  if (peak_ratio == 0) return "no image edge near the masks' outlines";
  s.precision(3);
  s << "the image edge lies " << std::abs(edge_offset_px) << " px "
    << (edge_offset_px >= 0 ? "inside" : "outside") << " the masks' outline (" << views_measured
    << " views; ";
  if (std::isfinite(peak_ratio)) {
    s << "edge " << peak_ratio << "x the gradient on the outline)";
  } else {
    s << "no image gradient on the outline)";
  }
  return s.str();
}

std::string MaskOutlineReport::BriefReport() const {
  if (views_measured == 0 || peak_ratio == 0) return Measured();
  return Measured() + (move ? "; the masks are moved onto it" : "; the masks are used as given");
}

MaskOutlineReport MeasureMaskOutline(const ViewSource& source, const MaskOutlineOptions& options) {
  options.Check();
  MaskOutlineReport report;
  // The profile: mean gradient magnitude of the grey image over the pixels
  // at signed distance [k - band, k - band + 1) from the outline, k = 0 ..
  // bins - 1 (positive inside the masks).
  const int bins = 2 * static_cast<int>(std::ceil(options.band_px));
  const double band = bins / 2;
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  for (const int i : EvenlySpacedViews(source.NumViews(), options.max_images)) {
    const cv::Mat mask = source.LoadMask(i);
    if (mask.empty()) continue;
    const cv::Mat gray = source.LoadGray(i);
    MR_CHECK(gray.size() == mask.size()) << source.Name(i) << ": mask and image sizes differ";
    ++report.views_measured;
    cv::Mat gx, gy;
    cv::Sobel(gray, gx, CV_32F, 1, 0, 3, 1.0 / 8);
    cv::Sobel(gray, gy, CV_32F, 0, 1, 3, 1.0 / 8);
    const cv::Mat sdf = MaskSignedDistance(mask);
    // Not along the image border, where a mask that runs out of the image has
    // no outline and the derivatives are one-sided.
    for (int r = 2; r < mask.rows - 2; ++r) {
      const float* s = sdf.ptr<float>(r);
      const float* dx = gx.ptr<float>(r);
      const float* dy = gy.ptr<float>(r);
      for (int c = 2; c < mask.cols - 2; ++c) {
        const int k = static_cast<int>(std::floor(s[c] + band));
        if (k < 0 || k >= bins) continue;
        sum[k] += std::hypot(dx[c], dy[c]);
        count[k] += 1;
      }
    }
  }
  std::vector<double> p(bins, 0.0);
  for (int k = 0; k < bins; ++k) p[k] = count[k] > 0 ? sum[k] / count[k] : 0.0;
  const int b = static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
  // The value on the outline: the two bins either side of it.
  const double on_outline = 0.5 * (p[bins / 2 - 1] + p[bins / 2]);
  // A peak at the band's end lies beyond what the band can place.
  if (report.views_measured == 0 || !(p[b] > 0) || b == 0 || b == bins - 1) return report;
  // Parabola through the peak bin and its neighbours (bin centres k - band + 0.5).
  const double denominator = p[b - 1] - 2 * p[b] + p[b + 1];
  const double shift = denominator < 0 ? 0.5 * (p[b - 1] - p[b + 1]) / denominator : 0.0;
  report.edge_offset_px = b - band + 0.5 + shift;
  report.peak_ratio = on_outline > 0 ? p[b] / on_outline : std::numeric_limits<double>::infinity();
  report.move = std::abs(report.edge_offset_px) >= options.min_offset_px &&
                report.peak_ratio >= options.min_peak_ratio;
  return report;
}

cv::Mat MoveMaskOutline(const cv::Mat& mask, double offset_px) {
  MR_CHECK(mask.type() == CV_8UC1) << "8-bit single-channel mask expected";
  const cv::Mat sdf = MaskSignedDistance(mask);
  return sdf > offset_px;
}

cv::Mat MovedMaskViewSource::LoadMask(int i) const {
  const cv::Mat mask = base_.LoadMask(i);
  if (mask.empty() || offset_px_ == 0) return mask;
  return MoveMaskOutline(mask, offset_px_);
}

}  // namespace mr
