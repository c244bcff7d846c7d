#pragma once

// Iso-surfaces of a scalar field sampled on a regular grid, by marching
// tetrahedra on the Freudenthal (Kuhn) subdivision of every cube into six
// tetrahedra that share the cube's main diagonal. The subdivision is the same
// in every cube, so neighbouring cubes agree on their shared faces and the
// result is the exact level set of a piecewise-linear function: for a field
// that is "outside" on the grid boundary it is closed, two-manifold (every
// edge in exactly two faces) and consistently oriented, without the ambiguous
// cases of marching cubes.

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mr {

// Values at the nodes of a regular grid: node (i, j, k) is at
// origin + spacing * (i, j, k) and stored at i + nx * (j + ny * k).
struct ScalarGrid {
  int nx = 0, ny = 0, nz = 0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double spacing = 1;
  std::vector<float> values;

  ScalarGrid() = default;
  ScalarGrid(int nx, int ny, int nz, const Eigen::Vector3d& origin, double spacing,
             float fill = 0.f);
  size_t Index(int i, int j, int k) const {
    return static_cast<size_t>(i) + static_cast<size_t>(nx) * (j + static_cast<size_t>(ny) * k);
  }
  float& At(int i, int j, int k) { return values[Index(i, j, k)]; }
  float At(int i, int j, int k) const { return values[Index(i, j, k)]; }
  Eigen::Vector3d Position(int i, int j, int k) const {
    return origin + spacing * Eigen::Vector3d(i, j, k);
  }
  size_t NumNodes() const { return values.size(); }
};

// Extracts the surface {value = iso} with "inside" meaning value > iso.
// Nodes on the grid's boundary are treated as outside, so the surface is
// always closed. Faces are counter-clockwise seen from outside (normals point
// toward decreasing values). Vertices lie on the grid edges at the linearly
// interpolated crossing (kept at least 1e-3 of an edge away from the nodes).
void ExtractIsosurface(const ScalarGrid& grid, double iso, Eigen::MatrixXd* V,
                       Eigen::MatrixXi* F);

// Keeps the connected component (through shared vertices) with the most
// faces, and drops unreferenced vertices. Returns the number of components.
int KeepLargestComponent(Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// True if every directed edge (a, b) of F appears exactly once and its
// reverse (b, a) exactly once: closed, edge-manifold and consistently
// oriented. Otherwise false, with the first problem in *why (if non-null).
bool IsClosedAndOriented(const Eigen::MatrixXi& F, std::string* why = nullptr);

// Signed volume enclosed by a closed mesh (positive when oriented outward).
double SignedVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

}  // namespace mr
