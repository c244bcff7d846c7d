#pragma once

// Which faces of a triangle mesh intersect each other: the test behind
// CountSelfIntersections, RemoveSelfIntersections, UndoSelfIntersections and
// the refiner's SelfIntersectionGuard (remesh.h). V is #V by 3, F #F by 3
// with valid indices.

#include <utility>
#include <vector>

#include <Eigen/Core>

namespace mr {

// The face pairs (a < b, sorted) of (V, F) that CGAL's
// PMP::self_intersections reports, with the same exact predicates: two faces
// intersect unless they touch only in the vertex or the edge they share (two
// faces sharing an edge intersect when they fold flat onto each other; two
// faces sharing a vertex when either one's opposite edge meets the other);
// every degenerate face is reported as (f, f) and tested against no other
// face. The candidates come from OverlappingBoxes, the exact tests from
// IntersectingCandidates.
std::vector<std::pair<int, int>> IntersectingFacePairs(const Eigen::MatrixXd& V,
                                                       const Eigen::MatrixXi& F);

// Whether face f's corners are collinear (exactly; CGAL's collinear).
bool FaceIsDegenerate(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f);
// FaceIsDegenerate of every face (1 = degenerate), on all OpenMP threads.
std::vector<char> DegenerateFaces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

// Whether faces a and b, neither degenerate, intersect other than in the
// vertex or the edge they share (exact; CGAL's do_faces_intersect).
bool FacesIntersect(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int a, int b);

// Axis-aligned boxes, box i spanning lo.row(i) to hi.row(i).
struct Boxes {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> lo, hi;
};
// The bounding box of each face.
Boxes FaceBoxes(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
// Sets box f of *boxes to face f's bounding box in V.
void SetFaceBox(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f, Boxes* boxes);
// Grows each face's box of *boxes to hold the face's corners in V too.
void GrowFaceBoxes(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Boxes* boxes);
// Whether closed boxes a of `x` and b of `y` overlap (touching counts).
bool BoxesOverlap(const Boxes& x, int a, const Boxes& y, int b);

// The pairs (i < j, in no particular order) of the boxes listed in `ids`
// whose closed boxes overlap. A uniform grid with cells about as large as a
// box finds them (each pair is tested in the one cell that holds the lower
// corner of the two boxes' overlap), in time linear in the boxes where
// CGAL's box_intersection_d sorts them; boxes that crowd a few cells (very
// unequal sizes) go to box_intersection_d instead.
std::vector<std::pair<int, int>> OverlappingBoxes(const Boxes& boxes, const std::vector<int>& ids);

// Of the candidate face pairs (those at the indices `which`, or all when it
// is null), in that order, the ones whose faces are both non-degenerate
// (`degenerate`, one flag per face), whose `boxes` overlap and which
// intersect (FacesIntersect); tested on all OpenMP threads.
std::vector<std::pair<int, int>> IntersectingCandidates(
    const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const Boxes& boxes,
    const std::vector<char>& degenerate, const std::vector<std::pair<int, int>>& candidates,
    const std::vector<int>* which = nullptr);

}  // namespace mr
