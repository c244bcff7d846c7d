#pragma once

// COLMAP sparse models: cameras, images, points3D in .bin and .txt.
// Layouts follow COLMAP 3.8 (see ../shared/docs/COLMAP-NOTES.md).
// rigs.bin/frames.bin of newer versions are ignored.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "colmap_io/camera_models.h"

namespace mr {

struct Camera {
  uint32_t camera_id = 0;
  CameraModel model = CameraModel::kPinhole;
  uint64_t width = 0;
  uint64_t height = 0;
  std::vector<double> params;  // in the model's order (camera_models.h)
};

struct Point2D {
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  int64_t point3D_id = -1;  // -1: not triangulated
};

struct Image {
  uint32_t image_id = 0;
  Eigen::Vector4d qvec = Eigen::Vector4d(1, 0, 0, 0);  // cam_from_world rotation (qw, qx, qy, qz)
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();      // cam_from_world translation
  uint32_t camera_id = 0;
  std::string name;
  std::vector<Point2D> points2D;

  Eigen::Matrix3d Rotation() const;               // cam_from_world R from qvec
  Eigen::Vector3d ProjectionCenter() const;       // -R^T t
};

struct TrackElement {
  uint32_t image_id = 0;
  uint32_t point2D_idx = 0;
};

struct Point3D {
  uint64_t point3D_id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Matrix<uint8_t, 3, 1> rgb = Eigen::Matrix<uint8_t, 3, 1>::Zero();
  double error = -1;
  std::vector<TrackElement> track;
};

struct Reconstruction {
  std::map<uint32_t, Camera> cameras;
  std::map<uint32_t, Image> images;
  std::map<uint64_t, Point3D> points3D;
};

// Reads a model folder holding cameras/images/points3D as .bin (preferred if
// both exist) or .txt. Throws InputError naming the file and the bad field
// (unknown camera model id, truncated file, image referring to a missing
// camera, ...).
Reconstruction ReadSparseModel(const std::string& dir);
Reconstruction ReadSparseModelBinary(const std::string& dir);
Reconstruction ReadSparseModelText(const std::string& dir);

// Write the three files atomically into an existing folder.
void WriteSparseModelBinary(const std::string& dir, const Reconstruction& model);
void WriteSparseModelText(const std::string& dir, const Reconstruction& model);

// Unit quaternion (qw, qx, qy, qz) <-> rotation matrix.
Eigen::Matrix3d QuaternionToRotation(const Eigen::Vector4d& qvec);
Eigen::Vector4d RotationToQuaternion(const Eigen::Matrix3d& R);

}  // namespace mr
