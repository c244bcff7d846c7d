#include "colmap_io/camera_models.h"

#include <cmath>

#include <gtest/gtest.h>

#include "colmap_io/test_models.h"
#include "util/error.h"

namespace mr {
namespace {

using test::RealisticParams;

TEST(CameraModels, NamesRoundTrip) {
  for (int id = 0; id <= 10; ++id) {
    const CameraModel model = static_cast<CameraModel>(id);
    EXPECT_TRUE(IsKnownCameraModelId(id));
    EXPECT_EQ(CameraModelFromName(CameraModelName(model)), model);
    EXPECT_EQ(CameraModelNumParams(model), static_cast<int>(RealisticParams(model).size()));
  }
  EXPECT_FALSE(IsKnownCameraModelId(11));
  EXPECT_FALSE(IsKnownCameraModelId(-1));
  EXPECT_THROW(CameraModelName(static_cast<CameraModel>(11)), InputError);
  EXPECT_THROW(CameraModelFromName("RAD_TAN_THIN_PRISM_FISHEYE"), InputError);
  EXPECT_TRUE(IsPinholeModel(CameraModel::kPinhole));
  EXPECT_TRUE(IsPinholeModel(CameraModel::kSimplePinhole));
  EXPECT_FALSE(IsPinholeModel(CameraModel::kSimpleRadial));
}

TEST(CameraModels, ParamNames) {
  for (int id = 0; id <= 10; ++id) {
    const CameraModel model = static_cast<CameraModel>(id);
    EXPECT_EQ(static_cast<int>(CameraModelParamNames(model).size()), CameraModelNumParams(model));
  }
  EXPECT_EQ(CameraModelParamNames(CameraModel::kOpenCV),
            (std::vector<std::string>{"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}));
  EXPECT_EQ(CameraModelParamNames(CameraModel::kRadial)[3], "k1");
  EXPECT_EQ(CameraModelNumDistortionParams(CameraModel::kRadial), 2);
  EXPECT_EQ(CameraModelNumDistortionParams(CameraModel::kPinhole), 0);
  EXPECT_EQ(CameraModelNumDistortionParams(CameraModel::kThinPrismFisheye), 8);
}

TEST(CameraModels, FocalAndPrincipalPoint) {
  const std::vector<double> p = {500, 510, 321.5, 239.25};
  EXPECT_EQ(CameraFocalX(CameraModel::kPinhole, p), 500);
  EXPECT_EQ(CameraFocalY(CameraModel::kPinhole, p), 510);
  EXPECT_EQ(CameraPrincipalX(CameraModel::kPinhole, p), 321.5);
  EXPECT_EQ(CameraPrincipalY(CameraModel::kPinhole, p), 239.25);
  const std::vector<double> s = {400, 30, 20, 0.1};
  EXPECT_EQ(CameraFocalY(CameraModel::kSimpleRadial, s), 400);
  EXPECT_EQ(CameraPrincipalX(CameraModel::kSimpleRadial, s), 30);
}

// Hand-evaluated COLMAP equations for a few models.
TEST(CameraModels, KnownValues) {
  const double u = 0.2, v = -0.1, r2 = u * u + v * v;
  {
    const std::vector<double> p = {400, 300, 200, 0.1};
    const Eigen::Vector2d x = CameraImageFromWorld(CameraModel::kSimpleRadial, p, {u, v});
    EXPECT_NEAR(x.x(), 400 * u * (1 + 0.1 * r2) + 300, 1e-12);
    EXPECT_NEAR(x.y(), 400 * v * (1 + 0.1 * r2) + 200, 1e-12);
  }
  {
    const std::vector<double> p = {400, 410, 300, 200, -0.1, 0.02, 0.001, -0.002};
    const double radial = 1 - 0.1 * r2 + 0.02 * r2 * r2;
    const double xd = u * radial + 2 * 0.001 * u * v + -0.002 * (r2 + 2 * u * u);
    const double yd = v * radial + 2 * -0.002 * u * v + 0.001 * (r2 + 2 * v * v);
    const Eigen::Vector2d x = CameraImageFromWorld(CameraModel::kOpenCV, p, {u, v});
    EXPECT_NEAR(x.x(), 400 * xd + 300, 1e-12);
    EXPECT_NEAR(x.y(), 410 * yd + 200, 1e-12);
  }
  {
    const std::vector<double> p = {400, 410, 300, 200, 0.05, -0.01, 0.002, -0.0005};
    const double r = std::sqrt(r2), th = std::atan(r), t2 = th * th;
    const double thd = th * (1 + 0.05 * t2 - 0.01 * t2 * t2 + 0.002 * t2 * t2 * t2 -
                             0.0005 * t2 * t2 * t2 * t2);
    const Eigen::Vector2d x = CameraImageFromWorld(CameraModel::kOpenCVFisheye, p, {u, v});
    EXPECT_NEAR(x.x(), 400 * u * thd / r + 300, 1e-12);
    EXPECT_NEAR(x.y(), 410 * v * thd / r + 200, 1e-12);
  }
  {
    const double omega = 0.9;
    const std::vector<double> p = {400, 410, 300, 200, omega};
    const double r = std::sqrt(r2);
    const double factor = std::atan(r * 2 * std::tan(omega / 2)) / (r * omega);
    const Eigen::Vector2d x = CameraImageFromWorld(CameraModel::kFOV, p, {u, v});
    EXPECT_NEAR(x.x(), 400 * u * factor + 300, 1e-12);
    EXPECT_NEAR(x.y(), 410 * v * factor + 200, 1e-12);
  }
}

// CameraWorldFromImage inverts CameraImageFromWorld over the whole image for
// every model, and the other way round.
TEST(CameraModels, WorldFromImageInvertsImageFromWorld) {
  for (int id = 0; id <= 10; ++id) {
    const CameraModel model = static_cast<CameraModel>(id);
    const std::vector<double> params = RealisticParams(model);
    double max_err_px = 0, max_err_norm = 0;
    for (double x = 0; x <= 640; x += 32) {
      for (double y = 0; y <= 480; y += 24) {
        const Eigen::Vector2d pixel(x, y);
        const Eigen::Vector2d n = CameraWorldFromImage(model, params, pixel);
        ASSERT_TRUE(n.allFinite()) << CameraModelName(model);
        const Eigen::Vector2d back = CameraImageFromWorld(model, params, n);
        max_err_px = std::max(max_err_px, (back - pixel).norm());
        const Eigen::Vector2d n2 = CameraWorldFromImage(model, params, back);
        max_err_norm = std::max(max_err_norm, (n2 - n).norm());
      }
    }
    EXPECT_LT(max_err_px, 1e-8) << CameraModelName(model);
    EXPECT_LT(max_err_norm, 1e-10) << CameraModelName(model);
  }
}

TEST(CameraModels, PrincipalPointIsFixed) {
  for (int id = 0; id <= 10; ++id) {
    const CameraModel model = static_cast<CameraModel>(id);
    const std::vector<double> params = RealisticParams(model);
    const Eigen::Vector2d c = CameraImageFromWorld(model, params, Eigen::Vector2d::Zero());
    EXPECT_NEAR(c.x(), CameraPrincipalX(model, params), 1e-12) << CameraModelName(model);
    EXPECT_NEAR(c.y(), CameraPrincipalY(model, params), 1e-12) << CameraModelName(model);
  }
}

}  // namespace
}  // namespace mr
