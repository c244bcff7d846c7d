#pragma once

// Small synthetic meshes and the noise model of the denoising protocol, for
// tests and benchmark/denoise.

#include <cstdint>

#include <Eigen/Core>

namespace mr {

// Closed cube [-1, 1]^3, each face an n by n grid of quads split into two
// triangles (12 n^2 faces), outward-oriented.
void SubdividedCube(int n, Eigen::MatrixXd* V, Eigen::MatrixXi* F);
// Regular octahedron (vertices at unit distance) with `levels` rounds of flat
// 1-to-4 midpoint subdivision (8 * 4^levels faces).
void SubdividedOctahedron(int levels, Eigen::MatrixXd* V, Eigen::MatrixXi* F);
// Flat 1-to-4 midpoint subdivision (shared edge midpoints).
void MidpointSubdivide(Eigen::MatrixXd* V, Eigen::MatrixXi* F);
// Adds Gaussian noise of standard deviation `sigma` along the area-weighted
// vertex normals (deterministic for a given seed).
Eigen::MatrixXd AddNormalNoise(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, double sigma,
                               uint64_t seed);

}  // namespace mr
