#pragma once

// Choice of neighbouring views for the reprojection error: for every view,
// the views that see the same part of the surface from a useful baseline.

#include <utility>
#include <vector>

#include <Eigen/Core>

#include "geometry/view.h"

namespace mr {

struct ViewSelectionOptions {
  // Neighbours per view (1..16). Pairs are used both ways.
  int num_neighbors = 3;
  // Preferred angle in degrees between the two viewing rays to a surface
  // point (0 < min < ideal < max < 90).
  double min_angle_deg = 3.0;
  double ideal_angle_deg = 20.0;
  double max_angle_deg = 60.0;
  // Minimum fraction (0..1) of the reference view's visible samples that the
  // neighbour must also see.
  double min_overlap = 0.1;
  bool Check() const;
};

// For each view i, its selected neighbours, best first. Scores use sampled
// mesh vertices that face both cameras and project inside both images
// (occlusion is not tested). Views with no acceptable neighbour get none.
std::vector<std::vector<int>> SelectNeighbors(const std::vector<PinholeView>& views,
                                              const Eigen::MatrixXd& V,
                                              const Eigen::MatrixXd& N,
                                              const ViewSelectionOptions& options);

// Unordered pairs {i, j} (i < j) from the neighbour lists, in an order
// that a small cache of per-view data (renders, images) serves well: the
// views are renumbered by Cuthill-McKee, so that neighbours get nearby
// numbers, and the pairs sorted by their later view, then their earlier
// one. An LRU cache holding more views than the renumbered pair graph's
// bandwidth then loads every view once per pass over the pairs
// (lexicographic order on a hemisphere of 100 views: 175 renders per pass).
std::vector<std::pair<int, int>> NeighborPairs(const std::vector<std::vector<int>>& neighbors);

// `pairs` split into `num_groups` (>= 1) groups, each in the pairs' order,
// such that every group covers as many views as it can: each pair goes to
// the group in which it covers the most views not yet covered there (ties to
// the smallest group), then a view missing from a group takes one of its
// pairs from a group where both views of that pair have another. On 100
// hemisphere views with 3 neighbours each, both halves cover every view.
// Two groups that still leave a view in two or more pairs out of one (sparse
// rings) are made instead by colouring the pairs in turn along Euler
// circuits of the pair graph, which covers every such view unless a
// component is an odd cycle (GroupsCoverEveryView tells).
std::vector<std::vector<std::pair<int, int>>> SplitPairsCoveringViews(
    const std::vector<std::pair<int, int>>& pairs, int num_groups);

// Whether each group of `groups` (as SplitPairsCoveringViews returns them)
// is not empty and holds a pair of every view that is in at least groups.size() of `pairs`
// (a view in fewer pairs cannot be in every group).
bool GroupsCoverEveryView(const std::vector<std::pair<int, int>>& pairs,
                          const std::vector<std::vector<std::pair<int, int>>>& groups);

// Median pixel footprint (world units per pixel) of the vertices V (with
// normals N) over the views that see them (facing the camera, inside the
// image), less, for each vertex, the views that see it more than 2^(3/4)
// times coarser than its sharpest pair (views from near and far: the far ones
// cannot resolve what the near pairs compare), the rest making the vertex's
// footprint at most an octave finer than the median of all; 0 if no view
// sees any vertex.
double MedianFootprint(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                       const Eigen::MatrixXd& N);

// The largest fraction of an image that the mesh (V, F) covers, over the
// views: the projected area of the faces in front of the camera, facing it
// and not wholly outside the image, over the image area, capped at 1.
// Occlusion is not resolved (the faces of a closed surface that face a
// camera cover its outline about once). 0 if no view sees a face.
double BestViewCoverage(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                        const Eigen::MatrixXi& F);

// The edge lengths a pyramid level remeshes the surface (V, F) to: `edge_px`
// pixel footprints where the footprint varies across the surface, as in a
// scene that recedes in depth (a table under an object, a street), not only
// for an object seen from around.
//
// A point's footprint is the median of depth / focal length over the views
// that see it (in front, facing it, inside the image; occlusion is not
// tested), less those more than 2^(3/4) times coarser than its sharpest
// pair (as MedianFootprint). The surface is divided into bands half an octave wide, centred on
// the footprint that the most area shares (the area-weighted median footprint
// in the half-octave window that holds the most area, f0: e.g. the object's,
// where a ground recedes behind it): the points within a factor 2^(1/4) of
// f0, those near sqrt(2) f0, 2 f0, and so on, over the bands between the 1st
// and the 99th percentile of the seen area (points beyond take the nearest);
// a point that no view sees takes the farthest. Band k gets edges of edge_px
// x f0 x 2^(k/2), at most 19 % off each point's own footprint. An object
// seen from around mostly lies within one band and gets one length, edge_px
// x m with m the whole mesh's median footprint (MedianFootprint), as the
// uniform remeshing always had. When the expected face count (area /
// (sqrt(3)/4 e^2) summed over the bands) exceeds `max_faces`, every length is
// scaled up alike to meet it.
class EdgeSizing {
 public:
  EdgeSizing(std::vector<PinholeView> views, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
             double edge_px, int max_faces);
  // Whether any view sees the surface (otherwise nothing else is set).
  bool visible() const { return median_footprint_ > 0; }
  double median_footprint() const { return median_footprint_; }
  // The edge in pixels of each band's footprint, after the face budget.
  double edge_px() const { return edge_px_; }
  // The lengths of the bands in use, shortest first (one when uniform).
  const std::vector<double>& band_edges() const { return band_edges_; }
  bool uniform() const { return band_edges_.size() == 1; }
  // The band of a point with unit normal n, as an index into band_edges().
  int BandOf(const Eigen::Vector3d& x, const Eigen::Vector3d& n) const;
  // Faces of an isotropic mesh with these lengths, at most max_faces.
  int expected_faces() const { return expected_faces_; }

 private:
  // The footprint at x (normal n), 0 where no view sees it.
  double Footprint(const Eigen::Vector3d& x, const Eigen::Vector3d& n) const;
  // (log2(footprint / median footprint) - anchor) / kBandWidth, rounded: the
  // band step, relative to the centre band.
  int BandStepOf(double footprint) const;
  // The index into band_edges() of a footprint (0: unseen, the farthest).
  int BandOfFootprint(double footprint) const;
  // Width of a band, in octaves (log2 of the footprint).
  static constexpr double kBandWidth = 0.5;
  std::vector<PinholeView> views_;
  double median_footprint_ = 0;
  double edge_px_ = 0;
  double anchor_ = 0;  // log2 of the bands' centre footprint over the median
  int min_step_ = 0;
  int max_step_ = 0;
  std::vector<double> band_edges_;
  int expected_faces_ = 0;
};

// EdgeSizing(...).expected_faces(): what remeshing for a pyramid level gives.
// 0 if no view sees the surface.
int RemeshedFaceCount(const std::vector<PinholeView>& views, const Eigen::MatrixXd& V,
                      const Eigen::MatrixXi& F, double edge_px, int max_faces);

}  // namespace mr
