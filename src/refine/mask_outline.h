#pragma once

// Masks whose outline is not where the object's edge is. Masks made for a
// visual hull are grown on purpose, so that no view cuts the object (the
// Middlebury recipe of middlebury_to_colmap: threshold, dilate 10 px, erode
// 7 px, about 3 px larger than the object); masks from a segmentation tool
// are often a few pixels loose or tight. The silhouette term (silhouette.h)
// pulls the rendered outline onto the mask's, so such a mask moves the whole
// outline of the surface by its error: on templeSparseRing the recipe's masks
// gave a held-out ZNCC of 0.449 against 0.514 with the same threshold closed
// without growing (docs/results.md).
//
// Where the object meets its background the image has an edge, and a mask
// that follows the object has that edge on its outline. The mean image
// gradient magnitude over the pixels at each signed distance from the masks'
// outlines (a profile across the outline, pooled over views) peaks where the
// edge lies; a peak that stands clearly away from the outline says by how
// much the masks are off, and they are moved by that much.

#include <string>

#include <opencv2/core.hpp>

#include "refine/view_source.h"

namespace mr {

struct MaskOutlineOptions {
  // Half-width of the band across the outline the profile covers, in pixels
  // (> 1): the largest offset that can be found.
  double band_px = 8;
  // The masks are moved when the edge lies at least this far from their
  // outline (pixels, >= 0). Exact masks measure within half a pixel (the
  // corpus's: docs/results.md), and a pixel of error in the other direction
  // costs much on them (the silhouette tolerance experiment there).
  double min_offset_px = 1.5;
  // The edge is clear when its peak is at least this many times the
  // profile's value on the outline (> 1): a mask that follows the object
  // has its peak there, so a ratio near 1 means no offset can be told.
  double min_peak_ratio = 1.5;
  // Views measured, evenly spaced (>= 1).
  int max_images = 16;

  bool Check() const;
};

struct MaskOutlineReport {
  int views_measured = 0;
  // Where the profile peaks (sub-pixel, positive: inside the masks, so the
  // masks are too large) and how far above the outline's value.
  double edge_offset_px = 0;
  double peak_ratio = 0;
  // Whether the masks are to be moved by edge_offset_px.
  bool move = false;

  // Where the edge lies (for any use of the masks), and BriefReport with
  // what the refiner does about it.
  std::string Measured() const;
  std::string BriefReport() const;
};

// Measures where the images' edges lie relative to the masks' outlines, over
// the views that have a mask among up to options.max_images evenly spaced
// ones (EvenlySpacedViews).
MaskOutlineReport MeasureMaskOutline(const ViewSource& source, const MaskOutlineOptions& options);

// `mask` (CV_8U, nonzero = inside) with its outline moved inwards by
// `offset_px` (outwards when negative): the pixels whose signed distance to
// the outline exceeds the offset. Returns 255 / 0.
cv::Mat MoveMaskOutline(const cv::Mat& mask, double offset_px);

// `base` with every mask's outline moved inwards by `offset_px`
// (MoveMaskOutline). `base` must outlive this.
class MovedMaskViewSource : public DerivedViewSource {
 public:
  MovedMaskViewSource(const ViewSource& base, double offset_px)
      : DerivedViewSource(base), offset_px_(offset_px) {}
  cv::Mat LoadMask(int i) const override;

 private:
  double offset_px_;
};

}  // namespace mr
