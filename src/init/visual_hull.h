#pragma once

// Visual hull of silhouettes by carving a regular grid, with a closed,
// outward-oriented surface extracted at sub-voxel accuracy.
//
// At every grid node X the field is
//   h(X) = min over the views that see X of  s_v(x_v(X)) * z_v(X) / f_v,
// where x_v(X) is the projection of X into view v, s_v the signed distance in
// pixels to the silhouette boundary of mask v (positive inside, bilinearly
// interpolated), z_v the depth and f_v the mean focal length (so the distance
// is roughly converted to scene units). A view "sees" X if X is in front of
// it and projects into its image; views that do not see X do not carve it
// (the object may leave the field of view). Nodes seen by fewer than
// `min_views` views are outside. The hull is {h > 0}; its surface h = 0 is
// extracted by marching tetrahedra (init/isosurface.h) and only the largest
// connected component is kept.

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "geometry/view.h"

namespace mr {

struct VisualHullOptions {
  // Grid cells along the longest side of the (padded) bounding box, in
  // [4, 2048]. The cost is O(resolution^3 * views); grids of more than 2^29
  // nodes (2 GiB) are refused.
  int resolution = 128;
  // Padding added to every side of the bounding box, as a fraction of its
  // longest side (>= 0). Middlebury's boxes are tight, and the silhouettes
  // are dilated.
  double padding = 0.05;
  // A node must project into at least this many images to be inside (>= 1).
  int min_views = 3;
  // If > 0, the resolution is adjusted once (from a first extraction at
  // `resolution`) so that the surface has about this many faces (+-30%).
  int target_faces = 0;
  bool Check() const;
};

struct VisualHullSummary {
  Eigen::AlignedBox3d bbox;  // the padded box carved
  int nx = 0, ny = 0, nz = 0;  // grid nodes per axis
  double voxel_size = 0;     // grid spacing, scene units
  long inside_nodes = 0;     // nodes with h > 0
  int num_components = 0;    // surface components before keeping the largest
  int num_vertices = 0;
  int num_faces = 0;
  double volume = 0;         // enclosed volume, scene units^3
  double carve_seconds = 0;    // filling the grid (last attempt)
  double extract_seconds = 0;  // marching tetrahedra + components (last attempt)
  double seconds = 0;          // total, including distance transforms
  std::string BriefReport() const;
};

// Computes the visual hull of `masks` (8-bit, nonzero = foreground; each the
// size of its view) inside `bbox`. Throws InputError if the sizes disagree,
// if there are no views, or if the hull is empty (all nodes carved).
VisualHullSummary ComputeVisualHull(const std::vector<PinholeView>& views,
                                    const std::vector<cv::Mat>& masks,
                                    const Eigen::AlignedBox3d& bbox,
                                    const VisualHullOptions& options, Eigen::MatrixXd* V,
                                    Eigen::MatrixXi* F);

// The bounding box of the region seen by all `views` (in front of each and
// inside its image), found by sampling around the point closest to all
// optical axes. Throws InputError if the views share no region.
Eigen::AlignedBox3d FrustumIntersectionBox(const std::vector<PinholeView>& views);

}  // namespace mr
