#include "refine/silhouette.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "util/error.h"

namespace mr {

namespace {

// How far (pixels) the visual-hull pull looks for the mask from a vertex
// outside it.
constexpr int kHullSearchRadius = 32;

// The nearest pixel to (row, col) whose `inside` value is `want`, searched
// only up to `radius` pixels away: the rings of pixels at growing Chebyshev
// distance k are searched until k^2 reaches the best squared distance found,
// so a pixel near the boundary costs a few dozen tests. Returns the squared
// distance (radius^2 + 1 where none lies within) and its offset in
// (*d_row, *d_col).
template <typename Inside>
int NearestWithValue(const Inside& inside, bool want, int rows, int cols, int row, int col,
                     int radius, int* d_row, int* d_col) {
  int best = radius * radius + 1;
  for (int k = 1; k <= radius && k * k < best; ++k) {
    for (int dr = -k; dr <= k; ++dr) {
      const int r = row + dr;
      if (r < 0 || r >= rows) continue;
      const int step = (dr == -k || dr == k) ? 1 : 2 * k;  // the ring only
      for (int dc = -k; dc <= k; dc += step) {
        const int c = col + dc;
        if (c < 0 || c >= cols || inside(r, c) != want || dr * dr + dc * dc >= best) continue;
        best = dr * dr + dc * dc;
        *d_row = dr;
        *d_col = dc;
      }
    }
  }
  return best;
}

// Signed distance (pixels, > 0 inside) from pixel (row, col) to the boundary
// of the pixel set `inside`, the distance between pixel centres to the
// nearest pixel of the other set less half a pixel, searched only up to
// `radius` pixels away: where none lies within, the distance is reported as
// radius + 1 (the true one is larger than radius; callers choose a radius
// beyond the distances they use).
template <typename Inside>
float SignedDistanceNear(const Inside& inside, int rows, int cols, int row, int col, int radius) {
  const bool in = inside(row, col);
  int d_row = 0, d_col = 0;
  const int best = NearestWithValue(inside, !in, rows, cols, row, col, radius, &d_row, &d_col);
  const float d = best > radius * radius ? radius + 1.0f : std::sqrt(static_cast<float>(best));
  return in ? d - 0.5f : 0.5f - d;
}

// Bilinear interpolation of SignedDistanceNear at image point (x, y), pixel
// centres at half-integers (SampleBilinear's convention); (x, y) must lie
// at least half a pixel inside the image.
template <typename Inside>
double SignedDistanceNear(const Inside& inside, int rows, int cols, double x, double y,
                          int radius) {
  const double u = x - 0.5, v = y - 0.5;
  const int c0 = static_cast<int>(std::floor(u)), r0 = static_cast<int>(std::floor(v));
  MR_CHECK(c0 >= 0 && r0 >= 0 && c0 + 1 < cols && r0 + 1 < rows);
  const double fu = u - c0, fv = v - r0;
  auto at = [&](int r, int c) { return SignedDistanceNear(inside, rows, cols, r, c, radius); };
  const double p00 = at(r0, c0), p01 = at(r0, c0 + 1), p10 = at(r0 + 1, c0),
               p11 = at(r0 + 1, c0 + 1);
  const double top = p00 + fu * (p01 - p00), bottom = p10 + fu * (p11 - p10);
  return top + fv * (bottom - top);
}

}  // namespace

double SignedDistanceToMaskAt(const cv::Mat& mask, double x, double y, int radius) {
  MR_CHECK(mask.type() == CV_8U);
  auto inside = [&](int r, int c) { return mask.at<uint8_t>(r, c) > 0; };
  return SignedDistanceNear(inside, mask.rows, mask.cols, x, y, radius);
}

void AccumulateSilhouetteTerm(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                              const Eigen::MatrixXd& vertex_normals, const PinholeView& view,
                              const RenderBuffers& render, const cv::Mat& mask, double max_px,
                              double hull_margin_px, Eigen::MatrixXd* displacement,
                              Eigen::VectorXd* count) {
  MR_CHECK(mask.type() == CV_8U && mask.cols == view.width && mask.rows == view.height);
  MR_CHECK(render.width == view.width && render.height == view.height);
  // The rendered silhouette's own signed distance: a contour vertex of a
  // triangle mesh can project up to an edge inside the outline that its
  // neighbours draw, so the error is the difference of the two fields at the
  // vertex, not the observed field alone (which pushed such vertices outward
  // even where outline and mask agree: the surface inflated).
  // Both distance fields are needed only at the contour vertices, and only
  // up to max_px beyond the rendered outline (a contour vertex lies within 2
  // pixels of it): they are searched near each vertex, not transformed over
  // the whole image (4 distance transforms per view and iteration were a
  // quarter of an iteration with 40 views of 1280x960).
  const int radius = static_cast<int>(std::ceil(max_px)) + 4;
  auto rendered = [&](int r, int c) { return render.FaceAt(r, c) >= 0; };
  auto observed = [&](int r, int c) { return mask.at<uint8_t>(r, c) > 0; };
  const Eigen::Vector3d center = view.Center();
  // A vertex is on the contour generator if it has both front- and
  // back-facing incident faces.
  std::vector<char> front(V.rows(), 0), back(V.rows(), 0);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const double s = (b - a).cross(c - a).dot(center - a);
    for (int k = 0; k < 3; ++k) (s > 0 ? front : back)[F(f, k)] = 1;
  }
  const bool hull = hull_margin_px >= 0;
  for (int v = 0; v < V.rows(); ++v) {
    const bool contour = front[v] && back[v];
    if (!contour && !hull) continue;
    const Eigen::Vector3d x = V.row(v);
    const Eigen::Vector3d xc = view.WorldToCamera(x);
    if (xc.z() <= 0) continue;
    const Eigen::Vector2d p = view.CameraToImage(xc);
    const int col = static_cast<int>(std::floor(p.x())), row = static_cast<int>(std::floor(p.y()));
    if (col < 1 || row < 1 || col >= view.width - 1 || row >= view.height - 1) continue;
    const double footprint = xc.z() / view.fx;
    if (!contour) {
      // The visual hull: toward the nearest mask pixel's centre, at the
      // vertex's depth.
      if (observed(row, col)) continue;
      int dr = 0, dc = 0;
      if (NearestWithValue(observed, true, view.height, view.width, row, col, kHullSearchRadius,
                           &dr, &dc) > kHullSearchRadius * kHullSearchRadius) {
        continue;
      }
      // Its distance to the mask's edge: to the nearest inside pixel's centre
      // less half a pixel, as SignedDistanceNear measures.
      const Eigen::Vector2d target(col + dc + 0.5, row + dr + 0.5);
      const double beyond = (target - p).norm() - 0.5 - hull_margin_px;
      if (!(beyond > 0)) continue;
      const Eigen::Vector3d direction =
          (center + xc.z() * view.RayDirection(target.x(), target.y()) - x).normalized();
      displacement->row(v) += (std::min(beyond, max_px) * footprint) * direction.transpose();
      (*count)(v) += 1;
      continue;
    }
    // Only contour points on the rendered outline (background next to them)
    // are horizons; the others are hidden behind the object.
    bool on_outline = false;
    for (int dr = -1; dr <= 1 && !on_outline; ++dr) {
      for (int dc = -1; dc <= 1; ++dc) {
        if (render.FaceAt(row + dr, col + dc) < 0) {
          on_outline = true;
          break;
        }
      }
    }
    if (!on_outline) continue;
    // The image-plane component of the normal, as a world direction.
    const Eigen::Vector3d ray = (x - center).normalized();
    Eigen::Vector3d n = vertex_normals.row(v);
    Eigen::Vector3d u = n - n.dot(ray) * ray;
    if (u.norm() < 1e-6) continue;
    u.normalize();
    const double s = std::clamp(
        SignedDistanceNear(observed, view.height, view.width, p.x(), p.y(), radius) -
            SignedDistanceNear(rendered, view.height, view.width, p.x(), p.y(), radius),
        -max_px, max_px);
    displacement->row(v) += (s * footprint) * u.transpose();
    (*count)(v) += 1;
  }
}

}  // namespace mr
