// The CGAL half of remesh.h: decimation, sqrt(3) subdivision, isotropic
// remeshing and self-intersections. CGAL types stay in this file: (V, F) is
// converted to a CGAL::Surface_mesh (Epick kernel) at entry and back at exit.

#include "geometry/remesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <iterator>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/exceptions.h>
#include <CGAL/tags.h>

#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/subdivision_method_3.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "geometry/mesh.h"
#include "geometry/self_intersection.h"
#include "util/error.h"
#include "util/isolated.h"
#include "util/logging.h"

namespace mr {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;
namespace SMS = CGAL::Surface_mesh_simplification;

// (V, F) -> *mesh by Surface_mesh::add_face, face after face. add_face
// refuses a face one of whose edges already has a face on the same side (a
// non-manifold edge, or an inconsistent orientation), but accepts a vertex
// whose faces form two fans: the faces met by circulating around each vertex
// are therefore counted against the faces that use it. Returns false on any
// refusal or mismatch (the mesh is then half-built).
bool AddFaces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Mesh* mesh) {
  mesh->reserve(V.rows(), 3 * F.rows() / 2 + F.rows(), F.rows());
  for (int v = 0; v < V.rows(); ++v) mesh->add_vertex(Point(V(v, 0), V(v, 1), V(v, 2)));
  std::vector<int> uses(V.rows(), 0);
  for (int f = 0; f < F.rows(); ++f) {
    const Mesh::Vertex_index a(F(f, 0)), b(F(f, 1)), c(F(f, 2));
    if (a == b || b == c || c == a) return false;
    if (mesh->add_face(a, b, c) == Mesh::null_face()) return false;
    for (int k = 0; k < 3; ++k) ++uses[F(f, k)];
  }
  for (Mesh::Vertex_index v : mesh->vertices()) {
    if (uses[v.idx()] == 0) continue;  // unreferenced: isolated
    int around = 0;
    for (Mesh::Face_index f : CGAL::faces_around_target(mesh->halfedge(v), *mesh)) {
      around += f != Mesh::null_face() ? 1 : 0;
    }
    if (around != uses[v.idx()]) return false;
  }
  return true;
}

// (V, F) -> Surface_mesh. Vertex i becomes vertex index i and face f face
// index f (fresh mesh, sequential insertion). Throws InputError when (V, F)
// is not an oriented 2-manifold. Built face by face (AddFaces), which takes a
// tenth of the time of CGAL's polygon-soup check and conversion (0.05
// against 0.5 s for 160k faces); the soup's check decides when that fails.
Mesh ToCgal(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const char* what) {
  {
    Mesh mesh;
    if (AddFaces(V, F, &mesh)) return mesh;
  }
  std::vector<Point> points(V.rows());
  for (int v = 0; v < V.rows(); ++v) points[v] = Point(V(v, 0), V(v, 1), V(v, 2));
  std::vector<std::array<int, 3>> polygons(F.rows());
  for (int f = 0; f < F.rows(); ++f) polygons[f] = {F(f, 0), F(f, 1), F(f, 2)};
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    MR_THROW_INPUT << what
                   << ": the mesh is not an oriented 2-manifold (non-manifold edge or vertex, "
                      "or inconsistent orientation); run CleanMesh first";
  }
  Mesh mesh;
  mesh.reserve(V.rows(), 3 * F.rows() / 2 + F.rows(), F.rows());
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  MR_CHECK_EQ(static_cast<long>(mesh.number_of_faces()), static_cast<long>(F.rows()));
  return mesh;
}

// Surface_mesh -> (V, F), dropping removed elements.
void FromCgal(const Mesh& mesh, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  std::vector<int> index(mesh.num_vertices(), -1);
  V->resize(mesh.number_of_vertices(), 3);
  int n = 0;
  for (Mesh::Vertex_index v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    V->row(n) << p.x(), p.y(), p.z();
    index[v.idx()] = n++;
  }
  F->resize(mesh.number_of_faces(), 3);
  int m = 0;
  for (Mesh::Face_index f : mesh.faces()) {
    int k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      MR_CHECK_LT(k, 3) << "non-triangular face in CGAL output";
      (*F)(m, k++) = index[v.idx()];
    }
    MR_CHECK_EQ(k, 3);
    ++m;
  }
}

// Stops when the mesh has at most `target` faces, or when *cancel is set.
struct FaceCountStop {
  const Mesh* mesh;
  std::size_t target;
  const std::atomic<bool>* cancel;
  template <typename FT, typename Profile>
  bool operator()(const FT&, const Profile&, std::size_t, std::size_t) const {
    return mesh->number_of_faces() <= target ||
           (cancel != nullptr && cancel->load(std::memory_order_relaxed));
  }
};

using VertexFlags = Mesh::Property_map<Mesh::Vertex_index, bool>;

// A placement that refuses every collapse of an edge with an end in *fixed
// (when given), so that those vertices keep their identity, position and
// neighbours: the cuts between spatial pieces (DecimateOptions::
// faces_per_piece) and the triangles along them stay as they are.
template <typename Base>
struct KeepFixedVertices {
  Base base;
  const VertexFlags* fixed;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile) const {
    if (fixed != nullptr && ((*fixed)[profile.v0()] || (*fixed)[profile.v1()])) {
      return boost::none;
    }
    return base(profile);
  }
};

// Collapses edges down to `target` faces; see KeepFixedVertices for *fixed.
template <typename Cost, typename Placement>
int CollapseEdges(Mesh* mesh, std::size_t target, const Cost& cost, const Placement& placement,
                  const DecimateOptions& options, const VertexFlags* fixed) {
  const FaceCountStop stop{mesh, target, options.cancel};
  const KeepFixedVertices<Placement> keep{placement, fixed};
  if (options.bounded_normal_change) {
    return SMS::edge_collapse(*mesh, stop,
                              CGAL::parameters::get_cost(cost).get_placement(keep).filter(
                                  SMS::Bounded_normal_change_filter<>()));
  }
  return SMS::edge_collapse(*mesh, stop, CGAL::parameters::get_cost(cost).get_placement(keep));
}

// Runs a CGAL call; a CGAL precondition/assertion failure (almost always
// caused by degenerate input) becomes an InputError with context.
template <typename Fn>
void RunCgal(const char* what, Fn&& fn) {
  try {
    fn();
  } catch (const CGAL::Failure_exception& e) {
    MR_THROW_INPUT << what << ": CGAL failed (" << e.what()
                   << "); the mesh may be degenerate, run CleanMesh first";
  }
}

}  // namespace

// ---------------------------------------------------------------------------

bool DecimateOptions::Check() const {
  if (policy != "garland_heckbert" && policy != "lindstrom_turk") {
    MR_THROW_INPUT << "DecimateOptions::policy = " << policy
                   << ". Violated constraint: policy in {garland_heckbert, lindstrom_turk}";
  }
  return true;
}

std::string DecimateSummary::BriefReport() const {
  std::ostringstream s;
  s << policy << ": faces " << initial_faces << " -> " << final_faces << ", vertices "
    << initial_vertices << " -> " << final_vertices << ", " << collapsed_edges
    << " edges collapsed in " << seconds << " s";
  if (pieces > 1) s << " (" << pieces << " pieces on " << threads << " threads)";
  s << (target_not_reached ? " (target NOT reached: collapses blocked)" : "")
    << (cancelled ? " (cancelled)" : "");
  return s.str();
}

namespace {

// Collapses edges of `mesh` down to `target` faces with the options' policy,
// leaving the vertices marked in *fixed (when given) and the triangles
// around them as they are. Returns the number of collapses.
int DecimateMesh(Mesh* mesh, int target, const DecimateOptions& options,
                 const VertexFlags* fixed) {
  int collapsed = 0;
  RunCgal("Decimate", [&] {
    if (options.policy == "garland_heckbert") {
      const SMS::GarlandHeckbert_plane_policies<Mesh, Kernel> gh(*mesh);
      collapsed = CollapseEdges(mesh, target, gh.get_cost(), gh.get_placement(), options, fixed);
    } else {
      collapsed = CollapseEdges(mesh, target, SMS::LindstromTurk_cost<Mesh>(),
                                SMS::LindstromTurk_placement<Mesh>(), options, fixed);
    }
  });
  mesh->collect_garbage();
  return collapsed;
}

// The spatial piece of every face: the faces' centroids cut at their median
// along the longest side of their box, again and again, until no piece has
// more than `max_faces` faces or there are `max_pieces` pieces (2^k pieces,
// k >= 0). Sets *num_pieces.
std::vector<int> SpatialPieces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int max_faces,
                               int max_pieces, int* num_pieces) {
  const int n = static_cast<int>(F.rows());
  std::vector<Eigen::Vector3d> centroid(n);
  for (int f = 0; f < n; ++f) centroid[f] = FaceCentroid(V, F, f);
  std::vector<int> order(n);
  for (int f = 0; f < n; ++f) order[f] = f;
  int pieces = 1;
  while (n / pieces > max_faces && 2 * pieces <= max_pieces) pieces *= 2;
  // Piece p holds order[bounds[p], bounds[p + 1]); each round halves all.
  std::vector<int> bounds = {0, n};
  while (static_cast<int>(bounds.size()) - 1 < pieces) {
    std::vector<int> next = {0};
    for (size_t p = 0; p + 1 < bounds.size(); ++p) {
      const auto begin = order.begin() + bounds[p], end = order.begin() + bounds[p + 1];
      Eigen::AlignedBox3d box;
      for (auto it = begin; it != end; ++it) box.extend(centroid[*it]);
      int axis = 0;
      box.sizes().maxCoeff(&axis);
      const auto middle = begin + (end - begin) / 2;
      std::nth_element(begin, middle, end, [&](int a, int b) {
        return centroid[a][axis] < centroid[b][axis] || (centroid[a][axis] == centroid[b][axis] && a < b);
      });
      next.push_back(static_cast<int>(middle - order.begin()));
      next.push_back(bounds[p + 1]);
    }
    bounds = std::move(next);
  }
  std::vector<int> piece(n);
  for (int p = 0; p + 1 < static_cast<int>(bounds.size()); ++p) {
    for (int k = bounds[p]; k < bounds[p + 1]; ++k) piece[order[k]] = p;
  }
  *num_pieces = pieces;
  return piece;
}

// Decimate on spatial pieces (DecimateOptions::faces_per_piece): each piece
// is decimated on a thread of its own to its share of the target, leaving
// the vertices on its cuts and the triangles around them as they are; the
// pieces are then joined at those vertices, by their (unchanged) positions.
// Returns false, leaving (V, F) as they were, when the target is too small
// for two pieces, a piece is not a 2-manifold by itself even with its
// pinched vertices split, or a cut vertex shares its position with another
// vertex; the caller then decimates the whole.
bool DecimateInPieces(Eigen::MatrixXd* V, Eigen::MatrixXi* F, int target_faces,
                      const DecimateOptions& options, DecimateSummary* summary) {
  int num_pieces = 1;
  // No piece is decimated below kMinPieceTarget faces: the faces kept along
  // its cuts would be too large a share of it, and the rest of it would be
  // decimated the harder (a hull's coarse level; a 20k-face sphere cut into 8
  // pieces and decimated to 2,000 faces turned faces on edge).
  constexpr int kMinPieceTarget = 8000;
  const std::vector<int> piece = SpatialPieces(*V, *F, options.faces_per_piece,
                                               std::max(1, target_faces / kMinPieceTarget),
                                               &num_pieces);
  if (num_pieces < 2) return false;
  // A vertex is on a cut when its faces lie in more than one piece.
  std::vector<int> first_piece(V->rows(), -1);
  std::vector<char> on_cut(V->rows(), 0);
  for (int f = 0; f < F->rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      int& p = first_piece[(*F)(f, k)];
      if (p < 0) p = piece[f];
      if (p != piece[f]) on_cut[(*F)(f, k)] = 1;
    }
  }
  std::vector<std::vector<int>> faces_of(num_pieces);
  for (int f = 0; f < F->rows(); ++f) faces_of[piece[f]].push_back(f);
  // The cut vertices by position, at which the pieces are joined.
  std::map<std::array<double, 3>, int> cut_at;
  for (int v = 0; v < V->rows(); ++v) {
    if (on_cut[v]) cut_at.emplace(std::array<double, 3>{(*V)(v, 0), (*V)(v, 1), (*V)(v, 2)}, v);
  }
  // A cut vertex must be the only vertex at its position (CleanMesh merges
  // such duplicates).
  long at_cut_positions = 0;
  for (int v = 0; v < V->rows(); ++v) {
    at_cut_positions += cut_at.count({(*V)(v, 0), (*V)(v, 1), (*V)(v, 2)});
  }
  if (at_cut_positions != static_cast<long>(cut_at.size())) {
    MR_LOG(INFO) << "Decimate: a vertex on a cut between pieces shares its position with "
                    "another; decimating the mesh as a whole";
    return false;
  }

  struct Piece {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    std::vector<int> input;  // the input row of each cut vertex of V, else -1
    int collapsed = 0;
    bool manifold = true;
    std::exception_ptr error;
  };
  std::vector<Piece> out(num_pieces);
  const double share = double(target_faces) / double(F->rows());
  int threads = 1;
#pragma omp parallel
  {
#ifdef _OPENMP
#pragma omp single
    threads = omp_get_num_threads();
#endif
#pragma omp for schedule(dynamic, 1)
    for (int p = 0; p < num_pieces; ++p) {
      Piece& result = out[p];
      try {
        // The piece as a mesh of its own.
        std::vector<int> local(V->rows(), -1), input;
        Eigen::MatrixXi Fp(faces_of[p].size(), 3);
        for (size_t i = 0; i < faces_of[p].size(); ++i) {
          for (int k = 0; k < 3; ++k) {
            const int v = (*F)(faces_of[p][i], k);
            if (local[v] < 0) {
              local[v] = static_cast<int>(input.size());
              input.push_back(v);
            }
            Fp(i, k) = local[v];
          }
        }
        Eigen::MatrixXd Vp(input.size(), 3);
        for (size_t i = 0; i < input.size(); ++i) Vp.row(i) = V->row(input[i]);
        // A cut can leave a vertex of the piece with two fans of faces: one
        // copy each, on the cut like the vertex, joined again below.
        SplitPinchedVertices(&Vp, &Fp);
        Mesh mesh;
        try {
          mesh = ToCgal(Vp, Fp, "Decimate");
        } catch (const InputError&) {
          result.manifold = false;
          continue;
        }
        // The cut vertices (found by position: the copies too) stay, with
        // the triangles around them.
        auto fixed = mesh.add_property_map<Mesh::Vertex_index, bool>("v:mr_cut", false).first;
        int cut_vertices = 0;
        for (int v = 0; v < Vp.rows(); ++v) {
          const bool cut = cut_at.count({Vp(v, 0), Vp(v, 1), Vp(v, 2)}) > 0;
          fixed[Mesh::Vertex_index(v)] = cut;
          cut_vertices += cut;
        }
        const int target = std::max(4, static_cast<int>(std::lround(share * Fp.rows())));
        result.collapsed = DecimateMesh(&mesh, target, options, &fixed);
        FromCgal(mesh, &result.V, &result.F);
        result.input.assign(result.V.rows(), -1);
        int found = 0;
        for (int v = 0; v < result.V.rows(); ++v) {
          const auto it = cut_at.find({result.V(v, 0), result.V(v, 1), result.V(v, 2)});
          if (it == cut_at.end()) continue;
          result.input[v] = it->second;
          ++found;
        }
        MR_CHECK_EQ(found, cut_vertices) << "Decimate: a vertex on a cut moved";
      } catch (...) {
        result.error = std::current_exception();
      }
    }
  }  // omp parallel
  for (const Piece& p : out) {
    if (p.error) std::rethrow_exception(p.error);
  }
  const long not_manifold = std::count_if(out.begin(), out.end(), [](const Piece& p) { return !p.manifold; });
  if (not_manifold > 0) {
    MR_LOG(INFO) << "Decimate: " << not_manifold << " of " << num_pieces
                 << " spatial pieces are not 2-manifolds by themselves; decimating the mesh "
                    "as a whole";
    return false;
  }
  // Join: one row per cut vertex, shared by its pieces.
  int rows = 0, faces = 0;
  for (const Piece& p : out) {
    rows += static_cast<int>(p.V.rows());
    faces += static_cast<int>(p.F.rows());
  }
  std::vector<int> joined(V->rows(), -1);
  Eigen::MatrixXd Vj(rows, 3);
  Eigen::MatrixXi Fj(faces, 3);
  int nv = 0, nf = 0;
  for (const Piece& p : out) {
    std::vector<int> index(p.V.rows());
    for (int v = 0; v < p.V.rows(); ++v) {
      const int r = p.input[v];
      if (r >= 0 && joined[r] >= 0) {
        index[v] = joined[r];
        continue;
      }
      Vj.row(nv) = p.V.row(v);
      index[v] = nv;
      if (r >= 0) joined[r] = nv;
      ++nv;
    }
    for (int f = 0; f < p.F.rows(); ++f, ++nf) {
      for (int k = 0; k < 3; ++k) Fj(nf, k) = index[p.F(f, k)];
    }
    summary->collapsed_edges += p.collapsed;
  }
  Vj.conservativeResize(nv, 3);
  *V = std::move(Vj);
  *F = std::move(Fj);
  summary->pieces = num_pieces;
  summary->threads = threads;
  return true;
}

}  // namespace

DecimateSummary Decimate(Eigen::MatrixXd* V, Eigen::MatrixXi* F, int target_faces,
                         const DecimateOptions& options) {
  MR_CHECK(V != nullptr && F != nullptr);
  options.Check();
  if (target_faces < 1) {
    MR_THROW_INPUT << "Decimate: target_faces = " << target_faces
                   << ". Violated constraint: target_faces >= 1";
  }
  CheckMeshInput(*V, *F, "Decimate");
  const double t0 = ElapsedSeconds();
  DecimateSummary summary;
  summary.policy = options.policy;
  summary.initial_vertices = summary.final_vertices = V->rows();
  summary.initial_faces = summary.final_faces = F->rows();
  if (F->rows() <= target_faces) {
    MR_LOG(INFO) << "Decimate: " << F->rows() << " faces <= target " << target_faces
                 << ", nothing to do";
    return summary;
  }
  // Converted first, also for pieces: a non-manifold input fails alike, and
  // the mesh serves when the pieces do not.
  Mesh mesh = ToCgal(*V, *F, "Decimate");
  const bool in_pieces = options.faces_per_piece > 0 && F->rows() > options.faces_per_piece &&
                         DecimateInPieces(V, F, target_faces, options, &summary);
  if (!in_pieces) {
    summary.collapsed_edges = DecimateMesh(&mesh, target_faces, options, nullptr);
    FromCgal(mesh, V, F);
  }
  summary.final_vertices = V->rows();
  summary.final_faces = F->rows();
  summary.cancelled = options.cancel != nullptr && options.cancel->load();
  // Pieces each stop at their share of the target, rounded: the whole may
  // end up to half a face per piece above it.
  summary.target_not_reached =
      F->rows() > target_faces + summary.pieces - 1 && !summary.cancelled;
  summary.seconds = ElapsedSeconds() - t0;
  if (summary.cancelled) {
    MR_LOG(VERBOSE) << "Decimate: " << summary.BriefReport();
  } else {
    MR_LOG(INFO) << "Decimate: " << summary.BriefReport();
  }
  if (summary.target_not_reached) {
    MR_LOG(WARNING) << "Decimate: stopped at " << summary.final_faces << " faces (target "
                    << target_faces << "): no admissible collapse left";
  }
  return summary;
}

// ---------------------------------------------------------------------------

SubdivisionSummary SubdivideSqrt3(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MR_CHECK(V != nullptr && F != nullptr);
  CheckMeshInput(*V, *F, "SubdivideSqrt3");
  const double t0 = ElapsedSeconds();
  SubdivisionSummary summary;
  summary.initial_vertices = summary.final_vertices = V->rows();
  summary.initial_faces = summary.final_faces = F->rows();
  if (F->rows() == 0) return summary;
  Mesh mesh = ToCgal(*V, *F, "SubdivideSqrt3");
  RunCgal("SubdivideSqrt3", [&] {
    CGAL::Subdivision_method_3::Sqrt3_subdivision(mesh,
                                                  CGAL::parameters::number_of_iterations(1));
  });
  FromCgal(mesh, V, F);
  summary.final_vertices = V->rows();
  summary.final_faces = F->rows();
  summary.seconds = ElapsedSeconds() - t0;
  MR_LOG(INFO) << "SubdivideSqrt3: " << summary.BriefReport();
  return summary;
}

// ---------------------------------------------------------------------------

bool IsotropicRemeshOptions::Check() const {
  if (iterations < 1 || iterations > 100) {
    MR_THROW_INPUT << "IsotropicRemeshOptions::iterations = " << iterations
                   << ". Violated constraint: 1 <= iterations <= 100";
  }
  if (relaxation_steps < 0 || relaxation_steps > 100) {
    MR_THROW_INPUT << "IsotropicRemeshOptions::relaxation_steps = " << relaxation_steps
                   << ". Violated constraint: 0 <= relaxation_steps <= 100";
  }
  if (!(sharp_angle_deg > 0 && sharp_angle_deg < 180)) {
    MR_THROW_INPUT << "IsotropicRemeshOptions::sharp_angle_deg = " << sharp_angle_deg
                   << ". Violated constraint: 0 < sharp_angle_deg < 180";
  }
  return true;
}

std::string IsotropicRemeshSummary::BriefReport() const {
  std::ostringstream s;
  s << "target edge " << target_edge_length << ": faces " << initial_faces << " -> "
    << final_faces << ", vertices " << initial_vertices << " -> " << final_vertices
    << ", mean edge " << initial_mean_edge_length << " -> " << final_mean_edge_length << ", "
    << protected_edges << " protected edges, "
    << (relaxation_dropped ? "without relaxation (CGAL's crashed), " : "") << seconds << " s";
  return s.str();
}

namespace {

// (V, F) and a count as bytes, and back: RemeshIsotropically's child process
// answers with them.
std::string PackMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int count) {
  const int64_t rows[2] = {V.rows(), F.rows()};
  const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v = V;
  const Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> f = F;
  std::string out(reinterpret_cast<const char*>(rows), sizeof rows);
  out.append(reinterpret_cast<const char*>(v.data()), sizeof(double) * v.size());
  out.append(reinterpret_cast<const char*>(f.data()), sizeof(int) * f.size());
  out.append(reinterpret_cast<const char*>(&count), sizeof count);
  return out;
}

void UnpackMesh(const std::string& bytes, Eigen::MatrixXd* V, Eigen::MatrixXi* F, int* count) {
  int64_t rows[2];
  MR_CHECK_GE(bytes.size(), sizeof rows);
  std::memcpy(rows, bytes.data(), sizeof rows);
  MR_CHECK_EQ(bytes.size(), sizeof rows + sizeof(double) * 3 * rows[0] +
                                 sizeof(int) * 3 * rows[1] + sizeof(int));
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> v(rows[0], 3);
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> f(rows[1], 3);
  const char* at = bytes.data() + sizeof rows;
  std::memcpy(v.data(), at, sizeof(double) * v.size());
  at += sizeof(double) * v.size();
  std::memcpy(f.data(), at, sizeof(int) * f.size());
  at += sizeof(int) * f.size();
  std::memcpy(count, at, sizeof(int));
  *V = v;
  *F = f;
}

// The isotropic remeshing of IsotropicRemesh and IsotropicRemeshBands:
// `passes` gets the CGAL mesh, the constrained-edge map, whether any edge
// is protected and the relaxation steps per round, and runs CGAL's
// remeshing on it.
//
// CGAL 5.5's tangential relaxation (Debian 12's) reads through a null
// halfedge when every face around a vertex it has just moved is degenerate,
// and the process ends with a segmentation fault: a closed bipyramid on
// three collinear vertices does it (IsotropicRemesh.SurvivesCgalsRelaxationCrash),
// and so did a refinement of a tangled Poisson blob between two pyramid
// levels. So the remeshing runs in a child process (RunIsolated); if that
// crashes, it runs again here without relaxation, which cannot.
template <typename Passes>
IsotropicRemeshSummary RemeshIsotropically(const char* what, Eigen::MatrixXd* V,
                                           Eigen::MatrixXi* F, double shortest_edge,
                                           const IsotropicRemeshOptions& options,
                                           const Passes& passes) {
  MR_CHECK(V != nullptr && F != nullptr);
  options.Check();
  CheckMeshInput(*V, *F, what);
  const double t0 = ElapsedSeconds();
  IsotropicRemeshSummary summary;
  summary.target_edge_length = shortest_edge;
  summary.initial_vertices = summary.final_vertices = V->rows();
  summary.initial_faces = summary.final_faces = F->rows();
  summary.initial_mean_edge_length = summary.final_mean_edge_length = MeanEdgeLength(*V, *F);
  if (F->rows() == 0) return summary;
  // The remeshed (V, F) and the number of protected edges.
  auto remesh = [&](int relaxation_steps, Eigen::MatrixXd* V_out, Eigen::MatrixXi* F_out) {
    Mesh mesh = ToCgal(*V, *F, what);
    int protected_edges = 0;
    RunCgal(what, [&] {
      auto constrained =
          mesh.add_property_map<Mesh::Edge_index, bool>("e:mr_constrained", false).first;
      if (options.protect_border) {
        for (Mesh::Edge_index e : mesh.edges()) {
          if (mesh.is_border(e)) constrained[e] = true;
        }
      }
      if (options.protect_sharp_edges) {
        auto sharp = mesh.add_property_map<Mesh::Edge_index, bool>("e:mr_sharp", false).first;
        PMP::detect_sharp_edges(mesh, options.sharp_angle_deg, sharp);
        for (Mesh::Edge_index e : mesh.edges()) {
          if (sharp[e]) constrained[e] = true;
        }
        mesh.remove_property_map(sharp);
      }
      std::vector<Mesh::Edge_index> protected_list;
      for (Mesh::Edge_index e : mesh.edges()) {
        if (constrained[e]) protected_list.push_back(e);
      }
      const bool protect = !protected_list.empty();
      if (protect) {
        // CGAL can only protect edges <= 4/3 of the target: split them first
        // (the pieces stay constrained).
        PMP::split_long_edges(protected_list, shortest_edge, mesh,
                              CGAL::parameters::edge_is_constrained_map(constrained));
        for (Mesh::Edge_index e : mesh.edges()) protected_edges += constrained[e] ? 1 : 0;
      }
      passes(mesh, constrained, protect, relaxation_steps);
      mesh.remove_property_map(constrained);
    });
    mesh.collect_garbage();
    FromCgal(mesh, V_out, F_out);
    return protected_edges;
  };
  Eigen::MatrixXd V_new;
  Eigen::MatrixXi F_new;
  const IsolatedResult isolated = RunIsolated([&] {
    Eigen::MatrixXd V_child;
    Eigen::MatrixXi F_child;
    const int protected_edges = remesh(options.relaxation_steps, &V_child, &F_child);
    return PackMesh(V_child, F_child, protected_edges);
  });
  if (isolated.status == IsolatedResult::Status::kDone) {
    UnpackMesh(isolated.payload, &V_new, &F_new, &summary.protected_edges);
  } else {
    MR_LOG(WARNING) << what << ": CGAL's remeshing crashed (signal " << isolated.signal
                    << "; CGAL 5.5's tangential relaxation on a vertex whose faces all became "
                       "degenerate); remeshing again without relaxation";
    summary.protected_edges = remesh(0, &V_new, &F_new);
    summary.relaxation_dropped = true;
  }
  *V = std::move(V_new);
  *F = std::move(F_new);
  summary.final_vertices = V->rows();
  summary.final_faces = F->rows();
  summary.final_mean_edge_length = MeanEdgeLength(*V, *F);
  summary.seconds = ElapsedSeconds() - t0;
  return summary;
}

void CheckEdgeLength(const char* what, double length) {
  if (!(length > 0) || !std::isfinite(length)) {
    MR_THROW_INPUT << what << ": target_edge_length = " << length
                   << ". Violated constraint: target_edge_length > 0 (finite)";
  }
}

}  // namespace

IsotropicRemeshSummary IsotropicRemesh(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                       double target_edge_length,
                                       const IsotropicRemeshOptions& options) {
  CheckEdgeLength("IsotropicRemesh", target_edge_length);
  const IsotropicRemeshSummary summary = RemeshIsotropically(
      "IsotropicRemesh", V, F, target_edge_length, options,
      [&](Mesh& mesh, auto& constrained, bool protect, int relaxation_steps) {
        PMP::isotropic_remeshing(faces(mesh), target_edge_length, mesh,
                                 CGAL::parameters::number_of_iterations(options.iterations)
                                     .number_of_relaxation_steps(relaxation_steps)
                                     .protect_constraints(protect)
                                     .edge_is_constrained_map(constrained));
      });
  MR_LOG(INFO) << "IsotropicRemesh: " << summary.BriefReport();
  return summary;
}

IsotropicRemeshSummary IsotropicRemeshBands(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                            const std::vector<double>& band_edges,
                                            const RemeshBandOf& band_of,
                                            const IsotropicRemeshOptions& options) {
  MR_CHECK(!band_edges.empty()) << "IsotropicRemeshBands: no band";
  for (const double e : band_edges) CheckEdgeLength("IsotropicRemeshBands", e);
  std::vector<int> order(band_edges.size());
  for (size_t b = 0; b < order.size(); ++b) order[b] = static_cast<int>(b);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return band_edges[a] > band_edges[b]; });
  const double shortest = band_edges[order.back()];
  std::ostringstream passes_report;
  const IsotropicRemeshSummary summary = RemeshIsotropically(
      "IsotropicRemeshBands", V, F, shortest, options,
      [&](Mesh& mesh, auto& constrained, bool protect, int relaxation_steps) {
        for (const int band : order) {
          std::vector<Mesh::Face_index> patch;
          for (Mesh::Face_index f : mesh.faces()) {
            Eigen::Vector3d p[3];
            int k = 0;
            for (Mesh::Vertex_index v : vertices_around_face(mesh.halfedge(f), mesh)) {
              const auto& q = mesh.point(v);
              p[k++] = Eigen::Vector3d(q.x(), q.y(), q.z());
            }
            const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
            const double norm = n.norm();
            const int b = band_of((p[0] + p[1] + p[2]) / 3.0,
                                  norm > 0 ? Eigen::Vector3d(n / norm) : Eigen::Vector3d::Zero());
            MR_CHECK(b >= 0 && b < static_cast<int>(band_edges.size()))
                << "IsotropicRemeshBands: band " << b << " of " << band_edges.size();
            if (b == band) patch.push_back(f);
          }
          passes_report << (passes_report.tellp() > 0 ? ", " : "") << patch.size() << " faces at "
                        << band_edges[band];
          if (patch.empty()) continue;
          PMP::isotropic_remeshing(patch, band_edges[band], mesh,
                                   CGAL::parameters::number_of_iterations(options.iterations)
                                       .number_of_relaxation_steps(relaxation_steps)
                                       .protect_constraints(protect)
                                       .edge_is_constrained_map(constrained));
        }
      });
  MR_LOG(INFO) << "IsotropicRemeshBands (" << passes_report.str() << "): "
               << summary.BriefReport();
  return summary;
}

// ---------------------------------------------------------------------------

std::string SelfIntersectionReport::BriefReport() const {
  std::ostringstream s;
  s << intersecting_pairs << " intersecting face pairs (" << intersecting_faces << " faces), "
    << (parallel ? "parallel" : "sequential") << ", " << seconds << " s";
  return s.str();
}

SelfIntersectionReport CountSelfIntersections(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                              bool keep_pairs) {
  CheckMeshInput(V, F, "CountSelfIntersections");
  const double t0 = ElapsedSeconds();
  SelfIntersectionReport report;
#ifdef _OPENMP
  report.parallel = omp_get_max_threads() > 1;
#endif
  if (F.rows() == 0) return report;
  ToCgal(V, F, "CountSelfIntersections");  // throws unless an oriented 2-manifold
  std::vector<std::pair<int, int>> pairs = IntersectingFacePairs(V, F);
  report.intersecting_pairs = static_cast<long>(pairs.size());
  std::vector<int> involved;
  involved.reserve(2 * pairs.size());
  for (const auto& [a, b] : pairs) {
    involved.push_back(a);
    involved.push_back(b);
  }
  std::sort(involved.begin(), involved.end());
  report.intersecting_faces =
      static_cast<int>(std::unique(involved.begin(), involved.end()) - involved.begin());
  if (keep_pairs) report.pairs = std::move(pairs);
  report.seconds = ElapsedSeconds() - t0;
  MR_LOG(VERBOSE) << "CountSelfIntersections: " << report.BriefReport();
  return report;
}

bool RemoveSelfIntersectionsOptions::Check() const {
  if (smoothing_rounds < 0 || smoothing_rounds > 1000) {
    MR_THROW_INPUT << "RemoveSelfIntersectionsOptions::smoothing_rounds = " << smoothing_rounds
                   << ". Violated constraint: 0 <= smoothing_rounds <= 1000";
  }
  if (!(smoothing_weight > 0 && smoothing_weight <= 1)) {
    MR_THROW_INPUT << "RemoveSelfIntersectionsOptions::smoothing_weight = " << smoothing_weight
                   << ". Violated constraint: 0 < smoothing_weight <= 1";
  }
  return true;
}

std::string RemoveSelfIntersectionsSummary::BriefReport() const {
  std::ostringstream s;
  s << "intersecting pairs " << initial_pairs << " -> " << final_pairs << " (CGAL repair "
    << (cgal_repair_used ? (cgal_repair_succeeded ? "succeeded" : "incomplete") : "not used")
    << ", " << smoothing_rounds_done << " smoothing rounds) in " << seconds << " s";
  return s.str();
}

RemoveSelfIntersectionsSummary RemoveSelfIntersections(
    Eigen::MatrixXd* V, Eigen::MatrixXi* F, const RemoveSelfIntersectionsOptions& options) {
  MR_CHECK(V != nullptr && F != nullptr);
  options.Check();
  const double t0 = ElapsedSeconds();
  RemoveSelfIntersectionsSummary summary;
  SelfIntersectionReport report = CountSelfIntersections(*V, *F, true);
  summary.initial_pairs = summary.final_pairs = report.intersecting_pairs;
  if (report.intersecting_pairs == 0) return summary;

  if (options.use_cgal_repair) {
    summary.cgal_repair_used = true;
    Mesh mesh = ToCgal(*V, *F, "RemoveSelfIntersections");
    try {
      summary.cgal_repair_succeeded =
          PMP::experimental::remove_self_intersections(mesh, CGAL::parameters::preserve_genus(true));
      mesh.collect_garbage();
      FromCgal(mesh, V, F);
    } catch (const CGAL::Failure_exception& e) {
      MR_LOG(WARNING) << "RemoveSelfIntersections: CGAL repair failed (" << e.what()
                      << "); continuing with smoothing";
    }
    report = CountSelfIntersections(*V, *F, true);
  }

  // Fallback: umbrella smoothing of the intersecting faces' vertices and
  // their one-ring, re-checked after every round.
  for (int round = 0; round < options.smoothing_rounds && report.intersecting_pairs > 0; ++round) {
    const IndexLists adjacency = VertexAdjacency(*F, V->rows());
    std::vector<int> verts;
    for (const auto& p : report.pairs) {
      for (int f : {p.first, p.second}) {
        for (int k = 0; k < 3; ++k) {
          const int v = (*F)(f, k);
          verts.push_back(v);
          verts.insert(verts.end(), adjacency[v].begin(), adjacency[v].end());
        }
      }
    }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    Eigen::MatrixXd target(verts.size(), 3);
    for (size_t i = 0; i < verts.size(); ++i) {
      Eigen::RowVector3d avg = Eigen::RowVector3d::Zero();
      for (int w : adjacency[verts[i]]) avg += V->row(w);
      const size_t n = adjacency[verts[i]].size();
      target.row(i) = n > 0 ? Eigen::RowVector3d(avg / n) : Eigen::RowVector3d(V->row(verts[i]));
    }
    for (size_t i = 0; i < verts.size(); ++i) {
      V->row(verts[i]) = (1 - options.smoothing_weight) * V->row(verts[i]) +
                         options.smoothing_weight * target.row(i);
    }
    report = CountSelfIntersections(*V, *F, true);
    summary.smoothing_rounds_done = round + 1;
    MR_LOG(VERBOSE) << "RemoveSelfIntersections: smoothing round " << round + 1 << ": "
                    << report.intersecting_pairs << " pairs remain";
  }
  summary.final_pairs = report.intersecting_pairs;
  summary.seconds = ElapsedSeconds() - t0;
  MR_LOG(INFO) << "RemoveSelfIntersections: " << summary.BriefReport();
  if (summary.final_pairs > 0) {
    MR_LOG(WARNING) << "RemoveSelfIntersections: " << summary.final_pairs
                    << " intersecting face pairs remain";
  }
  return summary;
}

std::string UndoSelfIntersectionsSummary::BriefReport() const {
  std::ostringstream s;
  s << "new intersecting pairs " << initial_pairs << " undone by resetting " << reset_vertices
    << " vertices in " << rounds << " rounds (" << initial_flipped
    << " faces folded by the resets, undone too), " << seconds << " s";
  return s.str();
}

namespace {

void CheckUndoInput(const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
                    const std::vector<std::pair<int, int>>& allowed,
                    const Eigen::MatrixXd* V_after) {
  MR_CHECK(V_after != nullptr);
  CheckMeshInput(V_before, F, "UndoSelfIntersections");
  CheckMeshInput(*V_after, F, "UndoSelfIntersections");
  if (V_before.rows() != V_after->rows()) {
    MR_THROW_INPUT << "UndoSelfIntersections: V_before has " << V_before.rows()
                   << " vertices, V_after " << V_after->rows();
  }
  MR_CHECK(std::is_sorted(allowed.begin(), allowed.end()));
}

// The candidate face pairs of every check of UndoSelfIntersections: each
// vertex is at its V_before or its V_after position in every check, so a
// face's box in any check lies within the union of its boxes at V_before and
// at V_after, and only pairs whose unions overlap can intersect. Found once
// per call; the later rounds look up the candidates of the faces they
// changed.
struct PairCandidates {
  std::vector<std::pair<int, int>> pairs;
  std::vector<int> start, of_face;  // the candidates of face f: of_face[start[f] .. start[f + 1])

  PairCandidates(const Eigen::MatrixXd& V_before, const Eigen::MatrixXd& V_after,
                 const Eigen::MatrixXi& F) {
    Boxes boxes = FaceBoxes(V_before, F);
    GrowFaceBoxes(V_after, F, &boxes);
    std::vector<int> all(F.rows());
    for (int f = 0; f < F.rows(); ++f) all[f] = f;
    pairs = OverlappingBoxes(boxes, all);
    start.assign(F.rows() + 1, 0);
    for (const auto& [a, b] : pairs) {
      ++start[a + 1];
      ++start[b + 1];
    }
    for (int f = 0; f < F.rows(); ++f) start[f + 1] += start[f];
    of_face.resize(2 * pairs.size());
    std::vector<int> next(start.begin(), start.end() - 1);
    for (int i = 0; i < static_cast<int>(pairs.size()); ++i) {
      of_face[next[pairs[i].first]++] = i;
      of_face[next[pairs[i].second]++] = i;
    }
  }
};

// The loop of UndoSelfIntersections.
UndoSelfIntersectionsSummary UndoOnMesh(const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
                                        const std::vector<std::pair<int, int>>& allowed,
                                        Eigen::MatrixXd* V_after) {
  const double t0 = ElapsedSeconds();
  UndoSelfIntersectionsSummary summary;
  const PairCandidates candidates(V_before, *V_after, F);
  const int num_faces = static_cast<int>(F.rows());
  Boxes boxes = FaceBoxes(*V_after, F);
  std::vector<char> degenerate = DegenerateFaces(*V_after, F);

  std::vector<char> reset(V_after->rows(), 0);
  // After the first (whole-mesh) check, new pairs can only involve faces
  // with a vertex reset in the last round: their candidates are checked.
  std::vector<int> changed_faces;
  std::vector<std::vector<int>> vertex_faces;
  std::vector<int> to_check;  // indices of the candidates of the changed faces
  for (bool first = true;; first = false) {
    std::vector<std::pair<int, int>> pairs;
    if (first) {
      for (int f = 0; f < num_faces; ++f) {
        if (degenerate[f]) pairs.emplace_back(f, f);
      }
    } else {
      to_check.clear();
      for (const int f : changed_faces) {
        if (degenerate[f]) pairs.emplace_back(f, f);
        to_check.insert(to_check.end(), candidates.of_face.begin() + candidates.start[f],
                        candidates.of_face.begin() + candidates.start[f + 1]);
      }
      std::sort(to_check.begin(), to_check.end());
      to_check.erase(std::unique(to_check.begin(), to_check.end()), to_check.end());
    }
    const std::vector<std::pair<int, int>> found = IntersectingCandidates(
        *V_after, F, boxes, degenerate, candidates.pairs, first ? nullptr : &to_check);
    pairs.insert(pairs.end(), found.begin(), found.end());
    std::sort(pairs.begin(), pairs.end());
    std::vector<int> offending;  // faces of new pairs, then flipped faces
    long new_pairs = 0;
    for (const auto& p : pairs) {
      if (std::binary_search(allowed.begin(), allowed.end(), p)) continue;
      ++new_pairs;
      offending.push_back(p.first);
      offending.push_back(p.second);
    }
    const std::vector<int> flipped = FlippedFaces(V_before, *V_after, F);
    offending.insert(offending.end(), flipped.begin(), flipped.end());
    if (first) summary.initial_pairs = new_pairs;
    summary.initial_flipped += static_cast<int>(flipped.size());
    if (offending.empty()) break;
    ++summary.rounds;
    if (vertex_faces.empty()) {
      vertex_faces.resize(V_after->rows());
      for (int f = 0; f < num_faces; ++f) {
        for (int k = 0; k < 3; ++k) vertex_faces[F(f, k)].push_back(f);
      }
    }
    int newly_reset = 0;
    changed_faces.clear();
    for (int f : offending) {
      for (int k = 0; k < 3; ++k) {
        const int v = F(f, k);
        if (reset[v]) continue;
        reset[v] = 1;
        V_after->row(v) = V_before.row(v);
        ++newly_reset;
        changed_faces.insert(changed_faces.end(), vertex_faces[v].begin(), vertex_faces[v].end());
      }
    }
    std::sort(changed_faces.begin(), changed_faces.end());
    changed_faces.erase(std::unique(changed_faces.begin(), changed_faces.end()),
                        changed_faces.end());
    for (const int f : changed_faces) {
      SetFaceBox(*V_after, F, f, &boxes);
      degenerate[f] = FaceIsDegenerate(*V_after, F, f) ? 1 : 0;
    }
    summary.reset_vertices += newly_reset;
    // Cannot happen when V_before has no pair outside `allowed` (see the
    // header); then the offending pairs were already in V_before.
    if (newly_reset == 0) {
      MR_LOG(WARNING) << "UndoSelfIntersections: " << new_pairs
                      << " intersecting pairs were already in V_before; left as they are";
      break;
    }
  }
  summary.seconds = ElapsedSeconds() - t0;
  MR_LOG(VERBOSE) << "UndoSelfIntersections: " << summary.BriefReport();
  return summary;
}

}  // namespace

UndoSelfIntersectionsSummary UndoSelfIntersections(
    const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
    const std::vector<std::pair<int, int>>& allowed, Eigen::MatrixXd* V_after) {
  CheckUndoInput(V_before, F, allowed, V_after);
  ToCgal(*V_after, F, "UndoSelfIntersections");  // throws unless an oriented 2-manifold
  return UndoOnMesh(V_before, F, allowed, V_after);
}

struct SelfIntersectionGuard::Impl {
  Eigen::MatrixXi F;
  std::vector<std::pair<int, int>> allowed;
};

SelfIntersectionGuard::SelfIntersectionGuard(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : impl_(new Impl) {
  CheckMeshInput(V, F, "SelfIntersectionGuard");
  ToCgal(V, F, "SelfIntersectionGuard");  // throws unless an oriented 2-manifold
  impl_->F = F;
  impl_->allowed = IntersectingFacePairs(V, F);
}

SelfIntersectionGuard::~SelfIntersectionGuard() = default;

const std::vector<std::pair<int, int>>& SelfIntersectionGuard::initial_pairs() const {
  return impl_->allowed;
}

UndoSelfIntersectionsSummary SelfIntersectionGuard::Undo(const Eigen::MatrixXd& V_before,
                                                         Eigen::MatrixXd* V_after) {
  CheckUndoInput(V_before, impl_->F, impl_->allowed, V_after);
  return UndoOnMesh(V_before, impl_->F, impl_->allowed, V_after);
}

}  // namespace mr
