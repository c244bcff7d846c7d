#include "synth/shape.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
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

TEST(AppearanceOptions, RejectsBadValues) {
  AppearanceOptions options;
  options.texture_style = "marble";
  EXPECT_THROW(options.Check(), InputError);
  options = AppearanceOptions();
  options.light = "sun";
  EXPECT_THROW(options.Check(), InputError);
  for (const double contrast : {0.0, -1.0, 101.0, std::nan("")}) {
    options = AppearanceOptions();
    options.texture_contrast = contrast;
    EXPECT_THROW(options.Check(), InputError) << contrast;
  }
  for (const double ambient : {-0.1, 1.5, std::nan("")}) {
    options = AppearanceOptions();
    options.ambient = ambient;
    EXPECT_THROW(options.Check(), InputError) << ambient;
  }
  for (const std::string style : {"contrast", "smooth_color", "none"}) {
    options = AppearanceOptions();
    options.texture_style = style;
    options.light = "headlight";
    EXPECT_TRUE(options.Check()) << style;
  }
}

// Surface points of the coarse built-in shape.
Eigen::MatrixXd SurfacePoints() { return CoarseShape().V; }

struct AlbedoStats {
  double luminance_sd = 0;
  double red_minus_green_sd = 0;
  double max_channel_sd = 0;
  double max_channel_spread = 0;  // largest |R - G|, |G - B|
  double lo = 1, hi = 0;
  // Mean |albedo(p) - albedo(p + 0.4 x)| (max over channels): fine-scale contrast.
  double neighbour_difference = 0;
};

AlbedoStats Stats(const AppearanceOptions& options, const Eigen::MatrixXd& P) {
  const int n = static_cast<int>(P.rows());
  Eigen::MatrixXd values(n, 5);  // R, G, B, luminance, R - G
  AlbedoStats stats;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    const Eigen::Vector3d a = Albedo(options, p);
    values.row(i) << a.transpose(), Luminance(a), a(0) - a(1);
    stats.lo = std::min(stats.lo, a.minCoeff());
    stats.hi = std::max(stats.hi, a.maxCoeff());
    stats.max_channel_spread =
        std::max({stats.max_channel_spread, std::abs(a(0) - a(1)), std::abs(a(1) - a(2))});
    stats.neighbour_difference +=
        (a - Albedo(options, p + Eigen::Vector3d(0.4, 0, 0))).cwiseAbs().maxCoeff() / n;
  }
  const Eigen::RowVectorXd mean = values.colwise().mean();
  const Eigen::RowVectorXd sd =
      ((values.rowwise() - mean).array().square().colwise().sum() / n).sqrt();
  stats.max_channel_sd = sd.head(3).maxCoeff();
  stats.luminance_sd = sd(3);
  stats.red_minus_green_sd = sd(4);
  return stats;
}

TEST(Texture, AlbedoRangeAndContrast) {
  AppearanceOptions options;
  double lo = 1, hi = 0, sum = 0, sum2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(0.37 * i, 0.11 * i - 50, 13.0 * std::sin(i));
    const Eigen::Vector3d rgb = Albedo(options, p);
    ASSERT_EQ(rgb(0), rgb(1));
    ASSERT_EQ(rgb(1), rgb(2));
    const double a = rgb(0);
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
    diff += std::abs(Albedo(options, p)(0) - Albedo(options, p + Eigen::Vector3d(0.4, 0, 0))(0));
  }
  EXPECT_GT(diff / 1000, 0.05);
}

// smooth_color: a quarter of the contrast style's luminance variation at
// most, clearly varying chroma, smooth at the scale of a few pixels.
TEST(Texture, SmoothColorHasLowLuminanceContrastAndVaryingChroma) {
  const Eigen::MatrixXd P = SurfacePoints();
  ASSERT_GT(P.rows(), 1000);
  AppearanceOptions contrast;
  AppearanceOptions smooth;
  smooth.texture_style = "smooth_color";
  const AlbedoStats c = Stats(contrast, P), s = Stats(smooth, P);
  EXPECT_GT(c.luminance_sd, 0.15);
  EXPECT_EQ(c.max_channel_spread, 0) << "contrast is grey";
  EXPECT_LT(s.luminance_sd, 0.25 * c.luminance_sd);
  EXPECT_GT(s.red_minus_green_sd, 0.1) << "chroma must vary";
  EXPECT_GT(s.max_channel_sd, 0.1);
  EXPECT_GE(s.lo, smooth.min_albedo);
  EXPECT_LE(s.hi, smooth.max_albedo);
  // Relative to its own variation, the albedo changes much less between
  // points 0.4 units (~2 pixels) apart than the contrast texture does.
  EXPECT_LT(s.neighbour_difference / s.max_channel_sd,
            0.5 * c.neighbour_difference / c.max_channel_sd)
      << "not smooth: " << s.neighbour_difference << " " << s.max_channel_sd << " vs "
      << c.neighbour_difference << " " << c.max_channel_sd;
}

// none: (nearly) uniform grey albedo.
TEST(Texture, NoneIsNearlyUniformGrey) {
  const Eigen::MatrixXd P = SurfacePoints();
  AppearanceOptions none;
  none.texture_style = "none";
  const AlbedoStats s = Stats(none, P);
  EXPECT_LT(s.max_channel_sd, 0.02);
  EXPECT_EQ(s.max_channel_spread, 0) << "none is grey";
  const double mid = 0.5 * (none.min_albedo + none.max_albedo);
  EXPECT_GE(s.lo, mid * 0.98 - 1e-12);
  EXPECT_LE(s.hi, mid * 1.02 + 1e-12);
}

TEST(Texture, ShadingIsLambertian) {
  AppearanceOptions options;
  const Eigen::Vector3d p(1, 2, 3), eye(50, -70, 40);
  const Eigen::Vector3d l = options.light_direction.normalized();
  const Eigen::Vector3d a = Albedo(options, p);
  EXPECT_NEAR((ShadePoint(options, p, l, eye) - a).norm(), 0, 1e-12);
  EXPECT_NEAR((ShadePoint(options, p, -l, eye) - a * options.ambient).norm(), 0, 1e-12);
}

// headlight: a patch facing the camera is fully lit wherever the world light
// is; one tilted by 60 degrees gets half the directional share.
TEST(Texture, HeadlightShinesFromTheCamera) {
  AppearanceOptions options;
  options.light = "headlight";
  options.ambient = 0.2;
  options.texture_style = "smooth_color";
  AppearanceOptions world = options;
  world.light = "world";
  const Eigen::MatrixXd P = SurfacePoints();
  const Eigen::Vector3d eye(80, -60, 50);
  int differs_from_world = 0;
  for (int i = 0; i < P.rows(); i += 7) {
    const Eigen::Vector3d p = P.row(i).transpose();
    const Eigen::Vector3d to_eye = (eye - p).normalized();
    const Eigen::Vector3d a = Albedo(options, p);
    const Eigen::Vector3d facing = ShadePoint(options, p, to_eye, eye);
    ASSERT_NEAR((facing - a * (options.ambient + (1 - options.ambient) * 1)).cwiseAbs().maxCoeff(),
                0, 1e-6);
    // A normal at 60 degrees from the direction to the camera.
    const Eigen::Vector3d side = to_eye.unitOrthogonal();
    const Eigen::Vector3d tilted = 0.5 * to_eye + std::sqrt(0.75) * side;
    EXPECT_NEAR((ShadePoint(options, p, tilted, eye) -
                 a * (options.ambient + (1 - options.ambient) * 0.5))
                    .cwiseAbs()
                    .maxCoeff(),
                0, 1e-6);
    EXPECT_NEAR((ShadePoint(options, p, -to_eye, eye) - a * options.ambient).cwiseAbs().maxCoeff(),
                0, 1e-12);
    if ((ShadePoint(world, p, to_eye, eye) - facing).norm() > 0.01) ++differs_from_world;
  }
  EXPECT_GT(differs_from_world, 0.5 * (P.rows() / 7));
}

// The highlight: white, at its strongest on the mirror direction (n halfway
// between the light and the eye), falling off away from it, absent where the
// light does not reach, and clipped at 1.
TEST(Texture, SpecularHighlightFollowsTheMirrorDirection) {
  AppearanceOptions options;
  options.specular = 0.3;
  options.shininess = 20;
  AppearanceOptions matte = options;
  matte.specular = 0;
  const Eigen::Vector3d p(1, 2, 3), eye(50, -70, 40);
  const Eigen::Vector3d l = options.light_direction.normalized();
  const Eigen::Vector3d half = (l + (eye - p).normalized()).normalized();
  const Eigen::Vector3d mirror = ShadePoint(options, p, half, eye) - ShadePoint(matte, p, half, eye);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mirror(c), 0.3, 1e-12);  // white, n.h = 1
  // 20 degrees off the mirror direction, towards the light: 0.3 cos(20)^20.
  const Eigen::Vector3d side = (l - l.dot(half) * half).normalized();
  const double angle = 20 * M_PI / 180;
  const Eigen::Vector3d off = std::cos(angle) * half + std::sin(angle) * side;
  const Eigen::Vector3d weaker = ShadePoint(options, p, off, eye) - ShadePoint(matte, p, off, eye);
  EXPECT_NEAR(weaker(0), 0.3 * std::pow(std::cos(angle), 20), 1e-12);
  // Facing away from the light: no highlight.
  EXPECT_EQ(ShadePoint(options, p, -l, eye), ShadePoint(matte, p, -l, eye));
  // Clipped at 1.
  options.specular = 1;
  EXPECT_EQ(ShadePoint(options, p, half, eye), Eigen::Vector3d::Ones());
  for (const double bad : {-0.1, 1.5, std::nan("")}) {
    AppearanceOptions o;
    o.specular = bad;
    EXPECT_THROW(o.Check(), InputError) << bad;
  }
  for (const double bad : {0.5, 2e4, std::nan("")}) {
    AppearanceOptions o;
    o.shininess = bad;
    EXPECT_THROW(o.Check(), InputError) << bad;
  }
}

}  // namespace
}  // namespace mr
