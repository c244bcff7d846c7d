#include "eval/evaluator.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "colmap_io/mesh_io.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

struct Mesh {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
};

// Icosahedron subdivided `levels` times, vertices on the unit sphere,
// counter-clockwise seen from outside.
Mesh Icosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> midpoints;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      midpoints[key] = static_cast<int>(v.size()) - 1;
      return static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& tri : f) {
      const int ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = next;
  }
  Mesh mesh;
  mesh.V.resize(v.size(), 3);
  for (size_t i = 0; i < v.size(); ++i) mesh.V.row(i) = v[i].transpose();
  mesh.F.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) mesh.F.row(i) = f[i].transpose();
  return mesh;
}

// n by n grid of squares on [0, 1]^2 at z = 0, normals +z.
Mesh Plane(int n) {
  Mesh mesh;
  mesh.V.resize((n + 1) * (n + 1), 3);
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) mesh.V.row(y * (n + 1) + x) << double(x) / n, double(y) / n, 0;
  }
  mesh.F.resize(2 * n * n, 3);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const int a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.F.row(2 * (y * n + x)) << a, b, d;
      mesh.F.row(2 * (y * n + x) + 1) << a, d, c;
    }
  }
  return mesh;
}

// Smallest and largest distance from the origin to a face plane.
std::pair<double, double> FacePlaneDistanceRange(const Mesh& mesh) {
  double lo = 1e300, hi = 0;
  for (int f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                          c = mesh.V.row(mesh.F(f, 2));
    const double h = std::abs((b - a).cross(c - a).normalized().dot(a));
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  return {lo, hi};
}

TEST(EvaluationOptions, DefaultsAreValid) { EXPECT_TRUE(EvaluationOptions().Check()); }

TEST(EvaluationOptions, InvalidValuesThrow) {
  EvaluationOptions options;
  options.threshold = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = EvaluationOptions();
  options.num_samples = 0;
  try {
    options.Check();
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("num_samples = 0. Violated constraint: num_samples >= 1"),
              std::string::npos);
  }
  options = EvaluationOptions();
  options.seed = -1;
  EXPECT_THROW(options.Check(), InputError);
}

// Unit icosphere against the same icosphere scaled by s = 1.01. Both are
// convex with parallel faces, so (writing h_f for the distance of face f's
// plane from the origin) every recon->GT distance lies in
// [(s-1) h_min, (s-1) h_max] and every GT->recon distance in
// [(s-1) h_min, (s-1)] (lower bound: the supporting plane of the nearest
// face; upper bound: radial projection onto the inner mesh).
TEST(EvaluateMesh, SphereAgainstLargerSphere) {
  const Mesh recon = Icosphere(5);
  const double s = 1.01;
  const Eigen::MatrixXd gt_V = s * recon.V;
  const auto [h_min, h_max] = FacePlaneDistanceRange(recon);
  ASSERT_GT(h_min, 0.9996);  // level 5: the bounds pin distances to ~4e-6
  EvaluationOptions options;
  options.num_samples = 20000;
  options.threshold = 0.02;
  const EvaluationResult full = EvaluateMesh(recon.V, recon.F, gt_V, recon.F, options);
  const double eps = 1e-12;
  EXPECT_GE(full.accuracy90, (s - 1) * h_min - eps);
  EXPECT_LE(full.accuracy90, (s - 1) * h_max + eps);
  EXPECT_GE(full.mean_accuracy, (s - 1) * h_min - eps);
  EXPECT_LE(full.mean_accuracy, (s - 1) * h_max + eps);
  EXPECT_GE(full.chamfer, 2 * (s - 1) * h_min - eps);
  EXPECT_LE(full.chamfer, (s - 1) * h_max + (s - 1) + eps);
  EXPECT_NEAR(full.accuracy90, 0.01, 5e-6);
  EXPECT_EQ(full.completeness, 100.0);
  EXPECT_LT(full.normal_deg, 0.5);
  EXPECT_EQ(full.faces, recon.F.rows());

  options.threshold = 0.005;
  const EvaluationResult none = EvaluateMesh(recon.V, recon.F, gt_V, recon.F, options);
  EXPECT_EQ(none.completeness, 0.0);
  EXPECT_EQ(none.accuracy90, full.accuracy90);  // the threshold only affects completeness
}

TEST(EvaluateMesh, IdenticalMeshesGiveZero) {
  const Mesh mesh = Icosphere(3);
  EvaluationOptions options;
  options.num_samples = 5000;
  options.threshold = 1e-9;
  const EvaluationResult result = EvaluateMesh(mesh.V, mesh.F, mesh.V, mesh.F, options);
  EXPECT_LT(result.accuracy90, 1e-12);
  EXPECT_LT(result.chamfer, 1e-12);
  EXPECT_EQ(result.completeness, 100.0);
  EXPECT_LT(result.normal_deg, 1e-3);
}

// Points above the unit square [0,1]^2 at known heights, and one beside it
// (its distance is to the square's edge, not to the plane).
TEST(MeasureSurfaceDisplacement, KnownDistances) {
  const Mesh plane = Plane(4);
  Eigen::MatrixXd points(3, 3);
  points << 0.3, 0.4, 0.1,   //
      0.7, 0.2, -0.3,        //
      1.3, 0.5, 0.4;         // beside the square: distance hypot(0.3, 0.4) = 0.5
  const SurfaceDisplacement d = MeasureSurfaceDisplacement(points, plane.V, plane.F);
  EXPECT_NEAR(d.max, 0.5, 1e-12);
  EXPECT_NEAR(d.mean, (0.1 + 0.3 + 0.5) / 3, 1e-12);
  int face = -1;
  const ClosestPointQuery query(plane.V, plane.F);
  EXPECT_NEAR(query.Distance(Eigen::Vector3d(0.05, 0.05, 0.2), &face), 0.2, 1e-12);
  ASSERT_GE(face, 0);  // the corner cell's faces are 0 and 1
  EXPECT_LE(face, 1);
  const SurfaceDisplacement none = MeasureSurfaceDisplacement(Eigen::MatrixXd(0, 3), plane.V, plane.F);
  EXPECT_EQ(none.max, 0);
}

// The error map: each vertex's exact distance, and the colour scale's ends.
TEST(MeasureVertexErrors, DistancesObservedFlagsAndColours) {
  const Mesh plane = Plane(4);  // the unit square, 32 faces
  Eigen::MatrixXd points(3, 3);
  points << 0.3, 0.4, 0.1,  //
      0.7, 0.2, -0.3,       //
      1.3, 0.5, 0.4;        // beside the square: hypot(0.3, 0.4) = 0.5
  VertexErrors errors = MeasureVertexErrors(points, plane.V, plane.F);
  ASSERT_EQ(errors.distance.size(), 3);
  ASSERT_EQ(errors.closest_face.size(), 3u);
  EXPECT_NEAR(errors.distance(0), 0.1, 1e-12);
  EXPECT_NEAR(errors.distance(1), 0.3, 1e-12);
  EXPECT_NEAR(errors.distance(2), 0.5, 1e-12);
  EXPECT_EQ(errors.observed, std::vector<char>(3, 1));
  // Only the faces over x < 0.5 observed: the first point's closest face is.
  std::vector<char> observed(plane.F.rows(), 0);
  for (int f = 0; f < plane.F.rows(); ++f) {
    double x = 0;
    for (int k = 0; k < 3; ++k) x += plane.V(plane.F(f, k), 0) / 3;
    observed[f] = x < 0.5;
  }
  errors = MeasureVertexErrors(points, plane.V, plane.F, &observed);
  EXPECT_EQ(errors.observed, std::vector<char>({1, 0, 0}));
  EXPECT_NEAR(errors.distance(1), 0.3, 1e-12);  // measured all the same

  // Colours at 0, half way (viridis at 1/2) and beyond the maximum; grey where
  // the closest ground truth is not observed.
  errors.distance << 0.0, 0.25, 0.9;
  errors.observed = {1, 1, 1};
  auto colors = ErrorColors(errors.distance, errors.observed, 0.5);
  EXPECT_EQ(colors.row(0).cast<int>(), Eigen::RowVector3i(68, 1, 84));
  EXPECT_EQ(colors.row(1).cast<int>(), Eigen::RowVector3i(33, 145, 140));
  EXPECT_EQ(colors.row(2).cast<int>(), Eigen::RowVector3i(253, 231, 37));
  errors.observed = {1, 0, 1};
  colors = ErrorColors(errors.distance, errors.observed, 0.5);
  EXPECT_EQ(colors.row(1).cast<int>(), Eigen::RowVector3i(128, 128, 128));
  errors.distance(0) = std::nan("");  // no normal error at a vertex in no face
  colors = ErrorColors(errors.distance, errors.observed, 0.5);
  EXPECT_EQ(colors.row(0).cast<int>(), Eigen::RowVector3i(128, 128, 128));
}

// The normal-error map: on the square folded up by 30 degrees beyond x = 0.5,
// the vertices of the flat part read 0, those of the folded part 30 (their
// closest ground truth is the flat square), and those on the fold the mean
// of their flat and folded faces; a vertex in no face reads NaN.
TEST(MeasureVertexNormalErrors, MeanAngleOfTheFacesAroundEachVertex) {
  const Mesh plane = Plane(4);  // x, y in {0, 0.25, ..., 1}
  Mesh folded = plane;
  for (int v = 0; v < folded.V.rows(); ++v) {
    folded.V(v, 2) = std::max(0.0, plane.V(v, 0) - 0.5) * std::tan(30.0 * M_PI / 180.0);
  }
  folded.V.conservativeResize(folded.V.rows() + 1, 3);
  folded.V.row(folded.V.rows() - 1) << 0.5, 0.5, 2.0;  // in no face
  const Eigen::VectorXd angles = MeasureVertexNormalErrors(
      folded.V, folded.F, plane.V, plane.F, MeasureVertexErrors(folded.V, plane.V, plane.F));
  ASSERT_EQ(angles.size(), folded.V.rows());
  for (int v = 0; v + 1 < folded.V.rows(); ++v) {
    const double x = plane.V(v, 0);
    if (x < 0.49) {
      EXPECT_NEAR(angles(v), 0.0, 1e-6) << v;
    } else if (x > 0.51) {
      EXPECT_NEAR(angles(v), 30.0, 1e-6) << v;
    } else {
      EXPECT_GT(angles(v), 1.0) << v;
      EXPECT_LT(angles(v), 29.0) << v;
    }
  }
  EXPECT_TRUE(std::isnan(angles(folded.V.rows() - 1)));
}

TEST(EvaluateMesh, TranslatedPlane) {
  const Mesh plane = Plane(8);
  Eigen::MatrixXd moved = plane.V;
  moved.col(2).array() += 0.1;
  EvaluationOptions options;
  options.num_samples = 5000;
  options.threshold = 0.1 + 1e-9;
  const EvaluationResult result = EvaluateMesh(plane.V, plane.F, moved, plane.F, options);
  EXPECT_NEAR(result.accuracy90, 0.1, 1e-12);
  EXPECT_NEAR(result.mean_accuracy, 0.1, 1e-12);
  EXPECT_NEAR(result.chamfer, 0.2, 1e-12);
  EXPECT_EQ(result.completeness, 100.0);
  EXPECT_LT(result.normal_deg, 1e-3);
  options.threshold = 0.1 - 1e-9;
  EXPECT_EQ(EvaluateMesh(plane.V, plane.F, moved, plane.F, options).completeness, 0.0);
}

// Normals are compared as unoriented lines: a ground truth wound the other
// way is the same surface (the oriented angle would be 180 degrees).
TEST(EvaluateMesh, FlippedNormalsGiveZeroDegrees) {
  const Mesh plane = Plane(4);
  Eigen::MatrixXi flipped = plane.F;
  flipped.col(1).swap(flipped.col(2));
  EvaluationOptions options;
  options.num_samples = 2000;
  const EvaluationResult result = EvaluateMesh(plane.V, plane.F, plane.V, flipped, options);
  EXPECT_LT(result.normal_deg, 1e-3);
  EXPECT_LT(result.accuracy90, 1e-12);
}

// The angle is min(theta, 180 - theta): a plane tilted by 30 degrees about
// the x axis gives 30 degrees whichever way either is wound.
TEST(EvaluateMesh, NormalAngleIsUnsigned) {
  const Mesh plane = Plane(4);
  Eigen::MatrixXd tilted = plane.V;
  const double a = 30.0 * M_PI / 180.0;
  tilted.col(2) = plane.V.col(1) * std::sin(a);
  tilted.col(1) = plane.V.col(1) * std::cos(a);
  Eigen::MatrixXi flipped = plane.F;
  flipped.col(1).swap(flipped.col(2));
  EvaluationOptions options;
  options.num_samples = 2000;
  for (const Eigen::MatrixXi* gt_F : std::vector<const Eigen::MatrixXi*>{&plane.F, &flipped}) {
    EXPECT_NEAR(EvaluateMesh(plane.V, plane.F, tilted, *gt_F, options).normal_deg, 30.0, 1e-6);
    EXPECT_NEAR(EvaluateMesh(plane.V, flipped, tilted, *gt_F, options).normal_deg, 30.0, 1e-6);
  }
}

// A flat ground truth and a reconstruction folded up by 30 degrees beyond
// x = 0.7: a third of its area (0.3 / cos 30 of 0.3 / cos 30 + 0.7) is off
// by 30 degrees and the rest by none, so the median is 0, the 90th
// percentile 30 and the mean about 10.
TEST(EvaluateMesh, NormalAngleMedianAndNinetiethPercentile) {
  const Mesh plane = Plane(10);
  Eigen::MatrixXd folded = plane.V;
  for (int v = 0; v < folded.rows(); ++v) {
    folded(v, 2) = std::max(0.0, plane.V(v, 0) - 0.7) * std::tan(30.0 * M_PI / 180.0);
  }
  EvaluationOptions options;
  options.num_samples = 20000;
  const EvaluationResult result = EvaluateMesh(folded, plane.F, plane.V, plane.F, options);
  EXPECT_NEAR(result.normal_deg_median, 0.0, 1e-6);
  EXPECT_NEAR(result.normal_deg_p90, 30.0, 1e-6);
  const double tilted_share = (0.3 / std::cos(30.0 * M_PI / 180.0)) /
                              (0.3 / std::cos(30.0 * M_PI / 180.0) + 0.7);
  // Binomial standard deviation of the tilted share with 20000 samples: 0.33 %.
  EXPECT_NEAR(result.normal_deg, 30.0 * tilted_share, 30.0 * 0.015);
  const std::string json = result.ToJson();
  EXPECT_NE(json.find("\"normal_deg_median\": 0.000000"), std::string::npos) << json;
  EXPECT_NE(json.find("\"normal_deg_p90\": 30.000000"), std::string::npos) << json;
}

// Half of the GT is missing from the reconstruction: completeness ~50%,
// accuracy unaffected.
TEST(EvaluateMesh, PartialReconstruction) {
  const Mesh gt = Plane(10);
  Mesh half;
  half.V = gt.V;
  half.V.col(0) *= 0.5;  // covers x in [0, 0.5]
  EvaluationOptions options;
  options.num_samples = 20000;
  options.threshold = 0.01;
  const EvaluationResult result = EvaluateMesh(half.V, gt.F, gt.V, gt.F, options);
  EXPECT_LT(result.accuracy90, 1e-12);
  // GT samples with x <= 0.51 are within 0.01: 51% of the area; the binomial
  // standard deviation with 20000 samples is 0.35%.
  EXPECT_NEAR(result.completeness, 51.0, 1.5);
}

TEST(EvaluateMesh, DeterministicForSeed) {
  const Mesh recon = Icosphere(2);
  const Mesh gt = Icosphere(4);
  EvaluationOptions options;
  options.num_samples = 3000;
  const EvaluationResult a = EvaluateMesh(recon.V, recon.F, gt.V, gt.F, options);
  const EvaluationResult b = EvaluateMesh(recon.V, recon.F, gt.V, gt.F, options);
  EXPECT_EQ(a.ToJson(), b.ToJson());
  options.seed = 7;
  const EvaluationResult c = EvaluateMesh(recon.V, recon.F, gt.V, gt.F, options);
  EXPECT_NE(a.mean_accuracy, c.mean_accuracy);
  EXPECT_NEAR(a.mean_accuracy, c.mean_accuracy, 0.1 * a.mean_accuracy);
}

TEST(EvaluateMesh, EmptyMesh) {
  const Mesh mesh = Icosphere(1);
  const Eigen::MatrixXd no_V(0, 3);
  const Eigen::MatrixXi no_F(0, 3);
  EXPECT_THROW(EvaluateMesh(no_V, no_F, mesh.V, mesh.F), InputError);
  EXPECT_THROW(EvaluateMesh(mesh.V, mesh.F, no_V, no_F), InputError);
  EXPECT_THROW(EvaluateMesh(mesh.V, no_F, mesh.V, mesh.F), InputError);
  // Zero area (all vertices at one point).
  const Eigen::MatrixXd collapsed = Eigen::MatrixXd::Zero(mesh.V.rows(), 3);
  EXPECT_THROW(EvaluateMesh(collapsed, mesh.F, mesh.V, mesh.F), InputError);
  Eigen::MatrixXi bad = mesh.F;
  bad(0, 0) = static_cast<int>(mesh.V.rows());
  EXPECT_THROW(EvaluateMesh(mesh.V, bad, mesh.V, mesh.F), InputError);
}

TEST(EvaluationResult, ToJsonIsOneLine) {
  EvaluationResult result;
  result.accuracy90 = 0.5;
  result.faces = 12;
  const std::string json = result.ToJson();
  EXPECT_EQ(json.find('\n'), std::string::npos);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  for (const char* key : {"\"accuracy90\": 0.5", "\"completeness\"", "\"chamfer\"",
                          "\"normal_deg\"", "\"mean_accuracy\"", "\"faces\": 12"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  }
}

// The command-line program, end to end.
TEST(MeshEvaluator, CommandLine) {
  const std::string exe = JoinPaths(MR_BIN_DIR, "mesh_evaluator");
  if (!ExistsFile(exe)) GTEST_SKIP() << exe << " not built";
  const std::string dir = MakeTestDir("evaluator_command_line");
  const Mesh plane = Plane(4);
  TriangleMesh recon, gt;
  recon.V = plane.V;
  recon.F = plane.F;
  gt = recon;
  gt.V.col(2).array() += 0.25;
  WriteMesh(JoinPaths(dir, "recon.ply"), recon);
  WriteMesh(JoinPaths(dir, "gt.obj"), gt);
  const std::string out = JoinPaths(dir, "out.txt");
  const std::string err = JoinPaths(dir, "err.txt");
  const std::string base = "'" + exe + "' --input_path '" + JoinPaths(dir, "recon.ply") + "'";
  const std::string command = base + " --gt_path '" + JoinPaths(dir, "gt.obj") +
                              "' --threshold 0.3 --num_samples 1000 --seed 3 > '" + out +
                              "' 2> '" + err + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << ReadFileToString(err);
  const std::string json = ReadFileToString(out);
  EXPECT_NE(json.find("\"accuracy90\": 0.25,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"completeness\": 100.000000"), std::string::npos) << json;
  EXPECT_NE(json.find("\"faces\": 32}"), std::string::npos) << json;

  // The error map: the evaluated mesh with each vertex's distance (0.25
  // everywhere) as its value and colour; yellow at --error_max 0.25.
  const std::string map_path = JoinPaths(dir, "map.ply");
  const std::string with_map = base + " --gt_path '" + JoinPaths(dir, "gt.obj") +
                               "' --num_samples 1000 --output_error_path '" + map_path +
                               "' --error_max 0.25 > '" + out + "' 2> '" + err + "'";
  ASSERT_EQ(std::system(with_map.c_str()), 0) << ReadFileToString(err);
  const TriangleMesh map = ReadMesh(map_path);
  ASSERT_EQ(map.NumVertices(), recon.NumVertices());
  EXPECT_EQ(map.F, recon.F);
  ASSERT_EQ(map.values.size(), recon.NumVertices());
  ASSERT_EQ(map.C.rows(), recon.NumVertices());
  for (int v = 0; v < map.NumVertices(); ++v) {
    EXPECT_NEAR(map.values(v), 0.25, 1e-6);
    EXPECT_EQ(map.C.row(v).cast<int>(), Eigen::RowVector3i(253, 231, 37));
  }
  // The normal-error map of the same: the planes are parallel, so every
  // vertex reads 0 degrees, dark blue.
  const std::string with_normal_map = base + " --gt_path '" + JoinPaths(dir, "gt.obj") +
                                      "' --num_samples 1000 --output_error_path '" + map_path +
                                      "' --error_map normal > '" + out + "' 2> '" + err + "'";
  ASSERT_EQ(std::system(with_normal_map.c_str()), 0) << ReadFileToString(err);
  const TriangleMesh normal_map = ReadMesh(map_path);
  ASSERT_EQ(normal_map.values.size(), recon.NumVertices());
  for (int v = 0; v < normal_map.NumVertices(); ++v) {
    EXPECT_NEAR(normal_map.values(v), 0.0, 1e-6);
    EXPECT_EQ(normal_map.C.row(v).cast<int>(), Eigen::RowVector3i(68, 1, 84));
  }
  // The map may not replace an input, and is a PLY.
  const std::string gt_bytes = ReadFileToString(JoinPaths(dir, "gt.obj"));
  for (const std::string& bad_map : {JoinPaths(dir, "gt.obj"), JoinPaths(dir, "map.obj")}) {
    const std::string refused = base + " --gt_path '" + JoinPaths(dir, "gt.obj") +
                                "' --output_error_path '" + bad_map + "' > '" + out + "' 2> '" +
                                err + "'";
    const int code = std::system(refused.c_str());
    EXPECT_TRUE(WIFEXITED(code) && WEXITSTATUS(code) == 1);
    EXPECT_NE(ReadFileToString(err).find("--output_error_path"), std::string::npos)
        << ReadFileToString(err);
  }
  EXPECT_EQ(ReadFileToString(JoinPaths(dir, "gt.obj")), gt_bytes);
  EXPECT_FALSE(ExistsFile(JoinPaths(dir, "map.obj")));

  // Missing file: one ERROR line, exit status 1.
  const std::string bad = base + " --gt_path '" + JoinPaths(dir, "nope.ply") + "' > '" + out +
                          "' 2> '" + err + "'";
  const int status = std::system(bad.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
  const std::string message = ReadFileToString(err);
  EXPECT_EQ(message.rfind("ERROR: ", 0), 0u) << message;
  EXPECT_NE(message.find("nope.ply"), std::string::npos) << message;

  // A point cloud (no faces) is rejected.
  TriangleMesh cloud = recon;
  cloud.F.resize(0, 3);
  WriteMesh(JoinPaths(dir, "cloud.ply"), cloud);
  const std::string empty = base + " --gt_path '" + JoinPaths(dir, "cloud.ply") + "' > '" + out +
                            "' 2> '" + err + "'";
  EXPECT_NE(std::system(empty.c_str()), 0);
  EXPECT_NE(ReadFileToString(err).find("mesh has no faces"), std::string::npos);
}

}  // namespace
}  // namespace mr

#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "util/testing.h"

namespace mr {
namespace {

// A ring of cameras above the equator never sees the bottom of a sphere: a
// bump there must not count with the observed-face mask, and must without.
TEST(ObservedFaces, UnseenBumpIsExcluded) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(4, 1.0, &V, &F);
  std::vector<PinholeView> views;
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * i / 8;
    views.push_back(LookAtView(Eigen::Vector3d(4 * std::cos(a), 4 * std::sin(a), 2.5),
                               Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), 80, 60, 80));
  }
  const std::vector<char> observed = ObservedFaces(V, F, views, 2);
  int seen_top = 0, seen_bottom = 0;
  const Eigen::MatrixXd N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) {
    if (N(f, 2) > 0.9) seen_top += observed[f];
    if (N(f, 2) < -0.9) seen_bottom += observed[f];
  }
  EXPECT_GT(seen_top, 0);
  EXPECT_EQ(seen_bottom, 0);

  Eigen::MatrixXd bumped = V;
  for (int v = 0; v < V.rows(); ++v) {
    if (V(v, 2) < -0.8) bumped.row(v) *= 1.2;
  }
  EvaluationOptions options;
  options.num_samples = 20000;
  const EvaluationResult all = EvaluateMesh(bumped, F, V, F, options);
  const EvaluationResult masked = EvaluateMesh(bumped, F, V, F, options, &observed);
  EXPECT_GT(all.accuracy90, 0.05);
  EXPECT_LT(masked.accuracy90, 1e-9);
  EXPECT_GT(masked.observed_percent, 30);
  EXPECT_LT(masked.observed_percent, 95);
  EXPECT_NE(masked.ToJson().find("observed_percent"), std::string::npos);
  EXPECT_EQ(all.ToJson().find("observed_percent"), std::string::npos);
}

// A closed ground truth wound outward and the same wound inward are the same
// surface: every figure, and the observed part, must be the same. The
// reconstruction is a coarser, bumpy, slightly larger sphere, so that
// distances, normal errors and completeness are all far from trivial.
double SignedVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double volume = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    volume += a.dot(b.cross(c)) / 6.0;
  }
  return volume;
}

TEST(EvaluateMesh, GroundTruthWindingDoesNotMatter) {
  Eigen::MatrixXd gt_V;
  Eigen::MatrixXi outward;
  MakeIcosphere(4, 1.0, &gt_V, &outward);
  ASSERT_GT(SignedVolume(gt_V, outward), 0);
  Eigen::MatrixXi inward = outward;
  inward.col(1).swap(inward.col(2));
  ASSERT_LT(SignedVolume(gt_V, inward), 0);
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, &V, &F);
  for (int v = 0; v < V.rows(); ++v) {
    V.row(v) *= 1.01 + 0.02 * std::sin(7 * V(v, 0)) * std::cos(5 * V(v, 2));
  }
  std::vector<PinholeView> views;  // a ring above the equator: the bottom is unseen
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * i / 8;
    views.push_back(LookAtView(Eigen::Vector3d(4 * std::cos(a), 4 * std::sin(a), 2.5),
                               Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), 80, 60, 80));
  }
  const std::vector<char> seen_outward = ObservedFaces(gt_V, outward, views, 2);
  const std::vector<char> seen_inward = ObservedFaces(gt_V, inward, views, 2);
  EXPECT_TRUE(seen_outward == seen_inward);
  EvaluationOptions options;
  options.num_samples = 20000;
  options.threshold = 0.02;
  for (const bool masked : {false, true}) {
    const EvaluationResult a = EvaluateMesh(V, F, gt_V, outward, options,
                                            masked ? &seen_outward : nullptr);
    const EvaluationResult b = EvaluateMesh(V, F, gt_V, inward, options,
                                            masked ? &seen_inward : nullptr);
    SCOPED_TRACE(masked ? "observed surface" : "whole surface");
    EXPECT_NEAR(a.accuracy90, b.accuracy90, 1e-9);
    EXPECT_NEAR(a.mean_accuracy, b.mean_accuracy, 1e-9);
    EXPECT_NEAR(a.chamfer, b.chamfer, 1e-9);
    EXPECT_NEAR(a.completeness, b.completeness, 1e-9);
    EXPECT_NEAR(a.normal_deg, b.normal_deg, 1e-9);
    EXPECT_NEAR(a.observed_percent, b.observed_percent, 1e-9);
    // Not a trivial comparison: the figures are far from 0 and 100, and the
    // mask keeps part of the surface only.
    EXPECT_GT(a.accuracy90, 0.01);
    EXPECT_GT(a.normal_deg, 1.0);
    EXPECT_LT(a.normal_deg, 45.0);  // the oriented angle would be about 180 for one of them
    EXPECT_GT(a.completeness, 5.0);
    EXPECT_LT(a.completeness, 95.0);
    if (masked) {
      EXPECT_GT(a.observed_percent, 30.0);
      EXPECT_LT(a.observed_percent, 95.0);
    }
  }
}

}  // namespace
}  // namespace mr
