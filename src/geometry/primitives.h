#pragma once

// Simple meshes for tests and examples.

#include <Eigen/Core>

namespace mr {

// Icosphere of the given radius centred at the origin: 20 * 4^subdivisions
// faces, outward-oriented.
void MakeIcosphere(int subdivisions, double radius, Eigen::MatrixXd* V, Eigen::MatrixXi* F);
// The same, centred at `center`.
void MakeIcosphere(int subdivisions, double radius, const Eigen::Vector3d& center,
                   Eigen::MatrixXd* V, Eigen::MatrixXi* F);

// Appends to (V, F) a flat grid of cells x cells squares (two triangles
// each) spanning origin + s u + t v for s, t in [0, 1], wound
// counter-clockwise seen from the side u x v points to.
void AppendGrid(const Eigen::Vector3d& origin, const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                int cells, Eigen::MatrixXd* V, Eigen::MatrixXi* F);

}  // namespace mr
