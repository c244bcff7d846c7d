#include "refine/photometric.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "refine/pyramid.h"
#include "util/error.h"
#include "util/threads.h"

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

namespace {

// The bounding box of the pixels of `render` that see the surface (empty if
// none does).
cv::Rect ForegroundBox(const RenderBuffers& render) {
  int top = -1, bottom = -1, left = render.width, right = -1;
  for (int row = 0; row < render.height; ++row) {
    const int32_t* ids = render.face_id.data() + static_cast<size_t>(row) * render.width;
    int first = -1, last = -1;
    for (int col = 0; col < render.width; ++col) {
      if (ids[col] < 0) continue;
      if (first < 0) first = col;
      last = col;
    }
    if (first < 0) continue;
    if (top < 0) top = row;
    bottom = row;
    left = std::min(left, first);
    right = std::max(right, last);
  }
  return top < 0 ? cv::Rect() : cv::Rect(left, top, right - left + 1, bottom - top + 1);
}

// The warp of view j into view i through the mesh, over the pixels `box` of
// view i (the maps are box-sized): Î_ij, the valid domain, and, when
// `derivative` is given, per valid pixel the change of Î per unit motion of
// the surface along its normal, a = ∇I_jᵀ Jπ_j r / (n·r), and the pixel's
// footprint d / fx (both CV_64F).
void WarpImage(const MeshGeometry& mesh, const PinholeView& view_i, const RenderBuffers& render_i,
               const PinholeView& view_j, const RenderBuffers& render_j, const cv::Mat& image_j,
               const PairTermOptions& options, const cv::Rect& box, cv::Mat* predicted,
               cv::Mat* mask, cv::Mat* derivative, cv::Mat* footprint) {
  MR_CHECK(image_j.type() == CV_32F) << "image_j must be CV_32F";
  MR_CHECK(render_i.width == view_i.width && render_i.height == view_i.height);
  MR_CHECK(render_j.width == view_j.width && render_j.height == view_j.height);
  MR_CHECK((box & cv::Rect(0, 0, view_i.width, view_i.height)) == box);
  // Allocated here and zeroed row by row by the threads (0 outside the valid
  // domain), not zeroed on one thread first.
  predicted->create(box.size(), CV_64F);
  mask->create(box.size(), CV_8U);
  if (derivative != nullptr) {
    derivative->create(box.size(), CV_64F);
    footprint->create(box.size(), CV_64F);
  }
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < box.height; ++r) {
    const int row = box.y + r;
    predicted->row(r).setTo(0);
    mask->row(r).setTo(0);
    if (derivative != nullptr) {
      derivative->row(r).setTo(0);
      footprint->row(r).setTo(0);
    }
    PixelWarp warp;
    for (int c = 0; c < box.width; ++c) {
      const int col = box.x + c;
      if (!WarpPixel(mesh, view_i, render_i, view_j, render_j, options, row, col, &warp)) continue;
      mask->at<uint8_t>(r, c) = 255;
      Eigen::Vector2d grad_j;
      predicted->at<double>(r, c) = SampleBilinear(image_j, warp.q.x(), warp.q.y(),
                                                   derivative != nullptr ? &grad_j : nullptr);
      if (derivative == nullptr) continue;
      const int f = render_i.face_id[static_cast<size_t>(row) * render_i.width + col];
      const Eigen::Vector3d n = mesh.face_normals.row(f);
      derivative->at<double>(r, c) = grad_j.dot(warp.jacobian_j * warp.ray) / n.dot(warp.ray);
      footprint->at<double>(r, c) = warp.depth / view_i.fx;
    }
  }
}

}  // namespace

void PredictImage(const MeshGeometry& mesh, const PinholeView& view_i,
                  const RenderBuffers& render_i, const PinholeView& view_j,
                  const RenderBuffers& render_j, const cv::Mat& image_j,
                  const PairTermOptions& options, cv::Mat* predicted, cv::Mat* mask) {
  WarpImage(mesh, view_i, render_i, view_j, render_j, image_j, options,
            cv::Rect(0, 0, view_i.width, view_i.height), predicted, mask, nullptr, nullptr);
}

DataTermAccumulator::DataTermAccumulator(int num_vertices)
    : num_vertices_(num_vertices), partial_(NumThreads()) {
  for (auto& p : partial_) p.Reset(num_vertices);
}

long DataTermAccumulator::AddPair(const MeshGeometry& mesh, const PinholeView& view_i,
                                  const RenderBuffers& render_i, const cv::Mat& image_i,
                                  const PinholeView& view_j, const RenderBuffers& render_j,
                                  const cv::Mat& image_j, const SimilarityOptions& similarity,
                                  const PairTermOptions& options, bool with_gradient) {
  MR_CHECK(mesh.V->rows() == num_vertices_) << "DataTermAccumulator not sized for the mesh";
  MR_CHECK(static_cast<int>(partial_.size()) >= NumThreads())
      << "DataTermAccumulator used with more threads than it was made for";
  // Only the pixels around the surface's image are warped and compared.
  const cv::Rect box = ForegroundBox(render_i);
  if (box.empty()) return 0;
  cv::Mat predicted, mask, derivative, footprint;
  WarpImage(mesh, view_i, render_i, view_j, render_j, image_j, options, box, &predicted, &mask,
            with_gradient ? &derivative : nullptr, with_gradient ? &footprint : nullptr);
  const long valid = cv::countNonZero(mask);
  if (valid == 0) return 0;
  // The similarity's Gaussian pads with zeros and every moment it filters is
  // zero outside the valid pixels, so the maps over their bounding box are
  // those over the whole image.
  const cv::Rect roi = cv::boundingRect(mask);
  predicted = predicted(roi);
  mask = mask(roi);
  if (with_gradient) {
    derivative = derivative(roi);
    footprint = footprint(roi);
  }
  const cv::Point origin = box.tl() + roi.tl();  // of the maps, in view i

  // Both images in the precision the similarity computes in.
  cv::Mat observed = image_i(cv::Rect(origin, roi.size()));
  if (similarity.double_precision) {
    observed.convertTo(observed, CV_64F);
  } else {
    predicted.convertTo(predicted, CV_32F);
  }
  const SimilarityResult maps =
      ComputeSimilarity(observed, predicted, mask, similarity, with_gradient);
  DataTerm& scalars = partial_[0];
  scalars.cost += maps.cost;
  scalars.zncc_sum += maps.zncc_sum;
  scalars.weight_sum += maps.weight_sum;
  scalars.valid_pixels += valid;
  if (!with_gradient) return valid;
  const bool dp = maps.gradient.depth() == CV_64F;

  const Eigen::MatrixXi& F = *mesh.F;
  // Each thread scatters into its own buffer, so no atomics are needed. A
  // static schedule gives every thread the same rows in every run, so the
  // sums (and the refinement) are reproducible for a given thread count.
#pragma omp parallel for schedule(static)
  for (int row = 0; row < roi.height; ++row) {
    DataTerm& acc = partial_[ThreadIndex()];
    const uint8_t* valid_row = mask.ptr<uint8_t>(row);
    for (int col = 0; col < roi.width; ++col) {
      if (valid_row[col] == 0) continue;
      const size_t idx = static_cast<size_t>(origin.y + row) * view_i.width + origin.x + col;
      const int f = render_i.face_id[idx];
      const Eigen::Vector3d n = mesh.face_normals.row(f);
      const double a = derivative.at<double>(row, col);
      const double g = dp ? maps.gradient.at<double>(row, col) : maps.gradient.at<float>(row, col);
      const double v2 = dp ? maps.variance_predicted.at<double>(row, col)
                           : maps.variance_predicted.at<float>(row, col);
      const double pixel_footprint = footprint.at<double>(row, col);
      const double u = render_i.bary[2 * idx], v = render_i.bary[2 * idx + 1];
      const double w[3] = {1.0 - u - v, u, v};
      for (int k = 0; k < 3; ++k) {
        const int vk = F(f, k);
        acc.gradient.row(vk) += (w[k] * g * a) * n.transpose();
        acc.curvature(vk) += w[k] * a * a / v2;
        acc.weight(vk) += w[k];
        acc.footprint(vk) += w[k] * pixel_footprint;
      }
    }
  }
  return valid;
}

DataTerm DataTermAccumulator::Sum() const {
  DataTerm sum;
  sum.Reset(num_vertices_);
  for (const auto& p : partial_) sum.Add(p);
  return sum;
}

long AccumulatePairTerm(const MeshGeometry& mesh, const PinholeView& view_i,
                        const RenderBuffers& render_i, const cv::Mat& image_i,
                        const PinholeView& view_j, const RenderBuffers& render_j,
                        const cv::Mat& image_j, const SimilarityOptions& similarity,
                        const PairTermOptions& options, DataTerm* term) {
  MR_CHECK(term->gradient.rows() == mesh.V->rows()) << "DataTerm not sized for the mesh";
  DataTermAccumulator accumulator(static_cast<int>(mesh.V->rows()));
  const long valid = accumulator.AddPair(mesh, view_i, render_i, image_i, view_j, render_j,
                                         image_j, similarity, options);
  term->Add(accumulator.Sum());
  return valid;
}

}  // namespace mr
