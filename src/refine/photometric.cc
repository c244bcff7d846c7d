#include "refine/photometric.h"

#include <algorithm>
#include <cmath>

#include "refine/pyramid.h"

#ifdef _OPENMP
#include <omp.h>
#endif
#include "util/error.h"

namespace mr {
namespace {

// What the data term needs to know about one valid pixel of view i.
struct PixelWarp {
  bool valid = false;
  Eigen::Vector3d ray;        // r_p, unit camera-z
  double depth = 0;           // d
  Eigen::Vector2d q;          // π_j(x)
  Eigen::Matrix<double, 2, 3> jacobian_j;  // ∂π_j/∂x
};

// Back-projects pixel (row, col) of view i onto the mesh and warps it into
// view j. Returns false if the point is outside the valid domain.
bool WarpPixel(const MeshGeometry& mesh, const PinholeView& view_i, const RenderBuffers& render_i,
               const PinholeView& view_j, const RenderBuffers& render_j,
               const PairTermOptions& options, int row, int col, PixelWarp* warp) {
  const size_t idx = static_cast<size_t>(row) * render_i.width + col;
  const int f = render_i.face_id[idx];
  if (f < 0) return false;
  const Eigen::Vector3d n = mesh.face_normals.row(f);
  const Eigen::Vector3d ray = view_i.RayDirection(col + 0.5, row + 0.5);
  if (std::abs(n.dot(ray.normalized())) < options.min_cos_angle) return false;
  // Exact depth of the ray's hit on the face's plane.
  const Eigen::Vector3d a = mesh.V->row((*mesh.F)(f, 0));
  const double d = n.dot(a - view_i.Center()) / n.dot(ray);
  if (!(d > 0)) return false;
  const Eigen::Vector3d x = view_i.Center() + d * ray;

  const Eigen::Vector3d xj = view_j.WorldToCamera(x);
  if (xj.z() <= 0) return false;
  const Eigen::Vector2d q = view_j.CameraToImage(xj);
  // One pixel of margin keeps the bilinear stencil inside image j.
  if (q.x() < 1 || q.y() < 1 || q.x() > view_j.width - 1 || q.y() > view_j.height - 1) {
    return false;
  }
  const Eigen::Vector3d ray_j = (x - view_j.Center()).normalized();
  const double cos_j = std::abs(n.dot(ray_j));
  if (cos_j < options.min_cos_angle) return false;

  // Depth test against view j's render at the nearest pixel centre.
  const int qc = std::min(view_j.width - 1, static_cast<int>(q.x()));
  const int qr = std::min(view_j.height - 1, static_cast<int>(q.y()));
  const size_t jdx = static_cast<size_t>(qr) * render_j.width + qc;
  if (render_j.face_id[jdx] < 0) return false;
  const double footprint_j = xj.z() / view_j.fx;
  const double tolerance =
      options.visibility_tolerance_px * footprint_j / std::max(cos_j, 0.2);
  if (std::abs(render_j.depth[jdx] - xj.z()) > tolerance && render_j.face_id[jdx] != f) {
    return false;
  }

  warp->valid = true;
  warp->ray = ray;
  warp->depth = d;
  warp->q = q;
  // ∂π_j/∂x = [fx/z, 0, -fx X/z²; 0, fy/z, -fy Y/z²] R_j
  Eigen::Matrix<double, 2, 3> dproj;
  const double iz = 1.0 / xj.z();
  dproj << view_j.fx * iz, 0, -view_j.fx * xj.x() * iz * iz, 0, view_j.fy * iz,
      -view_j.fy * xj.y() * iz * iz;
  warp->jacobian_j = dproj * view_j.R;
  return true;
}

}  // namespace

bool PairTermOptions::Check() const {
  if (!(visibility_tolerance_px > 0)) {
    MR_THROW_INPUT << "PairTermOptions::visibility_tolerance_px = " << visibility_tolerance_px
                   << ". Violated constraint: visibility_tolerance_px > 0";
  }
  if (!(min_cos_angle >= 0 && min_cos_angle < 1)) {
    MR_THROW_INPUT << "PairTermOptions::min_cos_angle = " << min_cos_angle
                   << ". Violated constraint: 0 <= min_cos_angle < 1";
  }
  return true;
}

void DataTerm::Reset(int num_vertices) {
  gradient = Eigen::MatrixXd::Zero(num_vertices, 3);
  curvature = Eigen::VectorXd::Zero(num_vertices);
  weight = Eigen::VectorXd::Zero(num_vertices);
  footprint = Eigen::VectorXd::Zero(num_vertices);
  cost = 0;
  zncc_sum = 0;
  weight_sum = 0;
  valid_pixels = 0;
}

void DataTerm::Add(const DataTerm& other) {
  gradient += other.gradient;
  curvature += other.curvature;
  weight += other.weight;
  footprint += other.footprint;
  cost += other.cost;
  zncc_sum += other.zncc_sum;
  weight_sum += other.weight_sum;
  valid_pixels += other.valid_pixels;
}

void PredictImage(const MeshGeometry& mesh, const PinholeView& view_i,
                  const RenderBuffers& render_i, const PinholeView& view_j,
                  const RenderBuffers& render_j, const cv::Mat& image_j,
                  const PairTermOptions& options, cv::Mat* predicted, cv::Mat* mask) {
  MR_CHECK(image_j.type() == CV_32F) << "image_j must be CV_32F";
  MR_CHECK(render_i.width == view_i.width && render_i.height == view_i.height);
  MR_CHECK(render_j.width == view_j.width && render_j.height == view_j.height);
  *predicted = cv::Mat::zeros(view_i.height, view_i.width, CV_64F);
  *mask = cv::Mat::zeros(view_i.height, view_i.width, CV_8U);
#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < view_i.height; ++row) {
    PixelWarp warp;
    for (int col = 0; col < view_i.width; ++col) {
      if (!WarpPixel(mesh, view_i, render_i, view_j, render_j, options, row, col, &warp)) continue;
      predicted->at<double>(row, col) = SampleBilinear(image_j, warp.q.x(), warp.q.y(), nullptr);
      mask->at<uint8_t>(row, col) = 255;
    }
  }
}

long AccumulatePairTerm(const MeshGeometry& mesh, const PinholeView& view_i,
                        const RenderBuffers& render_i, const cv::Mat& image_i,
                        const PinholeView& view_j, const RenderBuffers& render_j,
                        const cv::Mat& image_j, const SimilarityOptions& similarity,
                        const PairTermOptions& options, DataTerm* term) {
  MR_CHECK(term->gradient.rows() == mesh.V->rows()) << "DataTerm not sized for the mesh";
  cv::Mat predicted, mask;
  PredictImage(mesh, view_i, render_i, view_j, render_j, image_j, options, &predicted, &mask);
  const long valid = cv::countNonZero(mask);
  if (valid == 0) return 0;

  // Both images in the precision the similarity computes in.
  cv::Mat observed = image_i;
  if (similarity.double_precision) {
    image_i.convertTo(observed, CV_64F);
  } else {
    predicted.convertTo(predicted, CV_32F);
  }
  const SimilarityResult maps = ComputeSimilarity(observed, predicted, mask, similarity);
  term->cost += maps.cost;
  term->zncc_sum += maps.zncc_sum;
  term->weight_sum += maps.weight_sum;
  term->valid_pixels += valid;
  const bool dp = maps.gradient.depth() == CV_64F;

  const Eigen::MatrixXi& F = *mesh.F;
  const int height = view_i.height, width = view_i.width;
  // Rows are processed in two interleaved halves so that the per-vertex
  // scatter needs no atomics: each thread owns a private accumulator.
  const int num_threads =
#ifdef _OPENMP
      std::max(1, omp_get_max_threads());
#else
      1;
#endif
  std::vector<DataTerm> partial(num_threads);
  for (auto& p : partial) p.Reset(static_cast<int>(mesh.V->rows()));
#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < height; ++row) {
#ifdef _OPENMP
    DataTerm& acc = partial[omp_get_thread_num()];
#else
    DataTerm& acc = partial[0];
#endif
    PixelWarp warp;
    for (int col = 0; col < width; ++col) {
      if (mask.at<uint8_t>(row, col) == 0) continue;
      if (!WarpPixel(mesh, view_i, render_i, view_j, render_j, options, row, col, &warp)) continue;
      const size_t idx = static_cast<size_t>(row) * width + col;
      const int f = render_i.face_id[idx];
      const Eigen::Vector3d n = mesh.face_normals.row(f);
      Eigen::Vector2d grad_j;
      SampleBilinear(image_j, warp.q.x(), warp.q.y(), &grad_j);
      const double n_dot_r = n.dot(warp.ray);
      // a = ∇I_jᵀ Jπ_j r / (n·r): intensity change per unit normal motion.
      const double a = grad_j.dot(warp.jacobian_j * warp.ray) / n_dot_r;
      const double g = dp ? maps.gradient.at<double>(row, col) : maps.gradient.at<float>(row, col);
      const double v2 = dp ? maps.variance_predicted.at<double>(row, col)
                           : maps.variance_predicted.at<float>(row, col);
      const double footprint = warp.depth / view_i.fx;
      const double u = render_i.bary[2 * idx], v = render_i.bary[2 * idx + 1];
      const double w[3] = {1.0 - u - v, u, v};
      for (int k = 0; k < 3; ++k) {
        const int vk = F(f, k);
        acc.gradient.row(vk) += (w[k] * g * a) * n.transpose();
        acc.curvature(vk) += w[k] * a * a / v2;
        acc.weight(vk) += w[k];
        acc.footprint(vk) += w[k] * footprint;
      }
    }
  }
  for (const auto& p : partial) {
    term->gradient += p.gradient;
    term->curvature += p.curvature;
    term->weight += p.weight;
    term->footprint += p.footprint;
  }
  return valid;
}

}  // namespace mr
