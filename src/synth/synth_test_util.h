#pragma once

// Helpers shared by the synthesizer's tests: a small scene and brute-force
// point-to-mesh distances.

#include <algorithm>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "synth/scene.h"
#include "synth/shape.h"

namespace mr {
namespace testing_util {

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
inline Eigen::Vector3d ClosestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                              const Eigen::Vector3d& b,
                                              const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Unsigned distance from p to the mesh (brute force).
inline double PointMeshDistance(const Eigen::Vector3d& p, const Eigen::MatrixXd& V,
                                const Eigen::MatrixXi& F) {
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    // Cheap reject by bounding sphere of the triangle.
    const Eigen::Vector3d centre = (a + b + c) / 3;
    const double r = std::max({(a - centre).norm(), (b - centre).norm(), (c - centre).norm()});
    if ((p - centre).norm() - r >= best) continue;
    best = std::min(best, (p - ClosestPointOnTriangle(p, a, b, c)).norm());
  }
  return best;
}

// The coarse built-in shape, normalised to diagonal 100, as a scene.
inline SynthScene CoarseScene(double edge_length = 2.0) {
  BuiltinShapeOptions shape;
  shape.edge_length = edge_length;
  TriangleMesh mesh = MakeBuiltinShape(shape);
  NormalizeMesh(100, &mesh.V);
  SynthScene scene;
  scene.V = mesh.V;
  scene.F = mesh.F;
  scene.face_normals = FaceNormals(mesh.V, mesh.F);
  return scene;
}

}  // namespace testing_util
}  // namespace mr
