#pragma once

// Triangle-mesh kernels over Eigen matrices, libigl style:
// V is #V by 3 (double), F is #F by 3 (int, counter-clockwise = outward).

#include <Eigen/Core>
#include <vector>

namespace mr {

// #F by 3 unit face normals (zero rows for degenerate faces).
// The centroid of face f.
inline Eigen::Vector3d FaceCentroid(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, int f) {
  return (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))).transpose() / 3.0;
}

Eigen::MatrixXd FaceNormals(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
// #F face areas.
Eigen::VectorXd FaceAreas(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
// #V by 3 area-weighted unit vertex normals.
Eigen::MatrixXd VertexNormals(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
// Mean length over the (unique) edges; 0 for a mesh without faces.
double MeanEdgeLength(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);
// Length of the bounding-box diagonal of V (0 if empty).
double BoundingBoxDiagonal(const Eigen::MatrixXd& V);

// Lists of indices stored back to back (compressed rows): list i is
// values[offsets[i]] .. values[offsets[i + 1] - 1]. One allocation for all of
// them, where a vector per list costs a malloc each (3M of them for the edges
// of a 2M-face mesh).
struct IndexLists {
  class List {
   public:
    List(const int* begin, const int* end) : begin_(begin), end_(end) {}
    const int* begin() const { return begin_; }
    const int* end() const { return end_; }
    size_t size() const { return static_cast<size_t>(end_ - begin_); }
    int operator[](size_t i) const { return begin_[i]; }

   private:
    const int* begin_;
    const int* end_;
  };
  class Iterator {
   public:
    Iterator(const IndexLists* lists, size_t i) : lists_(lists), i_(i) {}
    List operator*() const { return (*lists_)[i_]; }
    Iterator& operator++() {
      ++i_;
      return *this;
    }
    bool operator!=(const Iterator& other) const { return i_ != other.i_; }

   private:
    const IndexLists* lists_;
    size_t i_;
  };

  std::vector<int> offsets{0};  // size() + 1 entries
  std::vector<int> values;

  size_t size() const { return offsets.size() - 1; }
  List operator[](size_t i) const {
    return List(values.data() + offsets[i], values.data() + offsets[i + 1]);
  }
  Iterator begin() const { return Iterator(this, 0); }
  Iterator end() const { return Iterator(this, size()); }
};

// Unique undirected edges and their incident faces.
struct EdgeTopology {
  Eigen::MatrixXi E;  // #E by 2 vertex indices, E(e,0) < E(e,1)
  // For each edge, the incident faces in increasing order (1: boundary, 2:
  // manifold interior, >2: non-manifold).
  IndexLists edge_faces;
  // For each face and corner k, the index of the edge opposite corner k
  // (between F(f,(k+1)%3) and F(f,(k+2)%3)).
  Eigen::MatrixXi face_edges;  // #F by 3

  int NumBoundaryEdges() const;
  int NumNonManifoldEdges() const;
};
EdgeTopology ComputeEdgeTopology(const Eigen::MatrixXi& F, int num_vertices);

// For each vertex, its one-ring neighbour vertices (sorted, unique, never the
// vertex itself).
IndexLists VertexAdjacency(const Eigen::MatrixXi& F, int num_vertices);

// For each vertex, the faces that use it, in increasing order (a face that
// uses a vertex twice is listed twice).
IndexLists VertexFaces(const Eigen::MatrixXi& F, int num_vertices);

// The vertices within `rings` edge rings of an open border, each with its
// one-ring neighbours. Ring 1 are the vertices of the edges that bound a
// single face, ring k + 1 the neighbours of ring k not in an earlier ring;
// edges with three or more faces are not border. A closed mesh, or rings <= 0,
// gives an empty band.
struct VertexBand {
  std::vector<int> vertices;  // in ring order
  IndexLists neighbours;      // neighbours[i] of vertices[i]
  int num_border = 0;         // how many of `vertices` are on the border (ring 1)
};
VertexBand OpenBorderBand(const Eigen::MatrixXi& F, int num_vertices, int rings);

// One step of the membrane (umbrella) flow on the band, all vertices at once:
// each band vertex moves by `step` x (the mean of its neighbours - itself).
// Vertices outside the band do not move. On an open border this shortens the
// border and pulls the band toward the surface inside it. With `weights`
// (one per band vertex), band vertex i moves weights(i) times as far.
void MembraneStep(const VertexBand& band, double step, Eigen::MatrixXd* V,
                  const Eigen::VectorXd* weights = nullptr);

// Removes vertices referenced by no face; `F` is re-indexed in place. Returns
// for each old vertex its new index or -1.
std::vector<int> RemoveUnreferencedVertices(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// Reorders faces and vertices along a space-filling curve (Morton order of
// the face centroids; vertices numbered by first use), so that faces and
// vertices near each other in space are near each other in memory. The
// surface is unchanged: the same triangles, each with its corners in the same
// cyclic order. Returns for each old vertex its new index.
std::vector<int> OrderSpatially(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

}  // namespace mr
