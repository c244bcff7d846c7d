#include "init/visual_hull.h"

#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "init/isosurface.h"
#include "util/error.h"
#include "util/mask_distance.h"

namespace mr {
namespace {

constexpr double kRadius = 1.0;

// A view at `center` looking at the origin.
PinholeView LookAtOrigin(const Eigen::Vector3d& center, int size, double f) {
  PinholeView v;
  v.width = v.height = size;
  v.fx = v.fy = f;
  v.cx = v.cy = size / 2.0;
  const Eigen::Vector3d z = (-center).normalized();
  Eigen::Vector3d up = std::abs(z.z()) > 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = up.cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  v.R.row(0) = x;
  v.R.row(1) = y;
  v.R.row(2) = z;
  v.t = -v.R * center;
  return v;
}

// Exact silhouette of the sphere: pixels whose centre ray hits it.
cv::Mat SphereMask(const PinholeView& v) {
  cv::Mat mask(v.height, v.width, CV_8U, cv::Scalar(0));
  const Eigen::Vector3d c = v.Center();
  for (int r = 0; r < v.height; ++r) {
    for (int col = 0; col < v.width; ++col) {
      const Eigen::Vector3d d = v.RayDirection(col + 0.5, r + 0.5).normalized();
      const double tca = -c.dot(d);
      const double d2 = c.squaredNorm() - tca * tca;
      if (d2 <= kRadius * kRadius) mask.at<uchar>(r, col) = 255;
    }
  }
  return mask;
}

// Eight views from the corners of a cube, 4 radii away.
void SphereScene(std::vector<PinholeView>* views, std::vector<cv::Mat>* masks) {
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d dir((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
    views->push_back(LookAtOrigin(4 * kRadius * dir.normalized(), 96, 100));
    masks->push_back(SphereMask(views->back()));
  }
}

// Generalized winding number of a point with respect to a closed mesh.
double WindingNumber(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                     const Eigen::Vector3d& p) {
  double w = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)).transpose() - p;
    const Eigen::Vector3d b = V.row(F(f, 1)).transpose() - p;
    const Eigen::Vector3d c = V.row(F(f, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    w += 2 * std::atan2(num, den);
  }
  return w / (4 * M_PI);
}

TEST(VisualHullOptions, DefaultsAreValid) { EXPECT_TRUE(VisualHullOptions().Check()); }

TEST(VisualHullOptions, RejectsBadValues) {
  VisualHullOptions o;
  o.resolution = 2;
  EXPECT_THROW(o.Check(), InputError);
  o = VisualHullOptions();
  o.min_views = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = VisualHullOptions();
  o.padding = -0.1;
  EXPECT_THROW(o.Check(), InputError);
}

TEST(MaskSignedDistance, BoundaryIsBetweenPixels) {
  cv::Mat mask(5, 8, CV_8U, cv::Scalar(0));
  mask.colRange(0, 4).setTo(255);
  const cv::Mat sdf = MaskSignedDistance(mask);
  EXPECT_FLOAT_EQ(sdf.at<float>(2, 3), 0.5f);
  EXPECT_FLOAT_EQ(sdf.at<float>(2, 4), -0.5f);
  EXPECT_FLOAT_EQ(sdf.at<float>(2, 1), 2.5f);
  EXPECT_FLOAT_EQ(sdf.at<float>(2, 7), -3.5f);
}

TEST(VisualHull, SphereFromEightViews) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  VisualHullOptions options;
  options.resolution = 32;
  options.min_views = 2;
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  const VisualHullSummary summary = ComputeVisualHull(views, masks, bbox, options, &V, &F);
  const double h = summary.voxel_size;
  ASSERT_GT(F.rows(), 200);
  EXPECT_EQ(summary.num_faces, F.rows());
  std::string why;
  EXPECT_TRUE(IsClosedAndOriented(F, &why)) << why;
  EXPECT_GT(SignedVolume(V, F), 4.0 / 3.0 * M_PI);  // contains the sphere's volume
  // The hull contains the sphere: points on it are inside, or within one voxel.
  for (int i = 0; i < 200; ++i) {
    // Fibonacci sphere.
    const double z = 1 - 2 * (i + 0.5) / 200, rho = std::sqrt(1 - z * z);
    const double phi = i * M_PI * (3 - std::sqrt(5.0));
    const Eigen::Vector3d p = kRadius * Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), z);
    if (WindingNumber(V, F, p) > 0.5) continue;
    double nearest = 1e9;
    for (Eigen::Index v = 0; v < V.rows(); ++v) nearest = std::min(nearest, (V.row(v).transpose() - p).norm());
    EXPECT_LT(nearest, h) << "sphere point " << p.transpose() << " is outside the hull";
  }
  // And is close to it: no vertex inside the sphere by more than a voxel, none
  // farther than the analytic bound of 8 cube-corner views (1.22 r for
  // orthographic views, a little more in perspective) plus a voxel.
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double r = V.row(v).norm();
    ASSERT_GT(r, kRadius - h) << "vertex " << v;
    ASSERT_LT(r, 1.3 * kRadius + h) << "vertex " << v;
  }
  // Every surface vertex lies on the boundary of some silhouette cone
  // (within a voxel), as every visual-hull surface point does.
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d X = V.row(v).transpose();
    double best = 1e9;
    for (size_t c = 0; c < views.size(); ++c) {
      const Eigen::Vector3d d = (X - views[c].Center()).normalized();
      const double tca = -views[c].Center().dot(d);
      const double ray_dist = std::sqrt(std::max(0.0, views[c].Center().squaredNorm() - tca * tca));
      best = std::min(best, std::abs(ray_dist - kRadius));
    }
    ASSERT_LT(best, h) << "vertex " << v << " is on no silhouette cone";
  }
}

TEST(VisualHull, ViewsThatDoNotSeeANodeDoNotCarveIt) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  VisualHullOptions options;
  options.resolution = 24;
  options.min_views = 2;
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V0, V1;
  Eigen::MatrixXi F0, F1;
  ComputeVisualHull(views, masks, bbox, options, &V0, &F0);
  // A camera looking away from the scene, with an empty mask.
  // (oriented like a camera at (0, 0, -4) looking at the origin, i.e. along
  // +z, but placed at (0, 0, 4)).
  views.push_back(LookAtOrigin(Eigen::Vector3d(0, 0, -4), 32, 40));
  views.back().t = -views.back().R * Eigen::Vector3d(0, 0, 4);
  masks.push_back(cv::Mat(32, 32, CV_8U, cv::Scalar(0)));
  ComputeVisualHull(views, masks, bbox, options, &V1, &F1);
  EXPECT_EQ(F0.rows(), F1.rows());
  EXPECT_NEAR(SignedVolume(V0, F0), SignedVolume(V1, F1), 1e-9);
}

TEST(VisualHull, TargetFacesAdjustsResolution) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  VisualHullOptions options;
  options.resolution = 16;
  options.min_views = 2;
  options.target_faces = 8000;
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  ComputeVisualHull(views, masks, bbox, options, &V, &F);
  EXPECT_GT(F.rows(), 0.7 * 8000);
  EXPECT_LT(F.rows(), 1.3 * 8000);
  EXPECT_TRUE(IsClosedAndOriented(F));
}

TEST(VisualHull, HugeGridIsRefused) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  VisualHullOptions options;
  options.resolution = 2048;  // 2051^3 nodes
  EXPECT_THROW(ComputeVisualHull(views, masks, bbox, options, &V, &F), InputError);
}

TEST(VisualHull, EmptyMasksThrow) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  for (cv::Mat& m : masks) m.setTo(0);
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  VisualHullOptions options;
  options.resolution = 16;
  EXPECT_THROW(ComputeVisualHull(views, masks, bbox, options, &V, &F), InputError);
}

TEST(VisualHull, MaskSizeMismatchThrows) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  masks[3] = cv::Mat(10, 10, CV_8U, cv::Scalar(255));
  const Eigen::AlignedBox3d bbox(Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  EXPECT_THROW(ComputeVisualHull(views, masks, bbox, VisualHullOptions(), &V, &F), InputError);
  masks.pop_back();
  EXPECT_THROW(ComputeVisualHull(views, masks, bbox, VisualHullOptions(), &V, &F), InputError);
}

TEST(FrustumIntersectionBox, ContainsTheSphere) {
  std::vector<PinholeView> views;
  std::vector<cv::Mat> masks;
  SphereScene(&views, &masks);
  const Eigen::AlignedBox3d box = FrustumIntersectionBox(views);
  EXPECT_TRUE(box.contains(Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-kRadius),
                                               Eigen::Vector3d::Constant(kRadius))));
  // The views' common region is bounded by the cameras (4 radii away).
  EXPECT_LT(box.sizes().maxCoeff(), 8 * kRadius);
}

TEST(FrustumIntersectionBox, ParallelAxesThrow) {
  std::vector<PinholeView> views(3);
  for (int i = 0; i < 3; ++i) {
    views[i].width = views[i].height = 10;
    views[i].fx = views[i].fy = 10;
    views[i].cx = views[i].cy = 5;
    views[i].t = Eigen::Vector3d(i, 0, 0);
  }
  EXPECT_THROW(FrustumIntersectionBox(views), InputError);
}

}  // namespace
}  // namespace mr
