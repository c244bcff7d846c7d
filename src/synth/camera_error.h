#pragma once

// Camera error of the kind an SfM model has: each image's pose moved by a
// random rigid motion whose reprojection error on the true surface is a given
// number of pixels, and each camera's focal length off by a given percentage.
// workspace_synthesizer applies it to the sparse model it writes, while the
// images and depth maps stay rendered with the true cameras.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "colmap_io/sparse_model.h"
#include "geometry/view.h"

namespace mr {

struct CameraErrorOptions {
  // RMS reprojection error (pixels) that each image's pose error causes on
  // the surface points the view sees (in front of the camera, inside the
  // image; occlusion ignored), measured with the true intrinsics.
  // 0 = exact poses. Range [0, 100].
  double pose_error_px = 0;
  // Relative error of each camera's focal length (percent): fx and fy are
  // multiplied together by 1 + e/100 or 1 - e/100, the sign drawn at random
  // per camera; the principal point is kept. 0 = exact. Range [0, 50].
  double focal_error_percent = 0;

  bool Check() const;
};

// What PerturbCameras did to one image.
struct ImageCameraError {
  uint32_t image_id = 0;
  int num_visible_points = 0;  // surface points used for the RMS (0: pose left exact)
  double rms_px = 0;           // achieved RMS reprojection displacement (pixels)
  double rotation_deg = 0;     // angle of R' R^T (degrees)
  double center_shift = 0;     // |C' - C| (scene units)
};

struct CameraErrorSummary {
  // One entry per image (id order) when pose_error_px > 0, else empty.
  std::vector<ImageCameraError> images;
  // Over the images whose pose was perturbed (num_visible_points > 0).
  int num_perturbed_images = 0;
  double mean_rms_px = 0, max_rms_px = 0;
  double mean_rotation_deg = 0, max_rotation_deg = 0;
  double mean_center_shift = 0, max_center_shift = 0;
  // Per camera id: the factor fx and fy were multiplied by (1 when
  // focal_error_percent is 0).
  std::map<uint32_t, double> focal_scale;

  std::string BriefReport() const;
};

// Makes `model`'s cameras wrong the way an SfM model's are. Per image (id
// order): draws a rigid motion direction, rotation vector w ~ N(0, I) and
// camera-centre shift u ~ N(0, I) times the median depth of the visible
// points, and scales it by the s for which the RMS displacement of the
// projections of the visible `surface_points` (#P by 3, world frame) equals
// options.pose_error_px within 0.1 % (a linear guess from a small probe, then
// secant steps safeguarded by bisection): R' = exp([s w]x) R, C' = C + s u,
// t' = -R' C'. Then scales each camera's focal length(s). points2D and
// points3D are left as they are. An image that sees no surface point keeps
// its pose (logged as a WARNING). Deterministic for a given seed; with both
// errors 0 the model is not touched. Pose error needs PINHOLE or
// SIMPLE_PINHOLE cameras (InputError otherwise).
CameraErrorSummary PerturbCameras(const CameraErrorOptions& options,
                                  const Eigen::MatrixXd& surface_points, uint32_t seed,
                                  Reconstruction* model);

// RMS displacement (pixels) of the projections of the `surface_points`
// (#P by 3) that `true_view` sees (in front, inside the image) between
// `true_view` and `other_view`; points behind `other_view` give infinity.
// `num_visible` (optional) receives the number of points used; 0 points give 0.
double ReprojectionRms(const PinholeView& true_view, const PinholeView& other_view,
                       const Eigen::MatrixXd& surface_points, int* num_visible = nullptr);

// How far the cameras of `model` are from those of `truth`, image by image
// (matched by name): the RMS displacement of the projections of the
// `surface_points` that each true view sees (ReprojectionRms), and each
// camera's focal error. What a camera refinement is judged by.
struct CameraComparison {
  int num_images = 0;              // images of `model` compared (all of them)
  double rms_px = 0;               // sqrt of the mean over images of their RMS squared
  double max_rms_px = 0;           // worst image
  std::string max_rms_image;       // its name
  double max_focal_percent = 0;    // worst |fx / fx_true - 1| (and fy) over cameras, in %

  // `"camera_images": n, "camera_rms_px": ..., ...` (JSON members, no braces).
  std::string JsonMembers() const;
};

// A similarity transform of the world: X' = scale * rotation * X + translation.
struct Similarity3 {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator()(const Eigen::Vector3d& X) const {
    return scale * rotation * X + translation;
  }
  // Every row of `points` (#P by 3) transformed.
  Eigen::MatrixXd Apply(const Eigen::MatrixXd& points) const;
  // The camera carried along: it sees X' where `view` saw X.
  PinholeView Apply(const PinholeView& view) const;
};

// The similarity that carries `model`'s world into `truth`'s so that its
// cameras agree best with the true ones: it minimises, over the images of
// `model` (matched by name, as CompareCameras), the squared displacement of
// the projections of up to 200 of the `surface_points` (true world) each true
// view sees. Started from the similarity of the camera centres (Umeyama)
// when there are 3 or more, else from the identity; solved with Ceres.
// An SfM model fixes its world only up to such a transform (the gauge), and
// so does a model whose every pose carries an independent error: the mean
// of the errors moves the whole reconstruction. Comparing after this
// alignment judges cameras, and a mesh in their world, by what the images
// can determine. Requirements as CompareCameras.
Similarity3 AlignCamerasToTruth(const Reconstruction& model, const Reconstruction& truth,
                                const Eigen::MatrixXd& surface_points);

// Every image of `model` must be in `truth` under the same name, with a
// PINHOLE or SIMPLE_PINHOLE camera in both (InputError otherwise, naming it);
// `truth` may hold more images. An image whose true view sees none of the
// points counts as 0 px. `model_to_truth` (optional) carries the model's
// cameras into the true world first (AlignCamerasToTruth).
CameraComparison CompareCameras(const Reconstruction& model, const Reconstruction& truth,
                                const Eigen::MatrixXd& surface_points,
                                const Similarity3* model_to_truth = nullptr);

}  // namespace mr
