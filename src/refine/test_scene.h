#pragma once

// A tiny synthetic scene builder for the refiner's unit tests: a textured,
// Lambertian-shaded object seen by a ring of cameras, rendered in memory.
// The scene can be moved by a similarity transform (scale, rotation,
// translation) applied to the object and the cameras alike; the texture and
// the light move with it, so the images are identical.

#include <Eigen/Core>

#include "refine/view_source.h"

namespace mr {

class Renderer;

struct SceneTransform {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Apply(const Eigen::Vector3d& x) const { return scale * (rotation * x) + translation; }
  Eigen::MatrixXd Apply(const Eigen::MatrixXd& V) const;
  Eigen::Vector3d Inverse(const Eigen::Vector3d& y) const {
    return rotation.transpose() * (y - translation) / scale;
  }
};

struct TestSceneOptions {
  int num_views = 8;
  int width = 160;
  int height = 120;
  double elevation_deg = 25;
  double distance = 4.0;  // camera distance, in units of the object radius (~1)
  int supersample = 2;
  // Lit from each camera (a flash) instead of by a light fixed in the world.
  bool headlight = false;
  // Grey level of the backdrop behind the object (0: black).
  double background = 0;
};

// A closed bumpy sphere of radius ~1 (icosphere with radial relief
// relief * sin(k_x x) sin(k_y y + 1) cos(k_z z), k = `wavenumbers`).
void MakeBumpySphere(int subdivisions, double relief, Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                     const Eigen::Vector3d& wavenumbers = Eigen::Vector3d(5, 4, 3));

// Renders the canonical-frame mesh (V, F), moved by `transform`, into a ring
// of views, with a solid texture evaluated in the canonical frame.
InMemoryViewSource MakeTestScene(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                 const TestSceneOptions& options, const SceneTransform& transform,
                                 Renderer* renderer);

}  // namespace mr
