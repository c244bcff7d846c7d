#pragma once

// Simple closed meshes for tests and examples.

#include <Eigen/Core>

namespace mr {

// Icosphere of the given radius centred at the origin: 20 * 4^subdivisions
// faces, outward-oriented.
void MakeIcosphere(int subdivisions, double radius, Eigen::MatrixXd* V, Eigen::MatrixXi* F);
// The same, centred at `center`.
void MakeIcosphere(int subdivisions, double radius, const Eigen::Vector3d& center,
                   Eigen::MatrixXd* V, Eigen::MatrixXi* F);

}  // namespace mr
