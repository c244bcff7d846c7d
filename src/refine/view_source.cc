#include "refine/view_source.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include <Eigen/Eigenvalues>
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

void WorkspaceViewSource::SetGrayWeights(const Eigen::Vector3d& rgb_weights) {
  MR_CHECK(rgb_weights.allFinite() && rgb_weights.norm() > 0) << "bad colour weights";
  gray_weights_ = rgb_weights;
  project_color_ = true;
}

cv::Mat WorkspaceViewSource::LoadGray(int i) const {
  if (project_color_) {
    const cv::Mat bgr = workspace_.ReadImage(ids_.at(i), /*grayscale=*/false);
    // Map the RGB cube onto [0, 1]: w . rgb ranges over [lo, hi].
    double lo = 0, hi = 0;
    for (int k = 0; k < 3; ++k) (gray_weights_(k) < 0 ? lo : hi) += gray_weights_(k);
    const double scale = 1.0 / ((hi - lo) * (bgr.depth() == CV_16U ? 65535.0 : 255.0));
    const cv::Matx13f m(static_cast<float>(gray_weights_(2) * scale),
                        static_cast<float>(gray_weights_(1) * scale),
                        static_cast<float>(gray_weights_(0) * scale));
    cv::Mat f, out;
    bgr.convertTo(f, CV_32F);
    cv::transform(f, out, m);
    out -= lo / (hi - lo);
    return out;
  }
  cv::Mat gray = workspace_.ReadImage(ids_.at(i), /*grayscale=*/true);
  cv::Mat out;
  gray.convertTo(out, CV_32F, gray.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
  return out;
}

cv::Mat WorkspaceViewSource::LoadColor(int i) const {
  return workspace_.ReadImage(ids_.at(i), /*grayscale=*/false);
}

cv::Mat WorkspaceViewSource::LoadMask(int i) const { return workspace_.ReadMask(ids_.at(i)); }

int WorkspaceViewSource::CameraId(int i) const {
  return static_cast<int>(workspace_.model.images.at(ids_.at(i)).camera_id);
}

std::vector<int> EvenlySpacedViews(int num_views, int max_views) {
  const int used = std::min(num_views, std::max(1, max_views));
  std::vector<int> views(std::max(0, used));
  for (int k = 0; k < used; ++k) views[k] = static_cast<int>(static_cast<long>(k) * num_views / used);
  return views;
}

Eigen::Vector3d PrincipalTextureColor(const ViewSource& source, int max_images,
                                      double sigma_px) {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double count = 0;
  for (const int i : EvenlySpacedViews(source.NumViews(), max_images)) {
    const cv::Mat bgr = source.LoadColor(i);
    cv::Mat f, blurred;
    bgr.convertTo(f, CV_32F, bgr.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
    cv::GaussianBlur(f, blurred, cv::Size(), sigma_px);
    const cv::Mat high = f - blurred;
    const cv::Mat mask = source.LoadMask(i);
    for (int r = 0; r < high.rows; ++r) {
      for (int c = 0; c < high.cols; ++c) {
        if (!mask.empty() && mask.at<uint8_t>(r, c) == 0) continue;
        const cv::Vec3f v = high.at<cv::Vec3f>(r, c);
        const Eigen::Vector3d rgb(v[2], v[1], v[0]);
        covariance += rgb * rgb.transpose();
        count += 1;
      }
    }
  }
  if (count == 0) return Eigen::Vector3d::Constant(1.0 / std::sqrt(3.0));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance / count);
  Eigen::Vector3d w = eigen.eigenvectors().col(2);  // largest eigenvalue last
  if (w.sum() < 0) w = -w;
  return w.normalized();
}

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

ResizedViewSource::ResizedViewSource(const ViewSource& base, int max_image_size)
    : DerivedViewSource(base) {
  for (int i = 0; i < base.NumViews(); ++i) {
    PinholeView view = base.View(i);
    const int longest = std::max(view.width, view.height);
    if (max_image_size > 0 && longest > max_image_size) {
      const double scale = static_cast<double>(max_image_size) / longest;
      const int width = std::max(1, static_cast<int>(std::lround(view.width * scale)));
      const int height = std::max(1, static_cast<int>(std::lround(view.height * scale)));
      view = view.Resized(width, height);
    }
    views_.push_back(view);
  }
}

bool ResizedViewSource::Resized(int i) const {
  return views_.at(i).width != base_.View(i).width || views_.at(i).height != base_.View(i).height;
}

cv::Mat ResizedViewSource::Resize(int i, const cv::Mat& image) const {
  if (image.empty() || !Resized(i)) return image;
  cv::Mat out;
  cv::resize(image, out, cv::Size(views_[i].width, views_[i].height), 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat ResizedViewSource::LoadGray(int i) const { return Resize(i, base_.LoadGray(i)); }

cv::Mat ResizedViewSource::LoadColor(int i) const { return Resize(i, base_.LoadColor(i)); }

cv::Mat ResizedViewSource::LoadMask(int i) const {
  const cv::Mat mask = base_.LoadMask(i);
  if (mask.empty() || !Resized(i)) return mask;
  cv::Mat binary;
  cv::threshold(Resize(i, mask), binary, 127, 255, cv::THRESH_BINARY);
  return binary;
}

double BackdropLevel(const cv::Mat& gray, const cv::Mat& mask) {
  MR_CHECK(gray.type() == CV_32F && mask.type() == CV_8U && gray.size() == mask.size());
  cv::Mat near, far;
  cv::dilate(mask, near, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  cv::dilate(mask, far, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(13, 13)));
  std::vector<float> ring;
  for (int r = 0; r < gray.rows; ++r) {
    const uint8_t* n = near.ptr<uint8_t>(r);
    const uint8_t* f = far.ptr<uint8_t>(r);
    const float* g = gray.ptr<float>(r);
    for (int c = 0; c < gray.cols; ++c) {
      if (f[c] != 0 && n[c] == 0) ring.push_back(g[c]);
    }
  }
  if (ring.empty()) return -1;
  std::nth_element(ring.begin(), ring.begin() + ring.size() / 2, ring.end());
  return ring[ring.size() / 2];
}

BlackOutsideMasksViewSource::BlackOutsideMasksViewSource(const ViewSource& base)
    : DerivedViewSource(base),
      levels_(base.NumViews(), std::numeric_limits<double>::quiet_NaN()) {}

cv::Mat BlackOutsideMasksViewSource::LoadGray(int i) const {
  cv::Mat gray = DerivedViewSource::LoadGray(i);
  const cv::Mat mask = LoadMask(i);
  if (mask.empty()) return gray;
  MR_CHECK(mask.size() == gray.size()) << Name(i) << ": mask " << mask.cols << "x" << mask.rows
                                       << ", image " << gray.cols << "x" << gray.rows;
  const double backdrop = BackdropLevel(gray, mask);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    levels_.at(i) = backdrop;
  }
  if (backdrop < kDarkBackdrop) return gray;  // already black (or nothing outside the mask)
  gray = gray.clone();
  gray.setTo(0, mask == 0);
  return gray;
}

std::string BlackOutsideMasksViewSource::Report() const {
  std::vector<double> levels;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const double level : levels_) {
      if (level >= 0) levels.push_back(level);
    }
  }
  if (levels.empty()) return "";
  const long blackened = std::count_if(levels.begin(), levels.end(),
                                       [](double level) { return level >= kDarkBackdrop; });
  std::nth_element(levels.begin(), levels.begin() + levels.size() / 2, levels.end());
  std::ostringstream out;
  out << "the backdrop outside the masks has a median grey level of " << std::fixed
      << std::setprecision(3) << levels[levels.size() / 2] << "; ";
  if (blackened == 0) {
    out << "dark in every view, the images are compared as they are";
  } else {
    out << "not dark in " << blackened << " of " << levels.size()
        << " views, compared as if shot against black (Refine.black_outside_masks)";
  }
  return out.str();
}

}  // namespace mr
