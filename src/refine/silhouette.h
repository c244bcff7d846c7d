#pragma once

// The horizon (silhouette) term, used when masks exist. The paper's
// M_horiz (eq. evolution_eq_horiz) moves contour generators so that the
// rendered silhouette matches the observed one against a black background.
// We use its geometric form: a vertex on the occluding contour of view i
// is pulled along the image-plane component of its normal by s pixel
// footprints, s = (signed distance to the mask boundary) - (signed distance
// to the rendered outline) at its projection (pixels, positive inside):
// outward where the mask reaches beyond the rendered outline, inward where
// it stops short, and not at all where the two agree.

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "geometry/view.h"
#include "render/renderer.h"

namespace mr {

// Signed distance (pixels, > 0 inside) from image point (x, y) to the
// boundary of `mask` (CV_8U, inside where > 0): the distance between pixel
// centres to the nearest pixel on the other side, less half a pixel,
// interpolated bilinearly (pixel centres at half-integers). Searched up to
// `radius` pixels: further boundaries give a magnitude of radius + 0.5.
// (x, y) must lie at least half a pixel inside the image.
double SignedDistanceToMaskAt(const cv::Mat& mask, double x, double y, int radius);

// Adds, for each contour vertex of `view`, its desired displacement (world
// units) to `displacement` (#V by 3) and 1 to `count` (#V). `mask` is the
// view's observed silhouette (CV_8U, inside where > 0). Distances are capped
// at `max_px` pixels.
//
// With hull_margin_px >= 0, the same for every other vertex in front of the
// view that projects more than hull_margin_px pixels beyond the mask's edge:
// no point of the surface lies outside a silhouette (the visual hull), so
// such a vertex (an open border's flap, or what Poisson extrapolated where
// no image looked) is pulled across the image plane toward the nearest mask
// pixel, by its distance beyond the margin (at most max_px). The edge is
// half a pixel short of the nearest inside pixel's centre; since a mask
// pixel is inside when its centre is, a point of the surface itself can lie
// up to sqrt(2)/2 px beyond it. Vertices more than 32 px outside are left
// to the next iterations.
void AccumulateSilhouetteTerm(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                              const Eigen::MatrixXd& vertex_normals, const PinholeView& view,
                              const RenderBuffers& render, const cv::Mat& mask, double max_px,
                              double hull_margin_px, Eigen::MatrixXd* displacement,
                              Eigen::VectorXd* count);

}  // namespace mr
