#pragma once

// A geodesic sphere (subdivided icosahedron) for tests and benchmarks:
// 20 * 4^subdivisions faces, outward counter-clockwise orientation.

#include <Eigen/Core>

namespace mr {

void MakeIcosphere(int subdivisions, double radius, const Eigen::Vector3d& center,
                   Eigen::MatrixXd* V, Eigen::MatrixXi* F);

}  // namespace mr
