#include "synth/camera_error.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "geometry/view.h"
#include "synth/synthesizer.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string FreshDir(const std::string& name) { return FreshTestPath("camera_error_" + name); }

// #n by 3 points evenly spread over a sphere of `radius` about the origin
// (Fibonacci spiral).
Eigen::MatrixXd SpherePoints(int n, double radius) {
  Eigen::MatrixXd P(n, 3);
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1 - 2 * (k + 0.5) / n;
    const double r = std::sqrt(1 - z * z);
    P.row(k) << radius * r * std::cos(golden * k), radius * r * std::sin(golden * k), radius * z;
  }
  return P;
}

// Eight 640x480 views in a ring at elevation 20 degrees, 120 units from the
// origin, looking at it.
std::vector<PinholeView> RingViews() {
  std::vector<PinholeView> views;
  for (int i = 0; i < 8; ++i) {
    const double azimuth = 2 * kPi * i / 8, elevation = 20 * kPi / 180;
    const Eigen::Vector3d centre =
        120 * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    views.push_back(LookAtView(centre, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 640,
                               480, 576));
  }
  return views;
}

// A model of `views`: one shared PINHOLE camera (or, with camera_per_image,
// one camera per image, alternately PINHOLE and SIMPLE_PINHOLE), and every
// 10th point of `P` (a sphere about the origin) with a track in the views it
// faces.
Reconstruction ModelOf(const std::vector<PinholeView>& views, const Eigen::MatrixXd& P,
                       bool camera_per_image = false) {
  Reconstruction model;
  for (size_t i = 0; i < views.size(); ++i) {
    const PinholeView& v = views[i];
    Camera camera;
    camera.camera_id = camera_per_image ? static_cast<uint32_t>(i + 1) : 1;
    camera.width = v.width;
    camera.height = v.height;
    if (camera_per_image && i % 2 == 1) {
      camera.model = CameraModel::kSimplePinhole;
      camera.params = {v.fx, v.cx, v.cy};
    } else {
      camera.model = CameraModel::kPinhole;
      camera.params = {v.fx, v.fy, v.cx, v.cy};
    }
    model.cameras[camera.camera_id] = camera;
    Image image;
    image.image_id = static_cast<uint32_t>(i + 1);
    image.camera_id = camera.camera_id;
    image.name = "view_" + std::to_string(i) + ".png";
    image.qvec = RotationToQuaternion(v.R);
    image.tvec = v.t;
    model.images[image.image_id] = image;
  }
  for (int k = 0; k < P.rows(); k += 10) {
    const Eigen::Vector3d X = P.row(k).transpose();
    Point3D point;
    point.point3D_id = static_cast<uint64_t>(k + 1);
    point.xyz = X;
    point.rgb << 10, 20, static_cast<uint8_t>(k % 256);
    point.error = 0.25;
    for (size_t i = 0; i < views.size(); ++i) {
      const Eigen::Vector2d p = views[i].Project(X);
      if (X.dot(views[i].Center() - X) <= 0 || !views[i].InImage(p)) continue;
      Image& image = model.images.at(static_cast<uint32_t>(i + 1));
      Point2D p2;
      p2.xy = p;
      p2.point3D_id = static_cast<int64_t>(point.point3D_id);
      point.track.push_back({image.image_id, static_cast<uint32_t>(image.points2D.size())});
      image.points2D.push_back(p2);
    }
    if (point.track.size() >= 2) model.points3D[point.point3D_id] = point;
  }
  return model;
}

PinholeView ViewOf(const Reconstruction& model, uint32_t image_id) {
  const Image& image = model.images.at(image_id);
  return ViewFromColmap(model.cameras.at(image.camera_id), image);
}

// RMS displacement, computed here independently of camera_error.cc, of the
// projections of the points of P that `truth` sees (in front, inside).
double TestRms(const PinholeView& truth, const PinholeView& moved, const Eigen::MatrixXd& P) {
  double sum = 0;
  int n = 0;
  for (int k = 0; k < P.rows(); ++k) {
    const Eigen::Vector3d X = P.row(k).transpose();
    if (truth.WorldToCamera(X).z() <= 0) continue;
    const Eigen::Vector2d p = truth.Project(X);
    if (p.x() < 0 || p.y() < 0 || p.x() >= truth.width || p.y() >= truth.height) continue;
    sum += (moved.Project(X) - p).squaredNorm();
    ++n;
  }
  EXPECT_GT(n, 0);
  return std::sqrt(sum / n);
}

// The three files of `model` written to a fresh folder, concatenated.
std::string ModelBytes(const Reconstruction& model, const std::string& name) {
  const std::string dir = FreshDir(name);
  CreateDirIfNotExists(dir);
  WriteSparseModelBinary(dir, model);
  return ReadFileToString(JoinPaths(dir, "cameras.bin")) + "|" +
         ReadFileToString(JoinPaths(dir, "images.bin")) + "|" +
         ReadFileToString(JoinPaths(dir, "points3D.bin"));
}

TEST(CameraErrorOptions, DefaultsAreValid) { EXPECT_TRUE(CameraErrorOptions().Check()); }

TEST(CameraErrorOptions, RejectsBadValuesNamingTheField) {
  const auto message = [](const std::function<void(CameraErrorOptions*)>& set) {
    CameraErrorOptions options;
    set(&options);
    try {
      options.Check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const auto expect_refused = [](const std::string& what, const std::string& field) {
    EXPECT_NE(what.find("CameraErrorOptions::" + field + " = "), std::string::npos) << what;
    EXPECT_NE(what.find("Violated constraint"), std::string::npos) << what;
  };
  for (const double v : {-0.1, 100.5, std::nan("")}) {
    expect_refused(message([v](CameraErrorOptions* o) { o->pose_error_px = v; }),
                   "pose_error_px");
  }
  for (const double v : {-1.0, 50.5, std::nan("")}) {
    expect_refused(message([v](CameraErrorOptions* o) { o->focal_error_percent = v; }),
                   "focal_error_percent");
  }
  EXPECT_EQ(message([](CameraErrorOptions* o) {
              o->pose_error_px = 100;
              o->focal_error_percent = 50;
            }),
            "accepted");
  // And through the synthesizer's options.
  SynthesizerOptions synth;
  synth.output_path = "/tmp/x";
  synth.camera_error.pose_error_px = -1;
  EXPECT_THROW(synth.Check(), InputError);
}

TEST(PerturbCameras, AchievesTargetRmsOnTheVisibleSurface) {
  const Eigen::MatrixXd P = SpherePoints(4000, 30);
  const std::vector<PinholeView> views = RingViews();
  const Reconstruction truth = ModelOf(views, P);
  for (const double target : {0.5, 1.0, 2.0}) {
    Reconstruction model = truth;
    CameraErrorOptions options;
    options.pose_error_px = target;
    const CameraErrorSummary summary = PerturbCameras(options, P, 7, &model);
    ASSERT_EQ(summary.images.size(), views.size());
    EXPECT_EQ(summary.num_perturbed_images, 8);
    double worst = 0, rotation_sum = 0, shift_sum = 0, rotation_part = 0, shift_part = 0;
    for (uint32_t id = 1; id <= 8; ++id) {
      const PinholeView before = ViewOf(truth, id), after = ViewOf(model, id);
      const double rms = TestRms(before, after, P);
      EXPECT_NEAR(rms, target, 0.01 * target) << "image " << id;
      worst = std::max(worst, std::abs(rms / target - 1));
      const ImageCameraError& record = summary.images[id - 1];
      EXPECT_EQ(record.image_id, id);
      EXPECT_GT(record.num_visible_points, 1000);
      EXPECT_NEAR(record.rms_px, rms, 1e-9 * target);
      EXPECT_NEAR(model.images.at(id).qvec.norm(), 1, 1e-12);
      // The summary's rotation and centre change are those of the new pose.
      const Eigen::AngleAxisd dR(after.R * before.R.transpose());
      EXPECT_NEAR(record.rotation_deg, dR.angle() * 180 / kPi, 1e-9);
      EXPECT_NEAR(record.center_shift, (after.Center() - before.Center()).norm(), 1e-9);
      rotation_sum += record.rotation_deg;
      shift_sum += record.center_shift;
      // Both the rotation and the centre shift move the projections.
      PinholeView rotated = before, shifted = before;
      rotated.R = after.R;
      rotated.t = -after.R * before.Center();
      shifted.t = -before.R * after.Center();
      rotation_part += TestRms(before, rotated, P) / 8;
      shift_part += TestRms(before, shifted, P) / 8;
    }
    EXPECT_NEAR(summary.mean_rotation_deg, rotation_sum / 8, 1e-12);
    EXPECT_NEAR(summary.mean_center_shift, shift_sum / 8, 1e-12);
    EXPECT_NEAR(summary.mean_rms_px, target, 0.01 * target);
    EXPECT_LE(summary.max_rms_px, 1.01 * target);
    EXPECT_GT(rotation_part, 0.2 * target);
    EXPECT_GT(shift_part, 0.2 * target);
    EXPECT_EQ(summary.focal_scale.at(1), 1.0);
    std::printf("target %.1f px: worst relative deviation %.2e, mean rotation %.4f deg, mean "
                "centre shift %.4f units, mean RMS of the rotation alone %.3f px, of the shift "
                "alone %.3f px\n",
                target, worst, summary.mean_rotation_deg, summary.mean_center_shift,
                rotation_part, shift_part);
  }
}

TEST(PerturbCameras, ZeroErrorLeavesModelBitIdentical) {
  const Eigen::MatrixXd P = SpherePoints(2000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P);
  Reconstruction model = truth;
  const CameraErrorSummary summary = PerturbCameras(CameraErrorOptions(), P, 7, &model);
  EXPECT_EQ(ModelBytes(model, "zero_a"), ModelBytes(truth, "zero_b"));
  EXPECT_TRUE(summary.images.empty());
  EXPECT_EQ(summary.num_perturbed_images, 0);
  EXPECT_EQ(summary.focal_scale.at(1), 1.0);
}

TEST(PerturbCameras, SameSeedSameModelOtherSeedOtherModel) {
  const Eigen::MatrixXd P = SpherePoints(2000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P, /*camera_per_image=*/true);
  CameraErrorOptions options;
  options.pose_error_px = 1;
  options.focal_error_percent = 3;
  Reconstruction a = truth, b = truth, c = truth;
  PerturbCameras(options, P, 11, &a);
  PerturbCameras(options, P, 11, &b);
  PerturbCameras(options, P, 12, &c);
  EXPECT_EQ(ModelBytes(a, "seed_a"), ModelBytes(b, "seed_b"));
  EXPECT_NE(ModelBytes(a, "seed_a"), ModelBytes(c, "seed_c"));
  for (uint32_t id = 1; id <= 8; ++id) {
    EXPECT_NE(a.images.at(id).qvec, c.images.at(id).qvec) << "image " << id;
  }
}

TEST(PerturbCameras, FocalErrorScalesFocalLengthsOnly) {
  const Eigen::MatrixXd P = SpherePoints(2000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P, /*camera_per_image=*/true);
  CameraErrorOptions options;
  options.focal_error_percent = 5;
  Reconstruction model = truth;
  const CameraErrorSummary summary = PerturbCameras(options, P, 3, &model);
  int up = 0, down = 0;
  for (const auto& [id, camera] : model.cameras) {
    const Camera& before = truth.cameras.at(id);
    const double scale = summary.focal_scale.at(id);
    ASSERT_TRUE(scale == 1 + 0.05 || scale == 1 - 0.05) << scale;
    (scale > 1 ? up : down)++;
    ASSERT_EQ(camera.params.size(), before.params.size());
    if (camera.model == CameraModel::kPinhole) {
      EXPECT_EQ(camera.params[0], before.params[0] * scale);  // fx
      EXPECT_EQ(camera.params[1], before.params[1] * scale);  // fy
      EXPECT_EQ(camera.params[2], before.params[2]);          // cx
      EXPECT_EQ(camera.params[3], before.params[3]);          // cy
    } else {
      EXPECT_EQ(camera.params[0], before.params[0] * scale);  // f
      EXPECT_EQ(camera.params[1], before.params[1]);          // cx
      EXPECT_EQ(camera.params[2], before.params[2]);          // cy
    }
    EXPECT_NEAR(CameraFocalX(camera.model, camera.params) /
                    CameraFocalX(before.model, before.params),
                scale, 1e-15);
  }
  EXPECT_GT(up, 0);
  EXPECT_GT(down, 0);
  // The poses are exact.
  for (const auto& [id, image] : model.images) {
    EXPECT_EQ(image.qvec, truth.images.at(id).qvec);
    EXPECT_EQ(image.tvec, truth.images.at(id).tvec);
  }
}

TEST(PerturbCameras, ObservationsAndPointsUnchanged) {
  const Eigen::MatrixXd P = SpherePoints(2000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P);
  ASSERT_GT(truth.points3D.size(), 100u);
  Reconstruction model = truth;
  CameraErrorOptions options;
  options.pose_error_px = 2;
  options.focal_error_percent = 10;
  PerturbCameras(options, P, 5, &model);
  ASSERT_EQ(model.images.size(), truth.images.size());
  for (const auto& [id, image] : model.images) {
    const Image& before = truth.images.at(id);
    EXPECT_NE(image.tvec, before.tvec);
    EXPECT_EQ(image.name, before.name);
    EXPECT_EQ(image.camera_id, before.camera_id);
    ASSERT_EQ(image.points2D.size(), before.points2D.size());
    for (size_t k = 0; k < image.points2D.size(); ++k) {
      EXPECT_EQ(image.points2D[k].xy, before.points2D[k].xy);
      EXPECT_EQ(image.points2D[k].point3D_id, before.points2D[k].point3D_id);
    }
  }
  ASSERT_EQ(model.points3D.size(), truth.points3D.size());
  for (const auto& [id, point] : model.points3D) {
    const Point3D& before = truth.points3D.at(id);
    EXPECT_EQ(point.xyz, before.xyz);
    EXPECT_EQ(point.rgb, before.rgb);
    EXPECT_EQ(point.error, before.error);
    ASSERT_EQ(point.track.size(), before.track.size());
    for (size_t k = 0; k < point.track.size(); ++k) {
      EXPECT_EQ(point.track[k].image_id, before.track[k].image_id);
      EXPECT_EQ(point.track[k].point2D_idx, before.track[k].point2D_idx);
    }
  }
}

TEST(PerturbCameras, ImageSeeingNoSurfaceKeepsItsPose) {
  const Eigen::MatrixXd P = SpherePoints(2000, 30);
  std::vector<PinholeView> views = RingViews();
  views.push_back(LookAtView(Eigen::Vector3d(100, 0, 0), Eigen::Vector3d(200, 0, 0),
                             Eigen::Vector3d::UnitZ(), 640, 480, 576));
  const Reconstruction truth = ModelOf(views, P);
  Reconstruction model = truth;
  CameraErrorOptions options;
  options.pose_error_px = 1;
  const CameraErrorSummary summary = PerturbCameras(options, P, 1, &model);
  ASSERT_EQ(summary.images.size(), 9u);
  EXPECT_EQ(summary.num_perturbed_images, 8);
  EXPECT_EQ(summary.images[8].num_visible_points, 0);
  EXPECT_EQ(model.images.at(9).qvec, truth.images.at(9).qvec);
  EXPECT_EQ(model.images.at(9).tvec, truth.images.at(9).tvec);
  EXPECT_NEAR(summary.mean_rms_px, 1, 0.01);
  EXPECT_NE(summary.BriefReport().find("1 seeing no surface"), std::string::npos)
      << summary.BriefReport();
}

// The synthesizer writes the true model to sparse_true/ and the perturbed
// one to dense/sparse; images and depth maps are those of the true cameras.
TEST(Synthesizer, PoseErrorWritesTrueModelBesideWorkspace) {
  const auto options_for = [](const std::string& dir, double pose_error_px) {
    SynthesizerOptions options;
    options.output_path = dir;
    options.builtin.edge_length = 2.0;
    options.cameras.num_views = 4;
    options.cameras.width = 64;
    options.cameras.height = 48;
    options.supersample = 1;
    options.num_sparse_points = 200;
    options.run_colmap = false;
    options.camera_error.pose_error_px = pose_error_px;
    return options;
  };
  const std::string exact_dir = FreshDir("synth_exact"), wrong_dir = FreshDir("synth_wrong");
  const SynthesizerSummary exact = SynthesizeWorkspace(options_for(exact_dir, 0));
  const SynthesizerSummary wrong = SynthesizeWorkspace(options_for(wrong_dir, 1));
  EXPECT_FALSE(exact.perturbed_cameras);
  EXPECT_FALSE(ExistsDir(JoinPaths(exact_dir, "sparse_true")));
  ASSERT_TRUE(wrong.perturbed_cameras);
  EXPECT_NE(wrong.BriefReport().find("camera error"), std::string::npos) << wrong.BriefReport();
  ASSERT_TRUE(ExistsDir(JoinPaths(wrong_dir, "sparse_true")));
  EXPECT_FALSE(ExistsDir(JoinPaths(wrong_dir, "dense/sparse_true")));

  // sparse_true is the unperturbed model; dense/sparse differs in the poses only.
  const std::string exact_sparse = JoinPaths(exact_dir, "dense/sparse");
  const std::string true_sparse = JoinPaths(wrong_dir, "sparse_true");
  const std::string wrong_sparse = JoinPaths(wrong_dir, "dense/sparse");
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(ReadFileToString(JoinPaths(true_sparse, file)),
              ReadFileToString(JoinPaths(exact_sparse, file)))
        << file;
  }
  EXPECT_NE(ReadFileToString(JoinPaths(wrong_sparse, "images.bin")),
            ReadFileToString(JoinPaths(exact_sparse, "images.bin")));
  EXPECT_EQ(ReadFileToString(JoinPaths(wrong_sparse, "cameras.bin")),
            ReadFileToString(JoinPaths(exact_sparse, "cameras.bin")));
  EXPECT_EQ(ReadFileToString(JoinPaths(wrong_sparse, "points3D.bin")),
            ReadFileToString(JoinPaths(exact_sparse, "points3D.bin")));
  for (int i = 0; i < 4; ++i) {
    const std::string name = SynthViewName(i);
    EXPECT_EQ(ReadFileToString(JoinPaths(wrong_dir, "dense/images/" + name)),
              ReadFileToString(JoinPaths(exact_dir, "dense/images/" + name)));
    EXPECT_EQ(
        ReadFileToString(JoinPaths(wrong_dir, "dense/stereo/depth_maps/" + name + ".geometric.bin")),
        ReadFileToString(JoinPaths(exact_dir, "dense/stereo/depth_maps/" + name + ".geometric.bin")));
  }

  // The written poses are 1 px RMS off the true ones on the ground truth.
  const Reconstruction truth = ReadSparseModelBinary(true_sparse);
  const Reconstruction model = ReadSparseModelBinary(wrong_sparse);
  const TriangleMesh gt = ReadPly(JoinPaths(wrong_dir, "ground_truth.ply"));
  ASSERT_EQ(model.images.size(), 4u);
  double sum = 0;
  for (const auto& [id, image] : model.images) {
    const double rms = TestRms(ViewOf(truth, id), ViewOf(model, id), gt.V);
    EXPECT_NEAR(rms, 1, 0.01) << "image " << id;
    sum += rms;
  }
  EXPECT_NEAR(wrong.camera_error.mean_rms_px, 1, 0.01);
  EXPECT_NEAR(wrong.camera_error.mean_rms_px, sum / 4, 1e-6);
  std::printf("synthesizer, 4 views 64x48, pose_error_px 1: mean RMS %.4f px, max %.4f px, "
              "rotation %.4f deg mean, centre shift %.4f units mean\n",
              sum / 4, wrong.camera_error.max_rms_px, wrong.camera_error.mean_rotation_deg,
              wrong.camera_error.mean_center_shift);
}

// CompareCameras measures what PerturbCameras did: 0 for the same model, the
// per-image RMS of ReprojectionRms combined as an RMS over images, the worst
// image, and the focal error; images are matched by name.
TEST(CompareCameras, MeasuresThePerturbation) {
  const Eigen::MatrixXd P = SpherePoints(4000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P);
  const CameraComparison same = CompareCameras(truth, truth, P);
  EXPECT_EQ(same.num_images, 8);
  EXPECT_LT(same.rms_px, 1e-9);  // world -> camera -> world round-off
  EXPECT_LT(same.max_rms_px, 1e-9);
  EXPECT_EQ(same.max_focal_percent, 0);

  CameraErrorOptions options;
  options.pose_error_px = 1;
  options.focal_error_percent = 0.5;
  Reconstruction model = truth;
  PerturbCameras(options, P, 5, &model);
  double sum_sq = 0, worst = 0;
  uint32_t worst_id = 0;
  for (uint32_t id = 1; id <= 8; ++id) {
    const double rms = TestRms(ViewOf(truth, id), ViewOf(model, id), P);
    sum_sq += rms * rms;
    if (rms > worst) worst = rms, worst_id = id;
  }
  const CameraComparison cmp = CompareCameras(model, truth, P);
  EXPECT_EQ(cmp.num_images, 8);
  EXPECT_NEAR(cmp.rms_px, std::sqrt(sum_sq / 8), 1e-9);
  EXPECT_NEAR(cmp.max_rms_px, worst, 1e-9);
  EXPECT_EQ(cmp.max_rms_image, model.images.at(worst_id).name);
  EXPECT_NEAR(cmp.max_focal_percent, 0.5, 1e-9);
  EXPECT_GT(cmp.rms_px, 0.5);  // the focal error adds to the 1 px of the poses
  const std::string json = "{" + cmp.JsonMembers() + "}";
  EXPECT_NE(json.find("\"camera_rms_px\": "), std::string::npos) << json;

  // Matched by name, not id: the ids of the truth renumbered.
  Reconstruction renumbered;
  renumbered.cameras = truth.cameras;
  for (const auto& [id, image] : truth.images) {
    Image copy = image;
    copy.image_id = id + 100;
    renumbered.images[id + 100] = copy;
  }
  EXPECT_NEAR(CompareCameras(model, renumbered, P).rms_px, cmp.rms_px, 1e-12);

  // An image the truth does not have is an input error that names it.
  Reconstruction stranger = model;
  stranger.images.at(3).name = "not_there.png";
  try {
    CompareCameras(stranger, truth, P);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not_there.png"), std::string::npos) << e.what();
  }
}

// The model's world carried by a similarity T (the truth's cameras moved with
// their world, and each also moved by its own pose error when `perturbed`).
Reconstruction CarriedModel(const Reconstruction& truth, const Similarity3& T) {
  Reconstruction model = truth;
  for (auto& [id, image] : model.images) {
    const PinholeView view = T.Apply(ViewOf(truth, id));
    image.qvec = RotationToQuaternion(view.R);
    image.tvec = view.t;
  }
  return model;
}

Similarity3 TestSimilarity() {
  Similarity3 T;
  T.scale = 1.7;
  T.rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  T.translation = Eigen::Vector3d(40, -15, 8);
  return T;
}

// Similarity3 carries a camera with its world: the carried view projects the
// carried point where the view projected the point.
TEST(Similarity3, CarriesCamerasWithTheirWorld) {
  const Similarity3 T = TestSimilarity();
  const PinholeView view = RingViews()[3];
  const PinholeView carried = T.Apply(view);
  const Eigen::MatrixXd P = SpherePoints(50, 30);
  const Eigen::MatrixXd Q = T.Apply(P);
  for (int k = 0; k < P.rows(); ++k) {
    EXPECT_LT((carried.Project(Q.row(k).transpose()) - view.Project(P.row(k).transpose())).norm(),
              1e-9);
  }
  EXPECT_NEAR((carried.Center() - T(view.Center())).norm(), 0, 1e-9);
}

// AlignCamerasToTruth undoes a similarity of the whole model (the gauge), and
// after it the comparison measures only what differs between the views.
TEST(AlignCamerasToTruth, RemovesTheGaugeAndOnlyIt) {
  const Eigen::MatrixXd P = SpherePoints(4000, 30);
  const Reconstruction truth = ModelOf(RingViews(), P);
  const Similarity3 T = TestSimilarity();
  const Reconstruction moved = CarriedModel(truth, T);
  EXPECT_GT(CompareCameras(moved, truth, P).rms_px, 100);
  const Similarity3 S = AlignCamerasToTruth(moved, truth, P);
  EXPECT_NEAR(S.scale * T.scale, 1, 1e-9);
  for (int k = 0; k < P.rows(); k += 97) {
    const Eigen::Vector3d X = P.row(k).transpose();
    EXPECT_LT((S(T(X)) - X).norm(), 1e-7);
  }
  EXPECT_LT(CompareCameras(moved, truth, P, &S).rms_px, 1e-7);

  // Pose errors: aligning never makes the comparison worse than the
  // identity (it minimises what the comparison measures), and carrying the
  // perturbed model by T changes nothing once aligned.
  CameraErrorOptions options;
  options.pose_error_px = 1;
  Reconstruction perturbed = truth;
  PerturbCameras(options, P, 7, &perturbed);
  const double raw = CompareCameras(perturbed, truth, P).rms_px;
  const Similarity3 A = AlignCamerasToTruth(perturbed, truth, P);
  const double aligned = CompareCameras(perturbed, truth, P, &A).rms_px;
  std::printf("pose error: %.3f px as it is, %.3f px aligned\n", raw, aligned);
  EXPECT_LT(aligned, raw);
  EXPECT_GT(aligned, 0.3);  // eight independent errors: most of them is not gauge
  const Reconstruction perturbed_moved = CarriedModel(perturbed, T);
  const Similarity3 B = AlignCamerasToTruth(perturbed_moved, truth, P);
  EXPECT_NEAR(CompareCameras(perturbed_moved, truth, P, &B).rms_px, aligned, 1e-6);
}

}  // namespace
}  // namespace mr
