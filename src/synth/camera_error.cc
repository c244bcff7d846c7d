#include "synth/camera_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <utility>

#include <Eigen/Geometry>
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "colmap_io/camera_models.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/statistics.h"

namespace mr {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative tolerance of the achieved RMS (the promise is 1 %).
constexpr double kRmsTolerance = 1e-3;

// The surface points one view sees: camera-frame coordinates and projections.
struct VisiblePoints {
  std::vector<Eigen::Vector3d> camera;
  std::vector<Eigen::Vector2d> image;
};

VisiblePoints FindVisible(const PinholeView& view, const Eigen::MatrixXd& points) {
  VisiblePoints visible;
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const Eigen::Vector3d Xc = view.WorldToCamera(points.row(k).transpose());
    if (!(Xc.z() > 0)) continue;
    const Eigen::Vector2d p = view.CameraToImage(Xc);
    if (!view.InImage(p)) continue;
    visible.camera.push_back(Xc);
    visible.image.push_back(p);
  }
  return visible;
}

// Rotation exp([w]x) (Rodrigues).
Eigen::Matrix3d ExpRotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// RMS displacement of the visible points' projections when the camera is
// rotated by exp([w]x) (camera side) and its centre moved by `shift_camera`
// (the world shift expressed in the camera frame): X'c = exp([w]x) (Xc - shift).
double DisplacementRms(const PinholeView& view, const VisiblePoints& visible,
                       const Eigen::Vector3d& w, const Eigen::Vector3d& shift_camera) {
  const Eigen::Matrix3d dR = ExpRotation(w);
  double sum = 0;
  for (size_t k = 0; k < visible.camera.size(); ++k) {
    const Eigen::Vector3d Xc = dR * (visible.camera[k] - shift_camera);
    if (!(Xc.z() > 0)) return kInf;
    sum += (view.CameraToImage(Xc) - visible.image[k]).squaredNorm();
  }
  return std::sqrt(sum / visible.camera.size());
}

// The scale s >= 0 of the motion direction (w, shift_camera) whose RMS
// displacement is `target` (> 0) within kRmsTolerance; `rms` receives it.
double SolveScale(const PinholeView& view, const VisiblePoints& visible, const Eigen::Vector3d& w,
                  const Eigen::Vector3d& shift_camera, double target, double* rms) {
  const auto f = [&](double s) { return DisplacementRms(view, visible, s * w, s * shift_camera); };
  // Probe: a motion far below a pixel, where the displacement is linear in s.
  const double probe = 1e-6;
  const double f_probe = f(probe);
  MR_CHECK(f_probe > 0 && std::isfinite(f_probe)) << "degenerate motion direction";
  double lo = 0, hi = kInf;  // f(lo) < target <= f(hi)
  double prev_s = 0, prev_f = 0;
  double s = target * probe / f_probe;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double value = f(s);
    if (std::abs(value - target) <= kRmsTolerance * target) {
      *rms = value;
      return s;
    }
    if (value < target) {
      lo = s;
    } else {
      hi = s;
    }
    // Secant step through the last two values; bisection (or doubling, with
    // no upper bound yet) when it leaves the bracket.
    double next = std::isfinite(value) && value != prev_f
                      ? s + (target - value) * (s - prev_s) / (value - prev_f)
                      : std::numeric_limits<double>::quiet_NaN();
    if (!(next > lo && next < hi)) next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2 * s;
    prev_s = s;
    prev_f = value;
    s = next;
  }
  MR_CHECK(false) << "pose error: no scale reaches " << target << " px (bracket " << lo << ", "
                  << hi << ")";
  return 0;
}

}  // namespace

bool CameraErrorOptions::Check() const {
  if (!(pose_error_px >= 0 && pose_error_px <= 100)) {
    MR_THROW_INPUT << "CameraErrorOptions::pose_error_px = " << pose_error_px
                   << ". Violated constraint: 0 <= pose_error_px <= 100";
  }
  if (!(focal_error_percent >= 0 && focal_error_percent <= 50)) {
    MR_THROW_INPUT << "CameraErrorOptions::focal_error_percent = " << focal_error_percent
                   << ". Violated constraint: 0 <= focal_error_percent <= 50";
  }
  return true;
}

std::string CameraErrorSummary::BriefReport() const {
  std::ostringstream s;
  s << "camera error: pose RMS " << mean_rms_px << " px mean, " << max_rms_px << " max over "
    << num_perturbed_images << " images";
  if (static_cast<int>(images.size()) > num_perturbed_images) {
    s << " (" << images.size() - num_perturbed_images << " seeing no surface left exact)";
  }
  s << "; rotation " << mean_rotation_deg << " deg mean, " << max_rotation_deg
    << " max; centre shift " << mean_center_shift << " mean, " << max_center_shift
    << " max; focal scale";
  for (const auto& [id, scale] : focal_scale) s << " " << scale;
  return s.str();
}

double ReprojectionRms(const PinholeView& true_view, const PinholeView& other_view,
                       const Eigen::MatrixXd& surface_points, int* num_visible) {
  MR_CHECK_EQ(surface_points.cols(), 3);
  const VisiblePoints visible = FindVisible(true_view, surface_points);
  if (num_visible != nullptr) *num_visible = static_cast<int>(visible.camera.size());
  if (visible.camera.empty()) return 0;
  double sum = 0;
  for (size_t k = 0; k < visible.camera.size(); ++k) {
    const Eigen::Vector3d Xc =
        other_view.WorldToCamera(true_view.R.transpose() * (visible.camera[k] - true_view.t));
    if (!(Xc.z() > 0)) return kInf;
    sum += (other_view.CameraToImage(Xc) - visible.image[k]).squaredNorm();
  }
  return std::sqrt(sum / visible.camera.size());
}

CameraErrorSummary PerturbCameras(const CameraErrorOptions& options,
                                  const Eigen::MatrixXd& surface_points, uint32_t seed,
                                  Reconstruction* model) {
  options.Check();
  MR_CHECK(model != nullptr);
  MR_CHECK_EQ(surface_points.cols(), 3);
  CameraErrorSummary summary;

  // Poses first, with the true intrinsics. Separate random streams for poses
  // and focal lengths, so that each error is the same with or without the other.
  if (options.pose_error_px > 0) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    for (auto& [image_id, image] : model->images) {
      // Draw before anything can skip the image, so that the draws of the
      // other images do not depend on it.
      Eigen::Vector3d w, u;
      for (int c = 0; c < 3; ++c) w(c) = gauss(rng);
      for (int c = 0; c < 3; ++c) u(c) = gauss(rng);
      ImageCameraError record;
      record.image_id = image_id;
      const auto camera = model->cameras.find(image.camera_id);
      MR_CHECK(camera != model->cameras.end()) << "image " << image_id << ": no camera";
      const PinholeView view = ViewFromColmap(camera->second, image);
      const VisiblePoints visible = FindVisible(view, surface_points);
      record.num_visible_points = static_cast<int>(visible.camera.size());
      if (visible.camera.empty()) {
        MR_LOG(WARNING) << "image " << image.name
                        << " sees no surface point; its pose is left exact";
        summary.images.push_back(record);
        continue;
      }
      std::vector<double> depths;
      depths.reserve(visible.camera.size());
      for (const Eigen::Vector3d& Xc : visible.camera) depths.push_back(Xc.z());
      const Eigen::Vector3d shift_world = u * Median(&depths);
      const double s = SolveScale(view, visible, w, view.R * shift_world,
                                  options.pose_error_px, &record.rms_px);
      const Eigen::Matrix3d R = ExpRotation(s * w) * view.R;
      const Eigen::Vector3d C = view.Center() + s * shift_world;
      image.qvec = RotationToQuaternion(R);
      image.tvec = -R * C;
      record.rotation_deg = s * w.norm() * 180 / kPi;
      record.center_shift = s * shift_world.norm();
      summary.images.push_back(record);
      ++summary.num_perturbed_images;
      summary.mean_rms_px += record.rms_px;
      summary.mean_rotation_deg += record.rotation_deg;
      summary.mean_center_shift += record.center_shift;
      summary.max_rms_px = std::max(summary.max_rms_px, record.rms_px);
      summary.max_rotation_deg = std::max(summary.max_rotation_deg, record.rotation_deg);
      summary.max_center_shift = std::max(summary.max_center_shift, record.center_shift);
    }
    if (summary.num_perturbed_images > 0) {
      summary.mean_rms_px /= summary.num_perturbed_images;
      summary.mean_rotation_deg /= summary.num_perturbed_images;
      summary.mean_center_shift /= summary.num_perturbed_images;
    }
  }

  // Focal lengths: f (SIMPLE_* models) or fx and fy, the first parameters.
  std::mt19937 focal_rng(seed ^ 0x9e3779b9u);
  const double e = options.focal_error_percent / 100;
  for (auto& [camera_id, camera] : model->cameras) {
    if (e == 0) {
      summary.focal_scale[camera_id] = 1;
      continue;
    }
    const double scale = (focal_rng() & 1u) ? 1 + e : 1 - e;
    const int num_focal = HasSeparateFocalLengths(camera.model) ? 2 : 1;
    MR_CHECK_GE(static_cast<int>(camera.params.size()), num_focal);
    for (int k = 0; k < num_focal; ++k) camera.params[k] *= scale;
    summary.focal_scale[camera_id] = scale;
  }
  return summary;
}

std::string CameraComparison::JsonMembers() const {
  std::ostringstream s;
  s.precision(6);
  s << "\"camera_images\": " << num_images << ", \"camera_rms_px\": " << rms_px
    << ", \"camera_max_rms_px\": " << max_rms_px << ", \"camera_max_rms_image\": \""
    << max_rms_image << "\", \"camera_max_focal_percent\": " << max_focal_percent;
  return s.str();
}

namespace {

// The views of the images of `model` and of their namesakes in `truth`, and
// the (model, true) camera ids of each.
struct MatchedViews {
  std::vector<std::string> names;
  std::vector<PinholeView> model, truth;
  std::vector<std::pair<uint32_t, uint32_t>> camera_ids;
};

MatchedViews MatchViews(const Reconstruction& model, const Reconstruction& truth) {
  std::map<std::string, const Image*> true_by_name;
  for (const auto& [id, image] : truth.images) true_by_name[image.name] = &image;
  MatchedViews matched;
  for (const auto& [id, image] : model.images) {
    const auto match = true_by_name.find(image.name);
    if (match == true_by_name.end()) {
      MR_THROW_INPUT << "image " << image.name << " (id " << id
                     << ") is not in the true model";
    }
    const Image& true_image = *match->second;
    matched.names.push_back(image.name);
    matched.model.push_back(ViewFromColmap(model.cameras.at(image.camera_id), image));
    matched.truth.push_back(ViewFromColmap(truth.cameras.at(true_image.camera_id), true_image));
    matched.camera_ids.emplace_back(image.camera_id, true_image.camera_id);
  }
  return matched;
}

// Residual of AlignCamerasToTruth: the projection of true point X through the
// model's view carried into the true world by the similarity (angle-axis
// rotation, translation, log scale) minus its true projection.
struct AlignmentResidual {
  AlignmentResidual(const PinholeView& view, const Eigen::Vector3d& X, const Eigen::Vector2d& x)
      : view(view), X(X), x(x) {}

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* log_scale, T* residual) const {
    // The carried view sees X where the model's view saw Rᵀ (X - t) / s; the
    // scale drops out of the projection, so R_i Rᵀ (X - t) + s t_i is used.
    const T shifted[3] = {T(X.x()) - translation[0], T(X.y()) - translation[1],
                          T(X.z()) - translation[2]};
    const T inverse[3] = {-rotation[0], -rotation[1], -rotation[2]};
    T Y[3];
    ceres::AngleAxisRotatePoint(inverse, shifted, Y);
    const T s = exp(log_scale[0]);
    T Z[3];
    for (int r = 0; r < 3; ++r) {
      Z[r] = view.R(r, 0) * Y[0] + view.R(r, 1) * Y[1] + view.R(r, 2) * Y[2] + s * view.t(r);
    }
    residual[0] = view.fx * Z[0] / Z[2] + view.cx - x.x();
    residual[1] = view.fy * Z[1] / Z[2] + view.cy - x.y();
    return true;
  }

  const PinholeView view;
  const Eigen::Vector3d X;
  const Eigen::Vector2d x;
};

}  // namespace

Eigen::MatrixXd Similarity3::Apply(const Eigen::MatrixXd& points) const {
  MR_CHECK_EQ(points.cols(), 3);
  Eigen::MatrixXd out(points.rows(), 3);
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    out.row(k) = (*this)(points.row(k).transpose()).transpose();
  }
  return out;
}

PinholeView Similarity3::Apply(const PinholeView& view) const {
  // X_c = R_i X + t_i with X = Rᵀ (X' - t) / s, times s (the projection is
  // unchanged): R_i Rᵀ X' + s t_i - R_i Rᵀ t.
  PinholeView out = view;
  out.R = view.R * rotation.transpose();
  out.t = scale * view.t - out.R * translation;
  return out;
}

Similarity3 AlignCamerasToTruth(const Reconstruction& model, const Reconstruction& truth,
                                const Eigen::MatrixXd& surface_points) {
  MR_CHECK_EQ(surface_points.cols(), 3);
  const MatchedViews matched = MatchViews(model, truth);
  const int n = static_cast<int>(matched.model.size());
  Similarity3 start;
  if (n >= 3) {
    Eigen::Matrix3Xd from(3, n), to(3, n);
    for (int i = 0; i < n; ++i) {
      from.col(i) = matched.model[i].Center();
      to.col(i) = matched.truth[i].Center();
    }
    const Eigen::Matrix4d T = Eigen::umeyama(from, to, true);
    const double scale = T.block<3, 3>(0, 0).determinant();
    if (std::isfinite(scale) && scale > 0) {
      start.scale = std::cbrt(scale);
      start.rotation = T.block<3, 3>(0, 0) / start.scale;
      start.translation = T.block<3, 1>(0, 3);
    }
  }
  double rotation[3], translation[3], log_scale = std::log(start.scale);
  const Eigen::AngleAxisd start_rotation(start.rotation);
  const Eigen::Vector3d start_vector = start_rotation.angle() * start_rotation.axis();
  for (int r = 0; r < 3; ++r) rotation[r] = start_vector(r);
  for (int r = 0; r < 3; ++r) translation[r] = start.translation(r);
  ceres::Problem problem;
  constexpr int kMaxPointsPerView = 200;
  for (int i = 0; i < n; ++i) {
    const PinholeView& true_view = matched.truth[i];
    const VisiblePoints visible = FindVisible(true_view, surface_points);
    const size_t stride = std::max<size_t>(1, visible.camera.size() / kMaxPointsPerView);
    for (size_t k = 0; k < visible.camera.size(); k += stride) {
      const Eigen::Vector3d X = true_view.R.transpose() * (visible.camera[k] - true_view.t);
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<AlignmentResidual, 2, 3, 3, 1>(
              new AlignmentResidual(matched.model[i], X, visible.image[k])),
          nullptr, rotation, translation, &log_scale);
    }
  }
  if (problem.NumResidualBlocks() == 0) return start;
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  Similarity3 result;
  result.scale = std::exp(log_scale);
  const Eigen::Vector3d w(rotation[0], rotation[1], rotation[2]);
  result.rotation = ExpRotation(w);
  result.translation = Eigen::Vector3d(translation[0], translation[1], translation[2]);
  return result;
}

CameraComparison CompareCameras(const Reconstruction& model, const Reconstruction& truth,
                                const Eigen::MatrixXd& surface_points,
                                const Similarity3* model_to_truth) {
  const MatchedViews matched = MatchViews(model, truth);
  CameraComparison comparison;
  double sum_sq = 0;
  std::set<std::pair<uint32_t, uint32_t>> cameras_seen;  // (model, true) camera ids
  for (size_t k = 0; k < matched.model.size(); ++k) {
    const PinholeView view =
        model_to_truth != nullptr ? model_to_truth->Apply(matched.model[k]) : matched.model[k];
    const PinholeView& true_view = matched.truth[k];
    const double rms = ReprojectionRms(true_view, view, surface_points);
    sum_sq += rms * rms;
    if (rms > comparison.max_rms_px || comparison.num_images == 0) {
      comparison.max_rms_px = rms;
      comparison.max_rms_image = matched.names[k];
    }
    ++comparison.num_images;
    if (!cameras_seen.insert(matched.camera_ids[k]).second) continue;
    for (const double ratio : {view.fx / true_view.fx, view.fy / true_view.fy}) {
      comparison.max_focal_percent =
          std::max(comparison.max_focal_percent, 100 * std::abs(ratio - 1));
    }
  }
  if (comparison.num_images > 0) comparison.rms_px = std::sqrt(sum_sq / comparison.num_images);
  return comparison;
}

}  // namespace mr
