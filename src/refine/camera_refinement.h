#pragma once

// Photometric refinement of the cameras against a fixed mesh (issue #11).
//
// COLMAP's poses carry errors of 0.4-1 px; the surface flow of the refiner
// then bends the surface to absorb them. Here the mesh is held fixed (it
// fixes the frame: there is no free gauge) and the cameras move to make the
// images consistent through it, as a Ceres least-squares problem:
//
//   sample p of view i (a pixel centre seeing face f, also seen unoccluded
//   in view j; strongest image gradient in j first, spread over the image)
//   X(p)  = C_i + d r_p, the hit of view i's ray r_p = R_iᵀ K_i⁻¹ (p, 1)
//           with the plane n·X = n·A of face f: d = n·(A - C_i) / (n·r_p)
//   q     = π_j(X) = K_j (R_j (X - C_j)) projected
//   r     = I_j(q) - (a_ij I_i(p) + b_ij)          (I_j bilinear)
//
// with a per-ordered-pair affine brightness (a_ij, b_ij), under a Huber loss
// and weighed as residuals of standard deviation intensity_sigma, plus
// priors that keep each camera near its start (they hold the directions the
// data barely sees, such as rotations about the centre of a sphere).
//
// The mesh is not exact (it was made with the wrong cameras), and cameras
// fitted to a fixed wrong surface absorb its error. So by default each face's
// plane may shift along its normal, n·X = n·A + δ_f, with δ_f shared by all
// samples on face f from every pair and held near 0 by a prior of
// surface_sigma_px pixel footprints: a photometric bundle adjustment whose
// structure is the mesh's face planes. The cameras are then fixed by what the
// views agree on, not by the mesh's depth. The frame the fixed mesh held is
// then held by a datum residual: the camera set's mean shift, rotation and
// scale stay at the prior views' (datum_sigma_px).
// The photometric Jacobian is analytic (see docs/camera_refinement.md).

#include <Eigen/Core>
#include <ceres/iteration_callback.h>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "geometry/view.h"

namespace ceres {
class CostFunction;
class Manifold;
}  // namespace ceres

namespace mr {

class Renderer;
struct RenderBuffers;

struct CameraRefinementOptions {
  // "poses": rotation and centre per view. "poses_intrinsics": also fx, fy,
  // cx, cy per camera (shared by the views of camera_of_view).
  std::string mode = "poses";
  // Pixels sampled per ordered pair (>= 1): highest image gradient first,
  // spread over the image.
  int max_samples_per_pair = 3000;
  // 1-sigma of an intensity residual (images in [0, 1]; > 0): the residuals
  // are divided by it, so it sets the weight of the images against the
  // priors. Well above the pixel noise: neighbouring samples are not
  // independent (they share texture and interpolation stencils), and the
  // mesh is not exact. Smaller values recover more of a pose error but let
  // the cameras drift further along directions the images barely see (see
  // docs/camera_refinement.md for measurements).
  double intensity_sigma = 0.1;
  // Huber threshold on the intensity residuals (images in [0, 1]; > 0).
  double huber_delta = 0.05;
  // 1-sigma of the prior that keeps each rotation near its start (degrees, > 0).
  double prior_rotation_deg = 0.2;
  // 1-sigma of the prior on each camera centre, in pixel footprints of the
  // view at the mesh (its median depth / fx; > 0).
  double prior_center_px = 2.0;
  // 1-sigma of the prior on fx and fy, in percent of the start (> 0;
  // poses_intrinsics only). The principal point has no prior of its own.
  double prior_focal_percent = 1.0;
  // 1-sigma of the prior on each face's plane offset δ_f, in pixel footprints
  // at the face (>= 0; of the finest view that samples it). 0 holds the mesh
  // fixed: its face planes are taken as exact, and the cameras absorb the
  // mesh's error. Larger values free the surface more but let faces whose
  // images say little slide into false matches (100 moved exact cameras
  // 0.6 px off on a noisy corpus case); 5 was chosen on the worst case of
  // four corpus cases with exact and 1 px cameras and on templeSparseRing
  // (docs/camera_refinement.md).
  double surface_sigma_px = 5.0;
  // Ceres iterations (>= 1).
  int max_iterations = 30;
  // Ceres stops when an iteration lowers the cost by less than this fraction
  // (0 < function_tolerance < 1). 1e-3 against Ceres's 1e-6: on four corpus
  // cases with exact and 1 px cameras the worst case was as good or better
  // (accuracy90 1.006x / 2.097x the exact-camera run against 1.012x /
  // 2.102x) in 4-17 iterations instead of 23-31, 2-3x faster.
  double function_tolerance = 1e-3;
  // 1-sigma of the camera set's datum, in pixels: the mean centre shift of
  // the refined views (in mean pixel footprints), their mean rotation (in
  // pixels at the mean focal length) and the scale of the set (in mean
  // footprints at the set's RMS radius), all from the prior views (>= 0).
  // The images and the free face planes barely see a rotation of the whole
  // set about the object, which the per-view priors alone hold only to
  // prior_rotation_deg / sqrt(#views), and in mesh_refiner the surface
  // follows the cameras wherever they go. 0 leaves the datum to the
  // per-view priors. Applied only with free face planes (surface_sigma_px >
  // 0) and no fixed views: a fixed mesh, or fixed views, hold the frame.
  double datum_sigma_px = 0.01;
  // How the other view's image is read at the warped samples: "cubic"
  // (SampleCubic) or "bilinear". mesh_refiner sets it from
  // --Refine.interpolation. At 1 px of pose error on four corpus cases,
  // cubic took the worst accuracy90 from 1.245x to 1.228x the exact-camera
  // run and the cameras from 0.314 to 0.302 px (docs/camera_refinement.md).
  std::string interpolation = "cubic";
  // Renders held at once while the samples are picked, in MB (>= 1): the
  // pairs are taken in their order, in batches whose views' renders (16
  // bytes a pixel) fit, so that memory does not grow with the number of
  // views; a view shared by two batches is rendered twice. mesh_refiner sets
  // it to half of --Refine.cache_mb.
  int max_render_mb = 512;
  // Memory for the least-squares problem, in MB (>= 1). Ceres holds about
  // kProblemBytesPerSample per photometric sample, so that
  // max_samples_per_pair samples for every ordered pair grow with the number
  // of views (436 views with 4.3 ordered pairs each: 5.6M samples, 6 GiB).
  // Where they would take more than this, every pair gets fewer
  // (SamplesPerPair). 1024 holds 892,000 samples on a mesh of 750,000
  // faces: 60 views of 1280x960 in 258 ordered pairs (774,000) are not cut;
  // at 368 a pair they still met the targets of docs/camera_refinement.md.
  int max_problem_mb = 1024;

  bool Check() const;
};

// The memory a camera refinement holds, for CameraRefinementOptions::
// max_problem_mb: kProblemBytesPerSample per photometric sample (the samples,
// the residual blocks with their cost functions, the solve's Jacobian and
// Schur elimination) and kProblemBytesPerFace per face of the mesh (its
// plane offsets and its copy in the renderer). Fitted to the growth of the
// in-use heap from before the samples were picked to the solve's peak in
// twelve rounds (the README's example: 162,000 samples on 160,000 faces; 60
// views of 1280x960: 112,000-774,000 samples on 747,000 faces), which it
// exceeds in every one; a sample took 1,097-1,467 bytes of it, more where
// there were fewer samples to share the mesh's part. Measured before the
// cost functions kept their image by address instead of a 96-byte cv::Mat
// header (the test scene's 48,000 samples: 40.8 -> 36.4 MB); two rounds
// since, with 94,944 samples, held 128 and 119 MB of a 150 MB budget.
constexpr size_t kProblemBytesPerSample = 1150;
constexpr size_t kProblemBytesPerFace = 64;

// The most samples each of `num_ordered_pairs` ordered pairs gets:
// options.max_samples_per_pair, or fewer (at least 1) where that many for
// every pair, with a mesh of `num_faces` faces, would take more than
// options.max_problem_mb.
int SamplesPerPair(const CameraRefinementOptions& options, size_t num_ordered_pairs,
                   size_t num_faces);

struct CameraRefinementSummary {
  std::string mode;
  int num_views_refined = 0;  // views in at least one pair with samples
  int num_ordered_pairs = 0;  // ordered pairs with samples
  long num_samples = 0;       // photometric residuals
  // The most samples an ordered pair could get (SamplesPerPair), and
  // max_problem_mb where it cut that below max_samples_per_pair (else 0).
  int samples_per_pair = 0;
  int cut_to_fit_mb = 0;
  // The most heap the refinement held above what was in use at its start,
  // at the end of any Ceres iteration: the samples, the problem and the
  // solver's (HeapBytesInUse; 0 where the C library does not say).
  double heap_mb = 0;
  // Faces whose plane offset was free (surface_sigma_px > 0), and the median
  // and largest |δ_f| at the end, in pixel footprints.
  int num_faces = 0;
  double median_surface_offset_px = 0;
  double max_surface_offset_px = 0;
  // Ceres's cost (photometric under the Huber loss, plus the priors), before
  // and after.
  double initial_cost = 0;
  double final_cost = 0;
  // Per view (all views; 0 for views not refined): rotation change (degrees),
  // centre change (scene units and pixel footprints of the view).
  std::vector<double> rotation_change_deg;
  std::vector<double> center_change;
  std::vector<double> center_change_px;
  std::vector<double> footprint;  // median pixel footprint of the view (scene units)
  // Per camera id (poses_intrinsics only): change of the mean focal length
  // (fx + fy) / 2 in percent, and of the principal point in pixels.
  std::map<int, double> focal_change_percent;
  std::map<int, double> principal_point_change_px;
  // How the refined set as a whole moved from the prior views (the datum
  // that datum_sigma_px holds): mean centre shift (in mean pixel footprints),
  // angle of the mean world-frame rotation (degrees), relative scale change.
  double set_shift_px = 0;
  double set_rotation_deg = 0;
  double set_scale_change = 0;
  int iterations = 0;
  bool converged = false;
  std::string ceres_brief_report;
  std::string ceres_full_report;
  double seconds = 0;
  double sample_seconds = 0;  // of which rendering the views and picking the samples

  // One line: mode, counts, cost before and after, largest changes, time.
  std::string BriefReport() const;
  // BriefReport, one line per refined view and camera, and Ceres's report.
  std::string FullReport() const;
};

// Refines `views` in place against the fixed mesh (V, F) (#V by 3, #F by 3).
// `gray_images`: one CV_32F image in [0, 1] per view, at the view's
// resolution (for a pyramid level, pass its images and PyramidLevelView
// views, then scale the intrinsics back). `pairs`: view pairs {i, j} (as
// NeighborPairs gives them), used in both directions. `camera_of_view`: the
// camera (any int id, e.g. COLMAP's camera_id) of each view; in
// poses_intrinsics the views of one camera must have equal intrinsics and
// share one refined set. Empty: one camera per view. `renderer` renders the mesh (its
// current mesh is replaced). Views in no pair keep their pose (but take their
// camera's new intrinsics). Samples are picked once, at the start poses.
// `prior_views` (optional, same size and resolution as `views`): the cameras
// the priors hold the views near, e.g. the SfM cameras when `views` are the
// result of an earlier refinement; without it, the start views. The reported
// changes are from the start views.
// Returns with the cameras unchanged (and a WARNING) if no pair has samples
// or Ceres finds no usable solution. Throws InputError on bad options or
// inputs.
// `fixed_views` (optional, one flag per view): views that keep their
// camera and only anchor the others (e.g. to register new images against a
// refined model); in poses_intrinsics the intrinsics of a camera with a
// fixed view stay fixed too. Views in no pair may pass an empty image.
CameraRefinementSummary RefineCameras(const std::vector<cv::Mat>& gray_images,
                                      const std::vector<std::pair<int, int>>& pairs,
                                      const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      Renderer* renderer, const std::vector<int>& camera_of_view,
                                      const CameraRefinementOptions& options,
                                      std::vector<PinholeView>* views,
                                      const std::vector<PinholeView>* prior_views = nullptr,
                                      const std::vector<char>* fixed_views = nullptr);

namespace internal {

// One photometric sample of the ordered pair (i, j): the image point p of
// view i (a pixel centre), the plane n·X = plane_offset of the face it sees
// (world frame, unit n) and the intensity I_i(p).
struct PhotometricSample {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double plane_offset = 0;
  double intensity = 0;
  double score = 0;  // |∇I_j| at the projection (px⁻¹), what the selection ranks by
  int face = -1;         // the face it sees
  double footprint = 0;  // the point's depth in view i / fx_i (scene units per pixel)
};

// The samples of the ordered pair (i, j) as RefineCameras picks them:
// pixels of view i inside the surface (their 5x5 neighbourhood sees it),
// seen within 60 degrees of the face normal in both views, projecting at
// least 3 px inside image j onto a 5x5 neighbourhood that sees the surface
// at the point's depth (not occluded), with |∇I_j| >= 1e-3 px⁻¹; at most
// `max_samples`, highest gradient first, spread over a grid of cells (round
// robin: every cell's best, then every cell's second best, ...).
// `face_normals`: #F by 3 unit normals.
std::vector<PhotometricSample> SelectSamples(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                             const Eigen::MatrixXd& face_normals,
                                             const PinholeView& view_i,
                                             const RenderBuffers& render_i, const cv::Mat& image_i,
                                             const PinholeView& view_j,
                                             const RenderBuffers& render_j, const cv::Mat& image_j,
                                             int max_samples);

// The photometric residual r = I_j(q) - (a I_i(p) + b) of one sample as a
// ceres::CostFunction with analytic Jacobians. Parameter blocks, with poses
// as the row-major 3x3 cam_from_world rotation followed by the centre (12
// values, with NewPoseManifold) and intrinsics as (fx, fy, cx, cy):
//   shared_intrinsics = false: pose_i (12), K_i (4), pose_j (12), K_j (4), (a, b)
//   shared_intrinsics = true:  pose_i (12), pose_j (12), K (4), (a, b)
// and with free_surface a last block (1): the offset δ of the sample's face
// plane, n·X = plane_offset + δ.
// `image_j` (CV_32F) must outlive the cost function, which keeps its
// address; it is read by cubic interpolation, or bilinear without
// cubic_interpolation.
ceres::CostFunction* NewPhotometricCost(const PhotometricSample& sample, const cv::Mat& image_j,
                                        bool shared_intrinsics, bool free_surface = false,
                                        bool cubic_interpolation = true);

// The rotation matrices (row-major, 9 values) with the tangent update
// Plus(R, δ) = Exp(δ) R (δ an angle-axis vector in the camera frame).
ceres::Manifold* NewRotationMatrixManifold();

// A pose block (R row-major, C): NewRotationMatrixManifold's update on R and
// the plain one on C (tangent (δ_R, δ_C), 6 values).
ceres::Manifold* NewPoseManifold();

// The datum of a camera set against reference cameras (R0_k cam_from_world,
// C0_k centres; at least 2) as a ceres::CostFunction of the cameras' pose
// blocks (12 values each, as NewPhotometricCost's): 7 residuals, the mean centre shift / sigma_center
// (scene units), the mean world-frame rotation change vee(skew(R0_kᵀ R_k)) /
// sigma_rotation (radians) and the relative scale change of the set about
// its mean centre / sigma_scale, each 0 at the reference and independent of
// the others to first order (see camera_refinement.cc).
ceres::CostFunction* NewCameraSetDatumCost(const std::vector<Eigen::Matrix3d>& R0,
                                           const std::vector<Eigen::Vector3d>& C0,
                                           double sigma_center, double sigma_rotation,
                                           double sigma_scale);

// A Ceres callback that ends the solve, on its last accepted iterate, at the
// first rejected step after an accepted step that lowered the cost by less
// than `below` of it (relative to the cost before that step). Levenberg-
// Marquardt would otherwise shrink its trust region through one rejected
// step after another, each a full linear solve, before function_tolerance
// stops it on the same iterate.
class StopOnRejectedStep : public ceres::IterationCallback {
 public:
  explicit StopOnRejectedStep(double below);
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override;

 private:
  double below_;
  double last_decrease_ = 1.0;
};

}  // namespace internal
}  // namespace mr
