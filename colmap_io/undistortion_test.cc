#include "colmap_io/undistortion.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap_io/test_models.h"
#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

using test::TempDir;

TEST(UndistortionOptions, DefaultsAreValid) {
  EXPECT_TRUE(UndistortionOptions().Check());
  UndistortionOptions bad;
  bad.jpeg_quality = 0;
  EXPECT_THROW(bad.Check(), InputError);
}

Camera MakeCamera(CameraModel model, const std::vector<double>& params) {
  Camera camera;
  camera.camera_id = 1;
  camera.model = model;
  camera.width = 320;
  camera.height = 240;
  camera.params = params;
  return camera;
}

// Renders the distorted image of a Gaussian blob centred on the ray
// `n0` (normalized coordinates) exactly: each pixel samples the scene
// along its own back-projected ray.
cv::Mat RenderBlob(const Camera& camera, const Eigen::Vector2d& n0, double sigma_norm) {
  cv::Mat image(camera.height, camera.width, CV_8UC1);
  for (int row = 0; row < image.rows; ++row) {
    for (int col = 0; col < image.cols; ++col) {
      const Eigen::Vector2d n =
          CameraWorldFromImage(camera.model, camera.params, Eigen::Vector2d(col + 0.5, row + 0.5));
      const double d2 = (n - n0).squaredNorm() / (sigma_norm * sigma_norm);
      image.at<uint8_t>(row, col) = cv::saturate_cast<uint8_t>(255 * std::exp(-0.5 * d2));
    }
  }
  return image;
}

// Intensity-weighted centroid (COLMAP convention: pixel centres at +0.5) in a
// window around `guess`.
Eigen::Vector2d Centroid(const cv::Mat& image, const Eigen::Vector2d& guess, int radius) {
  double sw = 0, sx = 0, sy = 0;
  for (int row = int(guess.y()) - radius; row <= int(guess.y()) + radius; ++row) {
    for (int col = int(guess.x()) - radius; col <= int(guess.x()) + radius; ++col) {
      if (row < 0 || col < 0 || row >= image.rows || col >= image.cols) continue;
      const double w = image.at<uint8_t>(row, col);
      sw += w;
      sx += w * (col + 0.5);
      sy += w * (row + 0.5);
    }
  }
  return {sx / sw, sy / sw};
}

// A known 3-D point lands, after undistortion, where the PINHOLE camera
// predicts, for every distorted model.
TEST(Undistortion, KnownPointLandsOnPinholeProjection) {
  const std::vector<std::pair<CameraModel, std::vector<double>>> cameras = {
      {CameraModel::kSimpleRadial, {250, 160, 120, -0.08}},
      {CameraModel::kRadial, {250, 160, 120, -0.08, 0.02}},
      {CameraModel::kOpenCV, {250, 255, 161, 119, -0.1, 0.02, 0.002, -0.003}},
      {CameraModel::kOpenCVFisheye, {200, 202, 160, 120, 0.05, -0.01, 0.002, -0.0005}},
      {CameraModel::kFullOpenCV,
       {250, 255, 161, 119, -0.1, 0.02, 0.002, -0.003, 0.001, 0.01, -0.005, 0.001}},
      {CameraModel::kFOV, {200, 200, 160, 120, 2.2}},
      {CameraModel::kSimpleRadialFisheye, {200, 160, 120, 0.05}},
      {CameraModel::kRadialFisheye, {200, 160, 120, 0.05, -0.01}},
      {CameraModel::kThinPrismFisheye,
       {200, 202, 160, 120, 0.05, -0.01, 0.001, -0.001, 0.002, -0.0005, 0.001, -0.001}},
  };
  const Eigen::Vector3d X(0.9, -0.55, 2.0);  // camera frame
  const Eigen::Vector2d n0 = X.head<2>() / X.z();
  double max_error = 0;
  for (const auto& [model, params] : cameras) {
    const Camera camera = MakeCamera(model, params);
    const Camera pinhole = UndistortedCamera(camera);
    ASSERT_EQ(pinhole.model, CameraModel::kPinhole);
    const Eigen::Vector2d expected = CameraImageFromWorld(pinhole.model, pinhole.params, n0);
    const Eigen::Vector2d distorted = CameraImageFromWorld(model, params, n0);
    // The test only means something if the distortion moves the point.
    EXPECT_GT((distorted - expected).norm(), 2.0) << CameraModelName(model);

    const double sigma = 2.5 / params[0];
    const cv::Mat image = RenderBlob(camera, n0, sigma);
    EXPECT_LT((Centroid(image, distorted, 12) - distorted).norm(), 0.5) << CameraModelName(model);
    const cv::Mat undistorted = UndistortImage(image, camera, cv::INTER_LINEAR);
    const Eigen::Vector2d found = Centroid(undistorted, expected, 12);
    EXPECT_LT((found - expected).norm(), 0.25)
        << CameraModelName(model) << " found " << found.transpose() << " expected "
        << expected.transpose();
    max_error = std::max(max_error, (found - expected).norm());
  }
  std::cout << "max undistorted point error: " << max_error << " px\n";
}

// Distortion that sends most of the undistorted image outside the distorted
// one (the refinement would compare black images and "finish" at similarity
// 0) is refused, naming the camera and the parameter to blame.
TEST(Undistortion, RefusesImplausibleDistortion) {
  const std::vector<std::pair<Camera, std::string>> cases = {
      {MakeCamera(CameraModel::kOpenCV, {250, 250, 160, 120, 5, 0, 0, 0}), "k1 = 5"},
      {MakeCamera(CameraModel::kRadial, {250, 160, 120, 240, 0}), "k1 = 240"},
      {MakeCamera(CameraModel::kSimpleRadial, {250, 160, 120, 30}), "k = 30"},
  };
  for (const auto& [camera, parameter] : cases) {
    cv::Mat mx, my;
    try {
      ComputeUndistortionMaps(camera, &mx, &my);
      ADD_FAILURE() << CameraModelName(camera.model) << ": no InputError";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("camera 1 (" + CameraModelName(camera.model)), std::string::npos) << what;
      EXPECT_NE(what.find("implausible distortion parameter " + parameter), std::string::npos)
          << what;
      EXPECT_NE(what.find("would sample outside the distorted image"), std::string::npos) << what;
    }
  }
  // Strong but plausible pincushion and barrel distortion pass.
  cv::Mat mx, my;
  ComputeUndistortionMaps(MakeCamera(CameraModel::kOpenCV, {250, 250, 160, 120, 0.3, 0, 0, 0}),
                          &mx, &my);
  ComputeUndistortionMaps(MakeCamera(CameraModel::kOpenCV, {250, 250, 160, 120, -0.3, 0, 0, 0}),
                          &mx, &my);
}

TEST(Undistortion, RefusesFoldingDistortion) {
  // k1 = -1.5 makes x(1 + k1 r^2) fold back inside the image.
  const Camera camera = MakeCamera(CameraModel::kOpenCV, {250, 250, 160, 120, -1.5, 0, 0, 0});
  cv::Mat mx, my;
  try {
    ComputeUndistortionMaps(camera, &mx, &my);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("camera 1 (OPENCV, k1 = -1.5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("folds"), std::string::npos) << e.what();
  }
}

TEST(Undistortion, SparseProjectToDenseWorkspace) {
  TempDir dir("undistort_project");
  const std::string images = dir.Sub("images"), masks = dir.Sub("masks");
  dir.Sub("images/sub");
  Reconstruction model;
  const Camera camera =
      MakeCamera(CameraModel::kOpenCV, {250, 255, 161, 119, -0.1, 0.02, 0.002, -0.003});
  model.cameras[1] = camera;
  const Eigen::Vector3d X(0.9, -0.55, 2.0);
  const Eigen::Vector2d n0 = X.head<2>() / X.z();
  const char* names[] = {"a.png", "sub/b.png"};
  for (uint32_t id = 1; id <= 2; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = names[id - 1];
    Point2D p;
    p.xy = CameraImageFromWorld(camera.model, camera.params, n0);
    p.point3D_id = 5;
    image.points2D.push_back(p);
    model.images[id] = image;
    ASSERT_TRUE(cv::imwrite(images + "/" + image.name, RenderBlob(camera, n0, 2.5 / 250)));
  }
  Point3D point;
  point.point3D_id = 5;
  point.xyz = X;
  point.track = {{1, 0}, {2, 0}};
  model.points3D[5] = point;
  cv::Mat mask(240, 320, CV_8UC1, cv::Scalar(255));
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", mask));

  const std::string out = dir.path() + "/dense";
  const UndistortionSummary summary = UndistortSparseModel(images, masks, model, out);
  EXPECT_EQ(summary.num_images, 2);
  EXPECT_EQ(summary.num_masks, 1);
  EXPECT_TRUE(ExistsFile(out + "/" + kUndistortionMarker));
  EXPECT_FALSE(ExistsFile(out + "/" + kUndistortionPartialMarker));
  const Reconstruction dense = ReadSparseModelBinary(out + "/sparse");
  ASSERT_EQ(dense.cameras.at(1).model, CameraModel::kPinhole);
  EXPECT_EQ(dense.cameras.at(1).params, (std::vector<double>{250, 255, 161, 119}));
  EXPECT_EQ(dense.cameras.at(1).width, 320u);
  const Eigen::Vector2d expected =
      CameraImageFromWorld(CameraModel::kPinhole, dense.cameras.at(1).params, n0);
  for (uint32_t id = 1; id <= 2; ++id) {
    // 2-D points move to the pinhole projection.
    EXPECT_LT((dense.images.at(id).points2D[0].xy - expected).norm(), 1e-6);
    const cv::Mat u = cv::imread(out + "/images/" + names[id - 1], cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(u.empty());
    EXPECT_LT((Centroid(u, expected, 12) - expected).norm(), 0.25);
  }
  EXPECT_EQ(dense.points3D.at(5).xyz, X);
  // The mask: the corners of the barrel-distorted image see outside the
  // source and become background; the centre stays foreground.
  const cv::Mat m = cv::imread(out + "/masks/a.png.png", cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.at<uint8_t>(120, 160), 255);
  EXPECT_FALSE(ExistsFile(out + "/masks/sub/b.png.png"));
}

TEST(Undistortion, WrongImageSize) {
  TempDir dir("undistort_size");
  const std::string images = dir.Sub("images");
  Reconstruction model;
  model.cameras[1] = MakeCamera(CameraModel::kSimpleRadial, {250, 160, 120, -0.08});
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "a.png";
  model.images[1] = image;
  ASSERT_TRUE(cv::imwrite(images + "/a.png", cv::Mat(100, 100, CV_8UC1, cv::Scalar(0))));
  try {
    UndistortSparseModel(images, "", model, dir.path() + "/out");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("100x100"), std::string::npos) << e.what();
  }
}

// Independent check: COLMAP's own image_undistorter (scale fixed to 1, so it
// keeps size, focal lengths and principal point) produces the same images
// and 2-D points from the same distorted project.
TEST(Undistortion, MatchesColmapImageUndistorter) {
  if (std::string(MR_COLMAP_EXECUTABLE).empty()) GTEST_SKIP() << "colmap not found";
  TempDir dir("undistort_colmap");
  const std::string images = dir.Sub("images"), sparse = dir.Sub("sparse");
  const std::vector<std::pair<CameraModel, std::vector<double>>> cameras = {
      {CameraModel::kOpenCV, {250, 255, 165.5, 117.25, -0.1, 0.02, 0.002, -0.003}},
      {CameraModel::kOpenCVFisheye, {200, 202, 158, 122, 0.05, -0.01, 0.002, -0.0005}},
      {CameraModel::kFullOpenCV,
       {250, 255, 161, 119, -0.1, 0.02, 0.002, -0.003, 0.001, 0.01, -0.005, 0.001}},
      {CameraModel::kThinPrismFisheye,
       {200, 202, 160, 120, 0.05, -0.01, 0.001, -0.001, 0.002, -0.0005, 0.001, -0.001}},
  };
  Reconstruction model;
  cv::RNG rng(11);
  for (size_t i = 0; i < cameras.size(); ++i) {
    Camera camera = MakeCamera(cameras[i].first, cameras[i].second);
    camera.camera_id = static_cast<uint32_t>(i + 1);
    model.cameras[camera.camera_id] = camera;
    Image image;
    image.image_id = camera.camera_id;
    image.camera_id = camera.camera_id;
    image.name = "img" + std::to_string(i) + ".png";
    image.tvec = Eigen::Vector3d(0.1 * i, 0, 0);
    Point2D p;
    p.xy = Eigen::Vector2d(30.25 + 20 * i, 200.5 - 10 * i);
    image.points2D.push_back(p);
    model.images[image.image_id] = image;
    // A smooth random texture.
    cv::Mat noise(240, 320, CV_32FC3), texture;
    rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
    cv::GaussianBlur(noise, texture, cv::Size(0, 0), 2.0);
    cv::normalize(texture, texture, 0, 255, cv::NORM_MINMAX);
    texture.convertTo(texture, CV_8UC3);
    ASSERT_TRUE(cv::imwrite(images + "/" + image.name, texture));
  }
  WriteSparseModelBinary(sparse, model);
  const std::string ours = dir.path() + "/ours", theirs = dir.path() + "/theirs";
  UndistortSparseModel(images, "", model, ours);
  const std::string cmd = std::string("QT_QPA_PLATFORM=offscreen ") + MR_COLMAP_EXECUTABLE +
                          " image_undistorter --image_path " + images + " --input_path " +
                          sparse + " --output_path " + theirs +
                          " --min_scale 1 --max_scale 1 > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const Reconstruction a = ReadSparseModelBinary(ours + "/sparse");
  const Reconstruction b = ReadSparseModel(theirs + "/sparse");
  for (const auto& [id, image] : a.images) {
    const Camera& ca = a.cameras.at(image.camera_id);
    const Camera& cb = b.cameras.at(b.images.at(id).camera_id);
    ASSERT_EQ(cb.width, ca.width);
    ASSERT_EQ(cb.height, ca.height);
    EXPECT_NEAR(CameraFocalX(cb.model, cb.params), ca.params[0], 1e-9);
    EXPECT_NEAR(CameraFocalY(cb.model, cb.params), ca.params[1], 1e-9);
    EXPECT_NEAR(CameraPrincipalX(cb.model, cb.params), ca.params[2], 1e-9);
    EXPECT_NEAR(CameraPrincipalY(cb.model, cb.params), ca.params[3], 1e-9);
    EXPECT_LT((image.points2D[0].xy - b.images.at(id).points2D[0].xy).norm(), 1e-6);
    const cv::Mat ia = cv::imread(ours + "/images/" + image.name, cv::IMREAD_COLOR);
    const cv::Mat ib = cv::imread(theirs + "/images/" + image.name, cv::IMREAD_COLOR);
    ASSERT_EQ(ia.size(), ib.size());
    const cv::Rect inner(10, 10, ia.cols - 20, ia.rows - 20);
    cv::Mat diff;
    cv::absdiff(ia(inner), ib(inner), diff);
    const cv::Scalar mean = cv::mean(diff);
    double max_diff = 0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
    const std::string what = CameraModelName(model.cameras.at(image.camera_id).model);
    EXPECT_LT((mean[0] + mean[1] + mean[2]) / 3, 0.25) << what;
    EXPECT_LE(max_diff, 2) << what;
    std::cout << what << ": mean |ours - colmap| " << (mean[0] + mean[1] + mean[2]) / 3
              << ", max " << max_diff << " gray levels\n";
  }
}

TEST(Undistortion, RefusesEscapingImageNames) {
  TempDir dir("undistort_names");
  Reconstruction model;
  model.cameras[1] = MakeCamera(CameraModel::kSimpleRadial, {250, 160, 120, -0.08});
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  for (const std::string name : {"../evil.png", "/abs.png", "a/../../b.png"}) {
    image.name = name;
    model.images[1] = image;
    try {
      UndistortSparseModel(dir.path(), "", model, dir.path() + "/out");
      ADD_FAILURE() << "no InputError for " << name;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(ExistsDir(dir.path() + "/out"));
}

}  // namespace
}  // namespace mr
