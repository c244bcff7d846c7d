#include "geometry/view.h"

#include <cmath>

#include "util/error.h"

namespace mr {

PinholeView PinholeView::Scaled(double scale) const {
  PinholeView v = *this;
  v.width = static_cast<int>(std::lround(width * scale));
  v.height = static_cast<int>(std::lround(height * scale));
  const double sx = static_cast<double>(v.width) / width;
  const double sy = static_cast<double>(v.height) / height;
  v.fx *= sx;
  v.cx *= sx;
  v.fy *= sy;
  v.cy *= sy;
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
