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
// both exist) or .txt. Throws InputError naming the file (and line, for
// text) and the bad field: truncated file or trailing bytes, a count larger
// than the rest of the file can hold, unknown camera model id (11+) or name,
// wrong parameter count, width/height outside 1..2^20, non-positive focal
// length, NaN/Inf anywhere, zero quaternion, empty image name, duplicate
// ids, an image referring to a missing camera, a track referring to a
// missing image or to a point2D index out of range. A point2D's point3D_id
// is only checked to be >= -1 (it may name a point absent from points3D).
// Quaternions are returned as stored (not re-normalized).
Reconstruction ReadSparseModel(const std::string& dir);
Reconstruction ReadSparseModelBinary(const std::string& dir);
Reconstruction ReadSparseModelText(const std::string& dir);
// One of the six files from its bytes `data`: the file name of `path`
// (cameras.bin, images.txt, ...) says which, and names it in errors. `model`
// must already hold what the file refers to (cameras for images, images for
// points3D); the file's records are added to it. Same checks as above.
void ReadSparseModelFile(const std::string& path, const std::string& data,
                         Reconstruction* model);

// Write the three files atomically into an existing folder. Text files use
// max_digits10 digits, so text round trips are exact.
void WriteSparseModelBinary(const std::string& dir, const Reconstruction& model);
void WriteSparseModelText(const std::string& dir, const Reconstruction& model);

// Unit quaternion (qw, qx, qy, qz) <-> rotation matrix.
Eigen::Matrix3d QuaternionToRotation(const Eigen::Vector4d& qvec);
Eigen::Vector4d RotationToQuaternion(const Eigen::Matrix3d& R);

}  // namespace mr
