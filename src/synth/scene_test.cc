#include "synth/scene.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "synth/synth_test_util.h"
#include "util/error.h"

namespace mr {
namespace {

using testing_util::CoarseScene;
using testing_util::PointMeshDistance;

std::vector<PinholeView> SmallRing(const SynthScene& scene, int width = 160, int height = 120) {
  CameraRigOptions rig;
  rig.num_views = 6;
  rig.width = width;
  rig.height = height;
  return MakeCameras(rig, scene.V.rowwise().norm().maxCoeff());
}

TEST(CameraRigOptions, DefaultsAreValid) { EXPECT_TRUE(CameraRigOptions().Check()); }
TEST(DepthNoiseOptions, DefaultsAreValid) { EXPECT_TRUE(DepthNoiseOptions().Check()); }

TEST(CameraRigOptions, RejectsBadValues) {
  CameraRigOptions rig;
  rig.layout = "spiral";
  EXPECT_THROW(rig.Check(), InputError);
  rig = CameraRigOptions();
  rig.num_views = 1;
  EXPECT_THROW(rig.Check(), InputError);
}

TEST(MakeCameras, RingLooksAtCentreAtElevation) {
  CameraRigOptions rig;
  const std::vector<PinholeView> views = MakeCameras(rig, 40.0);
  ASSERT_EQ(views.size(), 16u);
  for (const PinholeView& v : views) {
    EXPECT_NEAR((v.R * v.R.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
    EXPECT_NEAR(v.R.determinant(), 1, 1e-12);
    const Eigen::Vector2d o = v.Project(Eigen::Vector3d::Zero());
    EXPECT_NEAR(o.x(), 320, 1e-9);
    EXPECT_NEAR(o.y(), 240, 1e-9);
    const Eigen::Vector3d c = v.Center();
    EXPECT_NEAR(std::asin(c.z() / c.norm()) * 180 / M_PI, 30, 1e-9);
    // World up (+z) points up in the image (negative image y).
    EXPECT_LT(v.Project(Eigen::Vector3d(0, 0, 10)).y(), 240);
    // The bounding sphere fills fill_fraction of the height: the tangent ray
    // makes angle alpha with the axis, tan(alpha) * f = 0.35 * height.
    const double alpha = std::asin(40.0 / c.norm());
    EXPECT_NEAR(std::tan(alpha) * v.fy, 0.5 * rig.fill_fraction * 480, 1e-6);
  }
}

TEST(MakeCameras, AlternateFillFractionPutsTheOddViewsAtAnotherDistance) {
  CameraRigOptions rig;
  rig.fill_fraction = 0.45;
  rig.alternate_fill_fraction = 0.9;
  const std::vector<PinholeView> views = MakeCameras(rig, 40.0);
  for (size_t i = 0; i < views.size(); ++i) {
    const double alpha = std::asin(40.0 / views[i].Center().norm());
    EXPECT_NEAR(std::tan(alpha) * views[i].fy, 0.5 * (i % 2 == 0 ? 0.45 : 0.9) * 480, 1e-6) << i;
  }
  // About twice as far: the far views' pixels cover about twice the surface.
  EXPECT_NEAR(views[0].Center().norm() / views[1].Center().norm(), 2.0, 0.1);
  // Close-ups that see only the middle of the object: the bounding sphere
  // fills 1.5 times the image height, from outside it.
  rig.alternate_fill_fraction = 1.5;
  const std::vector<PinholeView> closeups = MakeCameras(rig, 40.0);
  EXPECT_NEAR(std::tan(std::asin(40.0 / closeups[1].Center().norm())) * closeups[1].fy,
              0.5 * 1.5 * 480, 1e-6);
  EXPECT_GT(closeups[1].Center().norm(), 40.0);
  rig.alternate_fill_fraction = 3.5;
  EXPECT_THROW(MakeCameras(rig, 40.0), InputError);
}

TEST(MakeCameras, HemisphereSpreadsElevations) {
  CameraRigOptions rig;
  rig.layout = "hemisphere";
  rig.num_views = 20;
  const std::vector<PinholeView> views = MakeCameras(rig, 40.0);
  double lo = 90, hi = -90;
  for (const PinholeView& v : views) {
    const Eigen::Vector3d c = v.Center();
    const double el = std::asin(c.z() / c.norm()) * 180 / M_PI;
    lo = std::min(lo, el);
    hi = std::max(hi, el);
  }
  EXPECT_GE(lo, rig.min_elevation_deg);
  EXPECT_LE(hi, rig.max_elevation_deg);
  EXPECT_GT(hi - lo, 40);
}

TEST(RenderImage, NonBlackExactlyWhereObjectProjects) {
  const SynthScene scene = CoarseScene();
  const std::vector<PinholeView> views = SmallRing(scene);
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  for (const PinholeView& view : views) {
    const SynthImage image = RenderImage(renderer, scene, view, 3);
    int covered = 0, vertex_hits = 0, vertex_total = 0;
    ASSERT_EQ(image.radiance.size(), 3 * image.coverage.size());
    for (size_t i = 0; i < image.coverage.size(); ++i) {
      for (int c = 0; c < 3; ++c) {
        if (image.coverage[i] == 0) {
          ASSERT_EQ(image.radiance[3 * i + c], 0.f);
        } else {
          ASSERT_GT(image.radiance[3 * i + c], 0.f);
        }
      }
      if (image.coverage[i] > 0) ++covered;
    }
    EXPECT_GT(covered, 0.1 * image.coverage.size());
    for (int v = 0; v < scene.V.rows(); ++v) {
      const Eigen::Vector2d p = view.Project(scene.V.row(v).transpose());
      if (!view.InImage(p)) continue;
      ++vertex_total;
      const size_t idx = static_cast<size_t>(p.y()) * image.width + static_cast<size_t>(p.x());
      if (image.coverage[idx] > 0) ++vertex_hits;
    }
    EXPECT_GT(vertex_hits, 0.99 * vertex_total);
  }
}

// The image at pixel (col, row) must show the texture-predicted radiance of
// the surface point seen through the pixel centre (col + 0.5, row + 0.5),
// found by an independent CPU ray cast. A one-pixel shift must be detectably
// worse. The colour texture lit by the headlight must match as well, in
// every channel (a swapped channel or a light from elsewhere would not).
TEST(RenderImage, PixelsMatchTexturePrediction) {
  for (const std::string style : {"contrast", "smooth_color"}) {
    SynthScene scene = CoarseScene();
    scene.appearance.texture_style = style;
    if (style == "contrast") {
      scene.appearance.texture_scale = 2.5;  // features of several pixels at 320x240
    } else {
      scene.appearance.texture_scale = 0.3;  // smooth_color's periods are 8-16x longer
      scene.appearance.light = "headlight";
    }
    const std::vector<PinholeView> views = SmallRing(scene, 320, 240);
    Renderer renderer;
    renderer.SetMesh(scene.V, scene.F);
    const PinholeView& view = views[1];
    const SynthImage image = RenderImage(renderer, scene, view, 3);
    const RenderBuffers ref = RenderCpu(scene.V, scene.F, view);
    double err = 0, err_shift = 0;
    int n = 0;
    for (int row = 1; row + 1 < view.height; ++row) {
      for (int col = 1; col + 2 < view.width; ++col) {
        const size_t idx = static_cast<size_t>(row) * view.width + col;
        if (image.coverage[idx] < 1 || image.coverage[idx + 1] < 1) continue;
        const std::optional<Eigen::Vector3d> predicted =
            ShadeBufferPixel(scene, ref, idx, view.Center());
        ASSERT_TRUE(predicted.has_value());
        for (int c = 0; c < 3; ++c) {
          err += std::abs(image.radiance[3 * idx + c] - (*predicted)(c)) / 3;
          err_shift += std::abs(image.radiance[3 * (idx + 1) + c] - (*predicted)(c)) / 3;
        }
        ++n;
      }
    }
    ASSERT_GT(n, 1000);
    err /= n;
    err_shift /= n;
    EXPECT_LT(err, 0.02) << style << ": mean |image - prediction| (radiance in [0, 1])";
    EXPECT_GT(err_shift, 2 * err) << style;
  }
}

// A 200 x 200 square in the plane z = 0, normal +z, filling the view from
// (0, 0, 100) straight down, whose optical axis passes through the centre of
// pixel (32, 24).
TEST(RenderImage, HeadlightFullyLightsAPatchFacingTheCamera) {
  SynthScene scene;
  scene.V.resize(4, 3);
  scene.V << -100, -100, 0, 100, -100, 0, 100, 100, 0, -100, 100, 0;
  scene.F.resize(2, 3);
  scene.F << 0, 1, 2, 0, 2, 3;
  scene.face_normals = FaceNormals(scene.V, scene.F);
  ASSERT_NEAR(scene.face_normals(0, 2), 1, 1e-12);
  scene.appearance.texture_style = "none";
  scene.appearance.ambient = 0.25;
  scene.appearance.light = "headlight";
  PinholeView view;
  view.width = 64;
  view.height = 48;
  view.fx = view.fy = 60;
  view.cx = 32.5;
  view.cy = 24.5;
  view.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Eigen::Vector3d eye(0, 0, 100);
  view.t = -view.R * eye;
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  const SynthImage image = RenderImage(renderer, scene, view, 1);
  const auto radiance = [&](int row, int col) {
    const size_t i = static_cast<size_t>(row) * view.width + col;
    EXPECT_EQ(image.coverage[i], 1.f);
    return Eigen::Vector3d(image.radiance[3 * i], image.radiance[3 * i + 1],
                           image.radiance[3 * i + 2]);
  };
  const AppearanceOptions& a = scene.appearance;
  const Eigen::Vector3d centre = radiance(24, 32);
  const Eigen::Vector3d albedo = Albedo(a, Eigen::Vector3d::Zero());
  EXPECT_NEAR((centre - albedo * (a.ambient + (1 - a.ambient) * 1)).cwiseAbs().maxCoeff(), 0,
              1e-6);
  // Off the axis the directional share falls with the cosine of the angle
  // between the normal and the direction to the camera.
  for (const auto& [row, col] : {std::pair(2, 3), std::pair(40, 60), std::pair(10, 50)}) {
    const Eigen::Vector3d ray = view.RayDirection(col + 0.5, row + 0.5);
    const Eigen::Vector3d p = eye + (-eye.z() / ray.z()) * ray;
    const double cosine = (eye - p).normalized().z();
    ASSERT_LT(cosine, 0.95);
    EXPECT_NEAR(
        (radiance(row, col) - Albedo(a, p) * (a.ambient + (1 - a.ambient) * cosine))
            .cwiseAbs()
            .maxCoeff(),
        0, 1e-5)
        << row << " " << col;
  }
  // The world light (0.4, -0.3, 1) does not light it fully.
  scene.appearance.light = "world";
  const SynthImage world = RenderImage(renderer, scene, view, 1);
  const size_t i = 24 * 64 + 32;
  EXPECT_LT(world.radiance[3 * i], centre(0) - 0.02);
}

// White noise of the requested level, ignoring pixels it could clip;
// reproducible from (seed, view index).
TEST(AddImageNoise, HasRequestedLevelAndIsDeterministic) {
  const SynthScene scene = CoarseScene();
  const std::vector<PinholeView> views = SmallRing(scene);
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  const SynthImage clean = RenderImage(renderer, scene, views[0], 2);
  for (const double sigma : {0.01, 0.04}) {
    SynthImage noisy = clean;
    AddImageNoise(sigma, 5, 0, &noisy);
    ASSERT_EQ(noisy.radiance.size(), clean.radiance.size());
    double sum = 0, sum2 = 0;
    int n = 0;
    for (size_t i = 0; i < clean.radiance.size(); ++i) {
      ASSERT_GE(noisy.radiance[i], 0.f);
      ASSERT_LE(noisy.radiance[i], 1.f);
      if (clean.radiance[i] < 4 * sigma || clean.radiance[i] > 1 - 4 * sigma) continue;
      const double d = noisy.radiance[i] - clean.radiance[i];
      sum += d;
      sum2 += d * d;
      ++n;
    }
    ASSERT_GT(n, 5000);
    const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
    EXPECT_NEAR(sd, sigma, 0.1 * sigma);
    EXPECT_NEAR(mean, 0, 0.1 * sigma);
  }
  SynthImage a = clean, b = clean, c = clean, zero = clean;
  AddImageNoise(0.02, 5, 0, &a);
  AddImageNoise(0.02, 5, 0, &b);
  AddImageNoise(0.02, 5, 1, &c);
  AddImageNoise(0, 5, 0, &zero);
  EXPECT_EQ(a.radiance, b.radiance);
  EXPECT_NE(a.radiance, c.radiance);
  EXPECT_EQ(zero.radiance, clean.radiance);
}

// One gain per view, log-normal with the requested spread, reproducible from
// (seed, view index), applied to every channel and clipped at 1.
TEST(ApplyExposureJitter, ScalesEachViewByItsOwnGain) {
  SynthImage image;
  image.width = 4;
  image.height = 1;
  image.coverage.assign(4, 1.f);
  image.radiance = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.05f, 0.15f, 0.25f, 0.35f, 0.45f, 0.9f};
  SynthImage a = image, b = image, zero = image;
  const double gain = ApplyExposureJitter(0.2, 3, 7, &a);
  EXPECT_EQ(ApplyExposureJitter(0.2, 3, 7, &b), gain);
  EXPECT_EQ(a.radiance, b.radiance);
  EXPECT_EQ(ApplyExposureJitter(0, 3, 7, &zero), 1.0);
  EXPECT_EQ(zero.radiance, image.radiance);
  for (size_t i = 0; i < image.radiance.size(); ++i) {
    EXPECT_FLOAT_EQ(a.radiance[i], std::min(1.0, image.radiance[i] * gain)) << i;
  }
  // The log-gains of many views have the requested spread and no bias.
  double sum = 0, sum2 = 0;
  const int n = 4000;
  for (int view = 0; view < n; ++view) {
    SynthImage copy = image;
    const double log_gain = std::log(ApplyExposureJitter(0.2, 3, view, &copy));
    sum += log_gain;
    sum2 += log_gain * log_gain;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(sd, 0.2, 0.01);
  EXPECT_NEAR(mean, 0, 0.015);
}

// The fall-off is 1 at the centre, 1 - strength at the corners, quadratic in
// the distance between, the same for every channel; strength 0 changes
// nothing.
TEST(ApplyVignetting, DarkensTowardsTheCornersQuadratically) {
  SynthImage image;
  image.width = 5;
  image.height = 3;
  image.coverage.assign(15, 1.f);
  image.radiance.assign(45, 0.8f);
  SynthImage zero = image;
  ApplyVignetting(0, &zero);
  EXPECT_EQ(zero.radiance, image.radiance);
  SynthImage dark = image;
  const double strength = 0.4;
  ApplyVignetting(strength, &dark);
  auto value = [&](int row, int col, int c) { return dark.radiance[3 * (row * 5 + col) + c]; };
  for (int c = 0; c < 3; ++c) {
    EXPECT_FLOAT_EQ(value(1, 2, c), 0.8f);  // the centre
    for (const auto& [row, col] : {std::pair{0, 0}, {0, 4}, {2, 0}, {2, 4}}) {
      EXPECT_FLOAT_EQ(value(row, col, c), static_cast<float>(0.8 * (1 - strength)));
    }
    // (1, 0): r^2 = 4 of the corner's 5.
    EXPECT_FLOAT_EQ(value(1, 0, c), static_cast<float>(0.8 * (1 - strength * 4 / 5)));
  }
  // Darker the farther out, along a row from the centre.
  EXPECT_GT(value(1, 2, 0), value(1, 3, 0));
  EXPECT_GT(value(1, 3, 0), value(1, 4, 0));
}

// The backdrop shows through in proportion to what the object leaves
// uncovered: all of it on the background, none on the object, half on a
// half-covered outline pixel.
TEST(ApplyBackground, BlendsTheBackdropByCoverage) {
  SynthImage image;
  image.width = 3;
  image.height = 1;
  image.coverage = {0.f, 0.5f, 1.f};
  image.radiance = {0, 0, 0, 0.2f, 0.3f, 0.4f, 0.6f, 0.7f, 0.8f};  // premultiplied by coverage
  SynthImage black = image;
  ApplyBackground(0, &black);
  EXPECT_EQ(black.radiance, image.radiance);
  ApplyBackground(0.5, &image);
  const std::vector<float> expected = {0.5f, 0.5f, 0.5f, 0.45f, 0.55f, 0.65f, 0.6f, 0.7f, 0.8f};
  for (int k = 0; k < 9; ++k) EXPECT_FLOAT_EQ(image.radiance[k], expected[k]) << k;
}

TEST(RenderDenseMaps, DepthPixelsBackProjectOntoSurfaceWithDenseConvention) {
  const SynthScene scene = CoarseScene();
  const std::vector<PinholeView> views = SmallRing(scene);
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  DepthNoiseOptions exact;
  exact.depth_noise = 0;
  exact.correlated_noise = 0;
  exact.depth_blur_px = 0;
  exact.outlier_fraction = 0;
  exact.normal_noise = 0;
  const PinholeView& view = views[2];
  const DenseMaps maps = RenderDenseMaps(renderer, scene, view, exact, 1);
  ASSERT_EQ(maps.depth.width, view.width);
  ASSERT_EQ(maps.normal.channels, 3);
  double max_dist = 0, sum_dist_sparse = 0;
  int n = 0, normals_ok = 0;
  for (int row = 0; row < view.height; row += 3) {
    for (int col = 0; col < view.width; col += 3) {
      const float d = maps.depth.At(row, col, 0);
      if (d == 0) continue;
      // COLMAP's dense convention: pixel (col, row) is image point (col, row).
      const Eigen::Vector3d X = view.Center() + d * view.RayDirection(col, row);
      max_dist = std::max(max_dist, PointMeshDistance(X, scene.V, scene.F));
      // The sparse convention would put it half a pixel off.
      const Eigen::Vector3d Y = view.Center() + d * view.RayDirection(col + 0.5, row + 0.5);
      sum_dist_sparse += PointMeshDistance(Y, scene.V, scene.F);
      const Eigen::Vector3d n_cam(maps.normal.At(row, col, 0), maps.normal.At(row, col, 1),
                                  maps.normal.At(row, col, 2));
      EXPECT_NEAR(n_cam.norm(), 1, 1e-5);
      EXPECT_LT(n_cam.dot(view.WorldToCamera(X)), 0) << "normal must face the camera";
      const int f = maps.exact.FaceAt(row, col);
      if (std::abs(n_cam.dot(view.R * scene.face_normals.row(f).transpose())) > 0.9999) {
        ++normals_ok;
      }
      ++n;
    }
  }
  ASSERT_GT(n, 200);
  EXPECT_LT(max_dist, 1e-3);
  EXPECT_GT(sum_dist_sparse / n, 20 * max_dist);
  EXPECT_EQ(normals_ok, n);
}

TEST(RenderDenseMaps, NoiseHasRequestedLevel) {
  const SynthScene scene = CoarseScene();
  const std::vector<PinholeView> views = SmallRing(scene);
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  DepthNoiseOptions noisy;
  noisy.depth_noise = 0.004;
  noisy.correlated_noise = 0.003;
  noisy.depth_blur_px = 0;
  noisy.outlier_fraction = 0;
  const DenseMaps maps = RenderDenseMaps(renderer, scene, views[0], noisy, 7);
  double sum2 = 0;
  int n = 0;
  for (int row = 0; row < views[0].height; ++row) {
    for (int col = 0; col < views[0].width; ++col) {
      const float d = maps.depth.At(row, col, 0);
      if (d == 0) continue;
      const double rel = d / maps.exact.DepthAt(row, col) - 1;
      sum2 += rel * rel;
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.005, 0.0005);  // sqrt(0.004^2 + 0.003^2)
}

TEST(MakeSparseModel, TracksReprojectAndAreVisible) {
  const SynthScene scene = CoarseScene();
  const std::vector<PinholeView> views = SmallRing(scene);
  Renderer renderer;
  renderer.SetMesh(scene.V, scene.F);
  std::vector<RenderBuffers> exact;
  std::vector<SynthImage> images;
  std::vector<std::string> names;
  for (size_t i = 0; i < views.size(); ++i) {
    exact.push_back(renderer.Render(DenseConventionView(views[i])));
    images.push_back(RenderImage(renderer, scene, views[i], 1));
    names.push_back("view_" + std::to_string(i) + ".png");
  }
  const Reconstruction model = MakeSparseModel(scene, views, names, exact, images, 300, 3);
  ASSERT_EQ(model.cameras.size(), 1u);
  ASSERT_EQ(model.images.size(), views.size());
  EXPECT_EQ(model.points3D.size(), 300u);
  std::vector<RenderBuffers> ref;  // independent ray casts, sparse convention
  for (const PinholeView& view : views) ref.push_back(RenderCpu(scene.V, scene.F, view));
  int observations = 0, visible = 0;
  for (const auto& [id, point] : model.points3D) {
    ASSERT_GE(point.track.size(), 2u);
    EXPECT_LT(PointMeshDistance(point.xyz, scene.V, scene.F), 1e-6);
    for (const TrackElement& el : point.track) {
      const Image& image = model.images.at(el.image_id);
      const PinholeView view = ViewFromColmap(model.cameras.at(image.camera_id), image);
      ASSERT_LT(el.point2D_idx, image.points2D.size());
      const Point2D& p2 = image.points2D[el.point2D_idx];
      EXPECT_EQ(p2.point3D_id, static_cast<int64_t>(id));
      EXPECT_LT((view.Project(point.xyz) - p2.xy).norm(), 0.5);
      // Visible: the ray through the observation's pixel meets the surface
      // at the point's depth.
      const RenderBuffers& r = ref[el.image_id - 1];
      const int col = static_cast<int>(p2.xy.x()), row = static_cast<int>(p2.xy.y());
      const double z = view.WorldToCamera(point.xyz).z();
      ++observations;
      if (r.FaceAt(row, col) >= 0 && std::abs(r.DepthAt(row, col) - z) < 0.01 * z) ++visible;
    }
  }
  EXPECT_GT(visible, 0.97 * observations);
}

}  // namespace
}  // namespace mr
