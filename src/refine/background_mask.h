#pragma once

// Masks made from a uniform background, for workspaces that come without
// masks. The silhouette term (silhouette.h) is what pulls a Poisson surface
// back to the object's outline where it lies over the background: on a
// uniform background both views of a pair see the same flat colour there, the
// ZNCC window has no variance and the data term no gradient. Where every
// image's border is one uniform colour, the background is that colour, and
// the object is what differs from it.
//
// Such a mask is wrong where a dark, unlit side of the object touches a dark
// background, and a silhouette term that trusts it carves that side away
// (accuracy90 3.8x the input on a stress case, docs/results.md). So it is
// trusted only as far as the input mesh and the other views allow:
// - a view whose mask and the input mesh's rendered coverage overlap by less
//   than `min_agreement` (intersection over union) gets no mask;
// - the mask moves the input's rendered outline by at most `max_offset` of
//   the image size;
// - a pixel it takes from the input's coverage is kept only when the other
//   views that see the mesh's point there see it, often enough
//   (`min_support`), on a pixel clearly unlike their background: a surface
//   bulging past the outline is seen against the object from other views; an
//   unlit side stays dark in every view.

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "refine/view_source.h"

namespace mr {

class Renderer;
struct RenderBuffers;

struct BackgroundMaskOptions {
  // Width in pixels of the image border band the background is estimated on
  // (>= 1).
  int border_px = 2;
  // The background is uniform when at least this share of the band lies
  // within the tolerance of its median colour, (0, 1].
  double min_border_share = 0.9;
  // Tolerance (8-bit levels, largest channel difference, on the 3x3 median of
  // the image): max(min_tolerance, tolerance_sigmas x the band's robust
  // spread), and the background is not uniform where the spread itself
  // exceeds max_spread.
  double min_tolerance = 6;
  double tolerance_sigmas = 4;
  double max_spread = 10;
  // Background-coloured regions that do not touch the border are holes the
  // background is seen through when they cover at least this share of the
  // image, and dark spots of the object otherwise, [0, 1]. 0: every one is a
  // hole; a dark spot taken so is a removal from the mesh's coverage like
  // any other, kept only near the outline and where other views confirm it
  // (below). At 0.002 the hole of rocker-arm's ring, about 400 px, was filled
  // and the silhouette term pulled the ring's inner surface shut
  // (docs/results.md).
  double min_hole_share = 0.0;
  // Object regions of fewer pixels are noise of the background (>= 0).
  int min_object_px = 16;
  // A view's mask is used when its intersection over union with the input
  // mesh's rendered coverage, both with their holes filled, is at least
  // this, [0, 1].
  double min_agreement = 0.85;
  // ... and when at least this share of its outline is clear: the object
  // pixels within 2 px of an outline pixel differ from the background by
  // witness_tolerances tolerances on average. Where the object's colours
  // come close to the background's (a grey texture on a grey backdrop) the
  // mask's outline follows the texture, not the object, [0, 1]. Views of the
  // corpus on black score 0.94-1.00, high-contrast textures on grey
  // 0.40-0.95; 0.8 was chosen over 0.95 by the worst case of the cases
  // without masks (docs/results.md).
  double min_clear_outline = 0.8;
  // ... and only within this share of the image's longest side of the input
  // mesh's rendered outline (4 px at 640): beyond, the mask is the rendered
  // input, so the silhouette term moves no outline further than that, [0, 1].
  double max_offset = 0.00625;
  // A pixel the mask takes from the mesh's coverage is kept only when, of
  // the other views with a uniform background that see the mesh's point
  // there, at least this share see it on a pixel that differs from their
  // background, [0, 1]; 0 keeps every pixel.
  double min_support = 0.3;
  // A view sees the point on the object when its pixel there differs from
  // its background by more than this many tolerances (>= 1): clearly, not
  // by noise.
  double witness_tolerances = 3;
  // Visibility in another view: the point's depth within this share of the
  // mesh's rendered depth there (> 0).
  double visibility_tolerance = 0.01;
  bool Check() const;
};

// The background colour of one image and how uniform it is.
struct BackgroundModel {
  bool uniform = false;
  cv::Vec3d color = {0, 0, 0};  // B, G, R (8-bit levels)
  double spread = 0;            // robust (MAD) spread of the band, largest channel
  double tolerance = 0;
  double border_share = 0;      // share of the band within the tolerance
};

// Estimates the background of an 8-bit BGR (or grey) image from its border.
BackgroundModel EstimateBackground(const cv::Mat& image, const BackgroundMaskOptions& options);

// The object mask (CV_8U, 255 = object) of `image` against `model`'s colour:
// pixels within the tolerance of it, connected to the border or in a
// large enough hole, are background; so are specks of fewer than
// min_object_px pixels, and the outline is drawn at half coverage: an
// outline pixel that differs from the background by less than half as much
// as the object beside it is background.
cv::Mat BackgroundMask(const cv::Mat& image, const BackgroundModel& model,
                       const BackgroundMaskOptions& options);

// The share of the outline of `mask` (its pixels with a 4-neighbour outside
// it) that is clear against `model` (min_clear_outline); 1 without outline.
double ClearOutlineShare(const cv::Mat& image, const cv::Mat& mask, const BackgroundModel& model,
                         const BackgroundMaskOptions& options);

// The pixels where `render` sees a face (CV_8U, 255) and the rest (0).
cv::Mat RenderedCoverage(const RenderBuffers& render);

// Intersection over union of two masks of one size (nonzero = inside); 1 if
// both are empty.
double MaskAgreement(const cv::Mat& a, const cv::Mat& b);

// `base` with masks made from the uniform background of the views
// MakeBackgroundMasks accepted; the other views have none. Every other query
// is `base`'s. `base` must outlive this.
class BackgroundMaskedViewSource : public DerivedViewSource {
 public:
  // `masks`: one PNG-encoded mask per view, or an empty vector for none.
  BackgroundMaskedViewSource(const ViewSource& base, std::vector<std::vector<uchar>> masks);
  cv::Mat LoadMask(int i) const override;
  bool HasMasks() const override { return num_masked_ > 0; }
  int NumMasked() const { return num_masked_; }

 private:
  std::vector<std::vector<uchar>> masks_;  // PNG, kept small in memory
  int num_masked_ = 0;
};

// `covered` (CV_8U, nonzero = inside) corrected by `mask` only within
// `max_offset_px` of the outline of `covered`: a pixel takes `mask`'s value
// where the two differ and it lies at most that far from the nearest pixel
// on the other side of `covered`'s outline; elsewhere `covered`'s. Returns
// 255 / 0.
cv::Mat LimitToOutlineBand(const cv::Mat& mask, const cv::Mat& covered, double max_offset_px);

struct BackgroundMaskReport {
  int num_views = 0;
  int num_uniform = 0;   // views whose border is one uniform colour
  int num_clear = 0;     // ... and whose mask's outline is clear
  int num_accepted = 0;  // ... and whose mask agrees with the mesh
  long num_removals = 0;   // pixels the masks would take from the mesh's coverage
  long num_confirmed = 0;  // ... that the other views confirm (min_support)
  std::vector<double> agreement;  // per view; -1 where the border is not uniform
  std::vector<double> clear_share;  // per view; -1 where the border is not uniform
  std::string BriefReport() const;
};

// For a source without masks: estimates each view's background, and keeps it
// for the views whose mask agrees with the mesh (V, F) rendered by
// `renderer` (its mesh is replaced). Returns the source with those masks.
std::unique_ptr<BackgroundMaskedViewSource> MakeBackgroundMasks(
    const ViewSource& source, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
    Renderer* renderer, const BackgroundMaskOptions& options, BackgroundMaskReport* report);

}  // namespace mr
