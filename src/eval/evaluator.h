#pragma once

// Mesh accuracy against a ground-truth mesh, Middlebury-style, using exact
// point-to-triangle distances (CGAL AABB tree) on area-uniform samples.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geometry/view.h"

namespace mr {

struct EvaluationOptions {
  // Completeness threshold, in scene units (Middlebury: 1.25 mm).
  double threshold = 1.25;
  // Number of area-uniform sample points drawn on each mesh (> 0).
  int num_samples = 200000;
  // Seed of the sampler (results are deterministic for a given seed).
  int seed = 1;
  bool Check() const;
};

struct EvaluationResult {
  double accuracy90 = 0;     // 90th percentile of recon->GT distances
  double completeness = 0;   // % of GT samples within `threshold` of recon
  double chamfer = 0;        // mean(recon->GT) + mean(GT->recon), i.e. sum of both means
  // Mean angle between recon and closest-GT face normals as unoriented lines,
  // min(theta, 180 - theta): independent of either mesh's face winding.
  double normal_deg = 0;
  // The upper median and the nearest-rank 90th percentile of the same
  // angles: a refined surface's mean is often held up by a tail of wrong
  // features (fingers, filled concavities) while its bulk is right.
  double normal_deg_median = 0;
  double normal_deg_p90 = 0;
  double mean_accuracy = 0;  // mean recon->GT distance
  int faces = 0;             // faces of the evaluated mesh
  // With an observed-face mask: % of the ground truth's area observed (the
  // part all other figures are measured on); -1 without a mask.
  double observed_percent = -1;
  std::string ToJson() const;  // one line
};

// With `gt_observed` (one flag per ground-truth face), the figures cover only
// the observed part of the ground truth, as Middlebury's evaluation does:
// reconstruction samples whose closest ground-truth face is observed, and
// ground-truth samples on observed faces.
EvaluationResult EvaluateMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                              const Eigen::MatrixXd& gt_V, const Eigen::MatrixXi& gt_F,
                              const EvaluationOptions& options = {},
                              const std::vector<char>* gt_observed = nullptr);

// Exact closest points on a triangle mesh (CGAL AABB tree, built once).
// Thread-safe queries.
class ClosestPointQuery {
 public:
  ClosestPointQuery(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  ~ClosestPointQuery();
  // Distance from q to the mesh; *face (if given) gets the closest face.
  double Distance(const Eigen::Vector3d& q, int* face = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Mean and maximum distance from the vertices of (V, F) to the surface
// (V0, F0): how far a refinement moved the surface (meaningful across
// remeshing, unlike per-vertex displacements).
struct SurfaceDisplacement {
  double mean = 0;
  double max = 0;
};
SurfaceDisplacement MeasureSurfaceDisplacement(const Eigen::MatrixXd& V,
                                               const Eigen::MatrixXd& V0,
                                               const Eigen::MatrixXi& F0);

// Where a mesh is wrong: the distance from each vertex of a mesh to the
// ground truth (exact, as Distance), and whether its closest ground-truth face
// is observed (every vertex is, without a mask).
struct VertexErrors {
  Eigen::VectorXd distance;
  std::vector<char> observed;
  std::vector<int> closest_face;  // the ground-truth face closest to each vertex
};
VertexErrors MeasureVertexErrors(const Eigen::MatrixXd& V, const Eigen::MatrixXd& gt_V,
                                 const Eigen::MatrixXi& gt_F,
                                 const std::vector<char>* gt_observed = nullptr);

// Where a mesh is turned wrong: at each vertex of (V, F), the mean over the
// faces around it of the angle between the face's normal and the normal of
// the ground-truth face closest to the vertex (`errors.closest_face`, from
// MeasureVertexErrors on the same V and ground truth), as unoriented lines in
// degrees (normal_deg's measure, taken at the vertices). NaN at a vertex
// whose faces are all degenerate, or that is in no face.
Eigen::VectorXd MeasureVertexNormalErrors(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const Eigen::MatrixXd& gt_V, const Eigen::MatrixXi& gt_F,
                                          const VertexErrors& errors);

// An error map's colours (RGB) for per-vertex `values` (distances, angles):
// the viridis scale from dark blue (0) through green to yellow (`max_value`
// and beyond); vertices whose closest ground-truth face is not observed, and
// NaN values, are mid grey. max_value > 0.
Eigen::Matrix<uint8_t, Eigen::Dynamic, 3> ErrorColors(const Eigen::VectorXd& values,
                                                      const std::vector<char>& observed,
                                                      double max_value);

// Faces of (V, F) visible in at least `min_views` of `views`: the face's
// centroid lies in the image and is not occluded (depth test against an EGL
// render, which draws both sides of every face). Works for faces smaller than
// a pixel; independent of the faces' winding (no back-face culling).
std::vector<char> ObservedFaces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                const std::vector<PinholeView>& views, int min_views);

// An axis-aligned box of scene space, for a region of interest.
struct RegionBox {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero();
  Eigen::Vector3d hi = Eigen::Vector3d::Zero();
  // "x0 y0 z0 x1 y1 z1" (spaces or commas), x0 < x1, y0 < y1, z0 < z1;
  // throws InputError naming `text` otherwise.
  static RegionBox Parse(const std::string& text);
  bool Contains(const Eigen::Vector3d& x) const {
    return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
  }
};

// Clears the flag of every face of (V, F) whose centroid lies outside `box`
// (first flagging every face when `flags` is empty): the faces a region of
// interest keeps, e.g. as EvaluateMesh's `gt_observed`. Returns how many
// stay flagged.
long KeepFacesInBox(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const RegionBox& box,
                    std::vector<char>* flags);

}  // namespace mr
