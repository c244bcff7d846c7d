#include "init/mesh_picture.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/ply.h"
#include "init/isosurface.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"
#include "util/logging.h"

namespace mr {
namespace {

void Sphere(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int n = 21;
  ScalarGrid grid(n, n, n, Eigen::Vector3d::Constant(-1), 0.1);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        grid.At(i, j, k) = static_cast<float>(0.8 - grid.Position(i, j, k).norm());
      }
    }
  }
  ExtractIsosurface(grid, 0.0, V, F);
}

std::unique_ptr<Renderer> MakeRenderer() {
  try {
    return std::make_unique<Renderer>();
  } catch (const InputError& e) {
    MR_LOG(WARNING) << "no EGL renderer (" << e.what() << "); using RenderCpu";
    return nullptr;
  }
}

TEST(MeshPictureOptions, DefaultsAreValid) {
  EXPECT_TRUE(MeshPictureOptions().Check());
  MeshPictureOptions o;
  o.lighting = "sun";
  EXPECT_THROW(o.Check(), InputError);
}

TEST(OrbitView, FramesTheBox) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(2, 4, 4));
  for (const double el : {-90.0, -30.0, 0.0, 45.0, 90.0}) {
    for (const double az : {0.0, 100.0, 250.0}) {
      const PinholeView v = OrbitView(box, az, el, 80, 60, Eigen::Vector3d::UnitZ(),
                                      Eigen::Vector3d::UnitX());
      EXPECT_NEAR(v.R.determinant(), 1.0, 1e-9);
      const Eigen::Vector2d c = v.Project(box.center());
      EXPECT_NEAR(c.x(), 40, 1e-9);
      EXPECT_NEAR(c.y(), 30, 1e-9);
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d corner = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i));
        EXPECT_GT(v.WorldToCamera(corner).z(), 0);
        EXPECT_TRUE(v.InImage(v.Project(corner))) << "az " << az << " el " << el;
      }
    }
  }
  // Azimuth 0, elevation 0 looks from `front`; world up is image up.
  const PinholeView v = OrbitView(box, 0, 0, 80, 60, Eigen::Vector3d::UnitZ(),
                                  Eigen::Vector3d::UnitX());
  EXPECT_GT((v.Center() - box.center()).normalized().x(), 0.999);
  EXPECT_LT(v.Project(box.center() + 0.1 * Eigen::Vector3d::UnitZ()).y(), 30);
}

// A 64x48 view of the mesh, from azimuth 30 and elevation 20 degrees.
PinholeView SmallOrbitView(const Eigen::MatrixXd& V) {
  const Eigen::AlignedBox3d box(V.colwise().minCoeff().transpose(),
                                V.colwise().maxCoeff().transpose());
  return OrbitView(box, 30, 20, 64, 48, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ());
}

TEST(RenderMeshPicture, ObjectPixelsAreShaded) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Sphere(&V, &F);
  std::unique_ptr<Renderer> renderer = MakeRenderer();
  const PinholeView view = SmallOrbitView(V);
  MeshPictureOptions options;
  options.background = 0;
  const cv::Mat image = RenderMeshPicture(renderer.get(), V, F, view, options);
  ASSERT_EQ(image.type(), CV_8UC3);
  ASSERT_EQ(image.cols, 64);
  ASSERT_EQ(image.rows, 48);
  // The centre is the sphere: non-black grey; a corner is background.
  const cv::Vec3b centre = image.at<cv::Vec3b>(24, 32);
  EXPECT_GT(centre[0], 30);
  EXPECT_EQ(centre[0], centre[2]);  // grey, no back faces
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));

  // Flipped faces show their back side: red.
  Eigen::MatrixXi flipped = F;
  flipped.col(1).swap(flipped.col(2));
  const cv::Mat inside_out = RenderMeshPicture(renderer.get(), V, flipped, view, options);
  const cv::Vec3b red = inside_out.at<cv::Vec3b>(24, 32);
  EXPECT_GT(red[2], red[0] + 50);
}

// Vertex colours replace the grey on front faces, shaded the same way: a
// sphere coloured pure green renders green, with the grey picture's shading.
TEST(RenderMeshPicture, VertexColoursAreShaded) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Sphere(&V, &F);
  std::unique_ptr<Renderer> renderer = MakeRenderer();
  const PinholeView view = SmallOrbitView(V);
  MeshPictureOptions options;
  options.background = 0;
  VertexColors green(V.rows(), 3);
  green.setZero();
  green.col(1).setConstant(225);  // the grey's own level, in green only
  const cv::Mat grey = RenderMeshPicture(renderer.get(), V, F, view, options);
  const cv::Mat image = RenderMeshPicture(renderer.get(), V, F, view, options, &green);
  const cv::Vec3b centre = image.at<cv::Vec3b>(24, 32);  // BGR
  EXPECT_GT(centre[1], 30);
  EXPECT_LE(centre[0], 1);
  EXPECT_LE(centre[2], 1);
  EXPECT_EQ(centre[1], grey.at<cv::Vec3b>(24, 32)[1]);
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  // Back faces stay red whatever the colours.
  Eigen::MatrixXi flipped = F;
  flipped.col(1).swap(flipped.col(2));
  const cv::Vec3b red =
      RenderMeshPicture(renderer.get(), V, flipped, view, options, &green).at<cv::Vec3b>(24, 32);
  EXPECT_GT(red[2], red[1] + 50);
  VertexColors too_few(3, 3);
  too_few.setZero();
  EXPECT_THROW(RenderMeshPicture(renderer.get(), V, F, view, options, &too_few), InputError);
}

TEST(MeshRender, ProgramWritesAPng) {
  const std::string exe = JoinPaths(MR_BIN_DIR, "mesh_render");
  ASSERT_TRUE(ExistsFile(exe)) << exe << " is not built";
  const std::string dir = MakeTestDir("mesh_render");
  TriangleMesh mesh;
  Sphere(&mesh.V, &mesh.F);
  WritePly(JoinPaths(dir, "sphere.ply"), mesh);
  const std::string out = JoinPaths(dir, "out.png");
  const std::string cmd = exe + " --input_path " + JoinPaths(dir, "sphere.ply") +
                          " --view \"20 10\" --width 60 --height 40 --background 0 --output_path " +
                          out + " 2> " + JoinPaths(dir, "log.txt");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFileToString(JoinPaths(dir, "log.txt"));
  const cv::Mat image = cv::imread(out, cv::IMREAD_COLOR);
  ASSERT_EQ(image.cols, 60);
  ASSERT_EQ(image.rows, 40);
  EXPECT_GT(image.at<cv::Vec3b>(20, 30)[1], 30);
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 0));
  // Side by side: twice as wide.
  const std::string cmd2 = exe + " --input_path " + JoinPaths(dir, "sphere.ply") +
                           " --side_by_side " + JoinPaths(dir, "sphere.ply") +
                           " --view \"20 10\" --width 60 --height 40 --output_path " + out +
                           " 2> " + JoinPaths(dir, "log.txt");
  ASSERT_EQ(std::system(cmd2.c_str()), 0) << ReadFileToString(JoinPaths(dir, "log.txt"));
  EXPECT_EQ(cv::imread(out, cv::IMREAD_COLOR).cols, 120);
  // --vertex_colors: the mesh's colours; a mesh without them is refused.
  TriangleMesh coloured = mesh;
  coloured.C.resize(mesh.NumVertices(), 3);
  coloured.C.setZero();
  coloured.C.col(0).setConstant(200);  // red
  WritePly(JoinPaths(dir, "red.ply"), coloured);
  const std::string cmd4 = exe + " --input_path " + JoinPaths(dir, "red.ply") +
                           " --vertex_colors 1 --view \"20 10\" --width 60 --height 40 "
                           "--background 0 --output_path " + out + " 2> " +
                           JoinPaths(dir, "log.txt");
  ASSERT_EQ(std::system(cmd4.c_str()), 0) << ReadFileToString(JoinPaths(dir, "log.txt"));
  const cv::Vec3b red = cv::imread(out, cv::IMREAD_COLOR).at<cv::Vec3b>(20, 30);
  EXPECT_GT(red[2], 30);
  EXPECT_LE(red[1], 1);
  const std::string cmd5 = exe + " --input_path " + JoinPaths(dir, "sphere.ply") +
                           " --vertex_colors 1 --view \"20 10\" --output_path " + out + " 2> " +
                           JoinPaths(dir, "log.txt");
  EXPECT_NE(std::system(cmd5.c_str()), 0);
  EXPECT_NE(ReadFileToString(JoinPaths(dir, "log.txt")).find("no vertex colours"),
            std::string::npos);
  // A missing mesh fails with a message.
  const std::string cmd3 = exe + " --input_path " + JoinPaths(dir, "missing.ply") +
                           " --view \"0 0\" --output_path " + out + " 2> " +
                           JoinPaths(dir, "log.txt");
  EXPECT_NE(std::system(cmd3.c_str()), 0);
  EXPECT_NE(ReadFileToString(JoinPaths(dir, "log.txt")).find("ERROR"), std::string::npos);
}

}  // namespace
}  // namespace mr
