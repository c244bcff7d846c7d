#include "refine/view_source.h"

#include <opencv2/imgproc.hpp>

#include "refine/pyramid.h"
#include "util/error.h"

namespace mr {

std::vector<PinholeView> ViewSource::Views() const {
  std::vector<PinholeView> views;
  for (int i = 0; i < NumViews(); ++i) views.push_back(View(i));
  return views;
}

WorkspaceViewSource::WorkspaceViewSource(const Workspace& workspace,
                                         const std::set<std::string>& excluded)
    : workspace_(workspace) {
  for (uint32_t id : workspace.image_ids) {
    const Image& image = workspace.model.images.at(id);
    if (excluded.count(image.name)) continue;
    ids_.push_back(id);
    views_.push_back(ViewFromColmap(workspace.model.cameras.at(image.camera_id), image));
  }
}

std::string WorkspaceViewSource::Name(int i) const {
  return workspace_.model.images.at(ids_.at(i)).name;
}

cv::Mat WorkspaceViewSource::LoadGray(int i) const {
  cv::Mat gray = workspace_.ReadImage(ids_.at(i), /*grayscale=*/true);
  cv::Mat out;
  gray.convertTo(out, CV_32F, gray.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
  return out;
}

cv::Mat WorkspaceViewSource::LoadColor(int i) const {
  return workspace_.ReadImage(ids_.at(i), /*grayscale=*/false);
}

cv::Mat WorkspaceViewSource::LoadMask(int i) const { return workspace_.ReadMask(ids_.at(i)); }

void InMemoryViewSource::Add(const std::string& name, const PinholeView& view, const cv::Mat& gray,
                             const cv::Mat& mask) {
  MR_CHECK(gray.type() == CV_32F && gray.cols == view.width && gray.rows == view.height);
  names_.push_back(name);
  views_.push_back(view);
  grays_.push_back(gray);
  masks_.push_back(mask);
}

cv::Mat InMemoryViewSource::LoadColor(int i) const {
  cv::Mat u8, bgr;
  grays_.at(i).convertTo(u8, CV_8U, 255.0);
  cv::cvtColor(u8, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

bool InMemoryViewSource::HasMasks() const {
  for (const auto& m : masks_) {
    if (!m.empty()) return true;
  }
  return false;
}

ImageCache::ImageCache(const ViewSource& source, size_t max_bytes)
    : source_(source), max_bytes_(max_bytes) {}

cv::Mat ImageCache::Gray(int i, int level) { return Get(0, i, level); }
cv::Mat ImageCache::Mask(int i, int level) { return Get(1, i, level); }

cv::Mat ImageCache::Get(int kind, int i, int level) {
  const Key key{kind, i, level};
  auto it = index_.find(key);
  if (it != index_.end()) {
    entries_.splice(entries_.begin(), entries_, it->second);
    return entries_.front().second;
  }
  cv::Mat image;
  if (level == 0) {
    image = kind == 0 ? source_.LoadGray(i) : source_.LoadMask(i);
  } else {
    const cv::Mat finer = Get(kind, i, level - 1);
    if (!finer.empty()) {
      if (kind == 0) {
        image = DownsampleHalf(finer);
      } else {
        // A mask pixel stays foreground if any of its 2x2 parents is.
        cv::Mat f, d;
        finer.convertTo(f, CV_32F);
        // Pad odd sizes by one replicated row/column so that level sizes are
        // (n + 1) / 2, as for the images.
        cv::copyMakeBorder(f, f, 0, finer.rows % 2, 0, finer.cols % 2, cv::BORDER_REPLICATE);
        cv::resize(f, d, cv::Size(f.cols / 2, f.rows / 2), 0, 0, cv::INTER_AREA);
        image = d > 0;
      }
    }
  }
  const size_t bytes = image.total() * image.elemSize();
  entries_.emplace_front(key, image);
  index_[key] = entries_.begin();
  bytes_ += bytes;
  // Evict least recently used entries, never the one just added.
  while (bytes_ > max_bytes_ && entries_.size() > 1) {
    auto last = std::prev(entries_.end());
    bytes_ -= last->second.total() * last->second.elemSize();
    index_.erase(last->first);
    entries_.erase(last);
  }
  return entries_.front().second;
}

}  // namespace mr
