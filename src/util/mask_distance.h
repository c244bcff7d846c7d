#pragma once

// Distances to the outline of a binary mask, shared by the visual hull
// (src/init) and the background masks (src/refine).

#include <opencv2/core.hpp>

namespace mr {

// Signed distance in pixels to the boundary of a mask (positive inside, 0 on
// the boundary between a foreground and a background pixel), CV_32F: a
// pixel centre next to the boundary is at ±0.5, so |sdf| + 0.5 is the
// distance to the nearest pixel centre on the other side.
cv::Mat MaskSignedDistance(const cv::Mat& mask);

}  // namespace mr
