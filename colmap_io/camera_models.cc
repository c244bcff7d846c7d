#include "colmap_io/camera_models.h"

#include <cmath>

#include <Eigen/Dense>

#include "util/error.h"

namespace mr {
namespace {

struct ModelInfo {
  const char* name;
  int num_params;
  bool separate_focal;  // fx, fy (else a single f)
  const char* params;   // COLMAP's parameter names, comma-separated
};

const ModelInfo kModels[] = {
    {"SIMPLE_PINHOLE", 3, false, "f,cx,cy"},
    {"PINHOLE", 4, true, "fx,fy,cx,cy"},
    {"SIMPLE_RADIAL", 4, false, "f,cx,cy,k"},
    {"RADIAL", 5, false, "f,cx,cy,k1,k2"},
    {"OPENCV", 8, true, "fx,fy,cx,cy,k1,k2,p1,p2"},
    {"OPENCV_FISHEYE", 8, true, "fx,fy,cx,cy,k1,k2,k3,k4"},
    {"FULL_OPENCV", 12, true, "fx,fy,cx,cy,k1,k2,p1,p2,k3,k4,k5,k6"},
    {"FOV", 5, true, "fx,fy,cx,cy,omega"},
    {"SIMPLE_RADIAL_FISHEYE", 4, false, "f,cx,cy,k"},
    {"RADIAL_FISHEYE", 5, false, "f,cx,cy,k1,k2"},
    {"THIN_PRISM_FISHEYE", 12, true, "fx,fy,cx,cy,k1,k2,p1,p2,k3,k4,sx1,sy1"},
};

const ModelInfo& Info(CameraModel model) {
  const int id = static_cast<int>(model);
  if (!IsKnownCameraModelId(id)) {
    MR_THROW_INPUT << "unknown camera model id " << id << " (COLMAP 3.8 knows ids 0-10)";
  }
  return kModels[id];
}

void CheckParams(CameraModel model, const std::vector<double>& params) {
  MR_CHECK_EQ(static_cast<int>(params.size()), Info(model).num_params)
      << "camera model " << Info(model).name;
}

// Offset of the distortion parameters in the parameter vector.
int ExtraOffset(CameraModel model) { return Info(model).separate_focal ? 4 : 3; }

// Fisheye angle mapping shared by the *_FISHEYE models: returns
// theta / r (the factor that maps (u, v) to the equidistant coordinates).
double FisheyeScale(double u, double v) {
  const double r = std::sqrt(u * u + v * v);
  if (r < std::numeric_limits<double>::epsilon()) return 1.0;
  return std::atan(r) / r;
}

// Distorted normalized coordinates of undistorted normalized coordinates.
Eigen::Vector2d Distort(CameraModel model, const double* k, double u, double v) {
  switch (model) {
    case CameraModel::kSimplePinhole:
    case CameraModel::kPinhole:
      return {u, v};
    case CameraModel::kSimpleRadial: {
      const double r2 = u * u + v * v;
      const double radial = k[0] * r2;
      return {u + u * radial, v + v * radial};
    }
    case CameraModel::kRadial: {
      const double r2 = u * u + v * v;
      const double radial = k[0] * r2 + k[1] * r2 * r2;
      return {u + u * radial, v + v * radial};
    }
    case CameraModel::kOpenCV: {
      const double u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
      const double radial = k[0] * r2 + k[1] * r2 * r2;
      return {u + u * radial + 2 * k[2] * uv + k[3] * (r2 + 2 * u2),
              v + v * radial + 2 * k[3] * uv + k[2] * (r2 + 2 * v2)};
    }
    case CameraModel::kOpenCVFisheye: {
      const double r = std::sqrt(u * u + v * v);
      if (r < std::numeric_limits<double>::epsilon()) return {u, v};
      const double theta = std::atan(r), t2 = theta * theta, t4 = t2 * t2, t6 = t4 * t2,
                   t8 = t4 * t4;
      const double thetad = theta * (1 + k[0] * t2 + k[1] * t4 + k[2] * t6 + k[3] * t8);
      return {u * thetad / r, v * thetad / r};
    }
    case CameraModel::kFullOpenCV: {
      const double u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2, r4 = r2 * r2,
                   r6 = r4 * r2;
      const double radial = (1 + k[0] * r2 + k[1] * r4 + k[4] * r6) /
                            (1 + k[5] * r2 + k[6] * r4 + k[7] * r6);
      return {u * radial + 2 * k[2] * uv + k[3] * (r2 + 2 * u2),
              v * radial + 2 * k[3] * uv + k[2] * (r2 + 2 * v2)};
    }
    case CameraModel::kFOV: {
      const double omega = k[0], omega2 = omega * omega, radius2 = u * u + v * v;
      const double eps = 1e-4;
      double factor;
      if (omega2 < eps) {
        factor = (omega2 * radius2) / 3 - omega2 / 12 + 1;
      } else if (radius2 < eps) {
        const double th = std::tan(omega / 2);
        factor = (-2 * th * (4 * radius2 * th * th - 3)) / (3 * omega);
      } else {
        const double radius = std::sqrt(radius2);
        factor = std::atan(radius * 2 * std::tan(omega / 2)) / (radius * omega);
      }
      return {u * factor, v * factor};
    }
    case CameraModel::kSimpleRadialFisheye:
    case CameraModel::kRadialFisheye: {
      const double s = FisheyeScale(u, v);
      const double theta2 = (u * u + v * v) * s * s;  // theta^2
      double radial = k[0] * theta2;
      if (model == CameraModel::kRadialFisheye) radial += k[1] * theta2 * theta2;
      return {u * s * (1 + radial), v * s * (1 + radial)};
    }
    case CameraModel::kThinPrismFisheye: {
      const double s = FisheyeScale(u, v);
      const double uu = u * s, vv = v * s;
      const double u2 = uu * uu, v2 = vv * vv, uv = uu * vv, r2 = u2 + v2, r4 = r2 * r2,
                   r6 = r4 * r2, r8 = r6 * r2;
      const double radial = k[0] * r2 + k[1] * r4 + k[4] * r6 + k[5] * r8;
      return {uu + uu * radial + 2 * k[2] * uv + k[3] * (r2 + 2 * u2) + k[6] * r2,
              vv + vv * radial + 2 * k[3] * uv + k[2] * (r2 + 2 * v2) + k[7] * r2};
    }
  }
  MR_CHECK(false) << "unreachable";
  return {};
}

}  // namespace

bool IsKnownCameraModelId(int id) { return id >= 0 && id <= 10; }

std::string CameraModelName(CameraModel model) { return Info(model).name; }

CameraModel CameraModelFromName(const std::string& name) {
  for (int id = 0; id <= 10; ++id) {
    if (name == kModels[id].name) return static_cast<CameraModel>(id);
  }
  MR_THROW_INPUT << "unknown camera model '" << name << "' (COLMAP 3.8 models: SIMPLE_PINHOLE, "
                 << "PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, FULL_OPENCV, FOV, "
                 << "SIMPLE_RADIAL_FISHEYE, RADIAL_FISHEYE, THIN_PRISM_FISHEYE)";
}

int CameraModelNumParams(CameraModel model) { return Info(model).num_params; }

std::vector<std::string> CameraModelParamNames(CameraModel model) {
  std::vector<std::string> names;
  std::string name;
  for (const char* c = Info(model).params;; ++c) {
    if (*c == ',' || *c == '\0') {
      names.push_back(name);
      name.clear();
      if (*c == '\0') break;
    } else {
      name += *c;
    }
  }
  return names;
}

int CameraModelNumDistortionParams(CameraModel model) {
  return Info(model).num_params - ExtraOffset(model);
}

bool IsPinholeModel(CameraModel model) {
  return model == CameraModel::kSimplePinhole || model == CameraModel::kPinhole;
}

bool HasSeparateFocalLengths(CameraModel model) { return Info(model).separate_focal; }

double CameraFocalX(CameraModel model, const std::vector<double>& params) {
  CheckParams(model, params);
  return params[0];
}
double CameraFocalY(CameraModel model, const std::vector<double>& params) {
  CheckParams(model, params);
  return Info(model).separate_focal ? params[1] : params[0];
}
double CameraPrincipalX(CameraModel model, const std::vector<double>& params) {
  CheckParams(model, params);
  return Info(model).separate_focal ? params[2] : params[1];
}
double CameraPrincipalY(CameraModel model, const std::vector<double>& params) {
  CheckParams(model, params);
  return Info(model).separate_focal ? params[3] : params[2];
}

Eigen::Vector2d CameraImageFromWorld(CameraModel model, const std::vector<double>& params,
                                     const Eigen::Vector2d& normalized) {
  CheckParams(model, params);
  const Eigen::Vector2d d =
      Distort(model, params.data() + ExtraOffset(model), normalized.x(), normalized.y());
  return {CameraFocalX(model, params) * d.x() + CameraPrincipalX(model, params),
          CameraFocalY(model, params) * d.y() + CameraPrincipalY(model, params)};
}

Eigen::Vector2d CameraWorldFromImage(CameraModel model, const std::vector<double>& params,
                                     const Eigen::Vector2d& image_point) {
  CheckParams(model, params);
  const Eigen::Vector2d target((image_point.x() - CameraPrincipalX(model, params)) /
                                   CameraFocalX(model, params),
                               (image_point.y() - CameraPrincipalY(model, params)) /
                                   CameraFocalY(model, params));
  if (IsPinholeModel(model)) return target;
  // Newton iterations on Distort(x) = target with a central-difference
  // Jacobian, as COLMAP's IterativeUndistortion does.
  const double* k = params.data() + ExtraOffset(model);
  Eigen::Vector2d x = target;
  for (int it = 0; it < 100; ++it) {
    const Eigen::Vector2d r = Distort(model, k, x.x(), x.y()) - target;
    if (r.squaredNorm() < 1e-28) break;
    Eigen::Matrix2d J;
    for (int c = 0; c < 2; ++c) {
      const double h = std::max(1e-10, std::abs(x[c]) * 1e-6);
      Eigen::Vector2d xp = x, xm = x;
      xp[c] += h;
      xm[c] -= h;
      J.col(c) = (Distort(model, k, xp.x(), xp.y()) - Distort(model, k, xm.x(), xm.y())) / (2 * h);
    }
    const Eigen::Vector2d step = J.partialPivLu().solve(r);
    if (!step.allFinite()) break;
    x -= step;
  }
  return x;
}

}  // namespace mr
