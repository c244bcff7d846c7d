#include "colmap_io/sparse_model.h"

#include <Eigen/Geometry>

#include "util/error.h"

namespace mr {

Eigen::Matrix3d QuaternionToRotation(const Eigen::Vector4d& qvec) {
  const Eigen::Quaterniond q(qvec(0), qvec(1), qvec(2), qvec(3));
  return q.normalized().toRotationMatrix();
}

Eigen::Vector4d RotationToQuaternion(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

Eigen::Matrix3d Image::Rotation() const { return QuaternionToRotation(qvec); }

Eigen::Vector3d Image::ProjectionCenter() const { return -Rotation().transpose() * tvec; }

}  // namespace mr
