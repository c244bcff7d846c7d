#include "synth/shape.h"

#include <cmath>
#include <map>
#include <utility>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "geometry/mesh.h"
#include "synth/texture.h"
#include "util/error.h"

namespace mr {
namespace {

// Signed volume (positive for an outward-oriented closed mesh).
double SignedVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double vol = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    vol += a.dot(b.cross(c)) / 6;
  }
  return vol;
}

TriangleMesh CoarseShape() {
  BuiltinShapeOptions options;
  options.edge_length = 2.0;
  return MakeBuiltinShape(options);
}

TEST(BuiltinShapeOptions, DefaultsAreValid) { EXPECT_TRUE(BuiltinShapeOptions().Check()); }

TEST(BuiltinShapeOptions, RejectsBadValues) {
  BuiltinShapeOptions options;
  options.edge_length = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = BuiltinShapeOptions();
  options.cut_angle_deg = 10;
  EXPECT_THROW(options.Check(), InputError);
}

TEST(AppearanceOptions, DefaultsAreValid) { EXPECT_TRUE(AppearanceOptions().Check()); }

TEST(BuiltinShape, ClosedManifoldGenusZeroOutward) {
  const TriangleMesh mesh = CoarseShape();
  ASSERT_GT(mesh.NumFaces(), 1000);
  const EdgeTopology topo = ComputeEdgeTopology(mesh.F, mesh.NumVertices());
  EXPECT_EQ(topo.NumBoundaryEdges(), 0);
  EXPECT_EQ(topo.NumNonManifoldEdges(), 0);
  // Euler characteristic 2 (genus 0, one component), every vertex used.
  const long chi = static_cast<long>(mesh.NumVertices()) - topo.E.rows() + mesh.NumFaces();
  EXPECT_EQ(chi, 2);
  std::vector<int> used(mesh.NumVertices(), 0);
  for (int f = 0; f < mesh.NumFaces(); ++f)
    for (int k = 0; k < 3; ++k) used[mesh.F(f, k)] = 1;
  for (int v = 0; v < mesh.NumVertices(); ++v) ASSERT_EQ(used[v], 1) << "vertex " << v;
  // Consistent orientation: each directed edge appears exactly once.
  std::map<std::pair<int, int>, int> directed;
  for (int f = 0; f < mesh.NumFaces(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[{mesh.F(f, k), mesh.F(f, (k + 1) % 3)}];
  for (const auto& [edge, count] : directed) ASSERT_EQ(count, 1);
  // Outward: positive volume, near that of the cut sphere (radius 32).
  const double vol = SignedVolume(mesh.V, mesh.F);
  EXPECT_GT(vol, 0.7 * 4.0 / 3.0 * M_PI * 32 * 32 * 32);
  EXPECT_LT(vol, 4.0 / 3.0 * M_PI * 33 * 33 * 33);
  // No degenerate faces.
  const Eigen::VectorXd areas = FaceAreas(mesh.V, mesh.F);
  EXPECT_GT(areas.minCoeff(), 1e-3);
}

TEST(BuiltinShape, HasSharpPlanarCrease) {
  const TriangleMesh mesh = CoarseShape();
  EXPECT_GT(MaxDihedralAngleDeg(mesh.V, mesh.F), 60.0);
  // The crease is an exact polyline: the flat cap's vertices (including the
  // crease ring) lie exactly in one plane. Its normal is the tilted +z axis.
  BuiltinShapeOptions options;
  const double tilt = options.tilt_deg * M_PI / 180;
  const Eigen::Vector3d n(0, -std::sin(tilt), std::cos(tilt));
  const double zc = 32 * std::cos(options.cut_angle_deg * M_PI / 180);
  int on_plane = 0;
  for (int v = 0; v < mesh.NumVertices(); ++v) {
    const double h = n.dot(mesh.V.row(v).transpose()) - zc;
    EXPECT_LT(h, 1e-9) << "vertex " << v << " above the cut plane";
    if (std::abs(h) < 1e-9) ++on_plane;
  }
  EXPECT_GT(on_plane, 100);
  // Faces with an edge on the crease: many dihedral angles near the cut angle.
  const Eigen::MatrixXd N = FaceNormals(mesh.V, mesh.F);
  const EdgeTopology topo = ComputeEdgeTopology(mesh.F, mesh.NumVertices());
  int sharp = 0;
  for (const auto& faces : topo.edge_faces) {
    const double angle = std::acos(std::clamp(N.row(faces[0]).dot(N.row(faces[1])), -1.0, 1.0));
    if (angle * 180 / M_PI > 60) ++sharp;
  }
  EXPECT_GT(sharp, 50);
}

TEST(BuiltinShape, HasFineRelief) {
  // Radial distance of the curved part varies by about the relief amplitude.
  BuiltinShapeOptions options;
  options.edge_length = 1.0;
  const TriangleMesh mesh = MakeBuiltinShape(options);
  double lo = 1e9, hi = -1e9;
  for (int v = 0; v < mesh.NumVertices(); ++v) {
    const double r = mesh.V.row(v).norm();
    if (r > 31) {  // skip the flat cap's interior
      lo = std::min(lo, r);
      hi = std::max(hi, r);
    }
  }
  EXPECT_GT(hi - lo, 1.0);
  EXPECT_LT(hi - lo, 4.0);
  options.relief_amplitude = 0;
  const TriangleMesh smooth = MakeBuiltinShape(options);
  for (int v = 0; v < smooth.NumVertices(); ++v) {
    EXPECT_LE(smooth.V.row(v).norm(), 32 + 1e-9);
  }
}

TEST(BuiltinShape, DefaultFaceCountInRange) {
  const TriangleMesh mesh = MakeBuiltinShape(BuiltinShapeOptions());
  EXPECT_GT(mesh.NumFaces(), 100000);
  EXPECT_LT(mesh.NumFaces(), 300000);
}

TEST(NormalizeMesh, CentresAndScales) {
  Eigen::MatrixXd V(3, 3);
  V << 1, 2, 3, 4, 6, 3, 1, 2, 15;
  NormalizeMesh(100, &V);
  const Eigen::RowVector3d lo = V.colwise().minCoeff(), hi = V.colwise().maxCoeff();
  EXPECT_NEAR((hi - lo).norm(), 100, 1e-9);
  EXPECT_NEAR((hi + lo).norm(), 0, 1e-9);
}

TEST(NormalizeMesh, EmptyMesh) {
  Eigen::MatrixXd V(0, 3);
  EXPECT_THROW(NormalizeMesh(100, &V), InputError);
  Eigen::MatrixXd P = Eigen::MatrixXd::Ones(4, 3);
  EXPECT_THROW(NormalizeMesh(100, &P), InputError);
}

TEST(Texture, AlbedoRangeAndContrast) {
  AppearanceOptions options;
  double lo = 1, hi = 0, sum = 0, sum2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(0.37 * i, 0.11 * i - 50, 13.0 * std::sin(i));
    const double a = Albedo(options, p);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
    sum += a;
    sum2 += a * a;
  }
  EXPECT_GE(lo, options.min_albedo);
  EXPECT_LE(hi, options.max_albedo);
  const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  EXPECT_GT(sd, 0.15) << "texture contrast too weak";
  // Fine-scale contrast: neighbours half a texture period apart differ.
  double diff = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d p(0.71 * i, 3.1 * std::cos(i), 0.29 * i);
    diff += std::abs(Albedo(options, p) - Albedo(options, p + Eigen::Vector3d(0.4, 0, 0)));
  }
  EXPECT_GT(diff / 1000, 0.05);
}

TEST(Texture, ShadingIsLambertian) {
  AppearanceOptions options;
  const Eigen::Vector3d p(1, 2, 3);
  const Eigen::Vector3d l = options.light_direction.normalized();
  const double a = Albedo(options, p);
  EXPECT_NEAR(ShadePoint(options, p, l), a, 1e-12);
  EXPECT_NEAR(ShadePoint(options, p, -l), a * options.ambient, 1e-12);
}

}  // namespace
}  // namespace mr
