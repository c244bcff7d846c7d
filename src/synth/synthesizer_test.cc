#include "synth/synthesizer.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap_io/dense_array.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "synth/synth_test_util.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/testing.h"

namespace mr {
namespace {

using testing_util::PointMeshDistance;

std::string FreshDir(const std::string& name) { return FreshTestPath("synth_" + name); }

SynthesizerOptions SmallOptions(const std::string& output_path) {
  SynthesizerOptions options;
  options.output_path = output_path;
  options.builtin.edge_length = 2.0;
  options.cameras.num_views = 6;
  options.cameras.width = 160;
  options.cameras.height = 120;
  options.supersample = 2;
  options.num_sparse_points = 500;
  options.run_colmap = false;
  return options;
}

TEST(SynthesizerOptions, DefaultsAreValid) {
  SynthesizerOptions options;
  options.output_path = "/tmp/x";  // the one required field
  EXPECT_TRUE(options.Check());
  EXPECT_TRUE(ColmapRunOptions().Check());
  ColmapRunOptions fusion;
  fusion.fusion_max_image_size = 2000;
  EXPECT_TRUE(fusion.Check());
  fusion.fusion_max_image_size = 50;
  EXPECT_THROW(fusion.Check(), InputError);
}

TEST(SynthesizerOptions, RejectsBadValues) {
  SynthesizerOptions options;
  EXPECT_THROW(options.Check(), InputError);  // no output_path
  options.output_path = "/tmp/x";
  options.supersample = 0;
  EXPECT_THROW(options.Check(), InputError);
  options.supersample = 3;
  options.shape = "teapot";
  EXPECT_THROW(options.Check(), InputError);
  options.shape = "builtin";
  options.colmap.poisson_trim = -1;
  EXPECT_THROW(options.Check(), InputError);
}

// The options behind the flags --texture_style, --light, --image_noise,
// --texture_contrast, --ambient, --focal_factor, --min/max_elevation_deg.
TEST(SynthesizerOptions, RejectsBadImageStyleAndCameraValues) {
  SynthesizerOptions base;
  base.output_path = "/tmp/x";
  const auto rejects = [&](const std::function<void(SynthesizerOptions*)>& set) {
    SynthesizerOptions options = base;
    set(&options);
    try {
      options.Check();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const auto expect_message = [](const std::string& what, const std::string& field) {
    EXPECT_NE(what.find(field), std::string::npos) << what;
    EXPECT_NE(what.find("Violated constraint"), std::string::npos) << what;
  };
  expect_message(rejects([](SynthesizerOptions* o) { o->appearance.texture_style = "marble"; }),
                 "texture_style = marble");
  expect_message(rejects([](SynthesizerOptions* o) { o->appearance.light = "sun"; }),
                 "light = sun");
  for (const double v : {-0.01, 0.6, std::nan("")}) {
    expect_message(rejects([v](SynthesizerOptions* o) { o->image_noise = v; }), "image_noise");
  }
  expect_message(rejects([](SynthesizerOptions* o) { o->appearance.texture_contrast = 0; }),
                 "texture_contrast");
  expect_message(rejects([](SynthesizerOptions* o) { o->appearance.ambient = 1.2; }), "ambient");
  expect_message(rejects([](SynthesizerOptions* o) { o->appearance.specular = -0.1; }),
                 "specular");
  expect_message(rejects([](SynthesizerOptions* o) { o->exposure_jitter = 1.5; }),
                 "exposure_jitter");
  for (const double v : {-0.1, 0.95, std::nan("")}) {
    expect_message(rejects([v](SynthesizerOptions* o) { o->vignetting = v; }), "vignetting");
  }
  for (const double g : {-0.1, 1.5, std::nan("")}) {
    expect_message(rejects([g](SynthesizerOptions* o) { o->background = g; }), "background");
  }
  for (const int q : {-1, 101}) {
    expect_message(rejects([q](SynthesizerOptions* o) { o->jpeg_quality = q; }), "jpeg_quality");
  }
  expect_message(rejects([](SynthesizerOptions* o) { o->cameras.focal_factor = 0.05; }),
                 "focal_factor");
  expect_message(rejects([](SynthesizerOptions* o) { o->cameras.focal_factor = 11; }),
                 "focal_factor");
  expect_message(rejects([](SynthesizerOptions* o) { o->cameras.min_elevation_deg = 80; }),
                 "min_elevation_deg");
  expect_message(rejects([](SynthesizerOptions* o) { o->cameras.max_elevation_deg = 90; }),
                 "max_elevation_deg");
  expect_message(rejects([](SynthesizerOptions* o) { o->cameras.min_elevation_deg = -90; }),
                 "min_elevation_deg");
  // And good values pass.
  EXPECT_EQ(rejects([](SynthesizerOptions* o) {
              o->appearance.texture_style = "none";
              o->appearance.light = "headlight";
              o->image_noise = 0.5;
              o->cameras.focal_factor = 2;
              o->cameras.min_elevation_deg = -30;
            }),
            "accepted");
}

TEST(Synthesizer, WritesWorkspaceAndGroundTruthBesideIt) {
  const std::string dir = FreshDir("layout");
  SynthesizerOptions options = SmallOptions(dir);
  options.noise.depth_blur_px = 0;  // so that the only error is the noise
  const SynthesizerSummary summary = SynthesizeWorkspace(options);
  EXPECT_EQ(summary.num_views, 6);
  EXPECT_GT(summary.num_points3D, 100);
  EXPECT_GE(summary.mean_track_length, 2.0);
  EXPECT_FALSE(summary.ran_colmap);
  const std::string dense = JoinPaths(dir, "dense");
  EXPECT_TRUE(ExistsFile(JoinPaths(dir, "ground_truth.ply")));
  EXPECT_FALSE(ExistsFile(JoinPaths(dense, "ground_truth.ply")));
  for (const char* f : {"sparse/cameras.bin", "sparse/images.bin", "sparse/points3D.bin",
                        "stereo/fusion.cfg", "stereo/patch-match.cfg"}) {
    EXPECT_TRUE(ExistsFile(JoinPaths(dense, f))) << f;
  }
  std::vector<std::string> names;
  for (int i = 0; i < 6; ++i) names.push_back(SynthViewName(i));
  EXPECT_EQ(names[0], "view_0000.png");
  EXPECT_EQ(ListFiles(JoinPaths(dense, "images")), names);
  std::string fusion_cfg, patch_cfg;
  for (const auto& n : names) {
    fusion_cfg += n + "\n";
    patch_cfg += n + "\n__auto__, 20\n";
    EXPECT_TRUE(ExistsFile(JoinPaths(dense, "masks/" + n + ".png")));
  }
  EXPECT_EQ(ReadFileToString(JoinPaths(dense, "stereo/fusion.cfg")), fusion_cfg);
  EXPECT_EQ(ReadFileToString(JoinPaths(dense, "stereo/patch-match.cfg")), patch_cfg);

  // The sparse model reads back (COLMAP's binary layout) and its tracks
  // reproject onto their points2D.
  const Reconstruction model = ReadSparseModelBinary(JoinPaths(dense, "sparse"));
  ASSERT_EQ(model.cameras.size(), 1u);
  ASSERT_EQ(model.images.size(), 6u);
  EXPECT_EQ(static_cast<int>(model.points3D.size()), summary.num_points3D);
  EXPECT_EQ(model.cameras.begin()->second.model, CameraModel::kPinhole);
  for (const auto& [id, point] : model.points3D) {
    ASSERT_GE(point.track.size(), 2u);
    for (const TrackElement& el : point.track) {
      const Image& image = model.images.at(el.image_id);
      const PinholeView view = ViewFromColmap(model.cameras.at(image.camera_id), image);
      ASSERT_LT(el.point2D_idx, image.points2D.size());
      EXPECT_EQ(image.points2D[el.point2D_idx].point3D_id, static_cast<int64_t>(id));
      EXPECT_LT((view.Project(point.xyz) - image.points2D[el.point2D_idx].xy).norm(), 0.5);
    }
  }
  EXPECT_EQ(model.images.at(1).name, "view_0000.png");

  // Ground truth normalised: diagonal 100, centred.
  const TriangleMesh gt = ReadPly(JoinPaths(dir, "ground_truth.ply"));
  EXPECT_EQ(gt.NumFaces(), summary.num_gt_faces);
  const Eigen::RowVector3d lo = gt.V.colwise().minCoeff(), hi = gt.V.colwise().maxCoeff();
  EXPECT_NEAR((hi - lo).norm(), 100, 1e-3);
  EXPECT_NEAR((hi + lo).norm(), 0, 1e-3);

  // The written depth maps back-project onto the ground truth, with COLMAP's
  // dense convention (pixel (col, row) = image point (col, row)), within the
  // noise (relative sigma ~0.0036 at depth ~130, i.e. ~0.47 units).
  const std::vector<PinholeView> views =
      MakeCameras(options.cameras, gt.V.rowwise().norm().maxCoeff());
  int n = 0, close = 0;
  for (size_t i = 0; i < views.size(); i += 2) {
    const DenseArray depth =
        ReadDenseArray(JoinPaths(dense, "stereo/depth_maps/" + names[i] + ".geometric.bin"));
    const DenseArray normal =
        ReadDenseArray(JoinPaths(dense, "stereo/normal_maps/" + names[i] + ".geometric.bin"));
    ASSERT_EQ(depth.width, 160);
    ASSERT_EQ(depth.height, 120);
    ASSERT_EQ(depth.channels, 1);
    ASSERT_EQ(normal.channels, 3);
    for (int row = 0; row < depth.height; row += 4) {
      for (int col = 0; col < depth.width; col += 4) {
        const float d = depth.At(row, col, 0);
        if (d == 0) continue;
        const Eigen::Vector3d X = views[i].Center() + d * views[i].RayDirection(col, row);
        const double sigma = std::hypot(options.noise.depth_noise, options.noise.correlated_noise) * d;
        ++n;
        if (PointMeshDistance(X, gt.V, gt.F) < 3 * sigma) ++close;
      }
    }
  }
  ASSERT_GT(n, 300);
  EXPECT_GT(close, 0.97 * n);
}

cv::Mat ReadRgb(const std::string& path) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  EXPECT_FALSE(image.empty()) << path;
  EXPECT_EQ(image.type(), CV_8UC3) << path;
  return image;
}

// --image_noise reaches the written images at the requested level (pixels
// that it could have clipped ignored) and nothing else; the default images
// are grey (R = G = B) and so are the point colours.
TEST(Synthesizer, ImageNoiseReachesTheWrittenImagesOnly) {
  const std::string dir = FreshDir("image_noise");
  SynthesizerOptions clean_options = SmallOptions(JoinPaths(dir, "clean"));
  SynthesizerOptions noisy_options = SmallOptions(JoinPaths(dir, "noisy"));
  const double sigma = 0.03;
  noisy_options.image_noise = sigma;
  SynthesizeWorkspace(clean_options);
  SynthesizeWorkspace(noisy_options);
  const std::string clean = JoinPaths(clean_options.output_path, "dense");
  const std::string noisy = JoinPaths(noisy_options.output_path, "dense");
  double sum = 0, sum2 = 0;
  long n = 0;
  for (int i = 0; i < 6; ++i) {
    const std::string name = SynthViewName(i);
    const cv::Mat a = ReadRgb(JoinPaths(clean, "images/" + name));
    const cv::Mat b = ReadRgb(JoinPaths(noisy, "images/" + name));
    for (int row = 0; row < a.rows; ++row) {
      for (int col = 0; col < a.cols; ++col) {
        const cv::Vec3b pa = a.at<cv::Vec3b>(row, col), pb = b.at<cv::Vec3b>(row, col);
        ASSERT_TRUE(pa[0] == pa[1] && pa[1] == pa[2]) << "grey expected";
        for (int c = 0; c < 3; ++c) {
          const double va = pa[c] / 255.0, vb = pb[c] / 255.0;
          if (va < 4 * sigma || va > 1 - 4 * sigma) continue;
          sum += vb - va;
          sum2 += (vb - va) * (vb - va);
          ++n;
        }
      }
    }
    EXPECT_EQ(ReadFileToString(JoinPaths(clean, "stereo/depth_maps/" + name + ".geometric.bin")),
              ReadFileToString(JoinPaths(noisy, "stereo/depth_maps/" + name + ".geometric.bin")));
    EXPECT_EQ(ReadFileToString(JoinPaths(clean, "masks/" + name + ".png")),
              ReadFileToString(JoinPaths(noisy, "masks/" + name + ".png")));
  }
  ASSERT_GT(n, 20000);
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(sd, sigma, 0.1 * sigma);
  EXPECT_NEAR(mean, 0, 0.1 * sigma);
  const Reconstruction model = ReadSparseModelBinary(JoinPaths(clean, "sparse"));
  ASSERT_FALSE(model.points3D.empty());
  for (const auto& [id, point] : model.points3D) {
    ASSERT_TRUE(point.rgb(0) == point.rgb(1) && point.rgb(1) == point.rgb(2));
  }
}

// --jpeg_quality writes JPEG images under .jpg names, which the sparse model
// and the masks (<name>.png) follow; they decode to the PNG images up to the
// compression's error, and the depth maps are the same. --vignetting darkens
// the corners of every view and leaves the centre.
TEST(Synthesizer, JpegImagesAndVignettingReachTheWrittenImages) {
  const std::string dir = FreshDir("jpeg");
  SynthesizerOptions png_options = SmallOptions(JoinPaths(dir, "png"));
  SynthesizerOptions jpeg_options = SmallOptions(JoinPaths(dir, "jpeg"));
  jpeg_options.jpeg_quality = 90;
  SynthesizerOptions vignetted_options = SmallOptions(JoinPaths(dir, "vignetted"));
  vignetted_options.vignetting = 0.5;
  SynthesizeWorkspace(png_options);
  SynthesizeWorkspace(jpeg_options);
  SynthesizeWorkspace(vignetted_options);
  const std::string png = JoinPaths(png_options.output_path, "dense");
  const std::string jpeg = JoinPaths(jpeg_options.output_path, "dense");
  const std::string vignetted = JoinPaths(vignetted_options.output_path, "dense");
  const Reconstruction model = ReadSparseModelBinary(JoinPaths(jpeg, "sparse"));
  ASSERT_EQ(model.images.size(), 6u);
  for (const auto& [id, image] : model.images) {
    EXPECT_EQ(image.name.substr(image.name.size() - 4), ".jpg") << image.name;
  }
  double abs_sum = 0;
  long n = 0;
  long mismatched = 0, lit_off_centre = 0;  // vignetting: pixels off the fall-off, object pixels
  for (int i = 0; i < 6; ++i) {
    const std::string name = SynthViewName(i, ".jpg");
    EXPECT_EQ(name, "view_000" + std::to_string(i) + ".jpg");
    const std::string bytes = ReadFileToString(JoinPaths(jpeg, "images/" + name));
    ASSERT_GE(bytes.size(), 3u);
    EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0xFF);  // a JPEG's start-of-image marker
    EXPECT_EQ(static_cast<unsigned char>(bytes[1]), 0xD8);
    EXPECT_TRUE(ExistsFile(JoinPaths(jpeg, "masks/" + name + ".png")));
    EXPECT_EQ(ReadFileToString(JoinPaths(jpeg, "masks/" + name + ".png")),
              ReadFileToString(JoinPaths(png, "masks/" + SynthViewName(i) + ".png")));
    EXPECT_EQ(
        ReadFileToString(JoinPaths(jpeg, "stereo/depth_maps/" + name + ".geometric.bin")),
        ReadFileToString(JoinPaths(png, "stereo/depth_maps/" + SynthViewName(i) + ".geometric.bin")));
    const cv::Mat a = ReadRgb(JoinPaths(png, "images/" + SynthViewName(i)));
    const cv::Mat b = ReadRgb(JoinPaths(jpeg, "images/" + name));
    ASSERT_EQ(a.size(), b.size());
    cv::Mat diff;
    cv::absdiff(a, b, diff);
    abs_sum += cv::sum(diff)[0] + cv::sum(diff)[1] + cv::sum(diff)[2];
    n += 3L * a.rows * a.cols;

    const cv::Mat v = ReadRgb(JoinPaths(vignetted, "images/" + SynthViewName(i)));
    ASSERT_EQ(a.size(), v.size());
    // Every pixel is the PNG's times 1 - 0.5 (r / r_corner)^2, up to the
    // rounding of the two 8-bit images.
    const double cx = 0.5 * (a.cols - 1), cy = 0.5 * (a.rows - 1);
    for (int row = 0; row < a.rows; ++row) {
      for (int col = 0; col < a.cols; ++col) {
        const double r2 = ((col - cx) * (col - cx) + (row - cy) * (row - cy)) / (cx * cx + cy * cy);
        const double expected = a.at<cv::Vec3b>(row, col)[0] * (1 - 0.5 * r2);
        const int got = v.at<cv::Vec3b>(row, col)[0];
        if (std::abs(got - expected) > 1.0) ++mismatched;
        if (a.at<cv::Vec3b>(row, col)[0] >= 60 && r2 >= 0.09) ++lit_off_centre;
      }
    }
  }
  EXPECT_EQ(mismatched, 0);
  EXPECT_GT(lit_off_centre, 300);  // object pixels where the fall-off exceeds the tolerance
  const double mean_abs = abs_sum / n;
  EXPECT_GT(mean_abs, 0.05);  // compressed, not a copy
  EXPECT_LT(mean_abs, 3.0);   // grey levels of 255
}

// smooth_color writes colour PNGs (in RGB order: the point colours, taken
// from the rendered radiance, match the pixels read back) under a headlight.
TEST(Synthesizer, SmoothColorWritesColourImagesAndPointColours) {
  const std::string dir = FreshDir("smooth_color");
  SynthesizerOptions options = SmallOptions(dir);
  options.appearance.texture_style = "smooth_color";
  options.appearance.light = "headlight";
  SynthesizeWorkspace(options);
  const std::string dense = JoinPaths(dir, "dense");
  std::vector<cv::Mat> images;
  for (int i = 0; i < 6; ++i) {
    images.push_back(ReadRgb(JoinPaths(dense, "images/" + SynthViewName(i))));
  }
  int coloured = 0, object = 0;
  for (int row = 0; row < images[0].rows; ++row) {
    for (int col = 0; col < images[0].cols; ++col) {
      const cv::Vec3b p = images[0].at<cv::Vec3b>(row, col);
      if (p[0] + p[1] + p[2] == 0) continue;
      ++object;
      if (std::max({std::abs(p[0] - p[1]), std::abs(p[1] - p[2]), std::abs(p[0] - p[2])}) > 20) {
        ++coloured;
      }
    }
  }
  ASSERT_GT(object, 1000);
  EXPECT_GT(coloured, 0.3 * object);
  const Reconstruction model = ReadSparseModelBinary(JoinPaths(dense, "sparse"));
  ASSERT_GT(model.points3D.size(), 100u);
  int coloured_points = 0;
  double max_error = 0;
  for (const auto& [id, point] : model.points3D) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const TrackElement& el : point.track) {
      const Image& image = model.images.at(el.image_id);
      const Eigen::Vector2d xy = image.points2D[el.point2D_idx].xy;
      const cv::Vec3b bgr = images[el.image_id - 1].at<cv::Vec3b>(static_cast<int>(xy.y()),
                                                                  static_cast<int>(xy.x()));
      mean += Eigen::Vector3d(bgr[2], bgr[1], bgr[0]) / point.track.size();
    }
    // rgb truncates the mean radiance, the PNG rounds each pixel.
    max_error = std::max(max_error, (point.rgb.cast<double>() - mean).cwiseAbs().maxCoeff());
    if (std::abs(int(point.rgb(0)) - int(point.rgb(2))) > 20) ++coloured_points;
  }
  EXPECT_LT(max_error, 1.5);
  EXPECT_GT(coloured_points, 0.2 * model.points3D.size());
}

TEST(Synthesizer, ExistingWorkspaceIsRejected) {
  const std::string dir = FreshDir("exists");
  CreateDirIfNotExists(JoinPaths(dir, "dense"));
  EXPECT_THROW(SynthesizeWorkspace(SmallOptions(dir)), InputError);
}

TEST(Synthesizer, MissingModelPath) {
  SynthesizerOptions options = SmallOptions(FreshDir("missing"));
  options.model_path = "/nonexistent/model.obj";
  EXPECT_THROW(SynthesizeWorkspace(options), InputError);
}

TEST(Synthesizer, LoadsObjModelAndNormalisesIt) {
  const std::string dir = FreshDir("obj");
  CreateDirIfNotExists(dir);
  // An octahedron 4 units across, off-centre.
  const std::string obj = JoinPaths(dir, "octa.obj");
  {
    std::ofstream out(obj);
    out << "v 12 0 0\nv 8 0 0\nv 10 2 0\nv 10 -2 0\nv 10 0 2\nv 10 0 -2\n"
        << "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  }
  SynthesizerOptions options = SmallOptions(JoinPaths(dir, "out"));
  options.model_path = obj;
  const SynthesizerSummary summary = SynthesizeWorkspace(options);
  EXPECT_EQ(summary.num_gt_faces, 8);
  const TriangleMesh gt = ReadPly(JoinPaths(options.output_path, "ground_truth.ply"));
  EXPECT_NEAR((gt.V.colwise().maxCoeff() - gt.V.colwise().minCoeff()).norm(), 100, 1e-3);
  EXPECT_GT(summary.mean_coverage, 0.05);
}

TEST(Synthesizer, ModelUpAxisIsRotatedOntoZ) {
  const std::string dir = FreshDir("upaxis");
  CreateDirIfNotExists(dir);
  // A tetrahedron elongated along y (10 units) and 2 units across otherwise.
  const std::string obj = JoinPaths(dir, "rod.obj");
  {
    std::ofstream out(obj);
    out << "v 0 0 0\nv 2 0 0\nv 1 0 2\nv 1 10 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
  }
  for (const std::string axis : {"y", "z"}) {
    SynthesizerOptions options = SmallOptions(JoinPaths(dir, "out_" + axis));
    options.model_path = obj;
    options.model_up_axis = axis;
    SynthesizeWorkspace(options);
    const TriangleMesh gt = ReadPly(JoinPaths(options.output_path, "ground_truth.ply"));
    const Eigen::RowVector3d extent = gt.V.colwise().maxCoeff() - gt.V.colwise().minCoeff();
    Eigen::Index longest = 0;
    extent.maxCoeff(&longest);
    EXPECT_EQ(longest, axis == "y" ? 2 : 1) << "up axis " << axis;
  }
  SynthesizerOptions bad = SmallOptions(JoinPaths(dir, "bad"));
  bad.model_up_axis = "w";
  EXPECT_THROW(bad.Check(), InputError);
}

// The ground is part of the ground truth and of the images, under the
// object's lowest point; the cameras still frame the object alone.
TEST(Synthesizer, GroundPlaneUnderTheObject) {
  const std::string dir = FreshDir("ground");
  SynthesizerOptions plain = SmallOptions(JoinPaths(dir, "plain"));
  const SynthesizerSummary without = SynthesizeWorkspace(plain);
  SynthesizerOptions options = SmallOptions(JoinPaths(dir, "ground"));
  options.ground_plane_radius = 3;
  const SynthesizerSummary with = SynthesizeWorkspace(options);
  EXPECT_EQ(with.num_gt_faces, without.num_gt_faces + 2 * 64 * 64);
  const TriangleMesh object = ReadPly(JoinPaths(plain.output_path, "ground_truth.ply"));
  const TriangleMesh scene = ReadPly(JoinPaths(options.output_path, "ground_truth.ply"));
  ASSERT_EQ(scene.NumVertices(), object.NumVertices() + 65 * 65);
  EXPECT_TRUE(scene.V.topRows(object.NumVertices()) == object.V);
  const double radius = object.V.rowwise().norm().maxCoeff();
  const Eigen::MatrixXd ground = scene.V.bottomRows(65 * 65);
  EXPECT_DOUBLE_EQ(ground.col(2).minCoeff(), object.V.col(2).minCoeff());
  EXPECT_DOUBLE_EQ(ground.col(2).maxCoeff(), object.V.col(2).minCoeff());
  EXPECT_NEAR(ground.col(0).maxCoeff(), 3 * radius, 1e-3);  // float PLY
  EXPECT_NEAR(ground.col(1).minCoeff(), -3 * radius, 1e-3);
  // Facing up.
  const Eigen::MatrixXd N = FaceNormals(scene.V, scene.F);
  EXPECT_NEAR(N(scene.NumFaces() - 1, 2), 1.0, 1e-9);
  // The same cameras, and more of every image covered.
  const Reconstruction a = ReadSparseModel(JoinPaths(plain.output_path, "dense/sparse"));
  const Reconstruction b = ReadSparseModel(JoinPaths(options.output_path, "dense/sparse"));
  for (const auto& [id, image] : a.images) {
    EXPECT_TRUE(b.images.at(id).tvec.isApprox(image.tvec, 1e-12));
  }
  EXPECT_GT(with.mean_coverage, without.mean_coverage + 0.1);
  SynthesizerOptions bad = SmallOptions(JoinPaths(dir, "bad"));
  bad.ground_plane_radius = 0.5;  // inside the object
  EXPECT_THROW(bad.Check(), InputError);
  bad.ground_plane_radius = -1;
  EXPECT_THROW(bad.Check(), InputError);
}

TEST(ColmapRunner, HelpersAndFailureMessage) {
  EXPECT_FALSE(FindExecutable("sh").empty());
  EXPECT_TRUE(FindExecutable("no_such_program_mr_synth").empty());
  EXPECT_TRUE(FindExecutable("/nonexistent/colmap").empty());
  const std::string dir = FreshDir("runner");
  CreateDirIfNotExists(dir);
  const std::string ply = JoinPaths(dir, "a.ply");
  {
    std::ofstream out(ply);
    out << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nelement face 0\n"
        << "property list uchar int vertex_indices\nend_header\n1\n2\n3\n";
  }
  long nv = 0, nf = 0;
  ReadPlyElementCounts(ply, &nv, &nf);
  EXPECT_EQ(nv, 3);
  EXPECT_EQ(nf, 0);
  {
    std::ofstream out(JoinPaths(dir, "b.ply"));
    out << "not a ply\n";
  }
  EXPECT_THROW(ReadPlyElementCounts(JoinPaths(dir, "b.ply"), &nv, &nf), InputError);
  ColmapRunOptions options;
  options.colmap_path = "/bin/false";
  try {
    RunColmapFusionAndPoisson(dir, JoinPaths(dir, "logs"), options);
    FAIL() << "expected a failure";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("stereo_fusion failed"), std::string::npos) << e.what();
  }
  options.colmap_path = "no_such_program_mr_synth";
  EXPECT_THROW(RunColmapFusionAndPoisson(dir, JoinPaths(dir, "logs"), options), InputError);
}

// A colmap run that does not end within timeout_s is killed, with the
// processes it started, and the synthesis fails naming the limit. `fake`
// stands in for colmap: it writes a one-point fused.ply and then sleeps in a
// child process of its own.
TEST(ColmapRunner, RunPastTheTimeoutIsKilled) {
  const std::string dir = FreshDir("runner_timeout");
  CreateDirIfNotExists(dir);
  const std::string fake = JoinPaths(dir, "fake_colmap.sh");
  const std::string pid_file = JoinPaths(dir, "sleeper.pid");
  {
    std::ofstream out(fake);
    out << "#!/bin/sh\n"
        << "printf 'ply\\nformat ascii 1.0\\nelement vertex 1\\nproperty float x\\n"
           "end_header\\n0\\n' > '" << JoinPaths(dir, "fused.ply") << "'\n"
        << "echo 'Writing output'\n"
        << "sleep 1000 &\n"
        << "echo $! > '" << pid_file << "'\n"
        << "wait\n";
  }
  ASSERT_EQ(::chmod(fake.c_str(), 0755), 0);
  ColmapRunOptions options;
  options.colmap_path = fake;
  options.timeout_s = 5;  // time for the fake to reach its sleep on a loaded machine
  const double t0 = ElapsedSeconds();
  try {
    RunColmapFusionAndPoisson(dir, JoinPaths(dir, "logs"), options);
    FAIL() << "expected a failure";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("stereo_fusion did not end within 5 s"), std::string::npos) << what;
    EXPECT_NE(what.find("Writing output"), std::string::npos) << what;
  }
  EXPECT_LT(ElapsedSeconds() - t0, 60);
  ASSERT_TRUE(ExistsFile(pid_file)) << "the fake did not reach its sleep in 5 s";
  const int sleeper = std::stoi(ReadFileToString(pid_file));
  // SIGKILL'd with its group; reaped by init shortly after.
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    gone = ::kill(sleeper, 0) != 0;
    if (!gone) ::usleep(20000);
  }
  EXPECT_TRUE(gone) << "the fake's child " << sleeper << " outlived the timeout";
  options.timeout_s = -1;
  EXPECT_THROW(options.Check(), InputError);
}

// The whole path with the real colmap: stereo_fusion + poisson_mesher give a
// non-empty mesh close to the ground truth.
TEST(Synthesizer, EndToEndWithColmap) {
  const std::string colmap = MR_COLMAP_EXECUTABLE;
  if (colmap.empty()) GTEST_SKIP() << "colmap not found at configure time";
  const std::string dir = FreshDir("e2e");
  SynthesizerOptions options = SmallOptions(dir);
  options.cameras.num_views = 10;
  options.cameras.width = 240;
  options.cameras.height = 180;
  options.run_colmap = true;
  options.colmap.colmap_path = colmap;
  options.colmap.poisson_depth = 8;
  options.colmap.num_threads = 1;  // see ColmapRunOptions::timeout_s
  options.colmap.timeout_s = 300;
  const SynthesizerSummary summary = SynthesizeWorkspace(options);
  ASSERT_TRUE(summary.ran_colmap);
  EXPECT_GT(summary.colmap.fused_points, 1000);
  EXPECT_GT(summary.colmap.poisson_faces, 1000);
  const std::string dense = JoinPaths(dir, "dense");
  const TriangleMesh mesh = ReadPly(JoinPaths(dense, "meshed-poisson.ply"));
  ASSERT_GT(mesh.NumFaces(), 0);
  const TriangleMesh gt = ReadPly(JoinPaths(dir, "ground_truth.ply"));
  double sum = 0;
  int n = 0;
  const int step = std::max(1, mesh.NumVertices() / 400);
  for (int v = 0; v < mesh.NumVertices(); v += step, ++n) {
    sum += PointMeshDistance(mesh.V.row(v).transpose(), gt.V, gt.F);
  }
  // Mean distance well under 1% of the 100-unit diagonal.
  EXPECT_LT(sum / n, 1.0);
  EXPECT_TRUE(ExistsFile(JoinPaths(dir, "logs/stereo_fusion.log")));
  EXPECT_TRUE(ExistsFile(JoinPaths(dir, "logs/poisson_mesher.log")));
}

}  // namespace
}  // namespace mr
