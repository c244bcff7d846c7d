#pragma once

// Undistortion of a sparse COLMAP project (distorted images + model) into a
// dense workspace with PINHOLE cameras, using the exact equations of
// camera_models.h (no approximation by another library's model).
//
// The undistorted camera of a camera is PINHOLE with the same width, height,
// fx, fy, cx, cy; each output pixel takes the bilinear (cv::remap) sample of
// the distorted image at CameraImageFromWorld(distorted, normalized ray).
// Pixels whose source lies outside the distorted image are black (masks: 0).
// Models whose distortion folds over inside the image, or sends more than
// a quarter of the undistorted image outside the distorted one (implausible
// parameters such as OPENCV k1 = 5), are refused, naming the camera and the
// parameter.

#include <string>

#include <opencv2/core.hpp>

#include "colmap_io/sparse_model.h"

namespace mr {

struct UndistortionOptions {
  // Quality of written JPEG images, in [1, 100].
  int jpeg_quality = 95;

  bool Check() const;
};

struct UndistortionSummary {
  int num_images = 0;        // images written
  int num_masks = 0;         // masks written
  std::string output_path;   // the dense workspace folder
};

// PINHOLE camera of the same size with the source's fx, fy, cx, cy.
Camera UndistortedCamera(const Camera& camera);

// Remap tables (CV_32FC1) for cv::remap: for each pixel of the undistorted
// image the position of its sample in the distorted image (cv::remap puts
// pixel centres at integers; COLMAP at +0.5, converted here). Throws
// InputError naming the camera and its distortion parameters if more than
// a quarter of the pixels sample outside the distorted image, or the mapping is
// not finite or folds over.
void ComputeUndistortionMaps(const Camera& camera, cv::Mat* map_x, cv::Mat* map_y);

// Undistorts one image (any depth/channels cv::remap handles) of `camera`.
// `interpolation`: cv::INTER_LINEAR for images, cv::INTER_NEAREST for masks.
cv::Mat UndistortImage(const cv::Mat& image, const Camera& camera, int interpolation);

// A text that identifies an undistortion job (source folders, cameras,
// images); written to <output>/mesh_refiner_undistortion.txt when the job
// has completed, so a later run can reuse the output.
std::string UndistortionFingerprint(const std::string& image_dir, const std::string& mask_dir,
                                    const Reconstruction& model);
// Name of the completion marker inside the output folder, and of the marker
// present while a job is writing (so an interrupted job's folder is known to
// be ours).
extern const char kUndistortionMarker[];
extern const char kUndistortionPartialMarker[];

// Writes <output_dir>/images/<name> for every image of `model` (read from
// `image_dir`), <output_dir>/masks/<name>.png for every image that has a mask
// "<name>.png" in `mask_dir` (if not empty), <output_dir>/sparse/*.bin with
// PINHOLE cameras and transformed 2-D points, and finally the completion
// marker. Throws InputError for unreadable or wrongly sized images and for
// models that cannot be undistorted.
UndistortionSummary UndistortSparseModel(const std::string& image_dir,
                                         const std::string& mask_dir,
                                         const Reconstruction& model,
                                         const std::string& output_dir,
                                         const UndistortionOptions& options = {});

}  // namespace mr
