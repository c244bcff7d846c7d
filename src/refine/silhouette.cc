#include "refine/silhouette.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "refine/pyramid.h"
#include "util/error.h"

namespace mr {

cv::Mat SignedDistanceToMask(const cv::Mat& mask) {
  MR_CHECK(mask.type() == CV_8U);
  cv::Mat inside = mask > 0, outside = mask == 0;
  cv::Mat d_in, d_out;
  // Distance of each inside pixel to the nearest outside pixel and vice versa.
  cv::distanceTransform(inside, d_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(outside, d_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  // Half a pixel puts the zero level on the boundary between the two sets.
  cv::Mat sd(mask.size(), CV_32F);
  for (int r = 0; r < mask.rows; ++r) {
    for (int c = 0; c < mask.cols; ++c) {
      const float in = d_in.at<float>(r, c), out = d_out.at<float>(r, c);
      sd.at<float>(r, c) = in > 0 ? in - 0.5f : -(out - 0.5f);
    }
  }
  return sd;
}

void AccumulateSilhouetteTerm(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                              const Eigen::MatrixXd& vertex_normals, const PinholeView& view,
                              const RenderBuffers& render, const cv::Mat& signed_distance,
                              double max_px, Eigen::MatrixXd* displacement,
                              Eigen::VectorXd* count) {
  MR_CHECK(signed_distance.type() == CV_32F && signed_distance.cols == view.width &&
           signed_distance.rows == view.height);
  MR_CHECK(render.width == view.width && render.height == view.height);
  // The rendered silhouette's own signed distance: a contour vertex of a
  // triangle mesh can project up to an edge inside the outline that its
  // neighbours draw, so the error is the difference of the two fields at the
  // vertex, not the observed field alone (which pushed such vertices outward
  // even where outline and mask agree: the surface inflated).
  cv::Mat rendered(view.height, view.width, CV_8U);
  for (int r = 0; r < view.height; ++r) {
    for (int c = 0; c < view.width; ++c) rendered.at<uint8_t>(r, c) = render.FaceAt(r, c) >= 0;
  }
  const cv::Mat rendered_distance = SignedDistanceToMask(rendered);
  const Eigen::Vector3d center = view.Center();
  // A vertex is on the contour generator if it has both front- and
  // back-facing incident faces.
  std::vector<char> front(V.rows(), 0), back(V.rows(), 0);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const double s = (b - a).cross(c - a).dot(center - a);
    for (int k = 0; k < 3; ++k) (s > 0 ? front : back)[F(f, k)] = 1;
  }
  for (int v = 0; v < V.rows(); ++v) {
    if (!front[v] || !back[v]) continue;
    const Eigen::Vector3d x = V.row(v);
    const Eigen::Vector3d xc = view.WorldToCamera(x);
    if (xc.z() <= 0) continue;
    const Eigen::Vector2d p = view.CameraToImage(xc);
    const int col = static_cast<int>(std::floor(p.x())), row = static_cast<int>(std::floor(p.y()));
    if (col < 1 || row < 1 || col >= view.width - 1 || row >= view.height - 1) continue;
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
    const double s =
        std::clamp(SampleBilinear(signed_distance, p.x(), p.y(), nullptr) -
                       SampleBilinear(rendered_distance, p.x(), p.y(), nullptr),
                   -max_px, max_px);
    const double footprint = xc.z() / view.fx;
    displacement->row(v) += (s * footprint) * u.transpose();
    (*count)(v) += 1;
  }
}

}  // namespace mr
