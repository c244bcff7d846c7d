#include "geometry/primitives.h"
#include "geometry/remesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "util/error.h"

namespace mr {
namespace {

// Unit icosphere: 20 * 4^levels faces.
void Icosphere(int levels, Eigen::MatrixXd* V, Eigen::MatrixXi* F) { MakeIcosphere(levels, 1.0, V, F); }

// The upper half of a unit icosphere: an open mesh with a border.
void OpenHemisphere(int levels, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  Icosphere(levels, V, F);
  Eigen::MatrixXi H(F->rows(), 3);
  int n = 0;
  for (int f = 0; f < F->rows(); ++f) {
    if ((*V)((*F)(f, 0), 2) + (*V)((*F)(f, 1), 2) + (*V)((*F)(f, 2), 2) > 0) H.row(n++) = F->row(f);
  }
  H.conservativeResize(n, 3);
  *F = H;
  RemoveUnreferencedVertices(V, F);
}

double MaxRadiusError(const Eigen::MatrixXd& V) {
  return (V.rowwise().norm().array() - 1.0).abs().maxCoeff();
}

// Max distance of face centroids to the unit sphere (the mesh-to-sphere side).
double MaxCentroidRadiusError(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double e = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    e = std::max(e, std::abs(c.norm() - 1.0));
  }
  return e;
}

bool IsClosedManifold(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const EdgeTopology topo = ComputeEdgeTopology(F, V.rows());
  return topo.NumBoundaryEdges() == 0 && topo.NumNonManifoldEdges() == 0;
}

TEST(RemeshOptions, DefaultsAreValid) {
  EXPECT_TRUE(DecimateOptions().Check());
  EXPECT_TRUE(IsotropicRemeshOptions().Check());
  EXPECT_TRUE(CleanMeshOptions().Check());
  EXPECT_TRUE(RemoveSelfIntersectionsOptions().Check());
  EXPECT_TRUE(FixFlippedFacesOptions().Check());
}

TEST(RemeshOptions, InvalidValuesThrow) {
  DecimateOptions d;
  d.policy = "edge_length";
  EXPECT_THROW(d.Check(), InputError);
  IsotropicRemeshOptions r;
  r.iterations = 0;
  EXPECT_THROW(r.Check(), InputError);
  CleanMeshOptions c;
  c.degenerate_area_tolerance = -1;
  EXPECT_THROW(c.Check(), InputError);
  RemoveSelfIntersectionsOptions s;
  s.smoothing_weight = 0;
  EXPECT_THROW(s.Check(), InputError);
  FixFlippedFacesOptions x;
  x.max_angle_deg = 0;
  EXPECT_THROW(x.Check(), InputError);
}

TEST(Decimate, GarlandHeckbertReachesTargetAndKeepsSphere) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(5, &V, &F);  // 20480 faces
  const int target = 2000;
  const DecimateSummary s = Decimate(&V, &F, target);
  EXPECT_EQ(s.policy, "garland_heckbert");
  EXPECT_EQ(s.initial_faces, 20480);
  EXPECT_NEAR(F.rows(), target, 0.05 * target);
  EXPECT_EQ(s.final_faces, F.rows());
  EXPECT_TRUE(IsClosedManifold(V, F));
  // Edges of ~0.1: chord sagitta ~1e-3. 1% of the radius is a generous bound
  // that a wrong placement (e.g. collapsing to a far vertex) breaks.
  EXPECT_LT(MaxRadiusError(V), 0.01);
  EXPECT_LT(MaxCentroidRadiusError(V, F), 0.01);
  // Still outward: every face normal points away from the centre.
  const Eigen::MatrixXd N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    ASSERT_GT(N.row(f).dot(c.normalized()), 0.5) << "face " << f;
  }
}

TEST(Decimate, LindstromTurk) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(4, &V, &F);  // 5120 faces
  DecimateOptions options;
  options.policy = "lindstrom_turk";
  Decimate(&V, &F, 1000, options);
  EXPECT_NEAR(F.rows(), 1000, 50);
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_LT(MaxRadiusError(V), 0.02);
}

// A decimation whose result is no longer wanted (the refiner's background
// remeshing) stops at its next collapse once the flag is set; without the
// flag, or with it unset, it runs to the target as before.
TEST(Decimate, CancelStopsTheCollapses) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(4, &V, &F);  // 5120 faces
  std::atomic<bool> cancel{false};
  DecimateOptions options;
  options.cancel = &cancel;
  Eigen::MatrixXd V1 = V;
  Eigen::MatrixXi F1 = F;
  const DecimateSummary unset = Decimate(&V1, &F1, 1000, options);
  EXPECT_FALSE(unset.cancelled);
  Eigen::MatrixXd V2 = V;
  Eigen::MatrixXi F2 = F;
  Decimate(&V2, &F2, 1000);
  EXPECT_EQ(F1, F2);
  EXPECT_EQ(V1, V2);
  cancel = true;
  const DecimateSummary set = Decimate(&V, &F, 1000, options);
  EXPECT_TRUE(set.cancelled);
  EXPECT_FALSE(set.target_not_reached);
  EXPECT_EQ(set.collapsed_edges, 0);
  EXPECT_EQ(F.rows(), 5120);
}

// Decimation on spatial pieces: the pieces join into one closed manifold at
// the target, as close to the sphere as one piece, and the result is the
// same on any number of threads (it depends on faces_per_piece only).
TEST(Decimate, InPiecesJoinsAClosedManifoldIndependentOfThreads) {
  Eigen::MatrixXd V0;
  Eigen::MatrixXi F0;
  Icosphere(6, &V0, &F0);  // 81920 faces
  const int target = 32000;  // the refiner's reductions: 2-3x; 8000 per piece
  DecimateOptions options;
  options.faces_per_piece = 25000;  // 81920 / 4 = 20480 per piece
  Eigen::MatrixXd V = V0;
  Eigen::MatrixXi F = F0;
  const DecimateSummary s = Decimate(&V, &F, target, options);
  EXPECT_EQ(s.pieces, 4);
  EXPECT_FALSE(s.target_not_reached);
  EXPECT_LE(F.rows(), target + s.pieces - 1);
  EXPECT_GE(F.rows(), target - s.pieces);
  EXPECT_EQ(s.final_faces, F.rows());
  EXPECT_EQ(s.final_vertices, V.rows());
  // One closed 2-manifold: the cuts were joined (a cut vertex left twice
  // would leave border edges), with the Euler characteristic of a sphere.
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_EQ(V.rows() - F.rows() / 2, 2);
  // As close to the sphere as the whole mesh decimated at once (1 %), and
  // no face turned (the triangles next to the kept cuts included).
  EXPECT_LT(MaxRadiusError(V), 0.01);
  EXPECT_LT(MaxCentroidRadiusError(V, F), 0.01);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) {
    ASSERT_GT(N.row(f).dot(FaceCentroid(V, F, f).normalized()), 0.5) << "face " << f;
  }
#ifdef _OPENMP
  const int threads = omp_get_max_threads();
  for (const int n : {1, 3}) {
    omp_set_num_threads(n);
    Eigen::MatrixXd Vn = V0;
    Eigen::MatrixXi Fn = F0;
    const DecimateSummary sn = Decimate(&Vn, &Fn, target, options);
    EXPECT_EQ(sn.threads, n);
    EXPECT_EQ(Vn, V) << n << " threads";
    EXPECT_EQ(Fn, F) << n << " threads";
  }
  omp_set_num_threads(threads);
#endif
}

// The vertices on the cuts keep their input positions bit for bit (the pieces
// are joined at them); those away from the cuts are decimated as usual.
TEST(Decimate, InPiecesKeepsTheCutVertices) {
  Eigen::MatrixXd V0;
  Eigen::MatrixXi F0;
  Icosphere(6, &V0, &F0);  // 81920 faces
  // Turned off the icosahedron's symmetry planes, so that no two centroids
  // tie at the median and the test's cut is the function's.
  V0 = V0 * Eigen::Matrix3d(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  DecimateOptions options;
  options.faces_per_piece = 41000;  // two pieces: one cut
  Eigen::MatrixXd V = V0;
  Eigen::MatrixXi F = F0;
  const DecimateSummary s = Decimate(&V, &F, 20000, options);
  ASSERT_EQ(s.pieces, 2);
  // The input vertices shared by faces on both sides of the median cut.
  Eigen::MatrixXd C(F0.rows(), 3);
  for (int f = 0; f < F0.rows(); ++f) C.row(f) = FaceCentroid(V0, F0, f);
  int axis = 0;
  (C.colwise().maxCoeff() - C.colwise().minCoeff()).maxCoeff(&axis);
  std::vector<double> along(C.rows());
  for (int f = 0; f < C.rows(); ++f) along[f] = C(f, axis);
  std::vector<double> sorted = along;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  std::vector<int> side(V0.rows(), 0);  // bit 1: a face below, bit 2: a face at or above
  for (int f = 0; f < F0.rows(); ++f) {
    for (int k = 0; k < 3; ++k) side[F0(f, k)] |= along[f] < median ? 1 : 2;
  }
  int cut = 0, kept = 0;
  for (int v = 0; v < V0.rows(); ++v) {
    if (side[v] != 3) continue;
    ++cut;
    for (int w = 0; w < V.rows(); ++w) {
      if (V.row(w) == V0.row(v)) {
        ++kept;
        break;
      }
    }
  }
  EXPECT_GT(cut, 20);
  EXPECT_EQ(kept, cut);
  EXPECT_TRUE(IsClosedManifold(V, F));
  // 81920 -> 20000 faces: about 10000 vertices of 40962 left.
  EXPECT_LT(V.rows(), 10010);
}

// A target too small to leave each piece 8,000 faces is decimated as a
// whole: the faces kept along the cuts would crowd the pieces (8 pieces of a
// 20k-face sphere decimated to 2,000 faces turned faces on edge).
TEST(Decimate, SmallTargetIsDecimatedWhole) {
  Eigen::MatrixXd V, V1;
  Eigen::MatrixXi F, F1;
  Icosphere(5, &V, &F);  // 20480 faces
  V1 = V;
  F1 = F;
  DecimateOptions options;
  options.faces_per_piece = 3000;
  EXPECT_EQ(Decimate(&V, &F, 2000, options).pieces, 1);
  Decimate(&V1, &F1, 2000);
  EXPECT_EQ(V, V1);
  EXPECT_EQ(F, F1);
}

TEST(Decimate, BelowTargetIsUnchanged) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(1, &V, &F);
  const Eigen::MatrixXd V0 = V;
  const Eigen::MatrixXi F0 = F;
  Decimate(&V, &F, 1000);
  EXPECT_EQ(V, V0);
  EXPECT_EQ(F, F0);
  EXPECT_THROW(Decimate(&V, &F, 0), InputError);
}

TEST(SubdivideSqrt3, TriplesFacesAndStaysClosed) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);  // 320 faces, 162 vertices
  const SubdivisionSummary s = SubdivideSqrt3(&V, &F);
  EXPECT_EQ(F.rows(), 3 * 320);
  EXPECT_EQ(V.rows(), 162 + 320);
  EXPECT_EQ(s.final_faces, 960);
  EXPECT_TRUE(IsClosedManifold(V, F));
  // Smoothing: points move, but only a little on a fine sphere, and inward.
  EXPECT_LT(MaxRadiusError(V), 0.05);
  EXPECT_GT(VertexNormals(V, F).row(0).dot(V.row(0).normalized()), 0.99);
}

TEST(SubdivideMidpoint, QuadruplesFacesWithoutMovingVertices) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  const Eigen::MatrixXd V0 = V;
  const Eigen::MatrixXi F0 = F;
  const double area0 = FaceAreas(V0, F0).sum();
  SubdivideMidpoint(&V, &F);
  EXPECT_EQ(F.rows(), 4 * F0.rows());
  EXPECT_EQ(V.rows(), V0.rows() + ComputeEdgeTopology(F0, V0.rows()).E.rows());
  EXPECT_EQ(V.topRows(V0.rows()), V0);  // old vertices do not move
  EXPECT_NEAR(FaceAreas(V, F).sum(), area0, 1e-12 * area0);  // same surface
  EXPECT_TRUE(IsClosedManifold(V, F));
  // Orientation kept: each child normal equals its parent's.
  const Eigen::MatrixXd N0 = FaceNormals(V0, F0), N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) ASSERT_GT(N.row(f).dot(N0.row(f / 4)), 1 - 1e-9);
}

TEST(SubdivideMidpoint, OpenMesh) {
  Eigen::MatrixXd V(3, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 2;
  SubdivideMidpoint(&V, &F);
  EXPECT_EQ(F.rows(), 4);
  EXPECT_EQ(V.rows(), 6);
  EXPECT_NEAR(FaceAreas(V, F).sum(), 0.5, 1e-15);
  EXPECT_EQ(ComputeEdgeTopology(F, V.rows()).NumBoundaryEdges(), 6);
}

// A roof: the square [-1, 1]^2 on an n x n grid (n odd, so that the ridge
// x = 0 is a grid line) folded along x = 0, z = -slope |x|.
void Roof(int n, double slope, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  V->resize(n * n, 3);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -1 + 2.0 * i / (n - 1), y = -1 + 2.0 * j / (n - 1);
      V->row(j * n + i) << x, y, -slope * std::abs(x);
    }
  }
  F->resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      F->row(f++) << a, b, d;
      F->row(f++) << a, d, c;
    }
  }
}

TEST(SubdividePointNormal, PutsTheNewVerticesOnTheSphereThatMidpointsCut) {
  Eigen::MatrixXd V, V_mid;
  Eigen::MatrixXi F, F_mid;
  Icosphere(3, &V, &F);
  const Eigen::MatrixXd V0 = V;
  V_mid = V;
  F_mid = F;
  SubdivideMidpoint(&V_mid, &F_mid);
  const SubdivisionSummary s = SubdividePointNormal(&V, &F, 0.35);
  EXPECT_EQ(s.final_faces, 4 * 1280);
  EXPECT_EQ(F, F_mid);  // the same connectivity as the midpoint split
  EXPECT_EQ(V.topRows(V0.rows()), V0);  // old vertices do not move
  EXPECT_TRUE(IsClosedManifold(V, F));
  // Edges of about 0.15: midpoints sit up to 1 - cos(0.075) ~ 0.3 % inside
  // the sphere. The PN edge curves are as right as the mesh's own vertex
  // normals let them be (O(h) off the radius on an icosphere): measured
  // 0.16 of the midpoints' error.
  const double midpoint_error = MaxRadiusError(V_mid);
  EXPECT_GT(midpoint_error, 0.003);
  EXPECT_LT(MaxRadiusError(V), 0.2 * midpoint_error);
  const Eigen::MatrixXd N0 = FaceNormals(V_mid, F), N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) ASSERT_GT(N.row(f).dot(N0.row(f)), 0.99);
}

TEST(SubdividePointNormal, KeepsAPlaneFlatAndTheSidesOfACreaseFlat) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Roof(9, 0.0, &V, &F);  // flat, with its open border
  Eigen::MatrixXd V_mid = V;
  Eigen::MatrixXi F_mid = F;
  SubdivideMidpoint(&V_mid, &F_mid);
  const Eigen::MatrixXd V_flat = V;
  Eigen::MatrixXi E;
  SubdividePointNormal(&V, &F, 0.35, &E);
  EXPECT_LT((V - V_mid).cwiseAbs().maxCoeff(), 1e-15);
  // Each new vertex is the midpoint of the edge it reports.
  ASSERT_EQ(E.rows(), V.rows() - V_flat.rows());
  for (int e = 0; e < E.rows(); ++e) {
    EXPECT_LT((V.row(V_flat.rows() + e) - 0.5 * (V_flat.row(E(e, 0)) + V_flat.row(E(e, 1))))
                  .norm(),
              1e-15);
  }
  // A ridge of 90 degrees: the faces across it weigh exp(-2 / (2 0.35^2)),
  // 3e-4, in the normals of the ridge's vertices, so the new vertices beside
  // the ridge stay on their plane (measured 1.0e-4 edge lengths off; the
  // bound is 2e-4). With plain
  // vertex normals (sigma 0) the ridge's normals lean 45 degrees off both
  // planes and the edges leaving it bulge by a twentieth of their length.
  const double h = 0.25;
  for (const double sigma : {0.35, 0.0}) {
    Roof(9, 1.0, &V, &F);
    SubdividePointNormal(&V, &F, sigma);
    double off_plane = 0;
    for (int v = 0; v < V.rows(); ++v) {
      off_plane = std::max(off_plane, std::abs(V(v, 2) + std::abs(V(v, 0))) / std::sqrt(2.0));
    }
    if (sigma > 0) {
      EXPECT_LT(off_plane, 2e-4 * h) << "sigma " << sigma;
    } else {
      EXPECT_GT(off_plane, 0.05 * h) << "sigma " << sigma;
    }
  }
}

TEST(IsotropicRemesh, SphereReachesTargetEdgeLength) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(4, &V, &F);  // edges ~0.05
  const double target = 0.12;
  const IsotropicRemeshSummary s = IsotropicRemesh(&V, &F, target);
  const double mean = MeanEdgeLength(V, F);
  EXPECT_NEAR(mean, target, 0.2 * target);
  EXPECT_NEAR(s.final_mean_edge_length, mean, 1e-12);
  // Equilateral triangles of side `target` tiling the sphere's area 4 pi.
  const double expected_faces = 4 * M_PI / (std::sqrt(3.0) / 4 * target * target);
  EXPECT_NEAR(F.rows(), expected_faces, 0.25 * expected_faces);
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_LT(MaxRadiusError(V), 0.02);
}

// A closed bipyramid over three collinear vertices a, c, b (no face is
// degenerate): relaxing its apex moves it onto the line, every face around
// it becomes degenerate, and CGAL 5.5's tangential relaxation reads through a
// null halfedge (a segmentation fault). The remeshing runs in a child
// process and, when that crashes, again without relaxation.
TEST(IsotropicRemesh, SurvivesCgalsRelaxationCrash) {
  Eigen::MatrixXd V(5, 3);
  V << 0, 0, 0,  // a
      2, 0, 0,   // b
      1, 0, 0,   // c, between them
      1, 1, 1,   // apex above
      1, -1, 1;  // apex below
  Eigen::MatrixXi F(6, 3);
  F << 0, 2, 3, 2, 1, 3, 1, 0, 3, 4, 2, 0, 4, 1, 2, 4, 0, 1;
  ASSERT_TRUE(IsClosedManifold(V, F));
  for (const double target : {0.5, 1.0}) {
    Eigen::MatrixXd V_out = V;
    Eigen::MatrixXi F_out = F;
    const IsotropicRemeshSummary s = IsotropicRemesh(&V_out, &F_out, target);
    EXPECT_TRUE(s.relaxation_dropped) << target;
    EXPECT_GT(F_out.rows(), 0) << target;
    EXPECT_TRUE(V_out.allFinite()) << target;
  }
  // A mesh CGAL's relaxation handles keeps it, and ends as remeshed in the
  // calling process (the child's answer is the mesh, bit for bit).
  Eigen::MatrixXd S;
  Eigen::MatrixXi T;
  Icosphere(3, &S, &T);
  const IsotropicRemeshSummary s = IsotropicRemesh(&S, &T, 0.15);
  EXPECT_FALSE(s.relaxation_dropped);
  EXPECT_TRUE(IsClosedManifold(S, T));
}

TEST(IsotropicRemesh, ProtectedBorderStaysOnInputBorder) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  OpenHemisphere(3, &V, &F);
  const EdgeTopology topo0 = ComputeEdgeTopology(F, V.rows());
  ASSERT_GT(topo0.NumBoundaryEdges(), 0);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> border;
  for (int e = 0; e < topo0.E.rows(); ++e) {
    if (topo0.edge_faces[e].size() == 1)
      border.emplace_back(V.row(topo0.E(e, 0)), V.row(topo0.E(e, 1)));
  }
  IsotropicRemesh(&V, &F, 0.08);
  const EdgeTopology topo = ComputeEdgeTopology(F, V.rows());
  ASSERT_GT(topo.NumBoundaryEdges(), 0);
  for (int e = 0; e < topo.E.rows(); ++e) {
    if (topo.edge_faces[e].size() != 1) continue;
    for (int j = 0; j < 2; ++j) {
      const Eigen::Vector3d p = V.row(topo.E(e, j));
      double best = std::numeric_limits<double>::infinity();
      for (const auto& s : border) {
        const Eigen::Vector3d d = s.second - s.first;
        const double t = std::clamp((p - s.first).dot(d) / d.squaredNorm(), 0.0, 1.0);
        best = std::min(best, (s.first + t * d - p).norm());
      }
      ASSERT_LT(best, 1e-9) << "border vertex left the input border";
    }
  }
}

// Each band gets its own length: the western half of a unit icosphere
// remeshed towards 0.06, the eastern towards 0.24, from a mesh of ~0.05.
TEST(IsotropicRemeshBands, EachBandReachesItsLength) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(4, &V, &F);
  const std::vector<double> edges = {0.06, 0.24};
  const RemeshBandOf band_of = [](const Eigen::Vector3d& c, const Eigen::Vector3d&) {
    return c.x() < 0 ? 0 : 1;
  };
  IsotropicRemeshBands(&V, &F, edges, band_of);
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_LT(MaxRadiusError(V), 0.02);
  const EdgeTopology topo = ComputeEdgeTopology(F, V.rows());
  double sum[2] = {0, 0};
  int count[2] = {0, 0};
  for (int e = 0; e < topo.E.rows(); ++e) {
    const Eigen::Vector3d a = V.row(topo.E(e, 0)), b = V.row(topo.E(e, 1));
    const double x = 0.5 * (a.x() + b.x());
    if (std::abs(x) < 0.3) continue;  // the seam, where the bands meet
    sum[x < 0 ? 0 : 1] += (a - b).norm();
    ++count[x < 0 ? 0 : 1];
  }
  ASSERT_GT(count[0], 0);
  ASSERT_GT(count[1], 0);
  EXPECT_NEAR(sum[0] / count[0], edges[0], 0.2 * edges[0]);
  EXPECT_NEAR(sum[1] / count[1], edges[1], 0.2 * edges[1]);
  // One band is IsotropicRemesh.
  Eigen::MatrixXd V1, V2;
  Eigen::MatrixXi F1, F2;
  Icosphere(3, &V1, &F1);
  V2 = V1;
  F2 = F1;
  IsotropicRemesh(&V1, &F1, 0.15);
  IsotropicRemeshBands(&V2, &F2, {0.15},
                       [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 0; });
  EXPECT_EQ(F1, F2);
  EXPECT_EQ(V1, V2);
}

TEST(IsotropicRemeshBands, InvalidBands) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(1, &V, &F);
  const RemeshBandOf zero = [](const Eigen::Vector3d&, const Eigen::Vector3d&) { return 0; };
  EXPECT_THROW(IsotropicRemeshBands(&V, &F, {0.1, -1.0}, zero), InputError);
  const RemeshBandOf out_of_range = [](const Eigen::Vector3d&, const Eigen::Vector3d&) {
    return 2;
  };
  EXPECT_ANY_THROW(IsotropicRemeshBands(&V, &F, {0.1, 0.2}, out_of_range));
}

TEST(IsotropicRemesh, InvalidTarget) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(1, &V, &F);
  EXPECT_THROW(IsotropicRemesh(&V, &F, 0.0), InputError);
  EXPECT_THROW(IsotropicRemesh(&V, &F, std::nan("")), InputError);
}

TEST(CleanMesh, CleanSphereIsUnchanged) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  const Eigen::MatrixXd V0 = V;
  const Eigen::MatrixXi F0 = F;
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(V, V0);
  EXPECT_EQ(F, F0);
  EXPECT_TRUE(r.IsCleanManifold());
  EXPECT_EQ(r.connected_components, 1);
  EXPECT_EQ(r.boundary_edges, 0);
}

TEST(CleanMesh, RemovesInjectedDegeneraciesAndDuplicates) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  const Eigen::MatrixXd V0 = V;
  const Eigen::MatrixXi F0 = F;
  const int nv = V.rows(), nf = F.rows();
  // A duplicate of vertex F(0,0), used by face 0.
  V.conservativeResize(nv + 2, 3);
  V.row(nv) = V.row(F(0, 0));
  F(0, 0) = nv;
  // An unreferenced vertex.
  V.row(nv + 1) << 5, 5, 5;
  // A face using a vertex twice and a duplicate of face 3 (other orientation).
  F.conservativeResize(nf + 2, 3);
  F.row(nf) << 1, 1, 2;
  F.row(nf + 1) << F(3, 0), F(3, 2), F(3, 1);
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.merged_duplicate_vertices, 1);
  EXPECT_EQ(r.removed_repeated_index_faces, 1);
  EXPECT_EQ(r.removed_duplicate_faces, 1);
  EXPECT_EQ(r.removed_unreferenced_vertices, 2);  // the merged copy and (5,5,5)
  EXPECT_EQ(V, V0);  // vertex order kept
  EXPECT_EQ(F, F0);
  EXPECT_TRUE(r.IsCleanManifold());
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_EQ(CountSelfIntersections(V, F).intersecting_pairs, 0);
}

TEST(CleanMesh, ZeroAreaCapIsFlippedAway) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  const int nv = V.rows(), nf = F.rows();
  // Split face 0 = (x, y, z) at b = midpoint(y, z) and add the cap (y, z, b):
  // still closed, but the cap has zero area.
  const int x = F(0, 0), y = F(0, 1), z = F(0, 2);
  V.conservativeResize(nv + 1, 3);
  V.row(nv) = 0.5 * (V.row(y) + V.row(z));
  const int b = nv;
  F.conservativeResize(nf + 2, 3);
  F.row(0) << x, y, b;
  F.row(nf) << x, b, z;
  F.row(nf + 1) << y, z, b;
  ASSERT_TRUE(IsClosedManifold(V, F));
  ASSERT_EQ(FaceAreas(V, F).minCoeff() < 1e-12, true);
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.flipped_degenerate_faces, 1);
  EXPECT_EQ(r.removed_degenerate_faces, 0);
  EXPECT_EQ(F.rows(), nf + 2);
  EXPECT_TRUE(IsClosedManifold(V, F));
  EXPECT_TRUE(r.IsCleanManifold());
  EXPECT_GT(FaceAreas(V, F).minCoeff(), 1e-4);
  // Orientation is still outward everywhere.
  const Eigen::MatrixXd N = FaceNormals(V, F);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    ASSERT_GT(N.row(f).dot(c.normalized()), 0) << "face " << f;
  }
}

TEST(CleanMesh, ReorientsMinorityFaces) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  const Eigen::MatrixXi F0 = F;
  for (int f : {3, 50, 51, 200}) std::swap(F(f, 1), F(f, 2));
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.reoriented_faces, 4);
  EXPECT_EQ(r.inconsistent_edges, 0);
  EXPECT_EQ(F, F0);
}

TEST(CleanMesh, SplitsPinchedVertex) {
  Eigen::MatrixXd A;
  Eigen::MatrixXi FA;
  Icosphere(1, &A, &FA);
  // Two spheres touching at one vertex: B = A + 2 A(0), whose vertex 3
  // (antipodal to vertex 0 on the icosahedron) lands on A's vertex 0.
  Eigen::MatrixXd B = A.rowwise() + 2.0 * A.row(0);
  B.row(3) = A.row(0);
  const Eigen::MatrixXi FB = FA;
  Eigen::MatrixXd V(A.rows() + B.rows(), 3);
  V << A, B;
  Eigen::MatrixXi F(FA.rows() + FB.rows(), 3);
  F << FA, (FB.array() + A.rows()).matrix();
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.merged_duplicate_vertices, 1);
  EXPECT_EQ(r.non_manifold_vertices, 1);
  EXPECT_EQ(r.split_vertices, 1);
  EXPECT_EQ(r.remaining_non_manifold_vertices, 0);
  EXPECT_EQ(r.connected_components, 2);
  EXPECT_TRUE(r.IsCleanManifold());
  EXPECT_EQ(V.rows(), 2 * A.rows());
  EXPECT_TRUE(IsClosedManifold(V, F));
}

TEST(CleanMesh, GarbageThrowsInputError) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(1, &V, &F);
  Eigen::MatrixXd Vn = V;
  Vn(5, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(CleanMesh(&Vn, &F), InputError);
  Eigen::MatrixXi Fb = F;
  Fb(2, 2) = V.rows();
  EXPECT_THROW(CleanMesh(&V, &Fb), InputError);
  Fb(2, 2) = -1;
  EXPECT_THROW(CleanMesh(&V, &Fb), InputError);
  Eigen::MatrixXi F4(1, 4);
  F4 << 0, 1, 2, 3;
  EXPECT_THROW(CleanMesh(&V, &F4), InputError);
  EXPECT_THROW(Decimate(&Vn, &F, 10), InputError);
  EXPECT_THROW(SubdivideMidpoint(&Vn, &F), InputError);
  EXPECT_THROW(CountSelfIntersections(Vn, F), InputError);
}

TEST(Remesh, EmptyMesh) {
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  EXPECT_NO_THROW(Decimate(&V, &F, 10));
  EXPECT_NO_THROW(SubdivideSqrt3(&V, &F));
  EXPECT_NO_THROW(SubdivideMidpoint(&V, &F));
  EXPECT_NO_THROW(IsotropicRemesh(&V, &F, 0.1));
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.final_faces, 0);
  EXPECT_EQ(CountSelfIntersections(V, F).intersecting_pairs, 0);
  EXPECT_EQ(RemoveSelfIntersections(&V, &F).final_pairs, 0);
  EXPECT_EQ(CountFlippedFaces(V, V, F), 0);
  EXPECT_EQ(V.rows(), 0);
  EXPECT_EQ(F.rows(), 0);
  // Default-constructed (0 by 0) matrices too.
  Eigen::MatrixXd V0;
  Eigen::MatrixXi F0;
  EXPECT_NO_THROW(CleanMesh(&V0, &F0));
  EXPECT_NO_THROW(SubdivideMidpoint(&V0, &F0));
}

TEST(Remesh, RandomSoupsNeverCrash) {
  // Random triangle soups (with repeated indices, duplicates, coincident
  // points, non-manifold edges): CleanMesh must make them usable, and the
  // CGAL functions must either work or throw InputError.
  std::srand(7);
  int usable = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const int nv = 10 + trial * 3, nf = 3 * nv;
    Eigen::MatrixXd V = Eigen::MatrixXd::Random(nv, 3);
    for (int v = 0; v < nv; v += 7) V.row(v) = V.row(0);  // exact duplicates
    Eigen::MatrixXi F(nf, 3);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) F(f, k) = std::rand() % nv;
    const CleanMeshReport r = CleanMesh(&V, &F);
    EXPECT_EQ(r.remaining_non_manifold_edges, 0) << "trial " << trial;
    EXPECT_EQ(r.remaining_non_manifold_vertices, 0) << "trial " << trial;
    if (!r.IsCleanManifold()) continue;  // a non-orientable component
    ++usable;
    const double edge = MeanEdgeLength(V, F);
    auto run = [&](auto&& fn) {
      Eigen::MatrixXd W = V;
      Eigen::MatrixXi G = F;
      try {
        fn(&W, &G);
      } catch (const InputError&) {
      }
    };
    run([&](Eigen::MatrixXd* W, Eigen::MatrixXi* G) { CountSelfIntersections(*W, *G); });
    run([&](Eigen::MatrixXd* W, Eigen::MatrixXi* G) { Decimate(W, G, std::max(1, nf / 4)); });
    run([&](Eigen::MatrixXd* W, Eigen::MatrixXi* G) { SubdivideSqrt3(W, G); });
    run([&](Eigen::MatrixXd* W, Eigen::MatrixXi* G) { IsotropicRemesh(W, G, edge); });
    run([&](Eigen::MatrixXd* W, Eigen::MatrixXi* G) { RemoveSelfIntersections(W, G); });
  }
  EXPECT_GE(usable, 10);  // the CGAL functions really ran on cleaned soups
}

TEST(SubdivideSqrt3, OpenMesh) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  OpenHemisphere(2, &V, &F);
  const int n = static_cast<int>(F.rows());  // faces before subdividing
  const int nb = ComputeEdgeTopology(F, V.rows()).NumBoundaryEdges();
  ASSERT_GT(nb, 0);
  SubdivideSqrt3(&V, &F);
  EXPECT_GE(F.rows(), 3 * n);
  const EdgeTopology topo = ComputeEdgeTopology(F, V.rows());
  EXPECT_EQ(topo.NumNonManifoldEdges(), 0);
  EXPECT_GE(topo.NumBoundaryEdges(), nb);
}

TEST(Remesh, NonManifoldInputToCgalThrows) {
  // Three triangles on one edge.
  Eigen::MatrixXd V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  Eigen::MatrixXi F(3, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  EXPECT_THROW(CountSelfIntersections(V, F), InputError);
  EXPECT_THROW(SubdivideSqrt3(&V, &F), InputError);
  const CleanMeshReport r = CleanMesh(&V, &F);
  EXPECT_EQ(r.non_manifold_edges, 1);
  EXPECT_EQ(r.remaining_non_manifold_edges, 0);
  EXPECT_NO_THROW(CountSelfIntersections(V, F));
}

// A sphere with vertex 0 pushed through the opposite side.
void PiercedSphere(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  Icosphere(3, V, F);
  V->row(0) *= -1.5;
}

TEST(SelfIntersections, SphereHasNone) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(3, &V, &F);
  const SelfIntersectionReport r = CountSelfIntersections(V, F);
  EXPECT_EQ(r.intersecting_pairs, 0);
  EXPECT_EQ(r.intersecting_faces, 0);
}

TEST(SelfIntersections, PushedVertexIntersects) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PiercedSphere(&V, &F);
  const SelfIntersectionReport r = CountSelfIntersections(V, F, true);
  EXPECT_GT(r.intersecting_pairs, 0);
  EXPECT_EQ(static_cast<long>(r.pairs.size()), r.intersecting_pairs);
  // Every pair involves one of the (long) faces around vertex 0.
  for (const auto& p : r.pairs) {
    const bool a = (F.row(p.first).array() == 0).any(), b = (F.row(p.second).array() == 0).any();
    EXPECT_TRUE(a || b);
  }
}

TEST(SelfIntersections, RemoveBySmoothing) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PiercedSphere(&V, &F);
  RemoveSelfIntersectionsOptions options;
  options.use_cgal_repair = false;
  const int nv = V.rows();
  const RemoveSelfIntersectionsSummary s = RemoveSelfIntersections(&V, &F, options);
  EXPECT_GT(s.initial_pairs, 0);
  EXPECT_EQ(s.final_pairs, 0);
  EXPECT_EQ(V.rows(), nv);  // smoothing keeps the connectivity
  EXPECT_EQ(CountSelfIntersections(V, F).intersecting_pairs, 0);
}

TEST(SelfIntersections, RemoveWithCgalRepair) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PiercedSphere(&V, &F);
  const RemoveSelfIntersectionsSummary s = RemoveSelfIntersections(&V, &F);
  EXPECT_TRUE(s.cgal_repair_used);
  EXPECT_EQ(s.final_pairs, 0);
  EXPECT_EQ(CountSelfIntersections(V, F).intersecting_pairs, 0);
}

TEST(SelfIntersections, UndoResetsOnlyWhatIntersects) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(3, &V, &F);
  // Every vertex moves a little outwards (harmless), vertex 0 through the
  // sphere to the other side (intersects).
  Eigen::MatrixXd W = 1.01 * V;
  W.row(0) = -1.5 * V.row(0);
  ASSERT_GT(CountSelfIntersections(W, F).intersecting_pairs, 0);
  const UndoSelfIntersectionsSummary s = UndoSelfIntersections(V, F, {}, &W);
  EXPECT_GT(s.initial_pairs, 0);
  EXPECT_GE(s.rounds, 1);
  EXPECT_EQ(CountSelfIntersections(W, F).intersecting_pairs, 0);
  EXPECT_EQ(CountFlippedFaces(V, W, F), 0);
  EXPECT_EQ(W.row(0), V.row(0));
  // Only vertex 0 and vertices of the faces it pierced were reset; the rest
  // kept their motion.
  int kept = 0;
  for (int v = 0; v < V.rows(); ++v) kept += W.row(v) == (1.01 * V.row(v)) ? 1 : 0;
  EXPECT_EQ(kept + s.reset_vertices, V.rows());
  EXPECT_LT(s.reset_vertices, 20);
  EXPECT_GT(kept, V.rows() - 20);
}

TEST(SelfIntersections, UndoLeavesNoneAfterManyWildMoves) {
  // Many large random moves; resets of some create pairs with others, which
  // the later (local) rounds must find: the full check of the result agrees.
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(3, &V, &F);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(V.rows()) - 1);
  std::normal_distribution<double> normal(0.0, 0.6);
  int most_rounds = 0;
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::MatrixXd W = V;
    for (int i = 0; i < 40; ++i) {
      W.row(pick(rng)) += Eigen::RowVector3d(normal(rng), normal(rng), normal(rng));
    }
    ASSERT_GT(CountSelfIntersections(W, F).intersecting_pairs, 0) << "trial " << trial;
    const UndoSelfIntersectionsSummary s = UndoSelfIntersections(V, F, {}, &W);
    EXPECT_GT(s.initial_pairs, 0);
    EXPECT_EQ(CountSelfIntersections(W, F).intersecting_pairs, 0) << "trial " << trial;
    EXPECT_EQ(CountFlippedFaces(V, W, F), 0) << "trial " << trial;
    most_rounds = std::max(most_rounds, s.rounds);
  }
  EXPECT_GE(most_rounds, 2);  // the local rounds did run
}

TEST(SelfIntersections, GuardEqualsUndoOverManyMotions) {
  // The guard serves many calls; each call must give what
  // the stateless function gives with the guard's initial pairs allowed.
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PiercedSphere(&V, &F);  // starts with allowed pairs
  SelfIntersectionGuard guard(V, F);
  EXPECT_EQ(guard.initial_pairs(), CountSelfIntersections(V, F, true).pairs);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(V.rows()) - 1);
  std::normal_distribution<double> normal(0.0, 0.3);
  Eigen::MatrixXd current = V;
  int total_reset = 0;
  for (int step = 0; step < 4; ++step) {
    Eigen::MatrixXd moved = current;
    for (int i = 0; i < 20; ++i) {
      moved.row(pick(rng)) += Eigen::RowVector3d(normal(rng), normal(rng), normal(rng));
    }
    Eigen::MatrixXd by_guard = moved, by_function = moved;
    const UndoSelfIntersectionsSummary g = guard.Undo(current, &by_guard);
    const UndoSelfIntersectionsSummary u =
        UndoSelfIntersections(current, F, guard.initial_pairs(), &by_function);
    EXPECT_EQ(by_guard, by_function) << "step " << step;
    EXPECT_EQ(g.initial_pairs, u.initial_pairs);
    EXPECT_EQ(g.reset_vertices, u.reset_vertices);
    total_reset += g.reset_vertices;
    current = by_guard;
  }
  EXPECT_GT(total_reset, 0);  // the motions did intersect
  Eigen::MatrixXd short_v = V.topRows(5);
  EXPECT_THROW(guard.Undo(V, &short_v), InputError);
}

TEST(SelfIntersections, UndoKeepsAllowedPairs) {
  // A mesh that already intersects: its pairs are allowed, so a harmless
  // motion is kept entirely; without the allowance the warning path stops.
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PiercedSphere(&V, &F);
  const SelfIntersectionReport before = CountSelfIntersections(V, F, true);
  ASSERT_GT(before.intersecting_pairs, 0);
  const Eigen::MatrixXd moved = 1.001 * V;
  Eigen::MatrixXd W = moved;
  const UndoSelfIntersectionsSummary s = UndoSelfIntersections(V, F, before.pairs, &W);
  EXPECT_EQ(s.initial_pairs, 0);
  EXPECT_EQ(s.reset_vertices, 0);
  EXPECT_EQ(W, moved);
  W = moved;
  const UndoSelfIntersectionsSummary t = UndoSelfIntersections(V, F, {}, &W);
  EXPECT_EQ(t.initial_pairs, before.intersecting_pairs);
  EXPECT_GT(t.reset_vertices, 0);
  EXPECT_THROW(UndoSelfIntersections(V, F, {}, nullptr), std::exception);
  Eigen::MatrixXd short_v = V.topRows(5);
  EXPECT_THROW(UndoSelfIntersections(V, F, {}, &short_v), InputError);
}

// A flat 3x3 vertex grid on z = 0 (8 triangles, CCW seen from +z); the
// centre vertex 4 is at (1, 1).
void Grid(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  V->resize(9, 3);
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) V->row(i + 3 * j) << i, j, 0;
  F->resize(8, 3);
  *F << 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4, 3, 4, 7, 3, 7, 6, 4, 5, 8, 4, 8, 7;
}

TEST(FlippedFaces, DetectsConstructedFlip) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Grid(&V, &F);
  EXPECT_EQ(CountFlippedFaces(V, V, F), 0);
  Eigen::MatrixXd W = V;
  // Centre to (2.5, 1): it crosses the lines x = 2 (edge 5-8) and x - y = 1
  // (edge 1-5): faces (1,5,4) and (4,5,8) fold over (normal -z), no other.
  W.row(4) << 2.5, 1, 0;
  EXPECT_EQ(FlippedFaces(V, W, F), (std::vector<int>{3, 6}));
  // Inside its ring nothing folds.
  W.row(4) << 1.4, 0.7, 0;
  EXPECT_EQ(CountFlippedFaces(V, W, F), 0);
  // Lifting out of the plane turns normals by less than 90 degrees.
  W.row(4) << 1, 1, 5;
  EXPECT_EQ(CountFlippedFaces(V, W, F), 0);
  // ... but by more than 45 (tilt atan(5 / 0.71..1) > 78 deg) for the 6
  // faces around vertex 4 (faces 2 and 5 do not contain it).
  EXPECT_EQ(CountFlippedFaces(V, W, F, 45.0), 6);
  EXPECT_THROW(CountFlippedFaces(V, W.topRows(5), F), InputError);
}

TEST(FlippedFaces, FixBySmoothing) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Grid(&V, &F);
  Eigen::MatrixXd W = V;
  W.row(4) << 2.5, 1, 0;
  const FixFlippedFacesSummary s = FixFlippedFaces(V, F, &W);
  EXPECT_EQ(s.initial_flipped, 2);
  EXPECT_EQ(s.final_flipped, 0);
  EXPECT_EQ(CountFlippedFaces(V, W, F), 0);
  EXPECT_GT(s.smoothing_rounds_done, 0);
  EXPECT_EQ(s.reset_vertices, 0);
  // Vertices of no flipped face did not move.
  for (int v : {0, 3, 6, 7}) EXPECT_EQ(W.row(v), V.row(v));
}

TEST(FlippedFaces, FixByResetWithoutSmoothing) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Icosphere(2, &V, &F);
  Eigen::MatrixXd W = V;
  // Push vertex 0 sideways past its neighbours: part of its fan folds.
  const int far = F(0, 1);
  W.row(0) = V.row(0) + 3.0 * (V.row(far) - V.row(0));
  ASSERT_GT(CountFlippedFaces(V, W, F), 0);
  FixFlippedFacesOptions options;
  options.smoothing_rounds = 0;
  const FixFlippedFacesSummary s = FixFlippedFaces(V, F, &W, options);
  EXPECT_EQ(s.final_flipped, 0);
  EXPECT_EQ(s.reset_vertices, 1);
  EXPECT_EQ(W, V);
}

}  // namespace
}  // namespace mr
