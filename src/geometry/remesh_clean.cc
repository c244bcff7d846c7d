// The Eigen-only half of remesh.h: input checks, midpoint subdivision,
// CleanMesh and flipped-face detection/repair. (CGAL-based functions are in
// remesh.cc.)

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "geometry/remesh.h"
#include "util/error.h"
#include "util/logging.h"

namespace mr {
namespace {

uint64_t DirectedKey(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}
uint64_t UndirectedKey(int a, int b) { return a < b ? DirectedKey(a, b) : DirectedKey(b, a); }

// Small union-find over local indices.
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void Union(int a, int b) { parent[Find(a)] = Find(b); }
};

// Keeps the rows of F whose flag is true.
void KeepFaces(const std::vector<char>& keep, Eigen::MatrixXi* F) {
  int n = 0;
  for (int f = 0; f < F->rows(); ++f) {
    if (keep[f]) F->row(n++) = F->row(f);
  }
  F->conservativeResize(n, 3);
}

// Removes vertices referenced by no face, keeping the order of the others
// (mr::RemoveUnreferencedVertices renumbers in order of first use).
int RemoveUnreferencedKeepOrder(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  std::vector<int> map(V->rows(), 0);
  for (int f = 0; f < F->rows(); ++f)
    for (int k = 0; k < 3; ++k) map[(*F)(f, k)] = 1;
  int next = 0;
  for (int v = 0; v < V->rows(); ++v) {
    if (map[v]) {
      if (next != v) V->row(next) = V->row(v);
      map[v] = next++;
    } else {
      map[v] = -1;
    }
  }
  const int removed = static_cast<int>(V->rows()) - next;
  if (removed == 0) return 0;
  V->conservativeResize(next, 3);
  for (int f = 0; f < F->rows(); ++f)
    for (int k = 0; k < 3; ++k) (*F)(f, k) = map[(*F)(f, k)];
  return removed;
}

// 2*area <= tol * (longest edge)^2 (also true for coincident vertices).
bool IsDegenerate(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f, double tol,
                  int* longest_corner) {
  const Eigen::Vector3d p[3] = {V.row(F(f, 0)), V.row(F(f, 1)), V.row(F(f, 2))};
  double longest = -1;
  for (int k = 0; k < 3; ++k) {
    const double l2 = (p[(k + 2) % 3] - p[(k + 1) % 3]).squaredNorm();
    if (l2 > longest) {
      longest = l2;
      *longest_corner = k;  // the edge opposite corner k is the longest
    }
  }
  const double area2 = (p[1] - p[0]).cross(p[2] - p[0]).norm();
  return area2 <= tol * longest;
}

// Counts vertices whose incident faces form more than one fan (faces
// connected through edges with exactly two faces). With `fix`, each extra fan
// gets its own copy of the vertex (appended to V). Returns the number of such
// vertices; *num_copies receives the number of copies added.
// `topo` is the edge topology of (V, F).
int ProcessVertexFans(const EdgeTopology& topo, Eigen::MatrixXd* V, Eigen::MatrixXi* F, bool fix,
                      int* num_copies) {
  *num_copies = 0;
  const int nv = V->rows();
  const IndexLists vertex_faces = VertexFaces(*F, nv);

  int bad = 0;
  std::vector<Eigen::RowVector3d> new_positions;
  for (int v = 0; v < nv; ++v) {
    const int n = static_cast<int>(vertex_faces[v].size());
    if (n <= 1) continue;
    const int* faces = vertex_faces[v].begin();
    UnionFind uf(n);
    for (int i = 0; i < n; ++i) {
      const int f = faces[i];
      for (int k = 0; k < 3; ++k) {
        if ((*F)(f, k) == v) continue;  // edge opposite k does not contain v
        const IndexLists::List ef = topo.edge_faces[topo.face_edges(f, k)];
        if (ef.size() != 2) continue;  // boundary or non-manifold: a cut
        const int g = ef[0] == f ? ef[1] : ef[0];
        const int j = static_cast<int>(std::find(faces, faces + n, g) - faces);
        if (j < n) uf.Union(i, j);
      }
    }
    bool single = true;
    for (int i = 1; i < n && single; ++i) single = uf.Find(i) == uf.Find(0);
    if (single) continue;
    ++bad;
    if (!fix) continue;
    std::vector<int> group_vertex(n, -1);  // root (local index) -> vertex index
    bool first = true;
    for (int i = 0; i < n; ++i) {
      int& target = group_vertex[uf.Find(i)];
      if (target < 0) {
        if (first) {
          target = v;
          first = false;
        } else {
          target = nv + static_cast<int>(new_positions.size());
          new_positions.push_back(V->row(v));
        }
      }
      const int f = faces[i];
      for (int k = 0; k < 3; ++k)
        if ((*F)(f, k) == v) (*F)(f, k) = target;
    }
  }
  if (fix && !new_positions.empty()) {
    V->conservativeResize(nv + new_positions.size(), 3);
    for (size_t i = 0; i < new_positions.size(); ++i) V->row(nv + i) = new_positions[i];
    *num_copies = static_cast<int>(new_positions.size());
  }
  return bad;
}

// +1 if face f traverses edge (u, w) as u->w, -1 if as w->u.
int EdgeDirection(const Eigen::MatrixXi& F, int f, int u, int w) {
  for (int k = 0; k < 3; ++k) {
    if (F(f, k) == u) return F(f, (k + 1) % 3) == w ? 1 : -1;
  }
  return 0;
}

int CountInconsistentEdges(const Eigen::MatrixXi& F, const EdgeTopology& topo) {
  int n = 0;
  for (int e = 0; e < topo.E.rows(); ++e) {
    const IndexLists::List ef = topo.edge_faces[e];
    if (ef.size() != 2) continue;
    if (EdgeDirection(F, ef[0], topo.E(e, 0), topo.E(e, 1)) ==
        EdgeDirection(F, ef[1], topo.E(e, 0), topo.E(e, 1)))
      ++n;
  }
  return n;
}

}  // namespace

int SplitPinchedVertices(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MR_CHECK(V != nullptr && F != nullptr);
  int copies = 0;
  ProcessVertexFans(ComputeEdgeTopology(*F, V->rows()), V, F, true, &copies);
  return copies;
}

void CheckMeshInput(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::string& what) {
  if (V.rows() > 0 && V.cols() != 3) {
    MR_THROW_INPUT << what << ": V has " << V.cols() << " columns (expected 3)";
  }
  if (F.rows() > 0 && F.cols() != 3) {
    MR_THROW_INPUT << what << ": F has " << F.cols() << " columns (expected 3, triangles)";
  }
  if (V.rows() > 0 && !V.allFinite()) {
    for (int v = 0; v < V.rows(); ++v) {
      if (!V.row(v).allFinite()) {
        MR_THROW_INPUT << what << ": vertex " << v << " has a non-finite position ("
                       << V(v, 0) << ", " << V(v, 1) << ", " << V(v, 2) << ")";
      }
    }
  }
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (F(f, k) < 0 || F(f, k) >= V.rows()) {
        MR_THROW_INPUT << what << ": face " << f << " references vertex " << F(f, k)
                       << " (expected 0 <= index < " << V.rows() << ")";
      }
    }
  }
}

// ---------------------------------------------------------------------------

std::string SubdivisionSummary::BriefReport() const {
  std::ostringstream s;
  s << "faces " << initial_faces << " -> " << final_faces << ", vertices " << initial_vertices
    << " -> " << final_vertices << " in " << seconds << " s";
  return s.str();
}

namespace {

// 1-to-4 split of every face, a new vertex per unique edge of `topo` placed
// by `edge_point(e)` and appended after the old vertices (vertex nv + e on
// edge e); orientation kept. Shared by the two 1-to-4 schemes below.
template <typename EdgePoint>
SubdivisionSummary SplitEveryEdge(const char* what, const EdgeTopology& topo,
                                  EdgePoint edge_point, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const double t0 = ElapsedSeconds();
  SubdivisionSummary summary;
  summary.initial_vertices = V->rows();
  summary.initial_faces = F->rows();
  const int nv = V->rows();
  const int ne = topo.E.rows();
  Eigen::MatrixXd points(ne, 3);
  for (int e = 0; e < ne; ++e) points.row(e) = edge_point(e);
  V->conservativeResize(nv + ne, 3);
  V->bottomRows(ne) = points;
  Eigen::MatrixXi F4(4 * F->rows(), 3);
  for (int f = 0; f < F->rows(); ++f) {
    const int a = (*F)(f, 0), b = (*F)(f, 1), c = (*F)(f, 2);
    // m_k: the new vertex on the edge opposite corner k.
    const int m0 = nv + topo.face_edges(f, 0), m1 = nv + topo.face_edges(f, 1),
              m2 = nv + topo.face_edges(f, 2);
    F4.row(4 * f + 0) << a, m2, m1;
    F4.row(4 * f + 1) << b, m0, m2;
    F4.row(4 * f + 2) << c, m1, m0;
    F4.row(4 * f + 3) << m0, m1, m2;
  }
  *F = std::move(F4);
  if (V->rows() == 0) V->resize(0, 3);
  summary.final_vertices = V->rows();
  summary.final_faces = F->rows();
  summary.seconds = ElapsedSeconds() - t0;
  MR_LOG(INFO) << what << ": " << summary.BriefReport();
  return summary;
}

}  // namespace

SubdivisionSummary SubdivideMidpoint(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MR_CHECK(V != nullptr && F != nullptr);
  CheckMeshInput(*V, *F, "SubdivideMidpoint");
  const EdgeTopology topo = ComputeEdgeTopology(*F, V->rows());
  const Eigen::MatrixXd& X = *V;
  return SplitEveryEdge(
      "SubdivideMidpoint", topo,
      [&](int e) -> Eigen::RowVector3d {
        return 0.5 * (X.row(topo.E(e, 0)) + X.row(topo.E(e, 1)));
      },
      V, F);
}

SubdivisionSummary SubdividePointNormal(Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                                        double normal_sigma, Eigen::MatrixXi* parent_edges) {
  MR_CHECK(V != nullptr && F != nullptr);
  CheckMeshInput(*V, *F, "SubdividePointNormal");
  const int nv = V->rows();
  const EdgeTopology topo = ComputeEdgeTopology(*F, nv);
  const IndexLists vertex_faces = VertexFaces(*F, nv);
  const Eigen::MatrixXd N = FaceNormals(*V, *F);
  const Eigen::VectorXd A = FaceAreas(*V, *F);
  const double inv_2s2 = normal_sigma > 0 ? 1.0 / (2 * normal_sigma * normal_sigma) : 0.0;
  // The normal at vertex v seen from an edge whose faces have the mean
  // normal n_edge: v's faces by area, those turned away from n_edge (across
  // a crease) weighted down.
  auto normal_at = [&](int v, const Eigen::RowVector3d& n_edge) -> Eigen::RowVector3d {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    for (const int f : vertex_faces[v]) {
      sum += A(f) * std::exp(-(N.row(f) - n_edge).squaredNorm() * inv_2s2) * N.row(f);
    }
    const double len = sum.norm();
    return len > 0 ? Eigen::RowVector3d(sum / len) : Eigen::RowVector3d::Zero();
  };
  const Eigen::MatrixXd& X = *V;
  if (parent_edges != nullptr) *parent_edges = topo.E;
  return SplitEveryEdge(
      "SubdividePointNormal", topo,
      [&](int e) -> Eigen::RowVector3d {
        const int a = topo.E(e, 0), b = topo.E(e, 1);
        Eigen::RowVector3d n_edge = Eigen::RowVector3d::Zero();
        for (const int f : topo.edge_faces[e]) n_edge += N.row(f);
        if (n_edge.norm() > 0) n_edge.normalize();
        const Eigen::RowVector3d na = normal_at(a, n_edge), nb = normal_at(b, n_edge);
        const Eigen::RowVector3d ab = X.row(b) - X.row(a);
        // The cubic edge curve of Vlachos et al.'s PN triangle at t = 1/2.
        return 0.5 * (X.row(a) + X.row(b)) - (ab.dot(na) * na - ab.dot(nb) * nb) / 8.0;
      },
      V, F);
}

// ---------------------------------------------------------------------------

bool CleanMeshOptions::Check() const {
  if (!(degenerate_area_tolerance >= 0 && degenerate_area_tolerance <= 1e-3)) {
    MR_THROW_INPUT << "CleanMeshOptions::degenerate_area_tolerance = " << degenerate_area_tolerance
                   << ". Violated constraint: 0 <= degenerate_area_tolerance <= 1e-3";
  }
  return true;
}

bool CleanMeshReport::IsCleanManifold() const {
  return remaining_non_manifold_edges == 0 && remaining_non_manifold_vertices == 0 &&
         inconsistent_edges == 0;
}

std::string CleanMeshReport::BriefReport() const {
  std::ostringstream s;
  s << "V " << initial_vertices << " -> " << final_vertices << ", F " << initial_faces << " -> "
    << final_faces << "; merged " << merged_duplicate_vertices << " duplicate vertices; removed "
    << removed_repeated_index_faces << " repeated-index, " << removed_duplicate_faces
    << " duplicate, " << removed_degenerate_faces << " zero-area faces (" << flipped_degenerate_faces
    << " more fixed by flips), " << removed_unreferenced_vertices
    << " unreferenced vertices; non-manifold: " << non_manifold_edges << " edges, "
    << non_manifold_vertices << " vertices (" << split_vertices << " copies added, "
    << remaining_non_manifold_edges << " edges / " << remaining_non_manifold_vertices
    << " vertices remain); reoriented " << reoriented_faces << " faces, "
    << non_orientable_components << " non-orientable of " << connected_components
    << " components, " << inconsistent_edges << " inconsistent edges; " << boundary_edges
    << " boundary edges; " << seconds << " s";
  return s.str();
}

CleanMeshReport CleanMesh(Eigen::MatrixXd* V, Eigen::MatrixXi* F, const CleanMeshOptions& options) {
  MR_CHECK(V != nullptr && F != nullptr);
  options.Check();
  CheckMeshInput(*V, *F, "CleanMesh");
  const double t0 = ElapsedSeconds();
  if (V->rows() == 0) V->resize(0, 3);
  if (F->rows() == 0) F->resize(0, 3);
  CleanMeshReport r;
  r.initial_vertices = V->rows();
  r.initial_faces = F->rows();

  // 1. Merge exactly duplicated vertices (lexicographic sort).
  {
    std::vector<int> order(V->rows());
    std::iota(order.begin(), order.end(), 0);
    const Eigen::MatrixXd& P = *V;
    auto less = [&P](int a, int b) {
      for (int c = 0; c < 3; ++c) {
        if (P(a, c) != P(b, c)) return P(a, c) < P(b, c);
      }
      return a < b;
    };
    std::sort(order.begin(), order.end(), less);
    std::vector<int> rep(V->rows());
    for (size_t i = 0; i < order.size(); ++i) {
      if (i > 0 && P.row(order[i]) == P.row(order[i - 1])) {
        rep[order[i]] = rep[order[i - 1]];
        ++r.merged_duplicate_vertices;
      } else {
        rep[order[i]] = order[i];
      }
    }
    for (int f = 0; f < F->rows(); ++f)
      for (int k = 0; k < 3; ++k) (*F)(f, k) = rep[(*F)(f, k)];
  }

  // 2. Faces using a vertex twice.
  {
    std::vector<char> keep(F->rows(), 1);
    for (int f = 0; f < F->rows(); ++f) {
      const int a = (*F)(f, 0), b = (*F)(f, 1), c = (*F)(f, 2);
      if (a == b || b == c || c == a) {
        keep[f] = 0;
        ++r.removed_repeated_index_faces;
      }
    }
    KeepFaces(keep, F);
  }

  // 3. Duplicate faces (same vertex set, any order or orientation): keep the first.
  {
    std::vector<std::array<int, 4>> keys(F->rows());
    for (int f = 0; f < F->rows(); ++f) {
      std::array<int, 4> k = {(*F)(f, 0), (*F)(f, 1), (*F)(f, 2), f};
      std::sort(k.begin(), k.begin() + 3);
      keys[f] = k;
    }
    std::sort(keys.begin(), keys.end());
    std::vector<char> keep(F->rows(), 1);
    for (size_t i = 1; i < keys.size(); ++i) {
      if (keys[i][0] == keys[i - 1][0] && keys[i][1] == keys[i - 1][1] &&
          keys[i][2] == keys[i - 1][2]) {
        keep[keys[i][3]] = 0;
        ++r.removed_duplicate_faces;
      }
    }
    KeepFaces(keep, F);
  }

  // 4. Zero-area faces. A cap (b lies on the longest edge a-c) is removed by
  // flipping a-c into the neighbour (c, a, d): faces (b,a,c), (c,a,d) become
  // (b,a,d), (b,d,c), which keeps closed meshes closed and orientation
  // consistent. What cannot be flipped (no unique neighbour, the new edge b-d
  // exists already, neighbour degenerate too) is deleted after three passes.
  {
    const double tol = options.degenerate_area_tolerance;
    // Most meshes have none (a Poisson mesh has none): then the hash maps
    // below, 3 entries per face and a large part of a big input's clean-up,
    // are not built at all.
    bool any_degenerate = false;
    for (int f = 0; f < F->rows() && !any_degenerate; ++f) {
      int k = 0;
      any_degenerate = IsDegenerate(*V, *F, f, tol, &k);
    }
    for (int pass = 0; pass < 3 && any_degenerate; ++pass) {
      std::unordered_map<uint64_t, int> directed;  // directed edge -> face (-1: several)
      std::unordered_set<uint64_t> undirected;
      directed.reserve(3 * F->rows());
      undirected.reserve(3 * F->rows());
      for (int f = 0; f < F->rows(); ++f) {
        for (int k = 0; k < 3; ++k) {
          const int a = (*F)(f, k), b = (*F)(f, (k + 1) % 3);
          auto ins = directed.emplace(DirectedKey(a, b), f);
          if (!ins.second) ins.first->second = -1;
          undirected.insert(UndirectedKey(a, b));
        }
      }
      std::vector<char> touched(F->rows(), 0);
      int flips = 0, degenerate = 0;
      for (int f = 0; f < F->rows(); ++f) {
        int k = 0;
        if (touched[f] || !IsDegenerate(*V, *F, f, tol, &k)) continue;
        ++degenerate;
        const int b = (*F)(f, k), a = (*F)(f, (k + 1) % 3), c = (*F)(f, (k + 2) % 3);
        const auto it = directed.find(DirectedKey(c, a));
        if (it == directed.end() || it->second < 0) continue;
        const int g = it->second;
        int kg = 0;
        if (g == f || touched[g] || IsDegenerate(*V, *F, g, tol, &kg)) continue;
        int d = -1;
        for (int j = 0; j < 3; ++j) {
          const int x = (*F)(g, j);
          if (x != a && x != c) d = x;
        }
        if (d < 0 || d == b || undirected.count(UndirectedKey(b, d))) continue;
        F->row(f) << b, a, d;
        F->row(g) << b, d, c;
        touched[f] = touched[g] = 1;
        undirected.insert(UndirectedKey(b, d));
        ++flips;
      }
      r.flipped_degenerate_faces += flips;
      if (degenerate == 0 || flips == 0) break;
    }
    std::vector<char> keep(F->rows(), 1);
    for (int f = 0; f < F->rows(); ++f) {
      int k = 0;
      if (IsDegenerate(*V, *F, f, tol, &k)) {
        keep[f] = 0;
        ++r.removed_degenerate_faces;
      }
    }
    KeepFaces(keep, F);
  }

  // 5. Unreferenced vertices (the order of the others is kept).
  r.removed_unreferenced_vertices = RemoveUnreferencedKeepOrder(V, F);
  if (V->rows() == 0) V->resize(0, 3);

  MR_LOG(VERBOSE) << "CleanMesh: merge/degenerate/duplicate/unreferenced done, "
                  << ElapsedSeconds() - t0 << " s";

  // 6. Non-manifold edges and vertices.
  EdgeTopology topo = ComputeEdgeTopology(*F, V->rows());
  r.non_manifold_edges = topo.NumNonManifoldEdges();
  r.non_manifold_vertices =
      ProcessVertexFans(topo, V, F, options.fix_non_manifold, &r.split_vertices);
  // Splitting can make a former non-manifold edge manifold and so change the
  // fans of its end points: repeat until stable (a few passes at most).
  for (int pass = 0; pass < 10 && r.split_vertices > 0; ++pass) {
    topo = ComputeEdgeTopology(*F, V->rows());
    int copies = 0;
    const int more = ProcessVertexFans(topo, V, F, true, &copies);
    MR_LOG(VERBOSE) << "CleanMesh: non-manifold pass " << pass + 2 << ": " << more
                    << " vertices";
    if (more == 0) break;
    r.split_vertices += copies;
  }
  MR_LOG(VERBOSE) << "CleanMesh: non-manifold check done, " << ElapsedSeconds() - t0 << " s";

  // 7. Orientation, per component over manifold edges, majority kept.
  {
    const int nf = F->rows();
    std::vector<int> component(nf, -1);
    std::vector<char> flip(nf, 0);
    std::vector<int> stack, members;
    for (int seed = 0; seed < nf; ++seed) {
      if (component[seed] >= 0) continue;
      const int id = r.connected_components++;
      bool orientable = true;
      members.clear();
      stack.assign(1, seed);
      component[seed] = id;
      while (!stack.empty()) {
        const int f = stack.back();
        stack.pop_back();
        members.push_back(f);
        for (int k = 0; k < 3; ++k) {
          const int e = topo.face_edges(f, k);
          const IndexLists::List ef = topo.edge_faces[e];
          if (ef.size() != 2) continue;
          const int g = ef[0] == f ? ef[1] : ef[0];
          const int u = topo.E(e, 0), w = topo.E(e, 1);
          const char want =
              flip[f] ^ (EdgeDirection(*F, f, u, w) == EdgeDirection(*F, g, u, w) ? 1 : 0);
          if (component[g] < 0) {
            component[g] = id;
            flip[g] = want;
            stack.push_back(g);
          } else if (flip[g] != want) {
            orientable = false;
          }
        }
      }
      if (!options.orient || !orientable) {
        if (!orientable) ++r.non_orientable_components;
        for (int f : members) flip[f] = 0;
        continue;
      }
      const size_t flipped = std::count_if(members.begin(), members.end(),
                                           [&flip](int f) { return flip[f] != 0; });
      if (2 * flipped > members.size()) {
        for (int f : members) flip[f] ^= 1;
      }
    }
    for (int f = 0; f < nf; ++f) {
      if (flip[f]) {
        std::swap((*F)(f, 1), (*F)(f, 2));
        std::swap(topo.face_edges(f, 1), topo.face_edges(f, 2));  // keep topo valid
        ++r.reoriented_faces;
      }
    }
  }

  MR_LOG(VERBOSE) << "CleanMesh: orientation done, " << ElapsedSeconds() - t0 << " s";

  // 8. Final state.
  r.remaining_non_manifold_edges = topo.NumNonManifoldEdges();
  int unused = 0;
  r.remaining_non_manifold_vertices = ProcessVertexFans(topo, V, F, false, &unused);
  r.inconsistent_edges = CountInconsistentEdges(*F, topo);
  r.boundary_edges = topo.NumBoundaryEdges();
  r.final_vertices = V->rows();
  r.final_faces = F->rows();
  r.seconds = ElapsedSeconds() - t0;
  MR_LOG(INFO) << "CleanMesh: " << r.BriefReport();
  if (!r.IsCleanManifold()) {
    MR_LOG(WARNING) << "CleanMesh: the result is not an oriented 2-manifold ("
                    << r.remaining_non_manifold_edges << " non-manifold edges, "
                    << r.remaining_non_manifold_vertices << " non-manifold vertices, "
                    << r.inconsistent_edges << " inconsistent edges)";
  }
  return r;
}

// ---------------------------------------------------------------------------

std::vector<int> FlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXd& V_after,
                              const Eigen::MatrixXi& F, double max_angle_deg) {
  CheckMeshInput(V_before, F, "FlippedFaces (V_before)");
  CheckMeshInput(V_after, F, "FlippedFaces (V_after)");
  if (V_before.rows() != V_after.rows()) {
    MR_THROW_INPUT << "FlippedFaces: V_before has " << V_before.rows() << " vertices, V_after "
                   << V_after.rows() << " (expected equal)";
  }
  if (!(max_angle_deg > 0 && max_angle_deg <= 180)) {
    MR_THROW_INPUT << "FlippedFaces: max_angle_deg = " << max_angle_deg
                   << ". Violated constraint: 0 < max_angle_deg <= 180";
  }
  const double cos_max = std::cos(max_angle_deg * M_PI / 180.0);
  std::vector<int> flipped;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a0 = V_before.row(F(f, 0)), b0 = V_before.row(F(f, 1)),
                          c0 = V_before.row(F(f, 2));
    const Eigen::Vector3d a1 = V_after.row(F(f, 0)), b1 = V_after.row(F(f, 1)),
                          c1 = V_after.row(F(f, 2));
    const Eigen::Vector3d n0 = (b0 - a0).cross(c0 - a0), n1 = (b1 - a1).cross(c1 - a1);
    const double l0 = n0.norm(), l1 = n1.norm();
    if (l0 == 0 || l1 == 0) continue;
    if (n0.dot(n1) < cos_max * l0 * l1) flipped.push_back(f);
  }
  return flipped;
}

int CountFlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXd& V_after,
                      const Eigen::MatrixXi& F, double max_angle_deg) {
  return static_cast<int>(FlippedFaces(V_before, V_after, F, max_angle_deg).size());
}

bool FixFlippedFacesOptions::Check() const {
  if (!(max_angle_deg > 0 && max_angle_deg <= 180)) {
    MR_THROW_INPUT << "FixFlippedFacesOptions::max_angle_deg = " << max_angle_deg
                   << ". Violated constraint: 0 < max_angle_deg <= 180";
  }
  if (smoothing_rounds < 0 || smoothing_rounds > 1000) {
    MR_THROW_INPUT << "FixFlippedFacesOptions::smoothing_rounds = " << smoothing_rounds
                   << ". Violated constraint: 0 <= smoothing_rounds <= 1000";
  }
  if (!(smoothing_weight > 0 && smoothing_weight <= 1)) {
    MR_THROW_INPUT << "FixFlippedFacesOptions::smoothing_weight = " << smoothing_weight
                   << ". Violated constraint: 0 < smoothing_weight <= 1";
  }
  return true;
}

std::string FixFlippedFacesSummary::BriefReport() const {
  std::ostringstream s;
  s << "flipped faces " << initial_flipped << " -> " << final_flipped << " ("
    << smoothing_rounds_done << " smoothing rounds, " << reset_vertices
    << " vertices reset to their previous position)";
  return s.str();
}

FixFlippedFacesSummary FixFlippedFaces(const Eigen::MatrixXd& V_before, const Eigen::MatrixXi& F,
                                       Eigen::MatrixXd* V_after,
                                       const FixFlippedFacesOptions& options) {
  MR_CHECK(V_after != nullptr);
  options.Check();
  FixFlippedFacesSummary summary;
  std::vector<int> flipped = FlippedFaces(V_before, *V_after, F, options.max_angle_deg);
  summary.initial_flipped = static_cast<int>(flipped.size());
  if (!flipped.empty()) {
    const IndexLists adjacency = VertexAdjacency(F, V_after->rows());
    // Phase 1: umbrella smoothing of the vertices of flipped faces.
    for (int round = 0; round < options.smoothing_rounds && !flipped.empty(); ++round) {
      std::vector<int> verts;
      for (int f : flipped)
        for (int k = 0; k < 3; ++k) verts.push_back(F(f, k));
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      Eigen::MatrixXd target(verts.size(), 3);
      for (size_t i = 0; i < verts.size(); ++i) {
        Eigen::RowVector3d avg = Eigen::RowVector3d::Zero();
        for (int w : adjacency[verts[i]]) avg += V_after->row(w);
        const size_t n = adjacency[verts[i]].size();
        target.row(i) = n > 0 ? Eigen::RowVector3d(avg / n) : Eigen::RowVector3d(V_after->row(verts[i]));
      }
      for (size_t i = 0; i < verts.size(); ++i) {
        V_after->row(verts[i]) = (1 - options.smoothing_weight) * V_after->row(verts[i]) +
                                 options.smoothing_weight * target.row(i);
      }
      flipped = FlippedFaces(V_before, *V_after, F, options.max_angle_deg);
      summary.smoothing_rounds_done = round + 1;
      MR_LOG(VERBOSE) << "FixFlippedFaces: smoothing round " << round + 1 << ": "
                      << flipped.size() << " flipped faces";
    }
    // Phase 2: reset the vertices of the remaining flipped faces. Each round
    // resets at least one vertex that differed from V_before (a face whose
    // three vertices equal V_before is never flipped), so it terminates.
    std::vector<char> reset(V_after->rows(), 0);  // counted once each
    while (!flipped.empty()) {
      for (int f : flipped) {
        for (int k = 0; k < 3; ++k) {
          const int v = F(f, k);
          if (V_after->row(v) != V_before.row(v)) {
            V_after->row(v) = V_before.row(v);
            if (!reset[v]) {
              reset[v] = 1;
              ++summary.reset_vertices;
            }
          }
        }
      }
      flipped = FlippedFaces(V_before, *V_after, F, options.max_angle_deg);
    }
  }
  summary.final_flipped = static_cast<int>(flipped.size());
  if (summary.initial_flipped > 0) {
    MR_LOG(INFO) << "FixFlippedFaces: " << summary.BriefReport();
  }
  return summary;
}

}  // namespace mr
