#pragma once

// The synthesizer's appearance model: a procedural SOLID texture (a function
// of the 3-D surface point, so it is the same from every view) in one of
// several styles, and Lambertian shading plus ambient under a fixed world
// light or a headlight at the viewing camera.

#include <string>

#include <Eigen/Core>

namespace mr {

struct AppearanceOptions {
  // Texture style, so that a benchmark corpus can span image styles:
  //   "contrast":     grey, high-contrast: 4 octaves of gradient noise (periods
  //                   8x down to 1x texture_scale) through a tanh contrast curve.
  //   "smooth_color": colour, low luminance contrast: hue and chroma follow 2
  //                   smooth noise fields (periods 16x and 8x texture_scale),
  //                   luminance (Luminance() below) stays within ~10% of the
  //                   middle of the albedo range.
  //   "none":         grey, textureless: the middle of the albedo range with at
  //                   most +-2% variation of period 16x texture_scale; the
  //                   shading carries the detail.
  std::string texture_style = "contrast";
  // Period (scene units) of the finest texture octave; the coarsest octave is
  // 8 times larger. At the default camera set-up one pixel is ~0.2 units, so
  // 0.8 units is a few pixels. Range (0, 1000].
  double texture_scale = 0.8;
  // Contrast gain of the "contrast" texture (tanh steepness). Range (0, 100].
  double texture_contrast = 2.5;
  // Albedo range (every channel). 0 <= min_albedo < max_albedo <= 1.
  double min_albedo = 0.15;
  double max_albedo = 0.95;
  // Ambient share of the lighting; the directional (Lambertian) share is
  // 1 - ambient. Range [0, 1].
  double ambient = 0.3;
  // Light: "world" (from the fixed world direction `light_direction`) or
  // "headlight" (from the centre of the camera that renders the view).
  std::string light = "world";
  // World direction towards the light (normalised internally; non-zero).
  Eigen::Vector3d light_direction = Eigen::Vector3d(0.4, -0.3, 1.0);
  // Strength of a white Blinn-Phong highlight, specular * (n.h)^shininess
  // (h halfway between the directions to the light and to the eye), added to
  // the diffuse colour and clipped at 1 like an over-exposed pixel. The
  // highlight moves with the viewpoint, so the views disagree where it is:
  // what glossy real objects do to a photo-consistency measure. Range [0, 1];
  // 0 = Lambertian only.
  double specular = 0;
  // Blinn-Phong exponent of the highlight (larger: smaller, sharper). Range
  // [1, 10000].
  double shininess = 40;

  bool Check() const;
};

// 3-D gradient (Perlin-style) noise, roughly in [-1, 1], smooth, seedless.
double GradientNoise(const Eigen::Vector3d& p);

// Luminance of a linear RGB colour with the weights OpenCV uses to read an
// image as grey (ITU-R BT.601: 0.299 R + 0.587 G + 0.114 B).
double Luminance(const Eigen::Vector3d& rgb);

// RGB albedo at world point p, every channel in [min_albedo, max_albedo]
// (equal channels for the grey styles "contrast" and "none").
Eigen::Vector3d Albedo(const AppearanceOptions& options, const Eigen::Vector3d& p);

// RGB radiance, every channel in [0, 1], of point p with outward unit
// normal n seen from the camera centre `eye`:
// albedo * (ambient + (1 - ambient) * max(0, n . l)), where l is the unit
// world light direction ("world") or (eye - p).normalized() ("headlight"),
// plus, where n . l > 0, the white highlight specular * max(0, n . h)^shininess
// (h the unit vector halfway between l and the direction to the eye),
// clipped at 1.
Eigen::Vector3d ShadePoint(const AppearanceOptions& options, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& n, const Eigen::Vector3d& eye);

}  // namespace mr
