#include "geometry/view.h"

#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "util/error.h"

namespace mr {

PinholeView PinholeView::Resized(int new_width, int new_height) const {
  PinholeView v = *this;
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  v.width = new_width;
  v.height = new_height;
  v.fx *= sx;
  v.cx *= sx;
  v.fy *= sy;
  v.cy *= sy;
  return v;
}

PinholeView PinholeView::Scaled(double scale) const {
  // Continuous image coordinates scale exactly by `scale`; the pixel count
  // rounds up (a half-resolution pyramid level of an odd size n has
  // (n + 1) / 2 pixels, as DownsampleHalf makes it).
  PinholeView v = *this;
  v.width = static_cast<int>(std::ceil(width * scale - 1e-9));
  v.height = static_cast<int>(std::ceil(height * scale - 1e-9));
  v.fx *= scale;
  v.cx *= scale;
  v.fy *= scale;
  v.cy *= scale;
  return v;
}

PinholeView LookAtView(const Eigen::Vector3d& center, const Eigen::Vector3d& target,
                       const Eigen::Vector3d& up, int width, int height, double focal) {
  const Eigen::Vector3d z = (target - center).normalized();
  Eigen::Vector3d y = -up + up.dot(z) * z;  // image y points down
  MR_CHECK(y.norm() > 1e-9) << "LookAtView: up is parallel to the viewing direction";
  y.normalize();
  const Eigen::Vector3d x = y.cross(z);
  PinholeView v;
  v.width = width;
  v.height = height;
  v.fx = v.fy = focal;
  v.cx = width / 2.0;
  v.cy = height / 2.0;
  v.R.row(0) = x.transpose();
  v.R.row(1) = y.transpose();
  v.R.row(2) = z.transpose();
  v.t = -v.R * center;
  return v;
}

PinholeView ViewFromColmap(const Camera& camera, const Image& image) {
  if (!IsPinholeModel(camera.model)) {
    MR_THROW_INPUT << "image " << image.name << ": camera " << camera.camera_id << " is "
                   << CameraModelName(camera.model)
                   << ", expected PINHOLE or SIMPLE_PINHOLE (undistort the workspace first)";
  }
  PinholeView v;
  v.width = static_cast<int>(camera.width);
  v.height = static_cast<int>(camera.height);
  v.fx = CameraFocalX(camera.model, camera.params);
  v.fy = CameraFocalY(camera.model, camera.params);
  v.cx = CameraPrincipalX(camera.model, camera.params);
  v.cy = CameraPrincipalY(camera.model, camera.params);
  v.R = image.Rotation();
  v.t = image.tvec;
  return v;
}

}  // namespace mr
