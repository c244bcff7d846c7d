#pragma once

// Test-only helpers shared by the colmap_io tests: a temporary folder and a
// small sparse model that uses every COLMAP 3.8 camera model.

#include <atomic>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "colmap_io/sparse_model.h"
#include "util/testing.h"

namespace mr {
namespace test {

// A fresh, empty folder in the test process's scratch folder
// (util/testing.h), removed on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    static std::atomic<int> counter{0};
    path_ = MakeTestDir(tag + "_" + std::to_string(counter++));
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string Sub(const std::string& name) const {
    const std::string p = path_ + "/" + name;
    std::filesystem::create_directories(p);
    return p;
  }

 private:
  std::string path_;
};

// Realistic parameters of every model for a 640x480 image.
inline std::vector<double> RealisticParams(CameraModel model) {
  switch (model) {
    case CameraModel::kSimplePinhole: return {500, 320, 240};
    case CameraModel::kPinhole: return {500, 510, 321.5, 239.25};
    case CameraModel::kSimpleRadial: return {500, 320, 240, -0.05};
    case CameraModel::kRadial: return {500, 320, 240, -0.05, 0.01};
    case CameraModel::kOpenCV: return {500, 505, 320, 240, -0.1, 0.02, 0.001, -0.002};
    case CameraModel::kOpenCVFisheye: return {300, 300, 320, 240, 0.05, -0.01, 0.002, -0.0005};
    case CameraModel::kFullOpenCV:
      return {500, 505, 320, 240, -0.1, 0.02, 0.001, -0.002, 0.001, 0.01, -0.005, 0.001};
    case CameraModel::kFOV: return {400, 400, 320, 240, 0.9};
    case CameraModel::kSimpleRadialFisheye: return {300, 320, 240, 0.05};
    case CameraModel::kRadialFisheye: return {300, 320, 240, 0.05, -0.01};
    case CameraModel::kThinPrismFisheye:
      return {300, 302, 320, 240, 0.05, -0.01, 0.001, -0.001, 0.002, -0.0005, 0.001, -0.001};
  }
  return {};
}

// One camera per model (ids 1..11), one image per camera, a few points3D
// whose tracks are consistent with the images' points2D. Doubles use their
// full mantissa so precision loss shows up in round trips.
inline Reconstruction MakeModelWithAllCameraModels(uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1, 1);
  Reconstruction model;
  for (int m = 0; m <= 10; ++m) {
    Camera camera;
    camera.camera_id = m + 1;
    camera.model = static_cast<CameraModel>(m);
    camera.width = 640;
    camera.height = 480;
    camera.params = RealisticParams(camera.model);
    for (double& p : camera.params) p *= 1 + 1e-3 * uni(rng);
    model.cameras[camera.camera_id] = camera;

    Image image;
    image.image_id = 10 + m;
    Eigen::Vector4d q(1 + 0.2 * uni(rng), 0.2 * uni(rng), 0.2 * uni(rng), 0.2 * uni(rng));
    image.qvec = q.normalized();
    image.tvec = Eigen::Vector3d(uni(rng), uni(rng), 4 + uni(rng));
    image.camera_id = camera.camera_id;
    image.name = (m % 3 == 0 ? "sub/" : "") + std::string("img_") + std::to_string(m) + ".jpg";
    model.images[image.image_id] = image;
  }
  for (uint64_t pid = 1; pid <= 20; ++pid) {
    Point3D point;
    point.point3D_id = pid * 3;
    point.xyz = Eigen::Vector3d(uni(rng), uni(rng), uni(rng));
    point.rgb << uint8_t(pid * 10), uint8_t(255 - pid), uint8_t(pid * 7);
    point.error = 0.5 + 0.5 * uni(rng);
    for (auto& [image_id, image] : model.images) {
      if ((image_id + pid) % 3 != 0) continue;
      Point2D p;
      p.xy = Eigen::Vector2d(320 + 300 * uni(rng), 240 + 200 * uni(rng));
      p.point3D_id = static_cast<int64_t>(point.point3D_id);
      point.track.push_back({image_id, static_cast<uint32_t>(image.points2D.size())});
      image.points2D.push_back(p);
    }
    model.points3D[point.point3D_id] = point;
  }
  // Untriangulated observations.
  for (auto& [image_id, image] : model.images) {
    Point2D p;
    p.xy = Eigen::Vector2d(100 * uni(rng) + 200, 100 * uni(rng) + 200);
    image.points2D.push_back(p);
  }
  return model;
}

}  // namespace test
}  // namespace mr
