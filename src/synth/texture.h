#pragma once

// The synthesizer's appearance model: a procedural SOLID texture (a function
// of the 3-D surface point, so it is the same from every view) and
// Lambertian shading under a fixed world light plus ambient.

#include <Eigen/Core>

namespace mr {

struct AppearanceOptions {
  // Period (scene units) of the finest texture octave; the coarsest octave is
  // 8 times larger. At the default camera set-up one pixel is ~0.2 units, so
  // 0.8 units is a few pixels. Range (0, 1000].
  double texture_scale = 0.8;
  // Contrast gain of the texture (tanh steepness). Range (0, 100].
  double texture_contrast = 2.5;
  // Albedo range. 0 <= min_albedo < max_albedo <= 1.
  double min_albedo = 0.15;
  double max_albedo = 0.95;
  // Ambient share of the lighting; the directional (Lambertian) share is
  // 1 - ambient. Range [0, 1].
  double ambient = 0.3;
  // World direction towards the light (normalised internally; non-zero).
  Eigen::Vector3d light_direction = Eigen::Vector3d(0.4, -0.3, 1.0);

  bool Check() const;
};

// 3-D gradient (Perlin-style) noise, roughly in [-1, 1], smooth, seedless.
double GradientNoise(const Eigen::Vector3d& p);

// Albedo in [min_albedo, max_albedo] at world point p.
double Albedo(const AppearanceOptions& options, const Eigen::Vector3d& p);

// Radiance in [0, max_albedo] of point p with outward unit normal n:
// albedo * (ambient + (1 - ambient) * max(0, n . light)).
double ShadePoint(const AppearanceOptions& options, const Eigen::Vector3d& p,
                  const Eigen::Vector3d& n);

}  // namespace mr
