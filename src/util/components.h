#pragma once

// Connected components of a binary mask, chosen by whether they touch the
// image border and by their area: the holes of a silhouette (src/init) and
// the background regions of a background mask (src/refine).

#include <functional>
#include <vector>

#include <opencv2/core.hpp>

namespace mr {

// Labels the connected components of the non-zero pixels of `binary`
// (CV_8U; `connectivity` 4 or 8) into `labels` (CV_32S, 0 on zero pixels)
// and returns, per label, whether `keep(touches_border, area_px)` holds for
// that component. `keep` is called once per component, in label order;
// label 0 is never kept.
std::vector<uchar> SelectComponents(const cv::Mat& binary, int connectivity,
                                    const std::function<bool(bool, int)>& keep, cv::Mat* labels);

}  // namespace mr
