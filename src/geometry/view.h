#pragma once

// A calibrated pinhole view, in COLMAP's conventions: x right, y down, z
// forward; the centre of the top-left pixel is image point (0.5, 0.5).

#include <Eigen/Core>

#include "colmap_io/sparse_model.h"

namespace mr {

struct PinholeView {
  int width = 0;
  int height = 0;
  double fx = 1, fy = 1, cx = 0, cy = 0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // cam_from_world rotation
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // cam_from_world translation

  Eigen::Vector3d Center() const { return -R.transpose() * t; }
  Eigen::Vector3d WorldToCamera(const Eigen::Vector3d& X) const { return R * X + t; }
  // Image point of a camera-frame point (no check of z > 0).
  Eigen::Vector2d CameraToImage(const Eigen::Vector3d& Xc) const {
    return Eigen::Vector2d(fx * Xc.x() / Xc.z() + cx, fy * Xc.y() / Xc.z() + cy);
  }
  Eigen::Vector2d Project(const Eigen::Vector3d& X) const { return CameraToImage(WorldToCamera(X)); }
  // World-frame direction of the ray through image point (x, y), with unit
  // z-component in the camera frame (so that a point at depth d is
  // Center() + d * RayDirection(x, y)).
  Eigen::Vector3d RayDirection(double x, double y) const {
    return R.transpose() * Eigen::Vector3d((x - cx) / fx, (y - cy) / fy, 1.0);
  }
  bool InImage(const Eigen::Vector2d& p) const {
    return p.x() >= 0 && p.y() >= 0 && p.x() < width && p.y() < height;
  }
  // The same view at `scale` times the resolution (a pyramid level is
  // Scaled(0.5)); continuous image coordinates scale exactly, the pixel
  // count rounds up.
  PinholeView Scaled(double scale) const;
  // The same view at `width` x `height` pixels, as COLMAP's Camera::Rescale:
  // fx, cx scale by the width's ratio, fy, cy by the height's.
  PinholeView Resized(int width, int height) const;
};

// A view at `center` looking at `target`, with the image's up direction
// closest to `up` (world); principal point at the image centre.
PinholeView LookAtView(const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                       const Eigen::Vector3d& up, int width, int height, double focal);

// The pinhole view of a registered image. Throws InputError if the camera is
// not PINHOLE or SIMPLE_PINHOLE (undistort first).
PinholeView ViewFromColmap(const Camera& camera, const Image& image);

}  // namespace mr
