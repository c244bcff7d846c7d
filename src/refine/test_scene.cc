#include "refine/test_scene.h"

#include <cmath>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "render/renderer.h"

namespace mr {
namespace {

// Solid texture in [0.15, 0.95] with detail at a few pixels' scale.
double Albedo(const Eigen::Vector3d& x) {
  const double a = std::sin(9.0 * x.x() + 2.0 * std::sin(7.0 * x.z())) *
                   std::cos(8.0 * x.y() - 3.0 * x.z());
  const double b = std::sin(17.0 * x.x() + 13.0 * x.y() + 11.0 * x.z());
  return 0.55 + 0.25 * a + 0.15 * b;
}

}  // namespace

Eigen::MatrixXd SceneTransform::Apply(const Eigen::MatrixXd& V) const {
  Eigen::MatrixXd out(V.rows(), 3);
  for (int i = 0; i < V.rows(); ++i) out.row(i) = Apply(Eigen::Vector3d(V.row(i))).transpose();
  return out;
}

void MakeBumpySphere(int subdivisions, double relief, Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                     const Eigen::Vector3d& wavenumbers) {
  MakeIcosphere(subdivisions, 1.0, V, F);
  const Eigen::Vector3d& k = wavenumbers;
  for (int i = 0; i < V->rows(); ++i) {
    const Eigen::Vector3d p = V->row(i);
    const double bump =
        std::sin(k.x() * p.x()) * std::sin(k.y() * p.y() + 1.0) * std::cos(k.z() * p.z());
    V->row(i) = (p * (1.0 + relief * bump)).transpose();
  }
}

InMemoryViewSource MakeTestScene(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                 const TestSceneOptions& options, const SceneTransform& transform,
                                 Renderer* renderer) {
  const Eigen::MatrixXd Vt = transform.Apply(V);
  const Eigen::MatrixXd N = FaceNormals(V, F);  // canonical frame
  const Eigen::Vector3d light = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  renderer->SetMesh(Vt, F);
  InMemoryViewSource source;
  const double elevation = options.elevation_deg * M_PI / 180.0;
  const double focal = 0.35 * options.width * options.distance;  // object ~70% of the width
  for (int i = 0; i < options.num_views; ++i) {
    const double azimuth = 2.0 * M_PI * i / options.num_views;
    const Eigen::Vector3d c = options.distance * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                                                 std::cos(elevation) * std::sin(azimuth),
                                                                 std::sin(elevation));
    const PinholeView canonical =
        LookAtView(c, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 1), options.width,
                   options.height, focal);
    // Move the camera with the scene: x_cam = R_c (T^-1 y) + t_c.
    PinholeView view = canonical;
    view.R = canonical.R * transform.rotation.transpose();
    view.t = canonical.t * transform.scale - view.R * transform.translation;
    const PinholeView fine = view.Scaled(options.supersample);
    const RenderBuffers render = renderer->Render(fine);
    cv::Mat hi(fine.height, fine.width, CV_32F, cv::Scalar(options.background));
    for (int r = 0; r < fine.height; ++r) {
      for (int col = 0; col < fine.width; ++col) {
        const int f = render.FaceAt(r, col);
        if (f < 0) continue;
        const size_t idx = static_cast<size_t>(r) * fine.width + col;
        const double u = render.bary[2 * idx], v = render.bary[2 * idx + 1];
        const Eigen::Vector3d x = (1 - u - v) * V.row(F(f, 0)) + u * V.row(F(f, 1)) +
                                  v * V.row(F(f, 2));
        const Eigen::Vector3d towards_light = options.headlight ? (c - x).normalized() : light;
        const double shade = 0.35 + 0.65 * std::max(0.0, N.row(f).dot(towards_light));
        hi.at<float>(r, col) = static_cast<float>(Albedo(x) * shade);
      }
    }
    cv::Mat image;
    cv::resize(hi, image, cv::Size(options.width, options.height), 0, 0, cv::INTER_AREA);
    source.Add("view_" + std::to_string(i), view, image);
  }
  return source;
}

}  // namespace mr
