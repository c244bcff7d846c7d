#pragma once

// COLMAP 3.8 camera models (ids 0-10), their parameter orders and their
// projection equations, following COLMAP's src/base/camera_models.h.

#include <string>
#include <vector>

#include <Eigen/Core>

namespace mr {

enum class CameraModel : int {
  kSimplePinhole = 0,        // f, cx, cy
  kPinhole = 1,              // fx, fy, cx, cy
  kSimpleRadial = 2,         // f, cx, cy, k
  kRadial = 3,               // f, cx, cy, k1, k2
  kOpenCV = 4,               // fx, fy, cx, cy, k1, k2, p1, p2
  kOpenCVFisheye = 5,        // fx, fy, cx, cy, k1, k2, k3, k4
  kFullOpenCV = 6,           // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
  kFOV = 7,                  // fx, fy, cx, cy, omega
  kSimpleRadialFisheye = 8,  // f, cx, cy, k
  kRadialFisheye = 9,        // f, cx, cy, k1, k2
  kThinPrismFisheye = 10,    // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1
};

// True for ids 0..10. Newer COLMAP ids (11+) are not known.
bool IsKnownCameraModelId(int id);
// "SIMPLE_PINHOLE", ... ; throws InputError for unknown ids.
std::string CameraModelName(CameraModel model);
// Inverse of CameraModelName; throws InputError naming the text.
CameraModel CameraModelFromName(const std::string& name);
int CameraModelNumParams(CameraModel model);
// COLMAP's names of the parameters, in order ("fx", "fy", "cx", "cy", "k1", ...).
std::vector<std::string> CameraModelParamNames(CameraModel model);
// Parameters after the focal length(s) and principal point: the distortion.
int CameraModelNumDistortionParams(CameraModel model);
// True for SIMPLE_PINHOLE and PINHOLE (no distortion).
bool IsPinholeModel(CameraModel model);

// True if the model has separate focal lengths fx, fy (else a single f).
bool HasSeparateFocalLengths(CameraModel model);

// Focal lengths and principal point of any model (f is duplicated for the
// SIMPLE_* models).
double CameraFocalX(CameraModel model, const std::vector<double>& params);
double CameraFocalY(CameraModel model, const std::vector<double>& params);
double CameraPrincipalX(CameraModel model, const std::vector<double>& params);
double CameraPrincipalY(CameraModel model, const std::vector<double>& params);

// Image point (COLMAP convention: the centre of the top-left pixel is
// (0.5, 0.5)) of a point in the camera frame given in normalized coordinates
// (X/Z, Y/Z), applying the model's exact distortion.
Eigen::Vector2d CameraImageFromWorld(CameraModel model, const std::vector<double>& params,
                                     const Eigen::Vector2d& normalized);
// Inverse: normalized coordinates of an image point (iterative undistortion
// for distorted models, as COLMAP does).
Eigen::Vector2d CameraWorldFromImage(CameraModel model, const std::vector<double>& params,
                                     const Eigen::Vector2d& image_point);

}  // namespace mr
