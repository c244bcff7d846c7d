#pragma once

// Helpers shared by the GPU renderer and the CPU reference. Internal to mr_render.

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geometry/view.h"
#include "render/renderer.h"

namespace mr {
namespace internal {

// Near plane (camera-frame z) used by both renderers: 0.9 times the smallest
// camera z of the mesh's bounding-box corners when that is positive (nothing is
// clipped), otherwise 1e-5 times max(largest corner z, bounding-box diagonal).
// Returns <= 0 when the whole mesh is behind the camera (nothing to render).
double NearPlane(const Eigen::MatrixXd& V, const PinholeView& view, double* far_plane);

// Throws InputError for bad views (size < 1, non-finite or zero focal lengths),
// vertices that are not finite, or face indices out of range.
void CheckViewAndMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const PinholeView& view);

// Buffers of the right size filled with the background (-1, 0, 0).
RenderBuffers EmptyBuffers(int width, int height);

// Intersection of the ray from the camera centre with direction
// d = ((x - cx) / fx, (y - cy) / fy, 1) and the triangle (P0, P1, P2), all in
// the camera frame (Möller-Trumbore, double precision). Sets the ray parameter
// t (= camera-frame z, since d.z = 1) and the barycentrics (u, v) of P1, P2.
// Returns false for a triangle parallel to the ray (det == 0 or not finite);
// u, v may then be anything.
inline bool IntersectRay(const Eigen::Vector3d& d, const Eigen::Vector3d& P0,
                         const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, double* t,
                         double* u, double* v) {
  const Eigen::Vector3d e1 = P1 - P0;
  const Eigen::Vector3d e2 = P2 - P0;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (!(det != 0.0) || !std::isfinite(det)) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = -P0;
  const Eigen::Vector3d q = s.cross(e1);
  *u = s.dot(p) * inv;
  *v = d.dot(q) * inv;
  *t = e2.dot(q) * inv;
  return std::isfinite(*u) && std::isfinite(*v) && std::isfinite(*t);
}

// Tolerance of the inside test in barycentric units (closes the gaps that
// rounding would open along shared edges).
constexpr double kInsideTolerance = 1e-12;

}  // namespace internal
}  // namespace mr
