#pragma once

// The data term of DCV for one ordered view pair (i, j): the predicted image
// Î_ij (image j warped into view i through the current mesh), its similarity
// to image i, and the derivative of that similarity with respect to the
// mesh vertices.
//
// Chain rule (the discrete form of the paper's eq. pf3-pf4). Pixel p of view
// i sees point x = C_i + d r_p (r_p the pixel ray, unit camera z) on face f
// with unit normal n and barycentric weights w. Moving vertex k of f by δ
// moves the plane of f at x by w_k δ, so the ray's hit point moves by
//   dx = r_p (n · w_k δ) / (n · r_p),
// and the predicted intensity Î(p) = I_j(π_j(x)) changes by
//   dÎ(p) = ∇I_j(π_j x)ᵀ Jπ_j(x) r_p (n · w_k δ) / (n · r_p).
// With g(p) = ∂C/∂Î(p) from the similarity measure (C = Σ_p (1 - m(p)), the
// reprojection error), the vertex gradient is
//   ∂C/∂X_k = Σ_p w_k(p) g(p) a(p) n(p),  a = ∇I_jᵀ Jπ_j r_p / (n · r_p).
// Pixels whose x is hidden in view j, falls outside image j, or is seen at a
// grazing angle are outside the valid domain π_i∘S_ij and contribute nothing.
//
// The depth d is recomputed in double precision from the face's plane, so the
// term is exact given the visible face of each pixel.
//
// Resolution matching (PairTermOptions::match_resolution). Pixel p of view i
// integrates the surface over its footprint, which covers s x s pixels of
// view j, s = sqrt|det ∂q/∂p| through the face's plane. A camera's pixel is
// a box of variance 1/12 pixel² per axis, so where s > 1 (view j sees the
// surface finer) image j is sharper than image i by a blur of variance
// (s² - 1) / 12 of its pixels, and where s < 1 image i is sharper by
// (1/s² - 1) / 12 of its own. The sharper side is blurred by that much:
// averaged over the four points at ±σ along each axis around the sampled
// point (a kernel of variance σ² per axis), each point interpolated. σ is
// held fixed in the derivative (it changes with the surface's tilt,
// slowly).
//
// Alongside the gradient a Gauss-Newton curvature H_k = Σ_p w_k a² / v₂(p)
// is accumulated (v₂ the local variance of Î; 1/v₂ is the curvature of
// 1 - ZNCC with respect to one predicted pixel near a match). The refiner
// steps by -G_k / H_k, which is invariant to the scale of the scene.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "geometry/view.h"
#include "refine/similarity.h"
#include "render/renderer.h"

namespace mr {

struct PairTermOptions {
  // Depth test in view j: a point is visible if its depth is within this many
  // pixel footprints of the rendered depth (divided by the cosine of the
  // viewing angle, capped at 5x).
  double visibility_tolerance_px = 1.5;
  // Pixels seen at |cos(angle between ray and normal)| below this in either
  // view are dropped (grazing surfaces give unreliable warps).
  double min_cos_angle = 0.15;
  // How image j is sampled at the warped points: "cubic" (Catmull-Rom, see
  // SampleCubic) or "bilinear".
  std::string interpolation = "cubic";
  // Compare each pixel at the coarser of the two views' resolutions on the
  // surface there (above).
  bool match_resolution = true;
  // Where the light is. Negative: fixed in the world (the sun, a room's
  // lamps), which shades a surface point alike in every view. In [0, 1]: at
  // the camera (a flash, a ring light), with this share of ambient light; a
  // point is then shaded by the angle to each camera, and image j's value is
  // relit to view i by HeadlightRelighting. The factor follows the mesh's
  // normals but is held fixed in the derivative.
  double headlight_ambient = -1;
  bool Check() const;
};

// The factor that relights a surface point seen by view j to view i under a
// light at the camera with ambient share `ambient`:
// (a + (1 - a) max(0, n.v_i)) / (a + (1 - a) max(0, n.v_j)), v the unit
// directions from the point x to the camera centres, n the unit normal.
// 1 where the point faces neither camera (0 / 0 for ambient 0).
double HeadlightRelighting(double ambient, const Eigen::Vector3d& n, const Eigen::Vector3d& x,
                           const Eigen::Vector3d& center_i, const Eigen::Vector3d& center_j);

// Per-vertex sums over pixels and pairs.
struct DataTerm {
  Eigen::MatrixXd gradient;   // #V by 3: ∂C/∂X (C = reprojection error, to be decreased)
  Eigen::VectorXd curvature;  // #V: Gauss-Newton curvature along the normal
  Eigen::VectorXd weight;     // #V: Σ_p w_k (pixel coverage)
  Eigen::VectorXd footprint;  // #V: Σ_p w_k * (pixel footprint in world units)
  Eigen::VectorXd similarity; // #V: Σ_p w_k * m(p)
  double cost = 0;            // C = Σ_p W(p) (1 - m(p)) over all pairs
  double zncc_sum = 0;        // Σ_p W(p) m(p)
  double weight_sum = 0;      // Σ_p W(p)
  long valid_pixels = 0;

  void Reset(int num_vertices);
  void Add(const DataTerm& other);
  // Mean local ZNCC over the valid pixels of all pairs, in [-1, 1].
  double MeanSimilarity() const { return weight_sum > 0 ? zncc_sum / weight_sum : 0.0; }
};

// The mesh as the pair term needs it.
struct MeshGeometry {
  const Eigen::MatrixXd* V = nullptr;  // #V by 3
  const Eigen::MatrixXi* F = nullptr;  // #F by 3
  Eigen::MatrixXd face_normals;        // #F by 3 unit normals
};

// Builds the predicted image Î_ij in view i (CV_64F, 0 outside the valid
// domain) and the valid-domain mask (CV_8U, 255 = valid). `image_j` is CV_32F,
// sampled as options.interpolation says, without resolution matching.
void PredictImage(const MeshGeometry& mesh, const PinholeView& view_i,
                  const RenderBuffers& render_i, const PinholeView& view_j,
                  const RenderBuffers& render_j, const cv::Mat& image_j,
                  const PairTermOptions& options, cv::Mat* predicted, cv::Mat* mask);

// Sums the data terms of many ordered pairs. The per-vertex sums are kept in
// one buffer per thread, allocated once and reused for every pair (a #V-sized
// allocation per pair and thread cost more than the pair's pixels on large
// meshes), and reduced by Sum().
class DataTermAccumulator {
 public:
  explicit DataTermAccumulator(int num_vertices);
  // Adds the data term of the ordered pair (i, j). Returns its number of
  // valid pixels. Without `with_gradient` only the scalars (cost,
  // similarity, weights, valid pixels) are added, for a measurement: the
  // similarity's backward pass and the scatter to the vertices are skipped.
  long AddPair(const MeshGeometry& mesh, const PinholeView& view_i, const RenderBuffers& render_i,
               const cv::Mat& image_i, const PinholeView& view_j, const RenderBuffers& render_j,
               const cv::Mat& image_j, const SimilarityOptions& similarity,
               const PairTermOptions& options, bool with_gradient = true);
  // The sum over the pairs added so far.
  DataTerm Sum() const;

 private:
  int num_vertices_;
  std::vector<DataTerm> partial_;  // one per thread
};

// Adds the data term of the ordered pair (i, j) to `term` (sized for the mesh).
// Returns the number of valid pixels. For many pairs, DataTermAccumulator is
// cheaper.
long AccumulatePairTerm(const MeshGeometry& mesh, const PinholeView& view_i,
                        const RenderBuffers& render_i, const cv::Mat& image_i,
                        const PinholeView& view_j, const RenderBuffers& render_j,
                        const cv::Mat& image_j, const SimilarityOptions& similarity,
                        const PairTermOptions& options, DataTerm* term);

}  // namespace mr
