#include "util/mask_distance.h"

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "util/error.h"

namespace mr {

cv::Mat MaskSignedDistance(const cv::Mat& mask) {
  MR_CHECK(mask.type() == CV_8UC1) << "8-bit single-channel mask expected";
  cv::Mat fg = mask != 0;
  cv::Mat bg = mask == 0;
  cv::Mat d_in, d_out;
  // Distance from each foreground pixel to the nearest background pixel, and
  // vice versa (pixel centres; the boundary is half a pixel from either).
  cv::distanceTransform(fg, d_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(bg, d_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat sdf(mask.size(), CV_32F);
  const float kFar = static_cast<float>(mask.rows + mask.cols);
  for (int r = 0; r < mask.rows; ++r) {
    const uchar* m = fg.ptr<uchar>(r);
    const float* a = d_in.ptr<float>(r);
    const float* b = d_out.ptr<float>(r);
    float* s = sdf.ptr<float>(r);
    for (int c = 0; c < mask.cols; ++c) {
      s[c] = m[c] ? std::min(a[c], kFar) - 0.5f : -(std::min(b[c], kFar) - 0.5f);
    }
  }
  return sdf;
}

}  // namespace mr
