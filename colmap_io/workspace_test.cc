#include "colmap_io/workspace.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap_io/test_models.h"
#include "colmap_io/undistortion.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

using test::TempDir;
namespace fs = std::filesystem;

// A model of 64x48 images "c.png", "a.png", "sub/b.png" (ids 1, 2, 3).
Reconstruction MakeModel(CameraModel model, const std::vector<double>& params) {
  Reconstruction r;
  Camera camera;
  camera.camera_id = 1;
  camera.model = model;
  camera.width = 64;
  camera.height = 48;
  camera.params = params;
  r.cameras[1] = camera;
  const char* names[] = {"c.png", "a.png", "sub/b.png"};
  for (uint32_t id = 1; id <= 3; ++id) {
    Image image;
    image.image_id = id;
    image.camera_id = 1;
    image.name = names[id - 1];
    image.tvec = Eigen::Vector3d(0.1 * id, 0, 0);
    r.images[id] = image;
  }
  return r;
}

Reconstruction PinholeModel() { return MakeModel(CameraModel::kPinhole, {60, 60, 32, 24}); }
Reconstruction DistortedModel(double k = -0.05) {
  return MakeModel(CameraModel::kSimpleRadial, {60, 32, 24, k});
}

void WriteImages(const std::string& dir, const Reconstruction& model, int width = 64) {
  for (const auto& [id, image] : model.images) {
    const std::string path = dir + "/" + image.name;
    fs::create_directories(fs::path(path).parent_path());
    cv::Mat m(48, width, CV_8UC3, cv::Scalar(10 * id, 20, 30));
    ASSERT_TRUE(cv::imwrite(path, m));
  }
}

// images/ + sparse/ (dense workspace) or images/ + sparse/0 (sparse project).
std::string MakeWorkspace(const TempDir& dir, const Reconstruction& model, const std::string& sparse,
                          bool text = false) {
  const std::string images = dir.Sub("images");
  WriteImages(images, model);
  const std::string s = dir.Sub(sparse);
  if (text) {
    WriteSparseModelText(s, model);
  } else {
    WriteSparseModelBinary(s, model);
  }
  return dir.path();
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

std::string Encode(const std::string& ext, const cv::Mat& image,
                   const std::vector<int>& params = {}) {
  std::vector<uchar> buffer;
  EXPECT_TRUE(cv::imencode(ext, image, buffer, params));
  return std::string(buffer.begin(), buffer.end());
}

// A JPEG (as written by OpenCV) with an APP1 Exif segment holding only
// Orientation = `orientation` inserted right after SOI, as cameras write it.
std::string JpegWithExifOrientation(const cv::Mat& image, int orientation) {
  const std::string jpeg = Encode(".jpg", image);
  std::string tiff("II*\0\x08\0\0\0", 8);              // little-endian TIFF header, IFD at 8
  tiff += std::string("\x01\0", 2);                    // 1 entry
  tiff += std::string("\x12\x01\x03\0\x01\0\0\0", 8);  // tag 0x0112 SHORT, count 1
  tiff += std::string(1, static_cast<char>(orientation)) + std::string(3, '\0');
  tiff += std::string(4, '\0');                         // no next IFD
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  const size_t length = payload.size() + 2;
  std::string app1 = "\xff\xe1";
  app1 += static_cast<char>(length >> 8);
  app1 += static_cast<char>(length & 0xff);
  app1 += payload;
  return jpeg.substr(0, 2) + app1 + jpeg.substr(2);
}

// 640x480, four quadrants of different grey so that any turn or flip shows.
cv::Mat QuadrantImage(int type) {
  cv::Mat image(480, 640, type);
  image(cv::Rect(0, 0, 320, 240)).setTo(cv::Scalar::all(30));
  image(cv::Rect(320, 0, 320, 240)).setTo(cv::Scalar::all(220));
  image(cv::Rect(0, 240, 320, 240)).setTo(cv::Scalar::all(120));
  image(cv::Rect(320, 240, 320, 240)).setTo(cv::Scalar::all(180));
  return image;
}

void ExpectQuadrants(const cv::Mat& image, const std::string& what) {
  ASSERT_EQ(image.cols, 640) << what;
  ASSERT_EQ(image.rows, 480) << what;
  cv::Mat gray = image;
  if (image.channels() == 3) cv::extractChannel(image, gray, 1);
  EXPECT_NEAR(gray.at<uint8_t>(100, 100), 30, 6) << what;
  EXPECT_NEAR(gray.at<uint8_t>(100, 540), 220, 6) << what;
  EXPECT_NEAR(gray.at<uint8_t>(380, 100), 120, 6) << what;
  EXPECT_NEAR(gray.at<uint8_t>(380, 540), 180, 6) << what;
}

TEST(WorkspaceOptions, DefaultsAreValid) { EXPECT_TRUE(WorkspaceOptions().Check()); }

TEST(Workspace, DenseWorkspace) {
  TempDir dir("ws_dense");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  const Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.root, root);
  EXPECT_EQ(ws.image_dir, root + "/images");
  EXPECT_EQ(ws.sparse_dir, root + "/sparse");
  EXPECT_TRUE(ws.mask_dir.empty());
  EXPECT_TRUE(ws.undistortion.empty());
  EXPECT_EQ(ws.image_ids, (std::vector<uint32_t>{2, 1, 3}));  // a, c, sub/b by name
  EXPECT_EQ(ws.ImagePath(3), root + "/images/sub/b.png");
  const cv::Mat color = ws.ReadImage(1, false), gray = ws.ReadImage(1, true);
  EXPECT_EQ(color.type(), CV_8UC3);
  EXPECT_EQ(gray.type(), CV_8UC1);
  EXPECT_EQ(color.cols, 64);
  EXPECT_EQ(color.at<cv::Vec3b>(0, 0)[0], 10);
  EXPECT_TRUE(ws.ReadMask(1).empty());
  EXPECT_EQ(ws.MaskPath(1), "");

  EXPECT_EQ(ws.DefaultMeshPath(), "");
  std::ofstream(root + "/meshed-delaunay.ply") << "ply";
  EXPECT_EQ(ws.DefaultMeshPath(), root + "/meshed-delaunay.ply");
  std::ofstream(root + "/meshed-poisson.ply") << "ply";
  EXPECT_EQ(ws.DefaultMeshPath(), root + "/meshed-poisson.ply");
}

TEST(Workspace, DenseWorkspaceTextModel) {
  TempDir dir("ws_dense_txt");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse", true);
  const Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.model.images.size(), 3u);
}

TEST(Workspace, PinholeSparseProject) {
  TempDir dir("ws_sparse_pinhole");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse/0");
  const Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.sparse_dir, root + "/sparse/0");
  EXPECT_TRUE(ws.undistortion.empty());
  EXPECT_FALSE(ExistsDir(root + "/mesh_refiner_undistorted"));
}

TEST(Workspace, DistortedSparseProjectIsUndistorted) {
  TempDir dir("ws_sparse_distorted");
  const std::string root = MakeWorkspace(dir, DistortedModel(), "sparse/0");
  const std::string out = root + "/mesh_refiner_undistorted";
  Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.root, out);
  EXPECT_EQ(ws.image_dir, out + "/images");
  EXPECT_EQ(ws.sparse_dir, out + "/sparse");
  EXPECT_NE(ws.undistortion.find("undistorted 3 images with built-in camera model equations"),
            std::string::npos)
      << ws.undistortion;
  EXPECT_EQ(ws.model.cameras.at(1).model, CameraModel::kPinhole);
  EXPECT_EQ(ws.model.cameras.at(1).params, (std::vector<double>{60, 60, 32, 24}));
  EXPECT_EQ(ws.ReadImage(3, false).cols, 64);
  // The user's files are untouched.
  EXPECT_EQ(ReadSparseModel(root + "/sparse/0").cameras.at(1).model, CameraModel::kSimpleRadial);

  // The project's own mesh is the default mesh.
  EXPECT_EQ(ws.DefaultMeshPath(), "");
  std::ofstream(root + "/meshed-poisson.ply") << "ply";
  EXPECT_EQ(ws.DefaultMeshPath(), root + "/meshed-poisson.ply");

  // Opening again reuses the complete output.
  const auto stamp = fs::last_write_time(out + "/images/a.png");
  ws = OpenWorkspace(root);
  EXPECT_NE(ws.undistortion.find("reused"), std::string::npos) << ws.undistortion;
  EXPECT_EQ(fs::last_write_time(out + "/images/a.png"), stamp);

  // A changed model is undistorted again.
  WriteSparseModelBinary(root + "/sparse/0", DistortedModel(-0.07));
  ws = OpenWorkspace(root);
  EXPECT_NE(ws.undistortion.find("undistorted 3 images"), std::string::npos) << ws.undistortion;

  // Replaced source images are undistorted again.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(cv::imwrite(root + "/images/a.png", cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3))));
  ws = OpenWorkspace(root);
  EXPECT_NE(ws.undistortion.find("undistorted 3 images"), std::string::npos) << ws.undistortion;

  // An interrupted run (partial marker, no completion marker) is redone.
  fs::remove(out + "/" + kUndistortionMarker);
  std::ofstream(out + "/" + kUndistortionPartialMarker) << "x";
  ws = OpenWorkspace(root);
  EXPECT_NE(ws.undistortion.find("undistorted 3 images"), std::string::npos) << ws.undistortion;
}

TEST(Workspace, NeverOverwritesUserFolder) {
  TempDir dir("ws_user_folder");
  const std::string root = MakeWorkspace(dir, DistortedModel(), "sparse/0");
  dir.Sub("mesh_refiner_undistorted");
  std::ofstream(root + "/mesh_refiner_undistorted/notes.txt") << "mine";
  ExpectInputError([&] { OpenWorkspace(root); }, {"mesh_refiner_undistorted", "will not overwrite"});
  EXPECT_EQ(ReadFileToString(root + "/mesh_refiner_undistorted/notes.txt"), "mine");
}

TEST(Workspace, Masks) {
  TempDir dir("ws_masks");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  const std::string masks = dir.Sub("masks");
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.mask_dir, masks);
  EXPECT_EQ(ws.MaskPath(2), masks + "/a.png.png");
  EXPECT_EQ(ws.ReadMask(2).at<uint8_t>(3, 3), 255);
  EXPECT_TRUE(ws.ReadMask(1).empty());  // c.png has no mask

  // An explicit folder wins; a wrongly sized mask is refused on reading.
  const std::string other = dir.Sub("other_masks");
  ASSERT_TRUE(cv::imwrite(other + "/c.png.png", cv::Mat(10, 10, CV_8UC1, cv::Scalar(255))));
  WorkspaceOptions options;
  options.mask_path = other;
  ws = OpenWorkspace(root, options);
  EXPECT_EQ(ws.mask_dir, other);
  ExpectInputError([&] { ws.ReadMask(1); }, {"c.png.png", "10x10"});

  options.mask_path = root + "/nope";
  ExpectInputError([&] { OpenWorkspace(root, options); }, {"nope", "mask folder does not exist"});
}

TEST(Workspace, MasksOfDistortedProjectAreUndistorted) {
  TempDir dir("ws_masks_distorted");
  const std::string root = MakeWorkspace(dir, DistortedModel(), "sparse/0");
  const std::string masks = dir.Sub("masks");
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  const Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.mask_dir, root + "/mesh_refiner_undistorted/masks");
  EXPECT_EQ(ws.ReadMask(2).at<uint8_t>(24, 32), 255);
  EXPECT_TRUE(ws.ReadMask(1).empty());
}

TEST(Workspace, LowestNumberedSparseModel) {
  TempDir dir("ws_sparse_numbered");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse/3");
  Reconstruction other = PinholeModel();
  other.images.erase(3);
  WriteSparseModelBinary(dir.Sub("sparse/12"), other);
  dir.Sub("sparse/1");  // empty: ignored
  EXPECT_EQ(OpenWorkspace(root).sparse_dir, root + "/sparse/3");
}

TEST(Workspace, StereoMasksFallback) {
  TempDir dir("ws_stereo_masks");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  const std::string masks = dir.Sub("stereo/masks");
  ASSERT_TRUE(cv::imwrite(masks + "/c.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(7))));
  const Workspace ws = OpenWorkspace(root);
  EXPECT_EQ(ws.mask_dir, masks);
  EXPECT_EQ(ws.ReadMask(1).at<uint8_t>(0, 0), 7);
}

TEST(Workspace, MissingFolder) {
  ExpectInputError([&] { OpenWorkspace("/nonexistent/ws"); },
                   {"/nonexistent/ws", "workspace folder does not exist"});
}

TEST(Workspace, NoImagesFolder) {
  TempDir dir("ws_no_images");
  WriteSparseModelBinary(dir.Sub("sparse"), PinholeModel());
  ExpectInputError([&] { OpenWorkspace(dir.path()); }, {"no images folder", "images"});
}

TEST(Workspace, NoSparseModel) {
  TempDir dir("ws_no_sparse");
  WriteImages(dir.Sub("images"), PinholeModel());
  ExpectInputError([&] { OpenWorkspace(dir.path()); }, {"no sparse model", "sparse/0"});
  dir.Sub("sparse/0");
  ExpectInputError([&] { OpenWorkspace(dir.path()); }, {"no sparse model"});
}

TEST(Workspace, MissingImages) {
  TempDir dir("ws_missing_images");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  fs::remove(root + "/images/a.png");
  fs::remove(root + "/images/sub/b.png");
  ExpectInputError([&] { OpenWorkspace(root); }, {"2 of 3 images", "a.png", "sub/b.png"});
}

// An image path that exists but is a folder is "not a file", not "missing".
TEST(Workspace, ImagePathIsAFolder) {
  TempDir dir("ws_image_folder");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  fs::remove(root + "/images/a.png");
  fs::create_directories(root + "/images/a.png");
  try {
    OpenWorkspace(root);
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(root + "/images/a.png"), std::string::npos) << what;
    EXPECT_NE(what.find("not a file"), std::string::npos) << what;
    EXPECT_EQ(what.find("missing"), std::string::npos) << what;
  }
}

TEST(Workspace, ZeroRegisteredImages) {
  TempDir dir("ws_zero_images");
  Reconstruction model = PinholeModel();
  model.images.clear();
  MakeWorkspace(dir, model, "sparse");
  ExpectInputError([&] { OpenWorkspace(dir.path()); }, {"zero registered images"});
}

TEST(Workspace, WrongImageSize) {
  TempDir dir("ws_image_size");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  ASSERT_TRUE(cv::imwrite(root + "/images/a.png", cv::Mat(48, 50, CV_8UC3, cv::Scalar(0))));
  const Workspace ws = OpenWorkspace(root);
  ExpectInputError([&] { ws.ReadImage(2, true); }, {"a.png", "50x48", "64x48"});
}

TEST(Workspace, CustomImageFolder) {
  TempDir dir("ws_custom_images");
  const Reconstruction model = PinholeModel();
  WriteSparseModelBinary(dir.Sub("sparse"), model);
  WriteImages(dir.Sub("elsewhere"), model);
  ExpectInputError([&] { OpenWorkspace(dir.path()); }, {"no images folder"});
  WorkspaceOptions options;
  options.image_path = dir.path() + "/elsewhere";
  const Workspace ws = OpenWorkspace(dir.path(), options);
  EXPECT_EQ(ws.ImagePath(1), dir.path() + "/elsewhere/c.png");
}

// COLMAP reads the raw pixels and ignores EXIF orientation (its undistorter
// copies the pixels and keeps the tag): a 640x480 JPEG tagged Orientation = 6
// is a 640x480 image here too, unrotated; so are masks and the images and
// masks of a distorted project.
TEST(Workspace, ExifOrientationIsIgnored) {
  for (const CameraModel camera_model : {CameraModel::kPinhole, CameraModel::kSimpleRadial}) {
    TempDir dir("ws_exif");
    Reconstruction model = camera_model == CameraModel::kPinhole
                               ? MakeModel(camera_model, {500, 500, 320, 240})
                               : MakeModel(camera_model, {500, 320, 240, 0.0});
    model.cameras.at(1).width = 640;
    model.cameras.at(1).height = 480;
    for (auto& [id, image] : model.images) image.name = "view_" + std::to_string(id) + ".jpg";
    const std::string images = dir.Sub("images"), masks = dir.Sub("masks");
    for (const auto& [id, image] : model.images) {
      WriteBytes(images + "/" + image.name, JpegWithExifOrientation(QuadrantImage(CV_8UC3), 6));
      // A mask is found by its name; its content may be any format OpenCV reads.
      WriteBytes(masks + "/" + image.name + ".png",
                 JpegWithExifOrientation(QuadrantImage(CV_8UC1), 6));
    }
    // Check that the tag is there: a reader that applies it turns the image.
    ASSERT_EQ(cv::imread(images + "/view_1.jpg", cv::IMREAD_COLOR).cols, 480);
    WriteSparseModelBinary(dir.Sub(camera_model == CameraModel::kPinhole ? "sparse" : "sparse/0"),
                           model);
    const Workspace ws = OpenWorkspace(dir.path());
    const std::string what = CameraModelName(camera_model);
    ExpectQuadrants(ws.ReadImage(1, /*grayscale=*/false), what + " color");
    ExpectQuadrants(ws.ReadImage(1, /*grayscale=*/true), what + " gray");
    ExpectQuadrants(ws.ReadMask(1), what + " mask");
  }
}

// libjpeg only warns ("Premature end of JPEG file") and OpenCV returns the
// grey-filled rest: a cut image is an error naming the file, for images and
// masks, in a dense workspace and when undistorting a sparse project.
TEST(Workspace, TruncatedImagesAreRefused) {
  cv::Mat noise(48, 64, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  const std::string jpeg = Encode(".jpg", noise), png = Encode(".png", noise);
  const std::string progressive = Encode(".jpg", noise, {cv::IMWRITE_JPEG_PROGRESSIVE, 1});
  const std::string restarts = Encode(".jpg", noise, {cv::IMWRITE_JPEG_RST_INTERVAL, 2});
  for (const std::string& bytes :
       {jpeg.substr(0, jpeg.size() / 2), png.substr(0, png.size() / 2),
        progressive.substr(0, progressive.size() * 3 / 4),
        restarts.substr(0, restarts.size() - 10), jpeg.substr(0, jpeg.size() - 2) + "\0\0"}) {
    TempDir dir("ws_truncated");
    const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
    WriteBytes(root + "/images/a.png", bytes);
    const Workspace ws = OpenWorkspace(root);
    ExpectInputError([&] { ws.ReadImage(2, true); },
                     {root + "/images/a.png", "truncated or corrupt image"});
    ExpectInputError([&] { ws.ReadImage(2, false); },
                     {root + "/images/a.png", "truncated or corrupt image"});
    EXPECT_EQ(ws.ReadImage(1, true).cols, 64);

    // A mask.
    const std::string masks = dir.Sub("masks");
    dir.Sub("masks/sub");
    WriteBytes(root + "/images/a.png", png);
    ASSERT_TRUE(cv::imwrite(masks + "/c.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
    ASSERT_TRUE(cv::imwrite(masks + "/sub/b.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
    WriteBytes(masks + "/a.png.png", bytes);
    ExpectInputError(
        [&] {
          const Workspace with_masks = OpenWorkspace(root);
          with_masks.ReadMask(2);
        },
        {masks + "/a.png.png", "truncated or corrupt image"});
  }
  // Undistortion of a sparse project reads them too.
  for (const std::string& bytes :
       {jpeg.substr(0, jpeg.size() / 2), png.substr(0, png.size() / 2)}) {
    TempDir dir("ws_truncated_distorted");
    const std::string root = MakeWorkspace(dir, DistortedModel(), "sparse/0");
    WriteBytes(root + "/images/sub/b.png", bytes);
    ExpectInputError([&] { OpenWorkspace(root); },
                     {root + "/images/sub/b.png", "truncated or corrupt image"});
  }
}

// Complete files with zero padding or data after the end of the image (as
// some cameras append) are read.
TEST(Workspace, CompleteImagesWithTrailingBytesAreRead) {
  cv::Mat noise(48, 64, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  const std::string jpeg = Encode(".jpg", noise), png = Encode(".png", noise);
  for (const std::string& bytes :
       {jpeg + std::string(100, '\0'), jpeg + "appended data", png + std::string(16, '\0'),
        JpegWithExifOrientation(noise, 1), Encode(".jpg", noise, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}),
        Encode(".jpg", noise, {cv::IMWRITE_JPEG_RST_INTERVAL, 2})}) {
    TempDir dir("ws_trailing");
    const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
    WriteBytes(root + "/images/a.png", bytes);
    EXPECT_EQ(OpenWorkspace(root).ReadImage(2, false).cols, 64);
  }
}

// Masks named after the image files (view.png) instead of COLMAP's
// "<image name>.png" (view.png.png): none is found, which is an error that
// says what was expected; for a distorted project too.
TEST(Workspace, MasksMatchingNoImageAreAnError) {
  for (const std::string sparse : {"sparse", "sparse/0"}) {
    TempDir dir("ws_masks_no_match");
    const std::string root =
        MakeWorkspace(dir, sparse == "sparse" ? PinholeModel() : DistortedModel(), sparse);
    const std::string masks = dir.Sub("masks");
    dir.Sub("masks/sub");
    for (const char* name : {"a.png", "c.png", "sub/b.png"}) {
      ASSERT_TRUE(cv::imwrite(masks + "/" + name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
    }
    ExpectInputError([&] { OpenWorkspace(root); },
                     {masks, "no mask matches the images",
                      "expected <image name>.png such as a.png.png",
                      "found 2 files such as a.png"});
    // A program that uses only the cameras does not look at masks.
    WorkspaceOptions options;
    options.use_masks = false;
    EXPECT_EQ(OpenWorkspace(root, options).mask_dir, "");
  }
}

TEST(Workspace, CheckImageNamesInModel) {
  TempDir dir("ws_names");
  const Workspace ws = OpenWorkspace(MakeWorkspace(dir, PinholeModel(), "sparse"));
  CheckImageNamesInModel(ws, {"a.png", "sub/b.png"}, "holdout.txt");
  CheckImageNamesInModel(ws, {}, "holdout.txt");
  ExpectInputError(
      [&] { CheckImageNamesInModel(ws, {"a.png", "b.png", "x.jpg"}, "holdout.txt"); },
      {"holdout.txt: 2 of 3 image names are not in the sparse model", "b.png, x.jpg",
       "e.g. a.png"});
}

TEST(Workspace, InputPaths) {
  TempDir dir("ws_input_paths");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  dir.Sub("masks");
  dir.Sub("mesh_refiner_undistorted/sparse");
  const std::vector<std::string> inputs = WorkspaceInputPaths(root);
  for (const std::string& output :
       {root + "/images/a.png", root + "/sparse/cameras.bin", root + "/sparse/0/images.txt",
        root + "/meshed-poisson.ply", root + "/masks/a.png.png",
        root + "/mesh_refiner_undistorted/sparse/cameras.bin"}) {
    ExpectInputError([&] { RefuseOutputOverInput("--output_path", output, inputs); },
                     {output, "refusing to overwrite"});
  }
  RefuseOutputOverInput("--output_path", root + "/meshed-refined.ply", inputs);
  RefuseOutputOverInput("--write_config", root + "/refine.ini", inputs);
  WorkspaceOptions options;
  options.image_path = dir.Sub("elsewhere");
  options.use_masks = false;
  const std::vector<std::string> custom = WorkspaceInputPaths(root, options);
  ExpectInputError(
      [&] { RefuseOutputOverInput("--output_path", options.image_path + "/x.ply", custom); },
      {"inside the input folder"});
  RefuseOutputOverInput("--output_path", root + "/masks/a.png.png", custom);
}

TEST(Workspace, CheckMasks) {
  TempDir dir("ws_check_masks");
  const Reconstruction model = PinholeModel();
  const std::string masks = dir.Sub("masks");
  dir.Sub("masks/sub");
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(0))));
  ASSERT_TRUE(cv::imwrite(masks + "/sub/b.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(0))));
  MaskCheck check = CheckMasks(masks, model);
  EXPECT_EQ(check.num_images, 3);
  EXPECT_EQ(check.missing, (std::vector<std::string>{"c.png"}));
  EXPECT_EQ(check.empty,
            (std::vector<std::string>{masks + "/a.png.png", masks + "/sub/b.png.png"}));
  cv::Mat one(48, 64, CV_8UC1, cv::Scalar(0));
  one.at<uint8_t>(47, 63) = 1;  // a single foreground pixel is enough
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", one));
  ASSERT_TRUE(cv::imwrite(masks + "/c.png.png", one));
  check = CheckMasks(masks, model);
  EXPECT_TRUE(check.missing.empty());
  EXPECT_EQ(check.empty, (std::vector<std::string>{masks + "/sub/b.png.png"}));
  // A mask that cannot be read is an error when the workspace is opened.
  std::ofstream(masks + "/c.png.png") << "not an image";
  ExpectInputError([&] { CheckMasks(masks, model); }, {masks + "/c.png.png", "mask"});
}

// Masks missing for some images, and masks with no foreground pixel, are
// reported with a warning (the run goes on).
TEST(Workspace, MissingAndEmptyMasksAreReported) {
  TempDir dir("ws_masks_partial");
  const std::string root = MakeWorkspace(dir, PinholeModel(), "sparse");
  const std::string masks = dir.Sub("masks");
  ASSERT_TRUE(cv::imwrite(masks + "/a.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(255))));
  ASSERT_TRUE(cv::imwrite(masks + "/c.png.png", cv::Mat(48, 64, CV_8UC1, cv::Scalar(0))));
  ::testing::internal::CaptureStderr();
  const Workspace ws = OpenWorkspace(root);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(ws.mask_dir, masks);
  EXPECT_NE(log.find("1 of 3 images have no mask"), std::string::npos) << log;
  EXPECT_NE(log.find("sub/b.png.png"), std::string::npos) << log;
  EXPECT_NE(log.find(masks + "/c.png.png"), std::string::npos) << log;
  EXPECT_NE(log.find("all background"), std::string::npos) << log;
  EXPECT_EQ(log.find(masks + "/a.png.png"), std::string::npos) << log;
}

}  // namespace
}  // namespace mr
