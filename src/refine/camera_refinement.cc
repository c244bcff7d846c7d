#include "refine/camera_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>

#include <Eigen/Geometry>
#include <ceres/ceres.h>
#include <ceres/product_manifold.h>
#include <opencv2/imgproc.hpp>

#include "geometry/mesh.h"
#include "refine/pyramid.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/program.h"
#include "util/statistics.h"

namespace mr {
namespace internal {
namespace {

using RowMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

// Samples seen at |cos(ray, normal)| below this (60 degrees) in either view
// are dropped: a pixel's footprint maps onto a strongly anisotropic area in
// the other view there, which the point-wise comparison does not model (on
// the test scene, 0.2 instead of 0.5 triples the drift from the true poses).
constexpr double kMinCosAngle = 0.5;
// I_i(p) and the bilinear stencil of I_j(q) must lie inside the surface: the
// (2 kMargin + 1)^2 pixels around p, and around q's pixel, see the surface
// (no silhouette blend; in j, at the point's depth).
constexpr int kMargin = 2;
// Depth test in view j: within this many pixel footprints / cos of the
// rendered depth (as PairTermOptions::visibility_tolerance_px).
constexpr double kVisibilityTolerancePx = 1.5;
// Projections closer than this to the border of image j are dropped, so that
// a pose change of a pixel or two keeps the bilinear stencil inside.
constexpr double kBorderPx = 3.0;
// Samples with a weaker gradient in view j carry no pose information.
constexpr double kMinGradient = 1e-3;

// The residual and its Jacobian with respect to every parameter (any pointer
// may be null). Returns false where the warp is undefined (ray parallel to
// the plane, plane behind camera i, point behind camera j).
// `delta` (may be null: 0) shifts the face plane: n·X = plane_offset + δ.
// Image j is read by cubic interpolation, or bilinear without `cubic`.
bool EvaluatePhotometric(const PhotometricSample& s, const cv::Mat& image_j, bool cubic,
                         const double* Ri_p,
                         const double* Ci_p, const double* Ki, const double* Rj_p,
                         const double* Cj_p, const double* Kj, const double* ab,
                         const double* delta, double* residual, double* J_Ri, double* J_Ci,
                         double* J_Ki, double* J_Rj, double* J_Cj, double* J_Kj, double* J_ab,
                         double* J_delta) {
  const Eigen::Map<const RowMatrix3d> Ri(Ri_p), Rj(Rj_p);
  const Eigen::Map<const Eigen::Vector3d> Ci(Ci_p), Cj(Cj_p);
  // Back-projection: m = K_i⁻¹ (p, 1), ray w = R_iᵀ m, hit X = C_i + d w.
  const Eigen::Vector3d m((s.point.x() - Ki[2]) / Ki[0], (s.point.y() - Ki[3]) / Ki[1], 1.0);
  const Eigen::Vector3d w = Ri.transpose() * m;
  const double nw = s.normal.dot(w);
  if (!(std::abs(nw) > 1e-12)) return false;
  const double offset = s.plane_offset + (delta != nullptr ? delta[0] : 0.0);
  const double d = (offset - s.normal.dot(Ci)) / nw;
  if (!(d > 0)) return false;
  const Eigen::Vector3d X = Ci + d * w;
  // Projection into view j.
  const Eigen::Vector3d y = X - Cj;
  const Eigen::Vector3d Xc = Rj * y;
  if (!(Xc.z() > 1e-12)) return false;
  const double iz = 1.0 / Xc.z();
  const double u = Xc.x() * iz, v = Xc.y() * iz;
  Eigen::Vector2d g;
  const double qx = Kj[0] * u + Kj[2], qy = Kj[1] * v + Kj[3];
  const double intensity_j =
      cubic ? SampleCubic(image_j, qx, qy, &g) : SampleBilinear(image_j, qx, qy, &g);
  residual[0] = intensity_j - (ab[0] * s.intensity + ab[1]);

  if (J_ab != nullptr) {
    J_ab[0] = -s.intensity;
    J_ab[1] = -1.0;
  }
  if (J_Kj != nullptr) {
    J_Kj[0] = g.x() * u;
    J_Kj[1] = g.y() * v;
    J_Kj[2] = g.x();
    J_Kj[3] = g.y();
  }
  if (J_Ri == nullptr && J_Ci == nullptr && J_Ki == nullptr && J_Rj == nullptr &&
      J_Cj == nullptr && J_delta == nullptr) {
    return true;
  }
  // G = ∂r/∂X_c = ∇I_jᵀ ∂q/∂X_c.
  const Eigen::RowVector3d G(g.x() * Kj[0] * iz, g.y() * Kj[1] * iz,
                             -(g.x() * Kj[0] * u + g.y() * Kj[1] * v) * iz);
  if (J_Rj != nullptr) {
    // X_c = R_j y: ∂X_c(r)/∂R_j(r, c) = y(c).
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) J_Rj[3 * r + c] = G(r) * y(c);
    }
  }
  const Eigen::RowVector3d H = G * Rj;  // ∂r/∂X
  if (J_Cj != nullptr) {
    for (int k = 0; k < 3; ++k) J_Cj[k] = -H(k);
  }
  // The plane's shift moves X along the ray: ∂X/∂δ = w / (n·w).
  if (J_delta != nullptr) J_delta[0] = H.dot(w) / nw;
  // X moves along the ray onto the plane: ∂X/∂C_i = I - w nᵀ / (n·w),
  // ∂X/∂w = d (I - w nᵀ / (n·w)).
  const Eigen::RowVector3d HP = H - (H.dot(w) / nw) * s.normal.transpose();
  if (J_Ci != nullptr) {
    for (int k = 0; k < 3; ++k) J_Ci[k] = HP(k);
  }
  const Eigen::RowVector3d E = d * HP;  // ∂r/∂w
  if (J_Ri != nullptr) {
    // w = R_iᵀ m: ∂w(c)/∂R_i(r, c) = m(r).
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) J_Ri[3 * r + c] = E(c) * m(r);
    }
  }
  if (J_Ki != nullptr) {
    const Eigen::Vector3d dm = Ri * E.transpose();  // ∂r/∂m
    J_Ki[0] = -dm(0) * m(0) / Ki[0];
    J_Ki[1] = -dm(1) * m(1) / Ki[1];
    J_Ki[2] = -dm(0) / Ki[0];
    J_Ki[3] = -dm(1) / Ki[1];
  }
  return true;
}

// Parameters: pose_i (R_i, C_i: 12), K_i, pose_j, K_j, (a, b) and, with a
// free surface, δ; views i and j of one camera (shared intrinsics): pose_i,
// pose_j, K, (a, b)[, δ].
class PhotometricCost : public ceres::CostFunction {
 public:
  PhotometricCost(const PhotometricSample& sample, const cv::Mat& image_j, bool shared_intrinsics,
                  bool free_surface, bool cubic)
      : sample_(sample),
        image_j_(&image_j),
        shared_(shared_intrinsics),
        free_(free_surface),
        cubic_(cubic) {
    set_num_residuals(1);
    std::vector<int32_t>* sizes = mutable_parameter_block_sizes();
    *sizes = shared_ ? std::vector<int32_t>{12, 12, 4, 2} : std::vector<int32_t>{12, 4, 12, 4, 2};
    if (free_) sizes->push_back(1);
  }
  bool Evaluate(double const* const* p, double* residual, double** J) const override {
    // A pose block is (R row-major, C); its Jacobian row likewise.
    const auto jac = [J](int k, int offset) {
      return J == nullptr || J[k] == nullptr ? nullptr : J[k] + offset;
    };
    if (!shared_) {
      return EvaluatePhotometric(sample_, *image_j_, cubic_, p[0], p[0] + 9, p[1], p[2], p[2] + 9,
                                 p[3],
                                 p[4], free_ ? p[5] : nullptr, residual, jac(0, 0), jac(0, 9),
                                 jac(1, 0), jac(2, 0), jac(2, 9), jac(3, 0), jac(4, 0),
                                 free_ ? jac(5, 0) : nullptr);
    }
    double J_Ki[4], J_Kj[4];
    const bool want_k = jac(2, 0) != nullptr;
    if (!EvaluatePhotometric(sample_, *image_j_, cubic_, p[0], p[0] + 9, p[2], p[1], p[1] + 9, p[2],
                             p[3],
                             free_ ? p[4] : nullptr, residual, jac(0, 0), jac(0, 9),
                             want_k ? J_Ki : nullptr, jac(1, 0), jac(1, 9),
                             want_k ? J_Kj : nullptr, jac(3, 0), free_ ? jac(4, 0) : nullptr)) {
      return false;
    }
    if (want_k) {
      for (int k = 0; k < 4; ++k) J[2][k] = J_Ki[k] + J_Kj[k];
    }
    return true;
  }

 private:
  PhotometricSample sample_;
  const cv::Mat* image_j_;  // by address: a cv::Mat header takes 96 bytes
  bool shared_;
  bool free_;
  bool cubic_;
};

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d h;
  h << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return h;
}

Eigen::Matrix3d ExpRotation(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
}

Eigen::Vector3d LogRotation(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

class RotationMatrixManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 9; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    Eigen::Map<RowMatrix3d> out(x_plus_delta);
    out = ExpRotation(Eigen::Vector3d(delta[0], delta[1], delta[2])) *
          Eigen::Map<const RowMatrix3d>(x);
    return true;
  }
  bool PlusJacobian(const double* x, double* jacobian) const override {
    // Column k: Hat(e_k) R, row-major entries.
    const Eigen::Map<const RowMatrix3d> R(x);
    Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> J(jacobian);
    for (int k = 0; k < 3; ++k) {
      const RowMatrix3d D = Hat(Eigen::Vector3d::Unit(k)) * R;
      for (int e = 0; e < 9; ++e) J(e, k) = D(e / 3, e % 3);
    }
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    const Eigen::Matrix3d D =
        Eigen::Map<const RowMatrix3d>(y) * Eigen::Map<const RowMatrix3d>(x).transpose();
    Eigen::Map<Eigen::Vector3d> out(y_minus_x);
    out = LogRotation(D);
    return true;
  }
  bool MinusJacobian(const double* x, double* jacobian) const override {
    // Minus(Y, X) = vee(skew(Y Xᵀ)) to first order at Y = X; with A = dY Xᵀ,
    // δ0 = (A21 - A12) / 2, δ1 = (A02 - A20) / 2, δ2 = (A10 - A01) / 2 and
    // ∂A(a, b)/∂Y(a, c) = X(b, c).
    const Eigen::Map<const RowMatrix3d> X(x);
    Eigen::Map<Eigen::Matrix<double, 3, 9, Eigen::RowMajor>> J(jacobian);
    J.setZero();
    const int pairs[3][2] = {{2, 1}, {0, 2}, {1, 0}};
    for (int k = 0; k < 3; ++k) {
      const int a = pairs[k][0], b = pairs[k][1];
      for (int c = 0; c < 3; ++c) {
        J(k, 3 * a + c) += 0.5 * X(b, c);
        J(k, 3 * b + c) -= 0.5 * X(a, c);
      }
    }
    return true;
  }
};

// Prior on the rotation of a pose block (R row-major, C): vee(skew(R R0ᵀ)) /
// sigma, which is sin(angle) * axis / sigma.
struct RotationPrior {
  RotationPrior(const Eigen::Matrix3d& R0, double sigma) : R0(R0), inv_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* R, T* residual) const {
    T D[3][3];  // R R0ᵀ
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        D[a][b] = R[3 * a] * R0(b, 0) + R[3 * a + 1] * R0(b, 1) + R[3 * a + 2] * R0(b, 2);
      }
    }
    residual[0] = 0.5 * (D[2][1] - D[1][2]) * inv_sigma;
    residual[1] = 0.5 * (D[0][2] - D[2][0]) * inv_sigma;
    residual[2] = 0.5 * (D[1][0] - D[0][1]) * inv_sigma;
    return true;
  }
  Eigen::Matrix3d R0;
  double inv_sigma;
};

// Prior on the centre of a pose block: (C - C0) / sigma.
struct CenterPrior {
  CenterPrior(const Eigen::Vector3d& C0, double sigma) : C0(C0), inv_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    const T* C = pose + 9;
    for (int k = 0; k < 3; ++k) residual[k] = (C[k] - C0(k)) * inv_sigma;
    return true;
  }
  Eigen::Vector3d C0;
  double inv_sigma;
};

// Prior on a face plane's offset: δ / sigma.
struct OffsetPrior {
  explicit OffsetPrior(double sigma) : inv_sigma(1.0 / sigma) {}
  template <typename T>
  bool operator()(const T* delta, T* residual) const {
    residual[0] = delta[0] * inv_sigma;
    return true;
  }
  double inv_sigma;
};

// Prior on fx and fy of an intrinsics block (fx, fy, cx, cy).
struct FocalPrior {
  FocalPrior(double fx0, double fy0, double sigma_fraction)
      : fx0(fx0),
        fy0(fy0),
        inv_sx(1.0 / (sigma_fraction * fx0)),
        inv_sy(1.0 / (sigma_fraction * fy0)) {}
  template <typename T>
  bool operator()(const T* K, T* residual) const {
    residual[0] = (K[0] - fx0) * inv_sx;
    residual[1] = (K[1] - fy0) * inv_sy;
    return true;
  }
  double fx0, fy0, inv_sx, inv_sy;
};

// The datum of a camera set: its mean centre shift, mean rotation change
// (world frame) and scale change from the reference cameras (R0_k, C0_k), to
// first order the translation, rotation and scale of the similarity that
// carries the reference set onto the current one. Parameter blocks: the
// poses (R row-major, C: 12 values) of the cameras; residuals (7):
//   (1/N) Σ (C_k - C0_k) / sigma_center
//   (1/N) Σ vee(skew(R0_kᵀ R_k)) / sigma_rotation
//   Σ (C_k - C0_k)·(C0_k - c̄0) / Σ |C0_k - c̄0|² / sigma_scale
// The three are independent to first order: a common shift leaves the
// rotation and scale terms at 0, a rotation of the set about c̄0 the shift
// and scale terms, and a scaling about c̄0 the shift and rotation terms.
struct CameraSetDatum {
  CameraSetDatum(std::vector<Eigen::Matrix3d> R0, std::vector<Eigen::Vector3d> C0,
                 double sigma_center, double sigma_rotation, double sigma_scale)
      : R0(std::move(R0)),
        C0(std::move(C0)),
        inv_center(1.0 / sigma_center),
        inv_rotation(1.0 / sigma_rotation),
        inv_scale(1.0 / sigma_scale) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& c : this->C0) mean += c;
    mean /= static_cast<double>(this->C0.size());
    double spread = 0;
    for (const Eigen::Vector3d& c : this->C0) {
      radial.push_back(c - mean);
      spread += (c - mean).squaredNorm();
    }
    for (Eigen::Vector3d& r : radial) r = spread > 0 ? Eigen::Vector3d(r / spread) : Eigen::Vector3d::Zero();
  }
  template <typename T>
  bool operator()(T const* const* blocks, T* residual) const {
    const int n = static_cast<int>(C0.size());
    for (int e = 0; e < 7; ++e) residual[e] = T(0);
    for (int k = 0; k < n; ++k) {
      const T* R = blocks[k];
      const T* C = blocks[k] + 9;
      T M[3][3];  // R0ᵀ R
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          M[a][b] = R0[k](0, a) * R[b] + R0[k](1, a) * R[3 + b] + R0[k](2, a) * R[6 + b];
        }
      }
      residual[3] += 0.5 * (M[2][1] - M[1][2]);
      residual[4] += 0.5 * (M[0][2] - M[2][0]);
      residual[5] += 0.5 * (M[1][0] - M[0][1]);
      for (int e = 0; e < 3; ++e) {
        const T shift = C[e] - C0[k](e);
        residual[e] += shift;
        residual[6] += shift * radial[k](e);
      }
    }
    for (int e = 0; e < 3; ++e) {
      residual[e] *= inv_center / n;
      residual[3 + e] *= inv_rotation / n;
    }
    residual[6] *= inv_scale;
    return true;
  }
  std::vector<Eigen::Matrix3d> R0;
  std::vector<Eigen::Vector3d> C0;
  std::vector<Eigen::Vector3d> radial;  // (C0_k - c̄0) / Σ |C0_k - c̄0|²
  double inv_center, inv_rotation, inv_scale;
};

}  // namespace

ceres::CostFunction* NewPhotometricCost(const PhotometricSample& sample, const cv::Mat& image_j,
                                        bool shared_intrinsics, bool free_surface,
                                        bool cubic_interpolation) {
  MR_CHECK_EQ(image_j.type(), CV_32F);
  return new PhotometricCost(sample, image_j, shared_intrinsics, free_surface,
                             cubic_interpolation);
}

ceres::Manifold* NewRotationMatrixManifold() { return new RotationMatrixManifold(); }

ceres::Manifold* NewPoseManifold() {
  return new ceres::ProductManifold<RotationMatrixManifold, ceres::EuclideanManifold<3>>();
}

ceres::CostFunction* NewCameraSetDatumCost(const std::vector<Eigen::Matrix3d>& R0,
                                           const std::vector<Eigen::Vector3d>& C0,
                                           double sigma_center, double sigma_rotation,
                                           double sigma_scale) {
  MR_CHECK(R0.size() == C0.size() && C0.size() >= 2);
  auto* cost = new ceres::DynamicAutoDiffCostFunction<CameraSetDatum, 4>(
      new CameraSetDatum(R0, C0, sigma_center, sigma_rotation, sigma_scale));
  for (size_t k = 0; k < C0.size(); ++k) cost->AddParameterBlock(12);
  cost->SetNumResiduals(7);
  return cost;
}

std::vector<PhotometricSample> SelectSamples(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                             const Eigen::MatrixXd& face_normals,
                                             const PinholeView& view_i,
                                             const RenderBuffers& render_i, const cv::Mat& image_i,
                                             const PinholeView& view_j,
                                             const RenderBuffers& render_j, const cv::Mat& image_j,
                                             int max_samples) {
  MR_CHECK_EQ(render_i.width, view_i.width);
  MR_CHECK_EQ(render_j.width, view_j.width);
  const int wi = view_i.width, hi = view_i.height, wj = view_j.width, hj = view_j.height;
  const Eigen::Vector3d Ci = view_i.Center();
  const Eigen::Vector3d Cj = view_j.Center();
  // I_i(p) must be a pixel of the surface alone (no silhouette blend): the
  // (2 kMargin + 1)^2 pixels around it see the surface (the foreground
  // eroded, the image's outside counting as background).
  cv::Mat interior(hi, wi, CV_8U);
  for (int r = 0; r < hi; ++r) {
    for (int c = 0; c < wi; ++c) interior.at<uint8_t>(r, c) = render_i.FaceAt(r, c) >= 0 ? 255 : 0;
  }
  cv::erode(interior, interior,
            cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kMargin + 1, 2 * kMargin + 1)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  std::vector<PhotometricSample> candidates;
  for (int r = 0; r < hi; ++r) {
    const uint8_t* interior_row = interior.ptr<uint8_t>(r);
    for (int c = 0; c < wi; ++c) {
      if (interior_row[c] == 0) continue;
      const int f = render_i.FaceAt(r, c);
      const Eigen::Vector3d n = face_normals.row(f);
      const Eigen::Vector3d ray = view_i.RayDirection(c + 0.5, r + 0.5);
      if (std::abs(n.dot(ray.normalized())) < kMinCosAngle) continue;
      const double offset = n.dot(Eigen::Vector3d(V.row(F(f, 0))));
      const double d = (offset - n.dot(Ci)) / n.dot(ray);
      if (!(d > 0)) continue;
      const Eigen::Vector3d X = Ci + d * ray;
      const Eigen::Vector3d xj = view_j.WorldToCamera(X);
      if (!(xj.z() > 0)) continue;
      const Eigen::Vector2d q = view_j.CameraToImage(xj);
      if (!(q.x() >= kBorderPx && q.y() >= kBorderPx && q.x() <= wj - kBorderPx &&
            q.y() <= hj - kBorderPx)) {
        continue;
      }
      const double cos_j = std::abs(n.dot((X - Cj).normalized()));
      if (cos_j < kMinCosAngle) continue;
      // Visible in j: the pixels around q see the surface at X's depth.
      const int qc = static_cast<int>(q.x()), qr = static_cast<int>(q.y());
      const double tolerance = kVisibilityTolerancePx * xj.z() / view_j.fx / std::max(cos_j, 0.2);
      if (render_j.FaceAt(qr, qc) != f &&
          !(std::abs(render_j.DepthAt(qr, qc) - xj.z()) <= tolerance)) {
        continue;
      }
      bool visible = true;
      for (int dr = -kMargin; dr <= kMargin && visible; ++dr) {
        for (int dc = -kMargin; dc <= kMargin && visible; ++dc) {
          const int rr = qr + dr, cc = qc + dc;
          visible = rr >= 0 && cc >= 0 && rr < hj && cc < wj && render_j.FaceAt(rr, cc) >= 0 &&
                    std::abs(render_j.DepthAt(rr, cc) - xj.z()) <= 3 * tolerance;
        }
      }
      if (!visible) continue;
      Eigen::Vector2d grad;
      SampleBilinear(image_j, q.x(), q.y(), &grad);
      const double score = grad.norm();
      if (!(score >= kMinGradient)) continue;
      PhotometricSample s;
      s.point = Eigen::Vector2d(c + 0.5, r + 0.5);
      s.normal = n;
      s.plane_offset = offset;
      s.intensity = image_i.at<float>(r, c);
      s.score = score;
      s.face = f;
      s.footprint = d / view_i.fx;  // d is the depth: the ray has z = 1 in view i
      candidates.push_back(s);
    }
  }
  if (static_cast<int>(candidates.size()) <= max_samples) return candidates;

  // Spread: cells of s x s pixels with s ~ 2 sqrt(candidates / max_samples)
  // (about 4 samples per cell for a dense region); each cell's best first,
  // then each cell's second best, ...; within a round, the strongest first.
  const int cell = std::max(
      1, static_cast<int>(2.0 * std::sqrt(static_cast<double>(candidates.size()) / max_samples)));
  const int cells_x = (wi + cell - 1) / cell;
  std::stable_sort(
      candidates.begin(), candidates.end(),
      [](const PhotometricSample& a, const PhotometricSample& b) { return a.score > b.score; });
  std::unordered_map<int, int> taken;
  std::vector<std::pair<int, int>> order;  // (rank in its cell, index by score)
  order.reserve(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    const int key = static_cast<int>(candidates[k].point.y() / cell) * cells_x +
                    static_cast<int>(candidates[k].point.x() / cell);
    order.emplace_back(taken[key]++, static_cast<int>(k));
  }
  std::sort(order.begin(), order.end());
  std::vector<PhotometricSample> selected;
  selected.reserve(max_samples);
  for (int k = 0; k < max_samples; ++k) selected.push_back(candidates[order[k].second]);
  return selected;
}

StopOnRejectedStep::StopOnRejectedStep(double below) : below_(below) {}

ceres::CallbackReturnType StopOnRejectedStep::operator()(const ceres::IterationSummary& s) {
  if (s.iteration == 0) return ceres::SOLVER_CONTINUE;
  if (s.step_is_successful) {
    last_decrease_ = s.cost_change / (s.cost + s.cost_change);
    return ceres::SOLVER_CONTINUE;
  }
  return last_decrease_ < below_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
}

}  // namespace internal

bool CameraRefinementOptions::Check() const {
  if (mode != "poses" && mode != "poses_intrinsics") {
    MR_THROW_INPUT << "CameraRefinementOptions::mode = " << mode
                   << ". Violated constraint: mode is poses or poses_intrinsics";
  }
  if (interpolation != "cubic" && interpolation != "bilinear") {
    MR_THROW_INPUT << "CameraRefinementOptions::interpolation = " << interpolation
                   << ". Violated constraint: interpolation is cubic or bilinear";
  }
  if (max_samples_per_pair < 1) {
    MR_THROW_INPUT << "CameraRefinementOptions::max_samples_per_pair = " << max_samples_per_pair
                   << ". Violated constraint: max_samples_per_pair >= 1";
  }
  const auto positive = [](const char* name, double value) {
    if (!(value > 0 && std::isfinite(value))) {
      MR_THROW_INPUT << "CameraRefinementOptions::" << name << " = " << value
                     << ". Violated constraint: 0 < " << name << " < inf";
    }
  };
  positive("intensity_sigma", intensity_sigma);
  positive("huber_delta", huber_delta);
  positive("prior_rotation_deg", prior_rotation_deg);
  positive("prior_center_px", prior_center_px);
  positive("prior_focal_percent", prior_focal_percent);
  if (!(surface_sigma_px >= 0 && std::isfinite(surface_sigma_px))) {
    MR_THROW_INPUT << "CameraRefinementOptions::surface_sigma_px = " << surface_sigma_px
                   << ". Violated constraint: 0 <= surface_sigma_px < inf";
  }
  if (!(datum_sigma_px >= 0 && std::isfinite(datum_sigma_px))) {
    MR_THROW_INPUT << "CameraRefinementOptions::datum_sigma_px = " << datum_sigma_px
                   << ". Violated constraint: 0 <= datum_sigma_px < inf";
  }
  if (!(function_tolerance > 0 && function_tolerance < 1)) {
    MR_THROW_INPUT << "CameraRefinementOptions::function_tolerance = " << function_tolerance
                   << ". Violated constraint: 0 < function_tolerance < 1";
  }
  if (max_iterations < 1) {
    MR_THROW_INPUT << "CameraRefinementOptions::max_iterations = " << max_iterations
                   << ". Violated constraint: max_iterations >= 1";
  }
  if (max_render_mb < 1) {
    MR_THROW_INPUT << "CameraRefinementOptions::max_render_mb = " << max_render_mb
                   << ". Violated constraint: max_render_mb >= 1";
  }
  if (max_problem_mb < 1) {
    MR_THROW_INPUT << "CameraRefinementOptions::max_problem_mb = " << max_problem_mb
                   << ". Violated constraint: max_problem_mb >= 1";
  }
  return true;
}

namespace {

constexpr double kDegree = M_PI / 180.0;

double MaxOf(const std::vector<double>& values) {
  double m = 0;
  for (double v : values) m = std::max(m, v);
  return m;
}

// Median of depth / fx over the pixels that see the mesh; 0 if none.
double MedianFootprint(const PinholeView& view, const RenderBuffers& render) {
  std::vector<float> depths;
  for (size_t k = 0; k < render.face_id.size(); ++k) {
    if (render.face_id[k] >= 0) depths.push_back(render.depth[k]);
  }
  if (depths.empty()) return 0;
  return Median(&depths) / view.fx;
}

// Which of `num_views` views take part in a pair (pairs naming a view out of
// range are left to CheckInputs).
std::vector<char> ViewsInPairs(const std::vector<std::pair<int, int>>& pairs, int num_views) {
  std::vector<char> involved(num_views, 0);
  for (const auto& [i, j] : pairs) {
    if (i >= 0 && j >= 0 && i < num_views && j < num_views) involved[i] = involved[j] = 1;
  }
  return involved;
}

void CheckInputs(const std::vector<cv::Mat>& gray_images,
                 const std::vector<std::pair<int, int>>& pairs, const Eigen::MatrixXd& V,
                 const Eigen::MatrixXi& F, const std::vector<int>& camera_of_view,
                 const std::vector<PinholeView>& views) {
  const int num_views = static_cast<int>(views.size());
  if (static_cast<int>(gray_images.size()) != num_views) {
    MR_THROW_INPUT << "RefineCameras: " << gray_images.size() << " images for " << num_views
                   << " views; expected one image per view";
  }
  const std::vector<char> involved = ViewsInPairs(pairs, num_views);
  for (int i = 0; i < num_views; ++i) {
    const cv::Mat& image = gray_images[i];
    if (!involved[i] && image.empty()) continue;
    if (image.type() != CV_32F || image.cols != views[i].width || image.rows != views[i].height) {
      MR_THROW_INPUT << "RefineCameras: image " << i << " is " << image.cols << "x" << image.rows
                     << " of OpenCV type " << image.type() << "; expected CV_32F (type " << CV_32F
                     << ") at the view's " << views[i].width << "x" << views[i].height;
    }
  }
  for (const auto& [i, j] : pairs) {
    if (i < 0 || j < 0 || i >= num_views || j >= num_views || i == j) {
      MR_THROW_INPUT << "RefineCameras: pair (" << i << ", " << j
                     << ") is not two distinct views among " << num_views;
    }
  }
  if (V.cols() != 3 || F.cols() != 3 || F.rows() == 0) {
    MR_THROW_INPUT << "RefineCameras: mesh is " << V.rows() << "x" << V.cols() << " vertices, "
                   << F.rows() << "x" << F.cols() << " faces; expected #V by 3 and #F by 3, #F > 0";
  }
  if (!camera_of_view.empty() && static_cast<int>(camera_of_view.size()) != num_views) {
    MR_THROW_INPUT << "RefineCameras: camera_of_view has " << camera_of_view.size()
                   << " entries for " << num_views << " views; expected one per view or none";
  }
}

// The parameter blocks of the problem (their addresses must not move).
struct CameraParameters {
  // Per view: the row-major cam_from_world rotation and the centre, one
  // block (the Schur complement then updates one cell per pair of views).
  std::vector<std::array<double, 12>> pose;
  // Intrinsics (fx, fy, cx, cy): one block per camera (poses_intrinsics) or
  // per view (poses, held constant), and the camera id of each block.
  std::vector<std::array<double, 4>> intrinsics;
  std::vector<int> block_of_view;
  std::vector<int> camera_of_block;
  std::vector<std::array<double, 2>> brightness;  // per ordered pair: a, b
  // Per face (free surface only): the offset δ_f of its plane, and the 1-sigma
  // of its prior (0 for faces without samples).
  std::vector<double> surface_offset;
  std::vector<double> surface_sigma;
};

// Rotations, centres and intrinsics blocks from the views; throws InputError
// if views of one camera start with different intrinsics.
CameraParameters InitialParameters(const std::vector<PinholeView>& views,
                                   const std::vector<int>& camera_of_view, bool per_camera) {
  const int num_views = static_cast<int>(views.size());
  CameraParameters p;
  p.pose.resize(num_views);
  p.block_of_view.resize(num_views);
  std::map<int, int> block_of_camera;
  std::vector<int> first_view_of_block;
  for (int i = 0; i < num_views; ++i) {
    const PinholeView& v = views[i];
    Eigen::Map<internal::RowMatrix3d>(p.pose[i].data()) = v.R;
    Eigen::Map<Eigen::Vector3d>(p.pose[i].data() + 9) = v.Center();
    const int camera = camera_of_view.empty() ? i : camera_of_view[i];
    const std::array<double, 4> k = {v.fx, v.fy, v.cx, v.cy};
    const auto [it, inserted] =
        block_of_camera.emplace(per_camera ? camera : i, static_cast<int>(p.intrinsics.size()));
    p.block_of_view[i] = it->second;
    if (inserted) {
      p.intrinsics.push_back(k);
      p.camera_of_block.push_back(camera);
      first_view_of_block.push_back(i);
      continue;
    }
    const std::array<double, 4>& first = p.intrinsics[it->second];
    for (int e = 0; e < 4; ++e) {
      if (std::abs(first[e] - k[e]) > 1e-9 * std::max(1.0, std::abs(k[e]))) {
        MR_THROW_INPUT << "RefineCameras: views " << first_view_of_block[it->second] << " and " << i
                       << " share camera " << camera
                       << " but have different intrinsics (fx, fy, cx, cy)";
      }
    }
  }
  return p;
}

struct OrderedPair {
  int i = 0, j = 0;
  std::vector<internal::PhotometricSample> samples;
};

// Renders the views in `pairs` through the mesh (footprints into
// `footprint`) and picks the samples of both orders of every pair; ordered
// pairs without samples are left out. The pairs are taken in their order, in
// batches of consecutive pairs whose views' renders take at most
// `max_render_bytes` (at least one pair a batch); a batch keeps the renders
// of the one before that it shares, and drops the others.
std::vector<OrderedPair> CollectSamples(const std::vector<cv::Mat>& gray_images,
                                        const std::vector<std::pair<int, int>>& pairs,
                                        const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                        Renderer* renderer, const std::vector<PinholeView>& views,
                                        int max_samples, size_t max_render_bytes,
                                        std::vector<double>* footprint) {
  renderer->SetMesh(V, F);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  std::vector<OrderedPair> all(2 * pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    all[2 * k].i = all[2 * k + 1].j = pairs[k].first;
    all[2 * k].j = all[2 * k + 1].i = pairs[k].second;
  }
  std::map<int, RenderBuffers> held;
  for (size_t begin = 0, end = 0; begin < pairs.size(); begin = end) {
    std::set<int> batch;
    size_t bytes = 0;
    for (end = begin; end < pairs.size(); ++end) {
      std::set<int> fresh;
      for (const int v : {pairs[end].first, pairs[end].second}) {
        if (batch.count(v) == 0) fresh.insert(v);
      }
      size_t more = 0;
      for (const int v : fresh) more += RenderBuffers::Bytes(views[v].width, views[v].height);
      if (end > begin && bytes + more > max_render_bytes) break;
      batch.insert(fresh.begin(), fresh.end());
      bytes += more;
    }
    for (auto it = held.begin(); it != held.end();) {
      it = batch.count(it->first) ? std::next(it) : held.erase(it);
    }
    for (const int v : batch) {
      if (held.count(v)) continue;
      held[v] = renderer->Render(views[v]);
      (*footprint)[v] = MedianFootprint(views[v], held[v]);
    }
#pragma omp parallel for schedule(dynamic)
    for (int k = static_cast<int>(2 * begin); k < static_cast<int>(2 * end); ++k) {
      const int i = all[k].i, j = all[k].j;
      all[k].samples = internal::SelectSamples(V, F, N, views[i], held.at(i), gray_images[i],
                                               views[j], held.at(j), gray_images[j], max_samples);
    }
  }
  std::vector<OrderedPair> ordered;
  for (OrderedPair& pair : all) {
    if (!pair.samples.empty()) ordered.push_back(std::move(pair));
  }
  return ordered;
}

// The refined views as the datum sees them: their prior cameras, their pose
// blocks in `params`, their mean footprint and focal length, and the RMS
// distance of the prior centres from their mean.
struct DatumViews {
  std::vector<Eigen::Matrix3d> R0;
  std::vector<Eigen::Vector3d> C0;
  std::vector<double*> blocks;
  double mean_footprint = 0, mean_focal = 0, radius = 0;
};

DatumViews GatherDatumViews(const CameraParameters& prior, const std::vector<char>& refined,
                            const std::vector<double>& footprint, CameraParameters* params) {
  DatumViews d;
  for (size_t i = 0; i < refined.size(); ++i) {
    if (!refined[i]) continue;
    d.R0.push_back(Eigen::Map<const internal::RowMatrix3d>(prior.pose[i].data()));
    d.C0.push_back(Eigen::Map<const Eigen::Vector3d>(prior.pose[i].data() + 9));
    d.blocks.push_back(params->pose[i].data());
    d.mean_footprint += footprint[i];
    const std::array<double, 4>& k = prior.intrinsics[prior.block_of_view[i]];
    d.mean_focal += 0.5 * (k[0] + k[1]);
  }
  if (d.C0.empty()) return d;
  const double n = static_cast<double>(d.C0.size());
  d.mean_footprint /= n;
  d.mean_focal /= n;
  Eigen::Vector3d mean_center = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& c : d.C0) mean_center += c;
  mean_center /= n;
  double spread = 0;
  for (const Eigen::Vector3d& c : d.C0) spread += (c - mean_center).squaredNorm();
  d.radius = std::sqrt(spread / n);
  return d;
}

// The least-squares problem over `params` (which it points into): the
// photometric residuals of every sample and the priors of every view (and
// camera) they involve, centred on `prior` (same layout as `params`).
// `refined` receives which views take part.
// With a free surface (options.surface_sigma_px > 0), every face with samples
// gets a plane offset and its prior, and the offsets are what the Schur
// complement eliminates; otherwise the brightness blocks are.
void BuildProblem(const std::vector<cv::Mat>& gray_images, const std::vector<OrderedPair>& ordered,
                  const std::vector<double>& footprint, int num_faces,
                  const CameraRefinementOptions& options, const CameraParameters& prior,
                  const std::vector<char>& fixed, CameraParameters* params,
                  ceres::Problem* problem, ceres::ParameterBlockOrdering* ordering,
                  std::vector<char>* refined) {
  CameraParameters& p = *params;
  const bool free_surface = options.surface_sigma_px > 0;
  const bool cubic = options.interpolation == "cubic";
  if (free_surface) {
    // σ_f from the finest view that samples the face.
    p.surface_offset.assign(num_faces, 0.0);
    p.surface_sigma.assign(num_faces, 0.0);
    for (const OrderedPair& pair : ordered) {
      for (const auto& sample : pair.samples) {
        double& sigma = p.surface_sigma[sample.face];
        const double s = options.surface_sigma_px * sample.footprint;
        sigma = sigma == 0 ? s : std::min(sigma, s);
      }
    }
  }
  // Huber on r with threshold huber_delta, weighed as residuals of std dev
  // intensity_sigma: ρ(r²) / σ².
  ceres::LossFunction* loss = new ceres::ScaledLoss(
      new ceres::HuberLoss(options.huber_delta),
      1.0 / (options.intensity_sigma * options.intensity_sigma), ceres::TAKE_OWNERSHIP);
  p.brightness.assign(ordered.size(), {1.0, 0.0});
  for (size_t k = 0; k < ordered.size(); ++k) {
    const int i = ordered[k].i, j = ordered[k].j;
    const int bi = p.block_of_view[i], bj = p.block_of_view[j];
    for (const auto& sample : ordered[k].samples) {
      std::vector<double*> blocks = {p.pose[i].data()};
      if (bi != bj) blocks.push_back(p.intrinsics[bi].data());
      blocks.insert(blocks.end(),
                    {p.pose[j].data(), p.intrinsics[bj].data(), p.brightness[k].data()});
      if (free_surface) blocks.push_back(&p.surface_offset[sample.face]);
      problem->AddResidualBlock(
          internal::NewPhotometricCost(sample, gray_images[j], bi == bj, free_surface, cubic),
          loss, blocks);
    }
    (*refined)[i] = !fixed[i];
    (*refined)[j] = !fixed[j];
    // Schur eliminates the offsets, which never share a residual with each
    // other; without them, the brightness blocks, which never do either.
    ordering->AddElementToGroup(p.brightness[k].data(), free_surface ? 1 : 0);
  }
  for (int f = 0; free_surface && f < num_faces; ++f) {
    if (p.surface_sigma[f] == 0) continue;
    problem->AddResidualBlock(new ceres::AutoDiffCostFunction<internal::OffsetPrior, 1, 1>(
                                  new internal::OffsetPrior(p.surface_sigma[f])),
                              nullptr, &p.surface_offset[f]);
    ordering->AddElementToGroup(&p.surface_offset[f], 0);
  }

  ceres::Manifold* manifold = internal::NewPoseManifold();
  for (size_t i = 0; i < refined->size(); ++i) {
    double* pose = p.pose[i].data();
    if (fixed[i] && problem->HasParameterBlock(pose)) {
      problem->SetParameterBlockConstant(pose);
      ordering->AddElementToGroup(pose, 1);
    }
    if (!(*refined)[i]) continue;
    const Eigen::Matrix3d R0 = Eigen::Map<const internal::RowMatrix3d>(prior.pose[i].data());
    const Eigen::Vector3d C0 = Eigen::Map<const Eigen::Vector3d>(prior.pose[i].data() + 9);
    problem->SetManifold(pose, manifold);
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<internal::RotationPrior, 3, 12>(
            new internal::RotationPrior(R0, options.prior_rotation_deg * kDegree)),
        nullptr, pose);
    MR_CHECK_GT(footprint[i], 0);
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<internal::CenterPrior, 3, 12>(
            new internal::CenterPrior(C0, options.prior_center_px * footprint[i])),
        nullptr, pose);
    ordering->AddElementToGroup(pose, 1);
  }
  // The datum of the refined set, held at the prior views' when the surface
  // is free (a fixed mesh, or fixed views, hold it themselves).
  const bool any_fixed = std::find(fixed.begin(), fixed.end(), 1) != fixed.end();
  if (free_surface && options.datum_sigma_px > 0 && !any_fixed) {
    const DatumViews d = GatherDatumViews(prior, *refined, footprint, params);
    if (d.C0.size() >= 2 && d.radius > 0) {
      const double sigma = options.datum_sigma_px;
      problem->AddResidualBlock(
          internal::NewCameraSetDatumCost(d.R0, d.C0, sigma * d.mean_footprint,
                                          sigma / d.mean_focal, sigma * d.mean_footprint / d.radius),
          nullptr, d.blocks);
    }
  }
  std::vector<char> fixed_block(p.intrinsics.size(), 0);
  for (size_t i = 0; i < fixed.size(); ++i) {
    if (fixed[i]) fixed_block[p.block_of_view[i]] = 1;
  }
  for (size_t b = 0; b < p.intrinsics.size(); ++b) {
    std::array<double, 4>& k = p.intrinsics[b];
    if (!problem->HasParameterBlock(k.data())) continue;
    ordering->AddElementToGroup(k.data(), 1);
    if (options.mode != "poses_intrinsics" || fixed_block[b]) {
      problem->SetParameterBlockConstant(k.data());
      continue;
    }
    problem->AddResidualBlock(
        new ceres::AutoDiffCostFunction<internal::FocalPrior, 2, 4>(
            new internal::FocalPrior(prior.intrinsics[b][0], prior.intrinsics[b][1],
                                     options.prior_focal_percent / 100.0)),
        nullptr, k.data());
  }
}

// Writes the solution into `views` and the changes into `summary`.
void WriteBack(const CameraParameters& p, const std::vector<char>& refined, bool intrinsics,
               std::vector<PinholeView>* views, CameraRefinementSummary* summary) {
  for (size_t i = 0; i < views->size(); ++i) {
    PinholeView& view = (*views)[i];
    if (refined[i]) {
      const Eigen::Matrix3d R = Eigen::Map<const internal::RowMatrix3d>(p.pose[i].data());
      const Eigen::Vector3d C = Eigen::Map<const Eigen::Vector3d>(p.pose[i].data() + 9);
      summary->rotation_change_deg[i] =
          internal::LogRotation(R * view.R.transpose()).norm() / kDegree;
      summary->center_change[i] = (C - view.Center()).norm();
      summary->center_change_px[i] = summary->center_change[i] / summary->footprint[i];
      view.R = R;
      view.t = -R * C;
    }
    if (!intrinsics) continue;
    const std::array<double, 4>& k = p.intrinsics[p.block_of_view[i]];
    const int camera = p.camera_of_block[p.block_of_view[i]];
    if (summary->focal_change_percent.count(camera) == 0) {
      summary->focal_change_percent[camera] = 100.0 * ((k[0] + k[1]) / (view.fx + view.fy) - 1.0);
      summary->principal_point_change_px[camera] = std::hypot(k[2] - view.cx, k[3] - view.cy);
    }
    view.fx = k[0];
    view.fy = k[1];
    view.cx = k[2];
    view.cy = k[3];
  }
}

// The most heap in use at the end of any Ceres iteration (HeapBytesInUse).
class HeapPeak : public ceres::IterationCallback {
 public:
  explicit HeapPeak(size_t bytes) : peak(bytes) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    peak = std::max(peak, HeapBytesInUse());
    return ceres::SOLVER_CONTINUE;
  }
  size_t peak;
};

}  // namespace

// The relative cost decrease of the last accepted step below which a
// rejected step ends the solve: 10 x the default function_tolerance.
constexpr double kStopRejectedBelow = 1e-2;

CameraRefinementSummary RefineCameras(const std::vector<cv::Mat>& gray_images,
                                      const std::vector<std::pair<int, int>>& pairs,
                                      const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                      Renderer* renderer, const std::vector<int>& camera_of_view,
                                      const CameraRefinementOptions& options,
                                      std::vector<PinholeView>* views,
                                      const std::vector<PinholeView>* prior_views,
                                      const std::vector<char>* fixed_views) {
  options.Check();
  MR_CHECK(views != nullptr && renderer != nullptr);
  CheckInputs(gray_images, pairs, V, F, camera_of_view, *views);
  if (prior_views != nullptr) {
    MR_CHECK_EQ(prior_views->size(), views->size());
    for (size_t i = 0; i < views->size(); ++i) {
      MR_CHECK((*prior_views)[i].width == (*views)[i].width &&
               (*prior_views)[i].height == (*views)[i].height)
          << "view " << i << ": prior and start views differ in resolution";
    }
  }
  if (fixed_views != nullptr) {
    MR_CHECK_EQ(fixed_views->size(), views->size());
  }
  const std::vector<char> fixed =
      fixed_views != nullptr ? *fixed_views : std::vector<char>(views->size(), 0);
  const double start_s = ElapsedSeconds();
  const int num_views = static_cast<int>(views->size());
  const bool intrinsics = options.mode == "poses_intrinsics";
  CameraRefinementSummary summary;
  summary.mode = options.mode;
  summary.rotation_change_deg.assign(num_views, 0.0);
  summary.center_change.assign(num_views, 0.0);
  summary.center_change_px.assign(num_views, 0.0);
  summary.footprint.assign(num_views, 0.0);

  CameraParameters params = InitialParameters(*views, camera_of_view, intrinsics);
  const CameraParameters prior =
      prior_views == nullptr ? params : InitialParameters(*prior_views, camera_of_view, intrinsics);
  // A pair of two fixed views tells nothing.
  std::vector<std::pair<int, int>> used_pairs;
  for (const auto& [i, j] : pairs) {
    if (!(fixed[i] && fixed[j])) used_pairs.emplace_back(i, j);
  }
  const size_t heap_start = HeapBytesInUse();
  summary.samples_per_pair = SamplesPerPair(options, 2 * used_pairs.size(), F.rows());
  if (summary.samples_per_pair < options.max_samples_per_pair) {
    summary.cut_to_fit_mb = options.max_problem_mb;
  }
  const std::vector<OrderedPair> ordered =
      CollectSamples(gray_images, used_pairs, V, F, renderer, *views, summary.samples_per_pair,
                     size_t(options.max_render_mb) << 20, &summary.footprint);
  summary.sample_seconds = ElapsedSeconds() - start_s;
  summary.num_ordered_pairs = static_cast<int>(ordered.size());
  for (const OrderedPair& pair : ordered) summary.num_samples += pair.samples.size();
  if (ordered.empty()) {
    MR_LOG(WARNING) << "Camera refinement: no view pair shares a visible textured surface; "
                       "cameras left as they are";
    summary.seconds = ElapsedSeconds() - start_s;
    return summary;
  }

  ceres::Problem problem;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  std::vector<char> refined(num_views, 0);
  BuildProblem(gray_images, ordered, summary.footprint, static_cast<int>(F.rows()), options,
               prior, fixed, &params, &problem, ordering.get(), &refined);
  summary.num_views_refined = static_cast<int>(std::count(refined.begin(), refined.end(), 1));

  ceres::Solver::Options solver;
  // After eliminating the brightness blocks: 6 parameters per view (+ 4 per
  // camera), dense up to a few hundred views.
  solver.linear_solver_type =
      num_views <= 200 || !ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE)
          ? ceres::DENSE_SCHUR
          : ceres::SPARSE_SCHUR;
  solver.linear_solver_ordering = ordering;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  // Residuals, Jacobians and the Schur elimination on every core (the
  // example's refinement 6.4 -> 5.3-5.9 s on 2 cores, the same cost to 4
  // digits).
  solver.num_threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  solver.logging_type = ceres::SILENT;
  // A step rejected after the cost has all but stopped falling ends the
  // solve (on the last accepted iterate). Levenberg-Marquardt would otherwise
  // shrink its trust region from 1e5 to a few units through one rejected step
  // after another, each a full linear solve, before function_tolerance
  // stops it on the same iterate: 4 of 11 iterations in the example's first
  // two rounds.
  internal::StopOnRejectedStep stop(kStopRejectedBelow);
  solver.callbacks.push_back(&stop);
  HeapPeak heap(HeapBytesInUse());
  solver.callbacks.push_back(&heap);
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver, &problem, &ceres_summary);
  if (heap_start > 0 && heap.peak > heap_start) {
    summary.heap_mb = static_cast<double>(heap.peak - heap_start) / (1 << 20);
  }

  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.converged = ceres_summary.termination_type == ceres::CONVERGENCE ||
                      ceres_summary.termination_type == ceres::USER_SUCCESS;
  summary.ceres_brief_report = ceres_summary.BriefReport();
  summary.ceres_full_report = ceres_summary.FullReport();
  if (!ceres_summary.IsSolutionUsable()) {
    MR_LOG(WARNING) << "Camera refinement failed; cameras left as they are: "
                    << summary.ceres_brief_report;
    summary.seconds = ElapsedSeconds() - start_s;
    return summary;
  }
  WriteBack(params, refined, intrinsics, views, &summary);
  // How far the set moved: the datum residuals in footprints, degrees and
  // relative scale.
  if (const DatumViews d = GatherDatumViews(prior, refined, summary.footprint, &params);
      d.C0.size() >= 2) {
    std::unique_ptr<ceres::CostFunction> datum(
        internal::NewCameraSetDatumCost(d.R0, d.C0, d.mean_footprint, kDegree, 1.0));
    double r[7];
    datum->Evaluate(d.blocks.data(), r, nullptr);
    summary.set_shift_px = Eigen::Vector3d(r[0], r[1], r[2]).norm();
    summary.set_rotation_deg = Eigen::Vector3d(r[3], r[4], r[5]).norm();
    summary.set_scale_change = r[6];
  }
  std::vector<double> offsets_px;
  for (size_t f = 0; f < params.surface_sigma.size(); ++f) {
    if (params.surface_sigma[f] == 0) continue;
    offsets_px.push_back(std::abs(params.surface_offset[f]) / params.surface_sigma[f] *
                         options.surface_sigma_px);
  }
  summary.num_faces = static_cast<int>(offsets_px.size());
  if (!offsets_px.empty()) {
    summary.max_surface_offset_px = MaxOf(offsets_px);
    summary.median_surface_offset_px = Median(&offsets_px);
  }
  summary.seconds = ElapsedSeconds() - start_s;

  for (int i = 0; i < num_views; ++i) {
    if (!refined[i]) continue;
    MR_LOG(VERBOSE) << "Camera refinement: view " << i << ": rotation "
                    << summary.rotation_change_deg[i] << " deg, centre " << summary.center_change[i]
                    << " (" << summary.center_change_px[i] << " px footprints)";
  }
  for (const auto& [camera, percent] : summary.focal_change_percent) {
    MR_LOG(VERBOSE) << "Camera refinement: camera " << camera << ": focal " << percent
                    << " %, principal point " << summary.principal_point_change_px.at(camera)
                    << " px";
  }
  MR_LOG(INFO) << summary.BriefReport();
  return summary;
}

int SamplesPerPair(const CameraRefinementOptions& options, size_t num_ordered_pairs,
                   size_t num_faces) {
  const size_t budget = size_t(options.max_problem_mb) << 20;
  const size_t mesh = num_faces * kProblemBytesPerFace;
  const size_t samples = budget > mesh ? (budget - mesh) / kProblemBytesPerSample : 0;
  const size_t fit = samples / std::max<size_t>(1, num_ordered_pairs);
  return static_cast<int>(
      std::clamp<size_t>(fit, 1, static_cast<size_t>(options.max_samples_per_pair)));
}

std::string CameraRefinementSummary::BriefReport() const {
  std::ostringstream out;
  out << "Camera refinement (" << mode << "): " << num_views_refined << " views, "
      << num_ordered_pairs << " ordered pairs, " << num_samples << " samples";
  if (heap_mb > 0) out << " in " << std::setprecision(3) << heap_mb << " MB";
  if (cut_to_fit_mb > 0) {
    out << " (at most " << samples_per_pair << " a pair: more would not fit max_problem_mb, "
        << cut_to_fit_mb << " MB)";
  }
  if (num_faces > 0) {
    out << ", " << num_faces << " face planes free (moved " << std::setprecision(3)
        << median_surface_offset_px << " px footprints median, " << max_surface_offset_px
        << " largest)";
  }
  out << "; cost "
      << std::setprecision(4) << initial_cost << " -> " << final_cost << " in " << iterations
      << " iterations" << (converged ? "" : " (not converged)") << "; largest change: rotation "
      << std::setprecision(3) << MaxOf(rotation_change_deg) << " deg, centre "
      << MaxOf(center_change_px) << " px footprints";
  if (num_views_refined >= 2) {
    out << "; the set moved " << set_shift_px << " px footprints, turned " << set_rotation_deg
        << " deg, scaled " << set_scale_change;
  }
  if (!focal_change_percent.empty()) {
    double focal = 0;
    for (const auto& [camera, percent] : focal_change_percent) {
      focal = std::max(focal, std::abs(percent));
    }
    out << ", focal " << focal << " %";
  }
  out << "; " << std::setprecision(3) << seconds << " s (samples " << sample_seconds << " s)";
  return out.str();
}

std::string CameraRefinementSummary::FullReport() const {
  std::ostringstream out;
  out << BriefReport() << "\n";
  out << "  view  rotation_deg  centre  centre_px  footprint\n";
  for (size_t i = 0; i < rotation_change_deg.size(); ++i) {
    if (footprint[i] == 0) continue;
    out << "  " << std::setw(4) << i << "  " << std::setprecision(4) << std::setw(12)
        << rotation_change_deg[i] << "  " << std::setw(6) << center_change[i] << "  "
        << std::setw(9) << center_change_px[i] << "  " << footprint[i] << "\n";
  }
  for (const auto& [camera, percent] : focal_change_percent) {
    out << "  camera " << camera << ": focal " << percent << " %, principal point "
        << principal_point_change_px.at(camera) << " px\n";
  }
  out << ceres_full_report;
  return out.str();
}

}  // namespace mr
