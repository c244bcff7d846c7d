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

// s = sqrt|det ∂q/∂p|: how many pixels of view j (per axis) one pixel of
// view i covers, through the plane (normal n) of the face it sees. The ray
// x(p) = C_i + d(p) r(p) meets the plane, so ∂x/∂p_k = d (e_k - r (n·e_k) / (n·r)),
// e_k = ∂r/∂p_k (`dray`, the columns of R_iᵀ over fx and fy).
double FootprintRatio(const Eigen::Matrix<double, 3, 2>& dray, const Eigen::Vector3d& n,
                      const PixelWarp& warp) {
  const double inv_nr = 1.0 / n.dot(warp.ray);
  Eigen::Matrix2d J;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d dx =
        warp.depth * (dray.col(k) - warp.ray * (n.dot(dray.col(k)) * inv_nr));
    J.col(k) = warp.jacobian_j * dx;
  }
  return std::sqrt(std::abs(J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0)));
}

// Standard deviation (pixels of the sharper view) of the blur that brings a
// view whose pixels are `ratio` times finer on the surface to the coarser
// one's: the difference of two box variances, (ratio² - 1) / 12. Below
// 0.1 pixel (ratio < 1.06) none: an eighth of a pixel's own variance; at
// most 3 pixels (ratio 10.4; min_cos_angle keeps ratios below about 7).
double MatchingBlurPx(double ratio) {
  const double sigma = ratio > 1 ? std::sqrt((ratio * ratio - 1) / 12) : 0.0;
  return sigma < 0.1 ? 0.0 : std::min(sigma, 3.0);
}

// `image` at (x, y) blurred by sigma pixels (the mean of the four points at
// ±sigma along each axis), interpolated as `cubic` says; sigma 0: one sample.
double SampleBlurred(const cv::Mat& image, double x, double y, double sigma, bool cubic,
                     Eigen::Vector2d* grad) {
  if (cubic) return SampleCubicBlurred(image, x, y, sigma, grad);
  if (sigma <= 0) return SampleBilinear(image, x, y, grad);
  double sum = 0;
  Eigen::Vector2d g_sum = Eigen::Vector2d::Zero(), g;
  for (const double dy : {-sigma, sigma}) {
    for (const double dx : {-sigma, sigma}) {
      sum += SampleBilinear(image, x + dx, y + dy, grad != nullptr ? &g : nullptr);
      if (grad != nullptr) g_sum += g;
    }
  }
  if (grad != nullptr) *grad = 0.25 * g_sum;
  return 0.25 * sum;
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
  if (interpolation != "cubic" && interpolation != "bilinear") {
    MR_THROW_INPUT << "PairTermOptions::interpolation = " << interpolation
                   << ". Violated constraint: interpolation is cubic or bilinear";
  }
  if (!(headlight_ambient < 0 || headlight_ambient <= 1)) {
    MR_THROW_INPUT << "PairTermOptions::headlight_ambient = " << headlight_ambient
                   << ". Violated constraint: negative (a light fixed in the world) or in [0, 1]";
  }
  return true;
}

double HeadlightRelighting(double ambient, const Eigen::Vector3d& n, const Eigen::Vector3d& x,
                           const Eigen::Vector3d& center_i, const Eigen::Vector3d& center_j) {
  const double cos_i = std::max(0.0, n.dot((center_i - x).normalized()));
  const double cos_j = std::max(0.0, n.dot((center_j - x).normalized()));
  const double lit_i = ambient + (1 - ambient) * cos_i, lit_j = ambient + (1 - ambient) * cos_j;
  return lit_j > 0 ? lit_i / lit_j : 1.0;
}

void DataTerm::Reset(int num_vertices) {
  gradient = Eigen::MatrixXd::Zero(num_vertices, 3);
  curvature = Eigen::VectorXd::Zero(num_vertices);
  weight = Eigen::VectorXd::Zero(num_vertices);
  footprint = Eigen::VectorXd::Zero(num_vertices);
  similarity = Eigen::VectorXd::Zero(num_vertices);
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
  similarity += other.similarity;
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
// footprint d / fx (both CV_64F). With `blur_i` (resolution matching), Î is
// blurred where view j is finer, and blur_i (CV_32F) receives the blur image
// i needs where view j is coarser (pixels of i; 0 elsewhere).
void WarpImage(const MeshGeometry& mesh, const PinholeView& view_i, const RenderBuffers& render_i,
               const PinholeView& view_j, const RenderBuffers& render_j, const cv::Mat& image_j,
               const PairTermOptions& options, const cv::Rect& box, cv::Mat* predicted,
               cv::Mat* mask, cv::Mat* derivative, cv::Mat* footprint, cv::Mat* blur_i) {
  MR_CHECK(image_j.type() == CV_32F) << "image_j must be CV_32F";
  MR_CHECK(render_i.width == view_i.width && render_i.height == view_i.height);
  MR_CHECK(render_j.width == view_j.width && render_j.height == view_j.height);
  MR_CHECK((box & cv::Rect(0, 0, view_i.width, view_i.height)) == box);
  // Allocated here and zeroed row by row by the threads (0 outside the valid
  // domain), not zeroed on one thread first.
  predicted->create(box.size(), CV_64F);
  mask->create(box.size(), CV_8U);
  if (blur_i != nullptr) blur_i->create(box.size(), CV_32F);
  const bool cubic = options.interpolation == "cubic";
  const bool headlight = options.headlight_ambient >= 0;
  const Eigen::Vector3d center_i = view_i.Center(), center_j = view_j.Center();
  Eigen::Matrix<double, 3, 2> dray;  // ∂r/∂p, the same for every pixel of view i
  dray.col(0) = view_i.R.row(0).transpose() / view_i.fx;
  dray.col(1) = view_i.R.row(1).transpose() / view_i.fy;
  if (derivative != nullptr) {
    derivative->create(box.size(), CV_64F);
    footprint->create(box.size(), CV_64F);
  }
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < box.height; ++r) {
    const int row = box.y + r;
    predicted->row(r).setTo(0);
    mask->row(r).setTo(0);
    if (blur_i != nullptr) blur_i->row(r).setTo(0);
    if (derivative != nullptr) {
      derivative->row(r).setTo(0);
      footprint->row(r).setTo(0);
    }
    PixelWarp warp;
    for (int c = 0; c < box.width; ++c) {
      const int col = box.x + c;
      if (!WarpPixel(mesh, view_i, render_i, view_j, render_j, options, row, col, &warp)) continue;
      mask->at<uint8_t>(r, c) = 255;
      const int f = render_i.face_id[static_cast<size_t>(row) * render_i.width + col];
      const Eigen::Vector3d n = mesh.face_normals.row(f);
      double blur_j = 0;
      if (blur_i != nullptr) {
        const double ratio = FootprintRatio(dray, n, warp);
        blur_j = MatchingBlurPx(ratio);
        blur_i->at<float>(r, c) = static_cast<float>(MatchingBlurPx(1 / ratio));
      }
      const double relight =
          headlight ? HeadlightRelighting(options.headlight_ambient, n,
                                          center_i + warp.depth * warp.ray, center_i, center_j)
                    : 1.0;
      Eigen::Vector2d grad_j;
      predicted->at<double>(r, c) =
          relight * SampleBlurred(image_j, warp.q.x(), warp.q.y(), blur_j, cubic,
                                  derivative != nullptr ? &grad_j : nullptr);
      if (derivative == nullptr) continue;
      derivative->at<double>(r, c) =
          relight * grad_j.dot(warp.jacobian_j * warp.ray) / n.dot(warp.ray);
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
            cv::Rect(0, 0, view_i.width, view_i.height), predicted, mask, nullptr, nullptr,
            nullptr);
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
  cv::Mat predicted, mask, derivative, footprint, blur_i;
  WarpImage(mesh, view_i, render_i, view_j, render_j, image_j, options, box, &predicted, &mask,
            with_gradient ? &derivative : nullptr, with_gradient ? &footprint : nullptr,
            options.match_resolution ? &blur_i : nullptr);
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
  if (options.match_resolution) {
    MR_CHECK(image_i.type() == CV_32F) << "image_i must be CV_32F";
    // Image i blurred where view j sees the surface coarser.
    observed = observed.clone();
    blur_i = blur_i(roi);
    const bool cubic = options.interpolation == "cubic";
#pragma omp parallel for schedule(static)
    for (int row = 0; row < roi.height; ++row) {
      for (int col = 0; col < roi.width; ++col) {
        const float sigma = blur_i.at<float>(row, col);
        if (sigma <= 0) continue;
        observed.at<float>(row, col) = static_cast<float>(SampleBlurred(
            image_i, origin.x + col + 0.5, origin.y + row + 0.5, sigma, cubic, nullptr));
      }
    }
  }
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
      const double m = dp ? maps.zncc.at<double>(row, col) : maps.zncc.at<float>(row, col);
      const double u = render_i.bary[2 * idx], v = render_i.bary[2 * idx + 1];
      const double w[3] = {1.0 - u - v, u, v};
      for (int k = 0; k < 3; ++k) {
        const int vk = F(f, k);
        acc.gradient.row(vk) += (w[k] * g * a) * n.transpose();
        acc.curvature(vk) += w[k] * a * a / v2;
        acc.weight(vk) += w[k];
        acc.footprint(vk) += w[k] * pixel_footprint;
        acc.similarity(vk) += w[k] * m;
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
