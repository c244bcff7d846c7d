#pragma once

// Where the refiner gets its views and images. Images are loaded on demand
// and kept in a bounded cache, so memory does not grow with the number of
// views times pixels.

#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "colmap_io/workspace.h"
#include "geometry/view.h"

namespace mr {

class ViewSource {
 public:
  virtual ~ViewSource() = default;
  virtual int NumViews() const = 0;
  // The view at full resolution.
  virtual const PinholeView& View(int i) const = 0;
  virtual std::string Name(int i) const = 0;
  // Grayscale CV_32F in [0, 1] at full resolution.
  virtual cv::Mat LoadGray(int i) const = 0;
  // BGR CV_8UC3 at full resolution (for vertex colours).
  virtual cv::Mat LoadColor(int i) const = 0;
  // CV_8U mask (nonzero = object) at full resolution, or empty if none.
  virtual cv::Mat LoadMask(int i) const { return {}; }
  virtual bool HasMasks() const { return false; }
  // The camera (intrinsics) view i shares with others, e.g. COLMAP's
  // camera_id; by default every view has its own.
  virtual int CameraId(int i) const { return i; }

  std::vector<PinholeView> Views() const;
};

// The registered images of a COLMAP workspace, minus `excluded` names
// (held-out views).
class WorkspaceViewSource : public ViewSource {
 public:
  explicit WorkspaceViewSource(const Workspace& workspace,
                               const std::set<std::string>& excluded = {});
  int NumViews() const override { return static_cast<int>(ids_.size()); }
  const PinholeView& View(int i) const override { return views_.at(i); }
  std::string Name(int i) const override;
  cv::Mat LoadGray(int i) const override;
  cv::Mat LoadColor(int i) const override;
  cv::Mat LoadMask(int i) const override;
  bool HasMasks() const override { return !workspace_.mask_dir.empty(); }
  int CameraId(int i) const override;
  // The COLMAP image id of view i.
  uint32_t ImageId(int i) const { return ids_.at(i); }

  // The grey image LoadGray returns: by default the image as COLMAP reads it
  // in grey (OpenCV's luminance). SetGrayWeights(w) makes it the projection
  // of the colour on w instead (R, G, B weights; rescaled so that the RGB
  // cube maps onto [0, 1]); one linear map for every image keeps brightness
  // constancy. See PrincipalTextureColor.
  void SetGrayWeights(const Eigen::Vector3d& rgb_weights);

 private:
  const Workspace& workspace_;
  bool project_color_ = false;
  Eigen::Vector3d gray_weights_ = Eigen::Vector3d::Zero();
  std::vector<uint32_t> ids_;
  std::vector<PinholeView> views_;
};

// A view source made from another: every query goes to `base` unless the
// derived source overrides it. `base` must outlive this.
class DerivedViewSource : public ViewSource {
 public:
  explicit DerivedViewSource(const ViewSource& base) : base_(base) {}
  int NumViews() const override { return base_.NumViews(); }
  const PinholeView& View(int i) const override { return base_.View(i); }
  std::string Name(int i) const override { return base_.Name(i); }
  cv::Mat LoadGray(int i) const override { return base_.LoadGray(i); }
  cv::Mat LoadColor(int i) const override { return base_.LoadColor(i); }
  cv::Mat LoadMask(int i) const override { return base_.LoadMask(i); }
  bool HasMasks() const override { return base_.HasMasks(); }
  int CameraId(int i) const override { return base_.CameraId(i); }

 protected:
  const ViewSource& base_;
};

// `base` with every image whose longest side exceeds `max_image_size` pixels
// scaled down to that size (cv::INTER_AREA), and its camera with it, as
// COLMAP's max_image_size options do: the sizes round to whole pixels, and
// fx, cx scale by the width's ratio, fy, cy by the height's. Masks are
// scaled the same way and thresholded at half. Smaller images pass through
// unchanged; max_image_size <= 0 means no limit. `base` must outlive this.
class ResizedViewSource : public DerivedViewSource {
 public:
  ResizedViewSource(const ViewSource& base, int max_image_size);
  const PinholeView& View(int i) const override { return views_.at(i); }
  cv::Mat LoadGray(int i) const override;
  cv::Mat LoadColor(int i) const override;
  cv::Mat LoadMask(int i) const override;
  // Whether view i is scaled down.
  bool Resized(int i) const;

 private:
  cv::Mat Resize(int i, const cv::Mat& image) const;
  std::vector<PinholeView> views_;
};

// Up to `max_views` of views 0 .. num_views - 1, evenly spaced from view 0
// (all of them when there are no more than max_views; max_views >= 1).
std::vector<int> EvenlySpacedViews(int num_views, int max_views);

// The colour direction along which the images' texture varies most: the
// principal eigenvector of the RGB covariance of the images' high-pass part
// (colour minus its Gaussian blur of `sigma_px`, the scale a ZNCC window
// sees), over the masks' foreground where there are masks, from up to
// `max_images` evenly spaced views. Sign: non-negative sum. For grey images
// (R = G = B) it is (1, 1, 1) / sqrt(3); for a texture that varies in hue
// more than in brightness it follows the hue.
Eigen::Vector3d PrincipalTextureColor(const ViewSource& source, int max_images = 16,
                                      double sigma_px = 4.0);

// The grey images with every pixel outside the view's mask set to 0, as if
// the object had been shot against black, where the backdrop is not dark
// already (BackdropLevel at least kDarkBackdrop); views without a mask, views
// shot on a dark backdrop, and the colour images are left as they are. The
// masks are taken as exact: on a grey backdrop the outline blends the
// object with grey, which the other views do not show there; on black the
// blend is the object's own colour scaled by its coverage, and leaving it
// keeps the outline's anti-aliasing (docs/results.md).
class BlackOutsideMasksViewSource : public DerivedViewSource {
 public:
  explicit BlackOutsideMasksViewSource(const ViewSource& base);
  cv::Mat LoadGray(int i) const override;
  // Of the views loaded so far: how many were blackened, out of how many
  // with a mask, and their median backdrop level; "" if none had a mask.
  std::string Report() const;

 private:
  mutable std::mutex mutex_;
  mutable std::vector<double> levels_;  // BackdropLevel per view; NaN: not loaded or no mask
};

// The median grey level of the ring of pixels 3 to 6 px outside a mask
// (CV_32F image in [0, 1], CV_8U mask, nonzero = object): what the object
// stands against. -1 where the ring is empty (the mask covers the image).
double BackdropLevel(const cv::Mat& gray, const cv::Mat& mask);
// A backdrop darker than this (about 13 of 255 grey levels) counts as black.
constexpr double kDarkBackdrop = 0.05;

// Views and images held in memory (tests, synthetic scenes).
class InMemoryViewSource : public ViewSource {
 public:
  void Add(const std::string& name, const PinholeView& view, const cv::Mat& gray,
           const cv::Mat& mask = {});
  int NumViews() const override { return static_cast<int>(views_.size()); }
  const PinholeView& View(int i) const override { return views_.at(i); }
  std::string Name(int i) const override { return names_.at(i); }
  cv::Mat LoadGray(int i) const override { return grays_.at(i); }
  cv::Mat LoadColor(int i) const override;
  cv::Mat LoadMask(int i) const override { return masks_.at(i); }
  bool HasMasks() const override;

 private:
  std::vector<std::string> names_;
  std::vector<PinholeView> views_;
  std::vector<cv::Mat> grays_, masks_;
};

// A least-recently-used cache of per-view pyramid levels of a ViewSource,
// bounded in bytes.
class ImageCache {
 public:
  ImageCache(const ViewSource& source, size_t max_bytes);
  // Grayscale CV_32F image of view i at pyramid level `level` (0 = full).
  // The returned header shares data with the cache entry (cheap copy) and
  // stays valid after the entry is evicted.
  cv::Mat Gray(int i, int level);
  // Mask (CV_8U) of view i at `level`, or an empty Mat.
  cv::Mat Mask(int i, int level);

 private:
  cv::Mat Get(int kind, int i, int level);
  const ViewSource& source_;
  size_t max_bytes_;
  size_t bytes_ = 0;
  using Key = std::tuple<int, int, int>;  // kind, view, level
  std::list<std::pair<Key, cv::Mat>> entries_;  // most recent first
  std::map<Key, std::list<std::pair<Key, cv::Mat>>::iterator> index_;
};

}  // namespace mr
