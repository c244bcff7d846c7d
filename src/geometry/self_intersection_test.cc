#include "geometry/self_intersection.h"

#include <algorithm>
#include <random>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include "geometry/primitives.h"
#include "geometry/remesh.h"

namespace mr {
namespace {

using Point = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;
using CgalMesh = CGAL::Surface_mesh<Point>;

// CGAL's own answer (sorted pairs a <= b), the reference.
std::vector<std::pair<int, int>> CgalPairs(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  CgalMesh mesh;
  for (int v = 0; v < V.rows(); ++v) mesh.add_vertex(Point(V(v, 0), V(v, 1), V(v, 2)));
  for (int f = 0; f < F.rows(); ++f) {
    const CgalMesh::Face_index added = mesh.add_face(
        CgalMesh::Vertex_index(F(f, 0)), CgalMesh::Vertex_index(F(f, 1)),
        CgalMesh::Vertex_index(F(f, 2)));
    EXPECT_NE(added, CgalMesh::null_face()) << "face " << f;
  }
  std::vector<std::pair<CgalMesh::Face_index, CgalMesh::Face_index>> found;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(found));
  std::vector<std::pair<int, int>> pairs;
  for (const auto& [a, b] : found) {
    const int x = static_cast<int>(a.idx()), y = static_cast<int>(b.idx());
    pairs.emplace_back(std::min(x, y), std::max(x, y));
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// An icosphere whose vertices are pushed along random directions by up to
// `amplitude` x its radius: from 0.05 on, many faces cross each other.
void NoisySphere(int subdivisions, double amplitude, unsigned seed, Eigen::MatrixXd* V,
                 Eigen::MatrixXi* F) {
  MakeIcosphere(subdivisions, 1.0, V, F);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  for (int v = 0; v < V->rows(); ++v) {
    for (int k = 0; k < 3; ++k) (*V)(v, k) += u(rng);
  }
}

TEST(IntersectingFacePairs, SphereHasNone) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(4, 1.0, &V, &F);
  EXPECT_TRUE(IntersectingFacePairs(V, F).empty());
}

TEST(IntersectingFacePairs, EqualsCgalOnNoisySpheres) {
  for (const double amplitude : {0.01, 0.05, 0.15}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      Eigen::MatrixXd V;
      Eigen::MatrixXi F;
      NoisySphere(4, amplitude, seed, &V, &F);
      const auto expected = CgalPairs(V, F);
      if (amplitude >= 0.05) {
        EXPECT_GT(expected.size(), 10u) << "the test needs intersections";
      }
      EXPECT_EQ(IntersectingFacePairs(V, F), expected) << "amplitude " << amplitude;
    }
  }
}

TEST(IntersectingFacePairs, EqualsCgalOnInterpenetratingSpheres) {
  Eigen::MatrixXd V1, V2;
  Eigen::MatrixXi F1, F2;
  MakeIcosphere(3, 1.0, &V1, &F1);
  MakeIcosphere(3, 0.7, Eigen::Vector3d(0.9, 0.2, 0.1), &V2, &F2);
  Eigen::MatrixXd V(V1.rows() + V2.rows(), 3);
  Eigen::MatrixXi F(F1.rows() + F2.rows(), 3);
  V << V1, V2;
  F << F1, (F2.array() + static_cast<int>(V1.rows())).matrix();
  const auto expected = CgalPairs(V, F);
  EXPECT_GT(expected.size(), 20u);
  EXPECT_EQ(IntersectingFacePairs(V, F), expected);
}

// A grid of identical coordinates has every case of a shared edge and vertex;
// folding one square's two triangles onto each other and collapsing one
// face to a segment gives the coplanar-overlap and degenerate cases.
TEST(IntersectingFacePairs, FoldedEdgeAndDegenerateFaceAsCgal) {
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  AppendGrid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), 6, &V,
             &F);
  EXPECT_TRUE(IntersectingFacePairs(V, F).empty());
  // Fold: move the corner (2, 2) of the grid across the diagonal, in plane.
  Eigen::MatrixXd folded = V;
  const int corner = 2 * 7 + 2;
  folded.row(corner) = V.row(corner) + Eigen::RowVector3d(0.4, 0.45, 0);
  EXPECT_EQ(IntersectingFacePairs(folded, F), CgalPairs(folded, F));
  EXPECT_FALSE(IntersectingFacePairs(folded, F).empty());
  // Degenerate: a vertex moved onto the line of its face's other two.
  Eigen::MatrixXd degenerate = V;
  const int f = 20;
  degenerate.row(F(f, 0)) = 0.5 * (V.row(F(f, 1)) + V.row(F(f, 2)));
  const auto pairs = IntersectingFacePairs(degenerate, F);
  EXPECT_EQ(pairs, CgalPairs(degenerate, F));
  EXPECT_TRUE(std::binary_search(pairs.begin(), pairs.end(), std::make_pair(f, f)));
}

// Faces of very different sizes crowd the cells of the grid: the candidates
// then come from box_intersection_d, with the same answer.
TEST(IntersectingFacePairs, CrowdedCellsAsCgal) {
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  AppendGrid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), 60, &V,
             &F);
  // A few huge triangles through the fine grid set the mean box size, so
  // the grid's cells are far larger than the fine faces.
  for (int i = 0; i < 40; ++i) {
    const int base = static_cast<int>(V.rows());
    V.conservativeResize(base + 3, 3);
    V.row(base) << -100 - i, -100, -1;
    V.row(base + 1) << 100, -100 + i, 1;
    V.row(base + 2) << 0, 100, 0.01 * i;
    F.conservativeResize(F.rows() + 1, 3);
    F.row(F.rows() - 1) << base, base + 1, base + 2;
  }
  const auto expected = CgalPairs(V, F);
  EXPECT_GT(expected.size(), 100u);
  EXPECT_EQ(IntersectingFacePairs(V, F), expected);
}

// UndoSelfIntersections finds its pairs with the candidates of both
// positions and local rounds: CGAL's whole-mesh test of the result must find
// nothing new, over motions wild enough to need several rounds.
TEST(IntersectingFacePairs, UndoLeavesNothingCgalFinds) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, &V, &F);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(V.rows()) - 1);
  std::normal_distribution<double> normal(0.0, 0.6);
  int most_rounds = 0;
  for (int trial = 0; trial < 6; ++trial) {
    Eigen::MatrixXd W = V;
    for (int i = 0; i < 40; ++i) {
      W.row(pick(rng)) += Eigen::RowVector3d(normal(rng), normal(rng), normal(rng));
    }
    ASSERT_FALSE(CgalPairs(W, F).empty()) << "trial " << trial;
    const UndoSelfIntersectionsSummary s = UndoSelfIntersections(V, F, {}, &W);
    EXPECT_TRUE(CgalPairs(W, F).empty()) << "trial " << trial;
    most_rounds = std::max(most_rounds, s.rounds);
  }
  EXPECT_GE(most_rounds, 2);
}

}  // namespace
}  // namespace mr
