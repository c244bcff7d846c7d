// End to end: a synthetic Middlebury-style data set of a sphere ->
// ConvertMiddlebury -> the mesh_initializer program -> a closed hull around
// the sphere, in millimetres.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/ply.h"
#include "init/isosurface.h"
#include "init/middlebury.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

constexpr double kRadius = 0.02;  // metres

// Writes 8 views (cube-corner directions, 0.3 m away) of a white sphere on
// black, in Middlebury's conventions (pixel centres at integer coordinates).
void WriteSphereDataSet(const std::string& dir) {
  const int w = 80, h = 60;
  Eigen::Matrix3d K;
  K << 250, 0, 39.5, 0, 250, 29.5, 0, 0, 1;  // the sphere is ~34 px wide
  std::ostringstream par;
  par.precision(17);
  par << "8\n";
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
    const Eigen::Vector3d c = 0.3 * corner.normalized();
    const Eigen::Vector3d z = -c.normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitZ().cross(z).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Matrix3d R;
    R.row(0) = x;
    R.row(1) = y;
    R.row(2) = z;
    const Eigen::Vector3d t = -R * c;
    cv::Mat img(h, w, CV_8UC3, cv::Scalar(0, 0, 0));
    for (int r = 0; r < h; ++r) {
      for (int col = 0; col < w; ++col) {
        const Eigen::Vector3d d = (R.transpose() * K.inverse() * Eigen::Vector3d(col, r, 1)).normalized();
        const double tca = -c.dot(d);
        if (c.squaredNorm() - tca * tca <= kRadius * kRadius) {
          img.at<cv::Vec3b>(r, col) = cv::Vec3b(220, 220, 220);
        }
      }
    }
    const std::string name = "s" + std::to_string(i + 1) + ".png";
    cv::imwrite(JoinPaths(dir, name), img);
    par << name;
    for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) par << " " << K(a, b);
    for (int a = 0; a < 3; ++a) for (int b = 0; b < 3; ++b) par << " " << R(a, b);
    par << " " << t.x() << " " << t.y() << " " << t.z() << "\n";
  }
  std::ofstream(JoinPaths(dir, "s_par.txt")) << par.str();
  std::ofstream(JoinPaths(dir, "README.txt"))
      << "The bounding box is\n(-0.03 -0.03 -0.03)\n(0.03 0.03 0.03)\n";
}

TEST(MiddleburyPipeline, SphereHullInMillimetres) {
  const std::string in = MakeTestDir("pipeline_in");
  const std::string ws = MakeTestDir("pipeline_ws");
  WriteSphereDataSet(in);
  MiddleburyConversionOptions convert;
  convert.holdout_every = 0;  // all 8 views carve
  convert.silhouette.dilate_px = 0;  // exact silhouettes
  convert.silhouette.erode_px = 0;
  ConvertMiddlebury(in, ws, convert);

  const std::string exe = JoinPaths(MR_BIN_DIR, "mesh_initializer");
  ASSERT_TRUE(ExistsFile(exe)) << exe << " is not built";
  const std::string out = JoinPaths(ws, "hull.ply");
  const std::string log = JoinPaths(ws, "log.txt");
  const std::string cmd = exe + " --workspace_path " + ws + " --output_path " + out +
                          " --resolution 40 --VisualHull.min_views 2 2> " + log;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFileToString(log);
  const TriangleMesh mesh = ReadPly(out);
  ASSERT_GT(mesh.NumFaces(), 200);
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(mesh.F, &why)) << why;
  EXPECT_GT(SignedVolume(mesh.V, mesh.F), 0);
  // Millimetres: the sphere has radius 20. The hull of 8 cube-corner views
  // lies between the sphere and 1.3 radii, up to a voxel (66 mm / 40).
  const double voxel = 66.0 / 40;
  for (int v = 0; v < mesh.NumVertices(); ++v) {
    const double r = mesh.V.row(v).norm();
    ASSERT_GT(r, 20 - voxel) << "vertex " << v;
    ASSERT_LT(r, 1.3 * 20 + voxel) << "vertex " << v;
  }
  // Decimated and remeshed hulls stay closed and outward (if this build has
  // mr_remesh; otherwise the flags are refused with an ERROR line).
  const std::string small = JoinPaths(ws, "hull_small.ply");
  const std::string cmd2 = exe + " --workspace_path " + ws + " --output_path " + small +
                           " --resolution 40 --VisualHull.min_views 2 --target_faces 2000"
                           " --remesh_edge_length 4 2> " + log;
  if (std::system(cmd2.c_str()) == 0) {
    const TriangleMesh dec = ReadPly(small);
    EXPECT_GT(dec.NumFaces(), 200);
    EXPECT_LT(dec.NumFaces(), mesh.NumFaces());
    EXPECT_TRUE(IsClosedAndOriented(dec.F, &why)) << why;
    EXPECT_GT(SignedVolume(dec.V, dec.F), 0);
    for (int v = 0; v < dec.NumVertices(); ++v) {
      ASSERT_GT(dec.V.row(v).norm(), 20 - 2 * voxel) << "vertex " << v;
      ASSERT_LT(dec.V.row(v).norm(), 1.3 * 20 + 2 * voxel) << "vertex " << v;
    }
  } else {
    EXPECT_NE(ReadFileToString(log).find("mr_remesh"), std::string::npos)
        << ReadFileToString(log);
  }
  // A missing workspace fails with one ERROR line.
  const std::string bad = exe + " --workspace_path " + JoinPaths(ws, "nope") + " 2> " + log;
  EXPECT_NE(std::system(bad.c_str()), 0);
  EXPECT_NE(ReadFileToString(log).find("ERROR"), std::string::npos);
}

// Masks that leave out part of the object make a hull that cuts it:
// mesh_initializer warns, and says nothing for exact masks.
TEST(MiddleburyPipeline, TightMasksAreReported) {
  const std::string in = MakeTestDir("pipeline_tight_in");
  WriteSphereDataSet(in);
  const std::string exe = JoinPaths(MR_BIN_DIR, "mesh_initializer");
  for (const int erode : {0, 3}) {
    const std::string ws = MakeTestDir("pipeline_tight_ws" + std::to_string(erode));
    MiddleburyConversionOptions convert;
    convert.holdout_every = 0;
    convert.silhouette.dilate_px = 0;
    convert.silhouette.erode_px = erode;  // 3: every mask 3 px inside the sphere's outline
    ConvertMiddlebury(in, ws, convert);
    const std::string log = JoinPaths(ws, "log.txt");
    const std::string cmd = exe + " --workspace_path " + ws + " --output_path " +
                            JoinPaths(ws, "hull.ply") +
                            " --resolution 30 --VisualHull.min_views 2 2> " + log;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadFileToString(log);
    const std::string text = ReadFileToString(log);
    const bool warned = text.find("masks are tighter than the objects") != std::string::npos;
    EXPECT_EQ(warned, erode > 0) << text;
    EXPECT_NE(text.find("the image edge lies"), std::string::npos) << text;
  }
}

}  // namespace
}  // namespace mr
