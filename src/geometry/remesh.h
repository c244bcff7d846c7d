#pragma once

// Mesh maintenance for the coarse-to-fine refinement loop: decimation,
// subdivision, isotropic remeshing, cleaning, self-intersection and
// flipped-face repair. libigl-style interface over Eigen:
//   V is #V by 3 (double), F is #F by 3 (int, counter-clockwise = outward).
// CGAL (Surface_mesh, Epick kernel) is used inside remesh.cc only; it never
// appears in this header. Functions that go through CGAL need an oriented
// 2-manifold mesh (every edge in at most two faces, consistently oriented,
// no pinched vertices): they throw mr::InputError otherwise, and CleanMesh()
// produces such a mesh from most garbage. Every entry point throws
// mr::InputError on malformed input (wrong column counts, indices out of
// range, NaN/Inf positions); an empty mesh (no faces) passes through.
//
// Library: mr_remesh (links CGAL; keep it out of mr_geometry).

#include <atomic>
#include <memory>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mr {

// Throws mr::InputError when V/F are malformed: V not #V by 3, F not #F by 3,
// an index outside [0, #V), or a non-finite (NaN/Inf) coordinate anywhere in V.
// `what` prefixes the message (e.g. the function name).
void CheckMeshInput(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& what);

// ---------------------------------------------------------------------------
// Decimation (CGAL Surface_mesh_simplification edge collapse).

struct DecimateOptions {
  // Cost/placement policy: "garland_heckbert" (plane quadrics, Garland &
  // Heckbert 1997; CGAL >= 5.5) or "lindstrom_turk" (Lindstrom & Turk 1998).
  std::string policy = "garland_heckbert";
  // Reject a collapse if any face of the resulting star turns its normal by
  // 90 degrees or more (CGAL Bounded_normal_change_filter): prevents folds.
  bool bounded_normal_change = true;
  // When given, the collapses stop as soon as *cancel is true (checked before
  // each collapse); the mesh is then partly decimated and the summary says
  // `cancelled`. For a decimation run on another thread whose result may
  // turn out not to be needed.
  const std::atomic<bool>* cancel = nullptr;
  // > 0: a mesh of more faces than this is cut into spatial pieces of at
  // most about this many faces (median cuts of the face centroids along the
  // longest side, a power of two of pieces, and no more than leave each
  // piece 8,000 faces of the target), which are decimated on parallel
  // threads, each to its share of the target, with the vertices on the cuts
  // and the triangles around them kept as they are; the pieces are then
  // joined. The result depends on this
  // number, not on the number of threads. The cuts stay at the input's
  // resolution, so follow it with a remeshing that may change them
  // (IsotropicRemesh). 0: the whole mesh at once, on one thread.
  int faces_per_piece = 0;

  bool Check() const;
};

struct DecimateSummary {
  int initial_vertices = 0, initial_faces = 0;
  int final_vertices = 0, final_faces = 0;
  int collapsed_edges = 0;
  int pieces = 1;   // spatial pieces decimated in parallel (faces_per_piece)
  int threads = 1;  // threads they ran on
  std::string policy;  // the policy actually used
  double seconds = 0;
  // True when the target was not reached (the filter/topology blocked collapses).
  bool target_not_reached = false;
  bool cancelled = false;  // stopped by DecimateOptions::cancel
  std::string BriefReport() const;
};

// Collapses edges until the mesh has at most `target_faces` faces (each
// interior collapse removes 2 faces, so the result is target_faces or
// target_faces - 1, unless collapses are blocked). target_faces >= 1;
// a mesh already at or below the target is returned unchanged. In place.
DecimateSummary Decimate(Eigen::MatrixXd* V, Eigen::MatrixXi* F, int target_faces,
                         const DecimateOptions& options = DecimateOptions());

// ---------------------------------------------------------------------------
// Subdivision.

struct SubdivisionSummary {
  int initial_vertices = 0, initial_faces = 0;
  int final_vertices = 0, final_faces = 0;
  double seconds = 0;
  std::string BriefReport() const;
};

// One step of Kobbelt's sqrt(3) subdivision (CGAL Subdivision_method_3):
// a vertex per face, edge flips, and smoothing of the old vertices. #F
// triples on a closed mesh. NOTE: it is an approximating scheme: the old
// vertices MOVE (the surface shrinks slightly towards its limit surface), so
// refinement that must keep the shape should use SubdivideMidpoint. Needs an
// oriented 2-manifold. In place.
SubdivisionSummary SubdivideSqrt3(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// One step of linear 1-to-4 subdivision: a new vertex at the midpoint of
// every unique edge, each face split into 4 (orientation kept). Old vertices
// do not move, new ones lie on the old surface: the shape is exactly kept.
// Works on any triangle soup (boundary and non-manifold edges included).
// New vertices are appended after the old ones (old indices stay valid).
// In place.
SubdivisionSummary SubdivideMidpoint(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// One step of 1-to-4 subdivision that keeps the old vertices and puts each
// new one on a smooth surface through them: on the cubic edge curve of the
// point-normal (PN) triangles of Vlachos et al. (I3D 2001), at its midpoint
//   (a + b) / 2 - ((b - a).n_a n_a - (b - a).n_b n_b) / 8,
// the curve through a and b tangent to the planes of the normals n_a, n_b.
// With exact normals, a sphere's new vertices are off it by O(h^4) where
// SubdivideMidpoint's are by h^2 / 8 (h the edge length); with a mesh's own
// vertex normals, by a sixth of the midpoints' (an icosphere). n_a is vertex a's normal
// seen from the edge: the area-weighted mean of the normals of a's faces,
// each weighted by exp(-|n_f - n_e|^2 / (2 normal_sigma^2)), n_e the mean
// normal of the edge's faces. On a crease the faces across it then barely
// count, and the edges beside it stay flat where plain vertex normals would
// bulge them (normal_sigma <= 0: the plain area-weighted vertex normals).
// New vertices are appended after the old ones, vertex #V + e on edge e of
// ComputeEdgeTopology(F); `parent_edges`, when given, gets that E (#E x 2,
// the ends of new vertex #V + e's edge). Any triangle soup (boundary and
// non-manifold edges included). In place.
SubdivisionSummary SubdividePointNormal(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                        double normal_sigma,
                                        Eigen::MatrixXi* parent_edges = nullptr);

// ---------------------------------------------------------------------------
// Isotropic remeshing (CGAL Polygon_mesh_processing::isotropic_remeshing:
// split long / collapse short edges, flip to valence 6, tangential relaxation).

struct IsotropicRemeshOptions {
  // Number of split/collapse/flip/relax rounds, in [1, 100].
  int iterations = 3;
  // Tangential relaxation steps per round, in [0, 100].
  int relaxation_steps = 1;
  // Keep border edges fixed (they are first split to <= 4/3 of the target
  // length so that CGAL can protect them).
  bool protect_border = true;
  // Keep sharp edges (dihedral angle above sharp_angle_deg) fixed likewise.
  bool protect_sharp_edges = false;
  // Dihedral angle (degrees, in (0, 180)) above which an edge is sharp.
  double sharp_angle_deg = 60.0;

  bool Check() const;
};

struct IsotropicRemeshSummary {
  int initial_vertices = 0, initial_faces = 0;
  int final_vertices = 0, final_faces = 0;
  double target_edge_length = 0;
  double initial_mean_edge_length = 0, final_mean_edge_length = 0;
  int protected_edges = 0;  // border + sharp edges kept
  // CGAL's relaxation crashed and the remeshing ran again without it
  // (RemeshIsotropically in remesh.cc).
  bool relaxation_dropped = false;
  double seconds = 0;
  std::string BriefReport() const;
};

// Remeshes towards edges of length `target_edge_length` (> 0, in the units of
// V). Needs an oriented 2-manifold. In place.
IsotropicRemeshSummary IsotropicRemesh(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                       double target_edge_length,
                                       const IsotropicRemeshOptions& options =
                                           IsotropicRemeshOptions());

// Which of the bands of IsotropicRemeshBands a face belongs to, from its
// centroid and unit normal: an index into the band edge lengths.
using RemeshBandOf = std::function<int(const Eigen::Vector3d& centroid,
                                       const Eigen::Vector3d& normal)>;

// Remeshes with an edge length that varies in steps (CGAL 5.5 has no
// adaptive sizing field): every face goes to the band `band_of` gives it,
// and each band is remeshed as a patch towards its own length
// `band_edges[b]` (> 0), from the longest to the shortest. The bands are
// recomputed from the faces before each pass, so that where two bands meet
// the shorter edges are made last. CGAL keeps a patch's border (it splits
// but does not collapse those edges). Border edges are protected at the
// shortest length. The summary's target is the shortest length.
IsotropicRemeshSummary IsotropicRemeshBands(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                            const std::vector<double>& band_edges,
                                            const RemeshBandOf& band_of,
                                            const IsotropicRemeshOptions& options =
                                                IsotropicRemeshOptions());

// ---------------------------------------------------------------------------
// Cleaning (Eigen only; works on arbitrary triangle soups).

struct CleanMeshOptions {
  // A face is degenerate (zero area) when 2*area <= tolerance * (longest
  // edge)^2; in [0, 1e-3]. Such faces are removed by flipping their longest
  // edge into the neighbour (keeps closed meshes closed) or, if impossible,
  // by deleting them.
  double degenerate_area_tolerance = 1e-12;
  // Duplicate each non-manifold vertex once per face fan (and cut
  // non-manifold edges, treated as fan separators), so that the result is a
  // 2-manifold with boundary. If false, they are only counted.
  bool fix_non_manifold = true;
  // Orient every connected component consistently, keeping the orientation
  // of the majority of its faces (Poisson meshes are outward).
  bool orient = true;

  bool Check() const;
};

struct CleanMeshReport {
  int initial_vertices = 0, initial_faces = 0;
  int final_vertices = 0, final_faces = 0;
  int merged_duplicate_vertices = 0;   // exactly equal positions merged
  int removed_repeated_index_faces = 0;  // faces using a vertex twice
  int removed_duplicate_faces = 0;     // same vertex triple (any order)
  int flipped_degenerate_faces = 0;    // zero-area faces removed by an edge flip
  int removed_degenerate_faces = 0;    // zero-area faces deleted
  int removed_unreferenced_vertices = 0;
  int non_manifold_edges = 0;          // found (before fixing)
  int non_manifold_vertices = 0;       // found (before fixing)
  int split_vertices = 0;              // copies added by the non-manifold fix
  int remaining_non_manifold_edges = 0;    // in the result
  int remaining_non_manifold_vertices = 0; // in the result
  int reoriented_faces = 0;            // faces whose orientation was reversed
  int non_orientable_components = 0;   // components that could not be oriented (left as input)
  int inconsistent_edges = 0;          // manifold edges with inconsistent orientation, in the result
  int connected_components = 0;
  int boundary_edges = 0;              // in the result
  double seconds = 0;
  // True when the result is an oriented 2-manifold (usable by the CGAL functions).
  bool IsCleanManifold() const;
  std::string BriefReport() const;
};

// Cleans (V, F) in place. Throws InputError on malformed input (see
// CheckMeshInput), never crashes on degenerate geometry.
CleanMeshReport CleanMesh(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                          const CleanMeshOptions& options = CleanMeshOptions());

// Gives every extra fan of faces around a pinched vertex (a vertex whose
// faces, joined through the edges they share, form more than one fan) a copy
// of the vertex of its own, appended to V. Returns the number of copies.
// Needs no edge in more than two faces. In place.
int SplitPinchedVertices(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// ---------------------------------------------------------------------------
// Self-intersections.

struct SelfIntersectionReport {
  long intersecting_pairs = 0;       // pairs of faces that intersect (not adjacent-legal)
  int intersecting_faces = 0;        // distinct faces involved
  std::vector<std::pair<int, int>> pairs;  // face index pairs (if requested)
  bool parallel = false;             // computed on more than one thread
  double seconds = 0;
  std::string BriefReport() const;
};

// Counts self-intersecting face pairs (IntersectingFacePairs in
// self_intersection.h: the pairs CGAL's PMP::self_intersections reports, on
// all OpenMP threads). Needs an oriented 2-manifold. `keep_pairs`: also
// return the pairs.
SelfIntersectionReport CountSelfIntersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                              bool keep_pairs = false);

struct RemoveSelfIntersectionsOptions {
  // Try CGAL's PMP::experimental::remove_self_intersections first (it may
  // remove faces and fill holes: the vertex/face count can change).
  bool use_cgal_repair = true;
  // Then, for what remains, Laplacian smoothing of the vertices of the
  // intersecting faces and of their one-ring: rounds in [0, 1000].
  int smoothing_rounds = 20;
  // Weight of the neighbours' average in each smoothing step, in (0, 1].
  double smoothing_weight = 0.5;

  bool Check() const;
};

struct RemoveSelfIntersectionsSummary {
  long initial_pairs = 0;
  long final_pairs = 0;  // what remains (0 = fixed)
  bool cgal_repair_used = false;
  bool cgal_repair_succeeded = false;
  int smoothing_rounds_done = 0;
  double seconds = 0;
  std::string BriefReport() const;
};

// Best effort; reports what remains. In place.
RemoveSelfIntersectionsSummary RemoveSelfIntersections(
    Eigen::MatrixXd* V, Eigen::MatrixXi* F,
    const RemoveSelfIntersectionsOptions& options = RemoveSelfIntersectionsOptions());

struct UndoSelfIntersectionsSummary {
  long initial_pairs = 0;   // intersecting pairs in the given *V_after, not counting `allowed`
  int initial_flipped = 0;  // flipped faces created by the resets (undone as well)
  int rounds = 0;           // checks that found something to undo
  int reset_vertices = 0;   // vertices moved back to V_before
  double seconds = 0;
  std::string BriefReport() const;
};

// Prevents a motion from creating self-intersections: the vertices of every
// face pair that intersects in *V_after but is not in `allowed` (sorted pairs
// a < b, e.g. those V_before already had; may be empty) are reset to their
// V_before positions, and so are those of faces flipped against V_before
// (a partial reset can fold a face), repeated until neither is left. This
// terminates: a round that finds something resets at least one vertex not
// yet reset, because a face pair whose six vertices are all back at V_before
// is a pair of V_before. The candidate pairs are found once per call (the
// faces whose boxes over both positions of their vertices overlap); the first
// check tests all of them (IntersectingFacePairs' exact test), the later ones
// those of the faces around reset vertices. Needs an oriented 2-manifold;
// V_before and *V_after have the same shape. In place.
UndoSelfIntersectionsSummary UndoSelfIntersections(
    const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
    const std::vector<std::pair<int, int>>& allowed, Eigen::MatrixXd* V_after);

// UndoSelfIntersections for a loop of motions over one connectivity: the
// pairs the mesh has when the guard is made are the allowed ones.
class SelfIntersectionGuard {
 public:
  // F must be an oriented 2-manifold (throws InputError otherwise).
  SelfIntersectionGuard(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
  ~SelfIntersectionGuard();
  SelfIntersectionGuard(const SelfIntersectionGuard&) = delete;
  SelfIntersectionGuard& operator=(const SelfIntersectionGuard&) = delete;

  // Intersecting pairs (a < b, sorted) of the mesh the guard was made with.
  const std::vector<std::pair<int, int>>& initial_pairs() const;
  // UndoSelfIntersections(V_before, F, initial_pairs(), V_after).
  UndoSelfIntersectionsSummary Undo(const Eigen::MatrixXd& V_before, Eigen::MatrixXd* V_after);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---------------------------------------------------------------------------
// Flipped faces (Eigen only): faces whose normal turned by more than
// `max_angle_deg` (default 90 degrees, i.e. n_before . n_after < 0) between
// two vertex sets over the same F. Degenerate faces (zero normal before or
// after) are not counted as flipped.

std::vector<int> FlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXd& V_after,
                              const Eigen::MatrixXi& F, double max_angle_deg = 90.0);
int CountFlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXd& V_after,
                      const Eigen::MatrixXi& F, double max_angle_deg = 90.0);

struct FixFlippedFacesOptions {
  // Flip threshold (degrees) in (0, 180].
  double max_angle_deg = 90.0;
  // Phase 1: rounds of umbrella smoothing of the vertices of flipped faces
  // (towards their one-ring average), in [0, 1000].
  int smoothing_rounds = 10;
  // Weight of the one-ring average per smoothing round, in (0, 1].
  double smoothing_weight = 0.5;

  bool Check() const;
};

struct FixFlippedFacesSummary {
  int initial_flipped = 0;
  int final_flipped = 0;  // always 0 (phase 2 guarantees it)
  int smoothing_rounds_done = 0;
  int reset_vertices = 0;  // vertices moved back to V_before in phase 2
  std::string BriefReport() const;
};

// Repairs *V_after in place so that no face is flipped relative to
// V_before. Phase 1: smoothing rounds (above). Phase 2: the vertices of the
// faces still flipped are reset to their V_before positions, repeated until
// none remains; terminates because a face whose three vertices are all reset
// equals its V_before self. V_before and *V_after must have the same shape.
FixFlippedFacesSummary FixFlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
                                       Eigen::MatrixXd* V_after,
                                       const FixFlippedFacesOptions& options =
                                           FixFlippedFacesOptions());

}  // namespace mr
