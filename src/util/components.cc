#include "util/components.h"

#include <opencv2/imgproc.hpp>

namespace mr {

std::vector<uchar> SelectComponents(const cv::Mat& binary, int connectivity,
                                    const std::function<bool(bool, int)>& keep, cv::Mat* labels) {
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(binary, *labels, stats, centroids, connectivity);
  std::vector<uchar> kept(n, 0);
  for (int k = 1; k < n; ++k) {
    const int x = stats.at<int>(k, cv::CC_STAT_LEFT), y = stats.at<int>(k, cv::CC_STAT_TOP);
    const int w = stats.at<int>(k, cv::CC_STAT_WIDTH), h = stats.at<int>(k, cv::CC_STAT_HEIGHT);
    const bool touches = x == 0 || y == 0 || x + w == binary.cols || y + h == binary.rows;
    kept[k] = keep(touches, stats.at<int>(k, cv::CC_STAT_AREA)) ? 1 : 0;
  }
  return kept;
}

}  // namespace mr
