#include "init/visual_hull.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "init/isosurface.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/mask_distance.h"

namespace mr {
namespace {

// Largest grid carved (4 bytes per node: 2 GiB).
constexpr double kMaxNodes = 512.0 * 1024 * 1024;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Bilinear sample of a CV_32F image at array coordinates (u, v), clamped to
// the image.
float Bilinear(const cv::Mat& img, double u, double v) {
  u = std::clamp(u, 0.0, img.cols - 1.0);
  v = std::clamp(v, 0.0, img.rows - 1.0);
  const int u0 = std::min(static_cast<int>(u), img.cols - 2 < 0 ? 0 : img.cols - 2);
  const int v0 = std::min(static_cast<int>(v), img.rows - 2 < 0 ? 0 : img.rows - 2);
  const int u1 = std::min(u0 + 1, img.cols - 1), v1 = std::min(v0 + 1, img.rows - 1);
  const double a = u - u0, b = v - v0;
  const float* r0 = img.ptr<float>(v0);
  const float* r1 = img.ptr<float>(v1);
  return static_cast<float>((1 - b) * ((1 - a) * r0[u0] + a * r0[u1]) +
                            b * ((1 - a) * r1[u0] + a * r1[u1]));
}

struct Carver {
  const std::vector<PinholeView>& views;
  std::vector<cv::Mat> sdf;  // per view, pixels
  int min_views;

  // Field value at X (scene units); -inf-like if seen by too few views.
  float Value(const Eigen::Vector3d& X, double outside) const {
    double h = std::numeric_limits<double>::infinity();
    int seen = 0;
    for (size_t v = 0; v < views.size(); ++v) {
      const PinholeView& view = views[v];
      const Eigen::Vector3d Xc = view.WorldToCamera(X);
      if (Xc.z() <= 0) continue;
      const Eigen::Vector2d p = view.CameraToImage(Xc);
      if (!view.InImage(p)) continue;
      ++seen;
      const double s = Bilinear(sdf[v], p.x() - 0.5, p.y() - 0.5);
      h = std::min(h, s * Xc.z() / (0.5 * (view.fx + view.fy)));
    }
    if (seen < min_views) return static_cast<float>(outside);
    return static_cast<float>(h);
  }
};

Eigen::AlignedBox3d Padded(const Eigen::AlignedBox3d& box, double padding) {
  const double pad = padding * box.sizes().maxCoeff();
  return Eigen::AlignedBox3d(box.min().array() - pad, box.max().array() + pad);
}

}  // namespace

bool VisualHullOptions::Check() const {
  if (resolution < 4 || resolution > 2048) {
    MR_THROW_INPUT << "VisualHullOptions::resolution = " << resolution
                   << ". Violated constraint: 4 <= resolution <= 2048";
  }
  if (!(padding >= 0) || !std::isfinite(padding)) {
    MR_THROW_INPUT << "VisualHullOptions::padding = " << padding
                   << ". Violated constraint: padding >= 0";
  }
  if (min_views < 1) {
    MR_THROW_INPUT << "VisualHullOptions::min_views = " << min_views
                   << ". Violated constraint: min_views >= 1";
  }
  if (target_faces < 0) {
    MR_THROW_INPUT << "VisualHullOptions::target_faces = " << target_faces
                   << ". Violated constraint: target_faces >= 0";
  }
  return true;
}

std::string VisualHullSummary::BriefReport() const {
  std::ostringstream s;
  s << "grid " << nx << "x" << ny << "x" << nz << " (voxel " << voxel_size << "), "
    << inside_nodes << " inside nodes, " << num_components << " component(s), kept "
    << num_vertices << " vertices / " << num_faces << " faces, volume " << volume << "; "
    << seconds << " s (carving " << carve_seconds << " s, surface " << extract_seconds << " s)";
  return s.str();
}

Eigen::AlignedBox3d FrustumIntersectionBox(const std::vector<PinholeView>& views) {
  if (views.empty()) MR_THROW_INPUT << "FrustumIntersectionBox: no views";
  // Point closest (least squares) to all optical axes.
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double max_dist = 0;
  for (const PinholeView& v : views) {
    const Eigen::Vector3d axis = v.R.transpose().col(2);
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    A += P;
    b += P * v.Center();
  }
  // A is symmetric positive semi-definite; it is singular iff all axes are
  // parallel.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
  if (!(eig.eigenvalues()(0) > 1e-6 * eig.eigenvalues()(2))) {
    MR_THROW_INPUT << "the optical axes of the " << views.size()
                   << " views are (nearly) parallel; give the bounding box explicitly";
  }
  const Eigen::Vector3d focus = A.ldlt().solve(b);
  for (const PinholeView& v : views) max_dist = std::max(max_dist, (v.Center() - focus).norm());
  auto seen_by_all = [&](const Eigen::Vector3d& X) {
    for (const PinholeView& v : views) {
      const Eigen::Vector3d Xc = v.WorldToCamera(X);
      if (Xc.z() <= 0 || !v.InImage(v.CameraToImage(Xc))) return false;
    }
    return true;
  };
  Eigen::AlignedBox3d search(focus.array() - max_dist, focus.array() + max_dist);
  // Two passes: coarse over the whole search box, then fine around the result.
  for (int pass = 0; pass < 2; ++pass) {
    constexpr int kSamples = 64;
    const Eigen::Vector3d step = search.sizes() / kSamples;
    Eigen::AlignedBox3d found;
    for (int k = 0; k <= kSamples; ++k) {
      for (int j = 0; j <= kSamples; ++j) {
        for (int i = 0; i <= kSamples; ++i) {
          const Eigen::Vector3d X =
              search.min() + Eigen::Vector3d(i * step.x(), j * step.y(), k * step.z());
          if (seen_by_all(X)) found.extend(X);
        }
      }
    }
    if (found.isEmpty()) {
      MR_THROW_INPUT << "the " << views.size()
                     << " views see no common region; give the bounding box explicitly";
    }
    search = Eigen::AlignedBox3d(found.min() - step, found.max() + step);
  }
  return search;
}

VisualHullSummary ComputeVisualHull(const std::vector<PinholeView>& views,
                                    const std::vector<cv::Mat>& masks,
                                    const Eigen::AlignedBox3d& bbox,
                                    const VisualHullOptions& options, Eigen::MatrixXd* V,
                                    Eigen::MatrixXi* F) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  if (views.empty()) MR_THROW_INPUT << "visual hull: no views";
  if (views.size() != masks.size()) {
    MR_THROW_INPUT << "visual hull: " << views.size() << " views but " << masks.size()
                   << " masks";
  }
  if (bbox.isEmpty() || !(bbox.sizes().array() > 0).all()) {
    MR_THROW_INPUT << "visual hull: empty bounding box";
  }
  Carver carver{views, {}, options.min_views};
  for (size_t v = 0; v < views.size(); ++v) {
    if (masks[v].empty() || masks[v].type() != CV_8UC1 || masks[v].cols != views[v].width ||
        masks[v].rows != views[v].height) {
      MR_THROW_INPUT << "visual hull: mask " << v << " is " << masks[v].cols << "x"
                     << masks[v].rows << " (type " << masks[v].type() << "), expected 8-bit "
                     << views[v].width << "x" << views[v].height;
    }
    carver.sdf.push_back(MaskSignedDistance(masks[v]));
  }

  const Eigen::AlignedBox3d box = Padded(bbox, options.padding);
  VisualHullSummary summary;
  summary.bbox = box;
  int resolution = options.resolution;
  for (int attempt = 0; attempt < 2; ++attempt) {
    const double h = box.sizes().maxCoeff() / resolution;
    // One extra layer on each side: boundary nodes are forced outside, so the
    // hull is cut flat by the padded box at worst, never left open.
    const int nx = static_cast<int>(std::ceil(box.sizes().x() / h)) + 3;
    const int ny = static_cast<int>(std::ceil(box.sizes().y() / h)) + 3;
    const int nz = static_cast<int>(std::ceil(box.sizes().z() / h)) + 3;
    const double num_nodes = static_cast<double>(nx) * ny * nz;
    if (num_nodes > kMaxNodes) {
      MR_THROW_INPUT << "visual hull: a " << nx << "x" << ny << "x" << nz << " grid ("
                     << num_nodes * 4 / (1 << 30) << " GiB) exceeds the limit of " << kMaxNodes
                     << " nodes; lower the resolution (now " << resolution << ")";
    }
    const Eigen::Vector3d origin =
        box.center() - 0.5 * h * Eigen::Vector3d(nx - 1, ny - 1, nz - 1);
    ScalarGrid grid(nx, ny, nz, origin, h);
    long inside = 0;
    const auto carve_start = std::chrono::steady_clock::now();
#pragma omp parallel for schedule(dynamic) reduction(+ : inside)
    for (int k = 0; k < nz; ++k) {
      for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
          const float value = carver.Value(grid.Position(i, j, k), -h);
          grid.At(i, j, k) = value;
          inside += value > 0;
        }
      }
    }
    summary.carve_seconds = Seconds(carve_start);
    if (inside == 0) {
      MR_THROW_INPUT << "visual hull is empty: every node of the " << nx << "x" << ny << "x"
                     << nz << " grid is outside some silhouette (check the masks, the "
                     << "bounding box and the cameras)";
    }
    const auto extract_start = std::chrono::steady_clock::now();
    ExtractIsosurface(grid, 0.0, V, F);
    summary.num_components = KeepLargestComponent(V, F);
    summary.extract_seconds = Seconds(extract_start);
    summary.nx = nx;
    summary.ny = ny;
    summary.nz = nz;
    summary.voxel_size = h;
    summary.inside_nodes = inside;
    MR_LOG(VERBOSE) << "Visual hull at resolution " << resolution << ": " << F->rows()
                    << " faces";
    if (options.target_faces == 0 || attempt == 1 || F->rows() == 0) break;
    const double ratio = std::sqrt(static_cast<double>(options.target_faces) / F->rows());
    const int next = std::clamp(static_cast<int>(std::lround(resolution * ratio)), 4, 2048);
    if (std::abs(ratio - 1) < 0.1 || next == resolution) break;
    resolution = next;
  }
  std::string why;
  MR_CHECK(IsClosedAndOriented(*F, &why)) << "visual hull surface: " << why;
  summary.num_vertices = static_cast<int>(V->rows());
  summary.num_faces = static_cast<int>(F->rows());
  summary.volume = SignedVolume(*V, *F);
  summary.seconds = Seconds(start);
  return summary;
}

}  // namespace mr
