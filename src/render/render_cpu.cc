// CPU reference renderer and helpers shared with the GPU renderer.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/render_internal.h"
#include "render/renderer.h"
#include "util/error.h"

namespace mr {
namespace internal {

double NearPlane(const Eigen::MatrixXd& V, const PinholeView& view, double* far_plane) {
  if (V.rows() == 0) {
    if (far_plane != nullptr) *far_plane = 0;
    return 0;
  }
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose();
  const Eigen::Vector3d hi = V.colwise().maxCoeff().transpose();
  double zmin = std::numeric_limits<double>::infinity();
  double zmax = -zmin;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d X((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(),
                            (corner & 4) ? hi.z() : lo.z());
    const double z = view.WorldToCamera(X).z();
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
  }
  if (far_plane != nullptr) *far_plane = 1.1 * zmax;
  if (!(zmax > 0)) return 0;
  if (zmin > 0) return 0.9 * zmin;
  const double diag = (hi - lo).norm();
  return 1e-5 * std::max(zmax, diag);
}

void CheckViewAndMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                      const PinholeView& view) {
  if (view.width < 1 || view.height < 1) {
    MR_THROW_INPUT << "PinholeView size = " << view.width << "x" << view.height
                   << ". Violated constraint: width >= 1 and height >= 1";
  }
  if (!std::isfinite(view.fx) || !std::isfinite(view.fy) || view.fx == 0 || view.fy == 0 ||
      !std::isfinite(view.cx) || !std::isfinite(view.cy) || !view.R.allFinite() ||
      !view.t.allFinite()) {
    MR_THROW_INPUT << "PinholeView has non-finite or zero intrinsics/extrinsics (fx = " << view.fx
                   << ", fy = " << view.fy << ", cx = " << view.cx << ", cy = " << view.cy << ")";
  }
  if (V.rows() > 0 && V.cols() != 3) {
    MR_THROW_INPUT << "mesh vertices have " << V.cols() << " columns, expected 3";
  }
  if (F.rows() > 0 && F.cols() != 3) {
    MR_THROW_INPUT << "mesh faces have " << F.cols() << " columns, expected 3 (triangles)";
  }
  if (!V.allFinite()) MR_THROW_INPUT << "mesh has non-finite vertex coordinates";
  if (F.rows() > 0 && (F.minCoeff() < 0 || F.maxCoeff() >= V.rows())) {
    MR_THROW_INPUT << "mesh face indices out of range [" << F.minCoeff() << ", " << F.maxCoeff()
                   << "], expected [0, " << V.rows() << ")";
  }
}

RenderBuffers EmptyBuffers(int width, int height) {
  RenderBuffers out;
  out.width = width;
  out.height = height;
  const size_t n = static_cast<size_t>(width) * height;
  out.face_id.assign(n, -1);
  out.depth.assign(n, 0.0f);
  out.bary.assign(2 * n, 0.0f);
  return out;
}

}  // namespace internal

RenderBuffers RenderCpu(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                        const PinholeView& view) {
  using internal::IntersectRay;
  internal::CheckViewAndMesh(V, F, view);
  const int W = view.width, H = view.height;
  RenderBuffers out = internal::EmptyBuffers(W, H);
  const double near = internal::NearPlane(V, view, nullptr);
  if (F.rows() == 0 || !(near > 0)) return out;

  const int nv = static_cast<int>(V.rows());
  const int nf = static_cast<int>(F.rows());
  std::vector<Eigen::Vector3d> Vc(nv);
#pragma omp parallel for schedule(static)
  for (int i = 0; i < nv; ++i) Vc[i] = view.WorldToCamera(V.row(i).transpose());

  // Pixel bounding box of each face after clipping it at the near plane:
  // pixel (col, row) is a candidate when its centre (col + .5, row + .5) lies
  // in the box of the clipped polygon's projection.
  std::vector<Eigen::Vector4i> box(nf);  // col0, col1, row0, row1 (inclusive); col0 > col1: none
#pragma omp parallel for schedule(static)
  for (int f = 0; f < nf; ++f) {
    Eigen::Vector3d poly[4];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& a = Vc[F(f, k)];
      const Eigen::Vector3d& b = Vc[F(f, (k + 1) % 3)];
      if (a.z() >= near) poly[n++] = a;
      if ((a.z() >= near) != (b.z() >= near)) {
        const double s = (near - a.z()) / (b.z() - a.z());
        poly[n] = a + s * (b - a);
        poly[n].z() = near;
        ++n;
      }
    }
    box[f] = Eigen::Vector4i(1, 0, 1, 0);
    if (n < 3) continue;
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d p = view.CameraToImage(poly[k]);
      x0 = std::min(x0, p.x());
      x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y());
      y1 = std::max(y1, p.y());
    }
    // Clamp in double before converting (projections near the plane can be huge).
    const double c0 = std::max(0.0, std::ceil(x0 - 0.5) - 1);
    const double c1 = std::min(W - 1.0, std::floor(x1 - 0.5) + 1);
    const double r0 = std::max(0.0, std::ceil(y0 - 0.5) - 1);
    const double r1 = std::min(H - 1.0, std::floor(y1 - 0.5) + 1);
    if (c0 > c1 || r0 > r1) continue;
    box[f] = Eigen::Vector4i(static_cast<int>(c0), static_cast<int>(c1), static_cast<int>(r0),
                             static_cast<int>(r1));
  }

  // Bin faces into bands of rows; bands are rendered in parallel, faces in
  // increasing index order within a band (equal depths: the lower index wins,
  // as on the GPU).
  const int band_rows = 8;
  const int num_bands = (H + band_rows - 1) / band_rows;
  std::vector<std::vector<int>> bands(num_bands);
  for (int f = 0; f < nf; ++f) {
    if (box[f][0] > box[f][1]) continue;
    for (int b = box[f][2] / band_rows; b <= box[f][3] / band_rows; ++b) bands[b].push_back(f);
  }
  const double tol = internal::kInsideTolerance;
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < num_bands; ++b) {
    const int row_lo = b * band_rows;
    const int row_hi = std::min(H - 1, row_lo + band_rows - 1);
    std::vector<double> zbuf(static_cast<size_t>(band_rows) * W,
                             std::numeric_limits<double>::infinity());
    for (int f : bands[b]) {
      const Eigen::Vector3d& P0 = Vc[F(f, 0)];
      const Eigen::Vector3d& P1 = Vc[F(f, 1)];
      const Eigen::Vector3d& P2 = Vc[F(f, 2)];
      for (int row = std::max(row_lo, box[f][2]); row <= std::min(row_hi, box[f][3]); ++row) {
        const double dy = (row + 0.5 - view.cy) / view.fy;
        for (int col = box[f][0]; col <= box[f][1]; ++col) {
          const Eigen::Vector3d d((col + 0.5 - view.cx) / view.fx, dy, 1.0);
          double t, u, v;
          if (!IntersectRay(d, P0, P1, P2, &t, &u, &v)) continue;
          if (u < -tol || v < -tol || u + v > 1 + tol || t < near) continue;
          double& z = zbuf[static_cast<size_t>(row - row_lo) * W + col];
          if (t >= z) continue;
          z = t;
          const size_t i = static_cast<size_t>(row) * W + col;
          out.face_id[i] = f;
          out.depth[i] = static_cast<float>(t);
          out.bary[2 * i] = static_cast<float>(u);
          out.bary[2 * i + 1] = static_cast<float>(v);
        }
      }
    }
  }
  return out;
}

}  // namespace mr
