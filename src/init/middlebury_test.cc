#include "init/middlebury.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap_io/sparse_model.h"
#include "geometry/view.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

// Two lines of dinoSR_par.txt (real values).
const char kLine1[] =
    "dinoSR0001.png 3310.400000 0.000000 316.730000 0.000000 3325.500000 200.550000 0.000000 "
    "0.000000 1.000000 -0.14396457836077139000 0.96965263281337499000 0.19760617153779569000 "
    "-0.90366580603479685000 -0.04743335255026152200 -0.42560419233334673000 "
    "-0.40331536459778505000 -0.23984130575212276000 0.88306936201487163000 -0.010415508744 "
    "-0.0294278883669 0.673097816109\n";
const char kLine2[] =
    "dinoSR0002.png 3310.400000 0.000000 316.730000 0.000000 3325.500000 200.550000 0.000000 "
    "0.000000 1.000000 -0.23143687262851170000 0.96422332027030622000 0.12926937165558827000 "
    "-0.65860811165749811000 -0.05749426020475298400 -0.75028640486482034000 "
    "-0.71601208187197274000 -0.25878137856376976000 0.64835049619606955000 -0.0143392676288 "
    "-0.0315356332107 0.659314086504\n";

TEST(ReadMiddleburyPar, Nominal) {
  const std::string path = JoinPaths(MakeTestDir("par"), "x_par.txt");
  WriteText(path, std::string("2\n") + kLine1 + "\n" + kLine2);
  const auto cams = ReadMiddleburyPar(path);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams[0].name, "dinoSR0001.png");
  EXPECT_EQ(cams[1].name, "dinoSR0002.png");
  EXPECT_DOUBLE_EQ(cams[0].K(0, 0), 3310.4);
  EXPECT_DOUBLE_EQ(cams[0].K(1, 2), 200.55);
  EXPECT_DOUBLE_EQ(cams[0].R(1, 0), -0.90366580603479685);
  EXPECT_DOUBLE_EQ(cams[1].t(2), 0.659314086504);
  EXPECT_NEAR(cams[0].R.determinant(), 1.0, 1e-6);  // the data set's precision
}

TEST(ReadMiddleburyPar, BadLines) {
  const std::string dir = MakeTestDir("par_bad");
  const std::string path = JoinPaths(dir, "x_par.txt");
  // A missing field.
  std::string short_line = kLine2;
  short_line = short_line.substr(0, short_line.rfind(' ')) + "\n";
  WriteText(path, std::string("2\n") + kLine1 + short_line);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // A non-numeric field.
  std::string bad = kLine2;
  bad.replace(bad.find("3310.4"), 6, "33x0.4");
  WriteText(path, std::string("2\n") + kLine1 + bad);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // A count that does not match.
  WriteText(path, std::string("3\n") + kLine1 + kLine2);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // No count.
  WriteText(path, kLine1);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // A rotation that is not one (r11 scaled).
  std::string scaled = kLine2;
  scaled.replace(scaled.find("-0.2314"), 7, "-0.9314");
  WriteText(path, std::string("2\n") + kLine1 + scaled);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // Duplicate names.
  WriteText(path, std::string("2\n") + kLine1 + kLine1);
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  // Empty and missing files.
  WriteText(path, "");
  EXPECT_THROW(ReadMiddleburyPar(path), InputError);
  EXPECT_THROW(ReadMiddleburyPar(JoinPaths(dir, "missing_par.txt")), InputError);
}

TEST(MiddleburyToColmap, ProjectionMatchesWithHalfPixelOffset) {
  const std::string path = JoinPaths(MakeTestDir("par_proj"), "x_par.txt");
  WriteText(path, std::string("2\n") + kLine1 + kLine2);
  for (const MiddleburyCamera& mb : ReadMiddleburyPar(path)) {
    for (const double scale : {1.0, 1000.0}) {
      Camera camera;
      Image image;
      MiddleburyToColmap(mb, 640, 480, scale, 7, &camera, &image);
      EXPECT_EQ(camera.model, CameraModel::kPinhole);
      EXPECT_EQ(camera.camera_id, 7u);
      EXPECT_EQ(image.camera_id, 7u);
      EXPECT_EQ(image.name, mb.name);
      const PinholeView view = ViewFromColmap(camera, image);
      for (const Eigen::Vector3d& X : {Eigen::Vector3d(-0.03, 0.02, -0.02),
                                      Eigen::Vector3d(0.0, 0.05, 0.01),
                                      Eigen::Vector3d(-0.06, -0.01, -0.05)}) {
        const Eigen::Vector3d x = mb.Projection() * X.homogeneous();
        const Eigen::Vector2d mb_pixel = x.hnormalized();
        const Eigen::Vector2d colmap_pixel = view.Project(scale * X);
        // Up to the orthonormalization of R (the file's R is orthonormal to
        // ~1e-7, i.e. ~1e-4 px here).
        EXPECT_NEAR(colmap_pixel.x() - 0.5, mb_pixel.x(), 1e-3);
        EXPECT_NEAR(colmap_pixel.y() - 0.5, mb_pixel.y(), 1e-3);
      }
      // The camera centre scales with the units.
      const Eigen::Vector3d c = -mb.R.transpose() * mb.t;
      EXPECT_NEAR((view.Center() - scale * c).norm(), 0, 1e-6 * scale);
    }
  }
}

TEST(MiddleburyToColmap, RejectsNonPinholeK) {
  MiddleburyCamera mb;
  mb.name = "a.png";
  mb.K << 100, 0, 50, 0, 100, 40, 0, 0, 1;
  Camera camera;
  Image image;
  EXPECT_NO_THROW(MiddleburyToColmap(mb, 100, 80, 1, 1, &camera, &image));
  mb.K(0, 1) = 0.5;  // skew
  EXPECT_THROW(MiddleburyToColmap(mb, 100, 80, 1, 1, &camera, &image), InputError);
  mb.K(0, 1) = 0;
  mb.K(2, 2) = 2;
  EXPECT_THROW(MiddleburyToColmap(mb, 100, 80, 1, 1, &camera, &image), InputError);
  mb.K(2, 2) = 1;
  mb.K(0, 0) = -100;
  EXPECT_THROW(MiddleburyToColmap(mb, 100, 80, 1, 1, &camera, &image), InputError);
}

TEST(ReadMiddleburyBoundingBox, DinoReadme) {
  const std::string dir = MakeTestDir("readme");
  const std::string path = JoinPaths(dir, "README.txt");
  WriteText(path,
            "dinoSparseRing data set\n\nThe (tight) bounding box for the dino model is\n"
            "(-0.061897 -0.018874 -0.057845)\n(0.010897 0.068227 0.015495)\n\n----\n");
  Eigen::AlignedBox3d box;
  ASSERT_TRUE(ReadMiddleburyBoundingBox(path, &box));
  EXPECT_DOUBLE_EQ(box.min().x(), -0.061897);
  EXPECT_DOUBLE_EQ(box.max().z(), 0.015495);
  WriteText(path, "no box here\n");
  EXPECT_FALSE(ReadMiddleburyBoundingBox(path, &box));
  WriteText(path, "bounding box\n(1 2 3)\n(0 5 6)\n");
  EXPECT_THROW(ReadMiddleburyBoundingBox(path, &box), InputError);
  WriteText(path, "bounding box\n(1 2)\n(4 5 6)\n");
  EXPECT_THROW(ReadMiddleburyBoundingBox(path, &box), InputError);
}

TEST(ParseBoundingBox, Malformed) {
  EXPECT_NO_THROW(ParseBoundingBox("0 0 0 1 1 1", "flag"));
  EXPECT_THROW(ParseBoundingBox("0 0 0 1 1", "flag"), InputError);
  EXPECT_THROW(ParseBoundingBox("0 0 0 1 1 x", "flag"), InputError);
  EXPECT_THROW(ParseBoundingBox("0 0 0 1 0 1", "flag"), InputError);
}

TEST(SilhouetteOptions, DefaultsAreValid) { EXPECT_TRUE(SilhouetteOptions().Check()); }

TEST(MiddleburyConversionOptions, DefaultsAreValid) {
  EXPECT_TRUE(MiddleburyConversionOptions().Check());
  MiddleburyConversionOptions o;
  o.scale = 0;
  EXPECT_THROW(o.Check(), InputError);
}

TEST(ComputeSilhouette, FillsShadowsAndGrowsByThreePixels) {
  cv::Mat image(100, 100, CV_8UC3, cv::Scalar(10, 10, 10));
  cv::circle(image, cv::Point(50, 50), 30, cv::Scalar(200, 200, 200), cv::FILLED);
  cv::circle(image, cv::Point(50, 50), 4, cv::Scalar(20, 20, 20), cv::FILLED);  // a shadow
  const cv::Mat mask = ComputeSilhouette(image, SilhouetteOptions());
  ASSERT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(mask.at<uchar>(50, 50), 255);           // the shadow is filled
  EXPECT_EQ(mask.at<uchar>(50, 50 + 30 + 2), 255);  // dilated 10, eroded 7: +3 px
  EXPECT_EQ(mask.at<uchar>(50, 50 + 30 + 5), 0);
  EXPECT_EQ(mask.at<uchar>(5, 5), 0);
  // Holes: a 26x26 one (20x20 after the net 3-px dilation) is filled, a
  // 60x60 one is kept, unless hole filling is off.
  cv::Mat holes(200, 200, CV_8UC1, cv::Scalar(0));
  holes(cv::Rect(20, 20, 160, 160)).setTo(200);
  holes(cv::Rect(40, 40, 26, 26)).setTo(0);
  holes(cv::Rect(100, 100, 60, 60)).setTo(0);
  SilhouetteStats stats;
  const cv::Mat filled = ComputeSilhouette(holes, SilhouetteOptions(), &stats);
  EXPECT_EQ(filled.at<uchar>(53, 53), 255);
  EXPECT_EQ(filled.at<uchar>(130, 130), 0);
  EXPECT_EQ(stats.filled_holes, 1);
  EXPECT_EQ(stats.kept_holes, 1);
  // 20x20 and 54x54, less the corners the disc morphology rounds off.
  EXPECT_GT(stats.largest_filled, 20 * 20 - 80);
  EXPECT_LE(stats.largest_filled, 20 * 20);
  EXPECT_GT(stats.smallest_kept, 54 * 54 - 80);
  EXPECT_LE(stats.smallest_kept, 54 * 54);
  SilhouetteOptions no_fill;
  no_fill.fill_holes_px = 0;
  EXPECT_EQ(ComputeSilhouette(holes, no_fill).at<uchar>(53, 53), 0);
  // An object cut by the image border is not eroded from the border.
  cv::Mat cut(50, 50, CV_8UC1, cv::Scalar(0));
  cut(cv::Rect(0, 10, 20, 30)).setTo(200);
  const cv::Mat cut_mask = ComputeSilhouette(cut, SilhouetteOptions());
  EXPECT_EQ(cut_mask.at<uchar>(25, 0), 255);
  EXPECT_EQ(cut_mask.at<uchar>(10, 0), 255);
  EXPECT_EQ(cut_mask.at<uchar>(25, 22), 255);  // +3 px on the inner side
  EXPECT_EQ(cut_mask.at<uchar>(25, 24), 0);
  // Just below and above the threshold (0.19 * 255 = 48.45).
  cv::Mat flat(20, 20, CV_8UC1, cv::Scalar(48));
  EXPECT_EQ(cv::countNonZero(ComputeSilhouette(flat, SilhouetteOptions())), 0);
  flat.setTo(49);
  EXPECT_EQ(cv::countNonZero(ComputeSilhouette(flat, SilhouetteOptions())), 400);
}

TEST(ConvertMiddlebury, TinyDataSet) {
  const std::string in = MakeTestDir("convert_in");
  const std::string out = MakeTestDir("convert_out");
  // Four 64x48 views of a small scene with a box in README units (metres).
  std::string par = "4\n";
  for (int i = 1; i <= 4; ++i) {
    const std::string name = "t" + std::to_string(i) + ".png";
    cv::Mat img(48, 64, CV_8UC3, cv::Scalar(0, 0, 0));
    cv::rectangle(img, cv::Rect(20, 15, 20, 15), cv::Scalar(255, 255, 255), cv::FILLED);
    cv::imwrite(JoinPaths(in, name), img);
    par += name + " 50 0 31.5 0 50 23.5 0 0 1 1 0 0 0 1 0 0 0 1 0 0 " +
           std::to_string(0.5 + 0.1 * i) + "\n";
  }
  WriteText(JoinPaths(in, "t_par.txt"), par);
  WriteText(JoinPaths(in, "README.txt"), "The bounding box is\n(-0.01 -0.02 -0.03)\n(0.01 0.02 0.03)\n");
  MiddleburyConversionOptions options;
  options.holdout = "2, 4";
  const MiddleburyConversionSummary summary = ConvertMiddlebury(in, out, options);
  EXPECT_EQ(summary.num_images, 4);
  ASSERT_EQ(summary.holdout.size(), 2u);
  EXPECT_EQ(summary.holdout[0], "t2.png");
  EXPECT_EQ(ReadImageNameList(JoinPaths(out, "holdout.txt")), summary.holdout);
  const Eigen::AlignedBox3d box = ReadBoundingBoxFile(JoinPaths(out, "bbox.txt"));
  EXPECT_NEAR(box.min().z(), -30, 1e-9);  // millimetres
  EXPECT_NEAR(box.max().y(), 20, 1e-9);
  const Reconstruction model = ReadSparseModel(JoinPaths(out, "sparse"));
  ASSERT_EQ(model.images.size(), 4u);
  ASSERT_EQ(model.cameras.size(), 4u);
  const Image& image = model.images.at(3);
  EXPECT_EQ(image.name, "t3.png");
  EXPECT_NEAR(image.tvec.z(), 800, 1e-9);
  const Camera& camera = model.cameras.at(image.camera_id);
  EXPECT_EQ(camera.width, 64u);
  EXPECT_EQ(camera.height, 48u);
  EXPECT_NEAR(camera.params[2], 32.0, 1e-12);
  EXPECT_NEAR(camera.params[3], 24.0, 1e-12);
  EXPECT_TRUE(ExistsFile(JoinPaths(out, "images/t1.png")));
  const cv::Mat mask = cv::imread(JoinPaths(out, "masks/t1.png.png"), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(mask.empty());
  EXPECT_EQ(mask.at<uchar>(22, 30), 255);
  EXPECT_EQ(mask.at<uchar>(2, 2), 0);
  // Default hold-out: every 4th image.
  options.holdout.clear();
  EXPECT_EQ(ConvertMiddlebury(in, out, options).holdout,
            std::vector<std::string>({"t4.png"}));
  // Bad hold-out lists.
  options.holdout = "5";
  EXPECT_THROW(ConvertMiddlebury(in, out, options), InputError);
  options.holdout = "1,2,3,4";
  EXPECT_THROW(ConvertMiddlebury(in, out, options), InputError);
}

TEST(ConvertMiddlebury, MissingImageOrParFile) {
  const std::string in = MakeTestDir("convert_missing");
  const std::string out = MakeTestDir("convert_missing_out");
  EXPECT_THROW(ConvertMiddlebury(in, out, MiddleburyConversionOptions()), InputError);
  WriteText(JoinPaths(in, "t_par.txt"), "1\nnope.png 50 0 31.5 0 50 23.5 0 0 1 1 0 0 0 1 0 0 0 1 0 0 1\n");
  EXPECT_THROW(ConvertMiddlebury(in, out, MiddleburyConversionOptions()), InputError);
}

}  // namespace
}  // namespace mr
