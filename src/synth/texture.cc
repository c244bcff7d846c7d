#include "synth/texture.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "util/error.h"

namespace mr {
namespace {

uint32_t Hash(int x, int y, int z) {
  uint32_t h = static_cast<uint32_t>(x) * 0x8da6b343u ^ static_cast<uint32_t>(y) * 0xd8163841u ^
               static_cast<uint32_t>(z) * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

// One of 12 cube-edge gradients, dotted with the offset (Perlin's improved noise).
double Grad(uint32_t h, double x, double y, double z) {
  switch (h % 12) {
    case 0: return x + y;
    case 1: return -x + y;
    case 2: return x - y;
    case 3: return -x - y;
    case 4: return x + z;
    case 5: return -x + z;
    case 6: return x - z;
    case 7: return -x - z;
    case 8: return y + z;
    case 9: return -y + z;
    case 10: return y - z;
    default: return -y - z;
  }
}

double Fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }
double Lerp(double a, double b, double t) { return a + t * (b - a); }

// Luminance weights (BT.601, as OpenCV's colour-to-grey conversion).
const Eigen::Vector3d kLuminanceWeights(0.299, 0.587, 0.114);

// "contrast": 4 octaves from 8x down to 1x texture_scale, the fine ones
// weighted nearly as much as the coarse ones so that there is contrast at the
// scale of a few pixels. Octaves are shifted to decorrelate them.
double ContrastAlbedo(const AppearanceOptions& options, const Eigen::Vector3d& p) {
  double sum = 0, norm = 0, period = 8 * options.texture_scale, weight = 1;
  for (int octave = 0; octave < 4; ++octave) {
    const Eigen::Vector3d shift(17.3 * octave, -5.1 * octave, 9.7 * octave);
    sum += weight * GradientNoise(p / period + shift);
    norm += weight;
    period *= 0.5;
    weight *= 0.8;
  }
  const double n = sum / norm;  // ~[-0.5, 0.5] typically
  const double t = 0.5 + 0.5 * std::tanh(options.texture_contrast * 2 * n);
  return options.min_albedo + (options.max_albedo - options.min_albedo) * t;
}

// A smooth field of periods 16x and 8x texture_scale, in [-1, 1] (standard
// deviation ~0.2); `shift` decorrelates fields.
double SmoothField(const AppearanceOptions& options, const Eigen::Vector3d& p,
                   const Eigen::Vector3d& shift) {
  const double period = 16 * options.texture_scale;
  const double coarse = GradientNoise(p / period + shift);
  const double fine = GradientNoise(2 * p / period + shift + Eigen::Vector3d(31.7, 7.3, -12.9));
  return std::clamp((coarse + 0.6 * fine) / 1.6, -1.0, 1.0);
}

// "smooth_color": luminance within 10% of the middle of the albedo range, a
// chroma vector with no luminance (red-green and blue-yellow axes) scaled by
// two smooth fields, shortened where a channel would leave the albedo range.
Eigen::Vector3d SmoothColorAlbedo(const AppearanceOptions& options, const Eigen::Vector3d& p) {
  // Chroma axes: (1, -1, 0) and (-0.5, -0.5, 1) minus their luminance.
  static const Eigen::Vector3d kRedGreen =
      Eigen::Vector3d(1, -1, 0) - kLuminanceWeights.dot(Eigen::Vector3d(1, -1, 0)) *
                                      Eigen::Vector3d::Ones();
  static const Eigen::Vector3d kBlueYellow =
      Eigen::Vector3d(-0.5, -0.5, 1) - kLuminanceWeights.dot(Eigen::Vector3d(-0.5, -0.5, 1)) *
                                           Eigen::Vector3d::Ones();
  constexpr double kChromaGain = 0.6;
  const double lo = options.min_albedo, hi = options.max_albedo;
  const double mid = 0.5 * (lo + hi);
  const double luminance = std::clamp(
      mid * (1 + 0.1 * SmoothField(options, p, Eigen::Vector3d(-41.3, 23.9, 5.5))), lo, hi);
  const Eigen::Vector3d chroma =
      kChromaGain * (SmoothField(options, p, Eigen::Vector3d(3.7, 61.1, -27.4)) * kRedGreen +
                     SmoothField(options, p, Eigen::Vector3d(-19.9, -8.3, 44.6)) * kBlueYellow);
  double t = 1;  // largest t <= 1 with luminance + t * chroma inside [lo, hi]
  for (int c = 0; c < 3; ++c) {
    if (chroma(c) > 0) t = std::min(t, (hi - luminance) / chroma(c));
    if (chroma(c) < 0) t = std::min(t, (lo - luminance) / chroma(c));
  }
  return luminance * Eigen::Vector3d::Ones() + std::max(0.0, t) * chroma;
}

// "none": the middle of the albedo range, +-2% at periods >= 16x texture_scale.
double UniformAlbedo(const AppearanceOptions& options, const Eigen::Vector3d& p) {
  const double mid = 0.5 * (options.min_albedo + options.max_albedo);
  const double n = std::clamp(
      GradientNoise(p / (16 * options.texture_scale) + Eigen::Vector3d(7.1, -3.3, 12.7)), -1.0,
      1.0);
  return std::clamp(mid * (1 + 0.02 * n), options.min_albedo, options.max_albedo);
}

}  // namespace

bool AppearanceOptions::Check() const {
  if (texture_style != "contrast" && texture_style != "smooth_color" && texture_style != "none") {
    MR_THROW_INPUT << "AppearanceOptions::texture_style = " << texture_style
                   << ". Violated constraint: texture_style is contrast, smooth_color or none";
  }
  if (!(texture_scale > 0 && texture_scale <= 1000)) {
    MR_THROW_INPUT << "AppearanceOptions::texture_scale = " << texture_scale
                   << ". Violated constraint: 0 < texture_scale <= 1000";
  }
  if (!(texture_contrast > 0 && texture_contrast <= 100)) {
    MR_THROW_INPUT << "AppearanceOptions::texture_contrast = " << texture_contrast
                   << ". Violated constraint: 0 < texture_contrast <= 100";
  }
  if (!(min_albedo >= 0 && min_albedo < max_albedo && max_albedo <= 1)) {
    MR_THROW_INPUT << "AppearanceOptions::min_albedo/max_albedo = " << min_albedo << "/"
                   << max_albedo << ". Violated constraint: 0 <= min_albedo < max_albedo <= 1";
  }
  if (!(ambient >= 0 && ambient <= 1)) {
    MR_THROW_INPUT << "AppearanceOptions::ambient = " << ambient
                   << ". Violated constraint: 0 <= ambient <= 1";
  }
  if (light != "world" && light != "headlight") {
    MR_THROW_INPUT << "AppearanceOptions::light = " << light
                   << ". Violated constraint: light is world or headlight";
  }
  if (!(specular >= 0 && specular <= 1)) {
    MR_THROW_INPUT << "AppearanceOptions::specular = " << specular
                   << ". Violated constraint: 0 <= specular <= 1";
  }
  if (!(shininess >= 1 && shininess <= 10000)) {
    MR_THROW_INPUT << "AppearanceOptions::shininess = " << shininess
                   << ". Violated constraint: 1 <= shininess <= 10000";
  }
  if (!(light_direction.norm() > 0) || !light_direction.allFinite()) {
    MR_THROW_INPUT << "AppearanceOptions::light_direction = (" << light_direction.transpose()
                   << "). Violated constraint: non-zero and finite";
  }
  return true;
}

double GradientNoise(const Eigen::Vector3d& p) {
  const double fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const int X = static_cast<int>(fx), Y = static_cast<int>(fy), Z = static_cast<int>(fz);
  const double x = p.x() - fx, y = p.y() - fy, z = p.z() - fz;
  const double u = Fade(x), v = Fade(y), w = Fade(z);
  const double n000 = Grad(Hash(X, Y, Z), x, y, z);
  const double n100 = Grad(Hash(X + 1, Y, Z), x - 1, y, z);
  const double n010 = Grad(Hash(X, Y + 1, Z), x, y - 1, z);
  const double n110 = Grad(Hash(X + 1, Y + 1, Z), x - 1, y - 1, z);
  const double n001 = Grad(Hash(X, Y, Z + 1), x, y, z - 1);
  const double n101 = Grad(Hash(X + 1, Y, Z + 1), x - 1, y, z - 1);
  const double n011 = Grad(Hash(X, Y + 1, Z + 1), x, y - 1, z - 1);
  const double n111 = Grad(Hash(X + 1, Y + 1, Z + 1), x - 1, y - 1, z - 1);
  return Lerp(Lerp(Lerp(n000, n100, u), Lerp(n010, n110, u), v),
              Lerp(Lerp(n001, n101, u), Lerp(n011, n111, u), v), w);
}

double Luminance(const Eigen::Vector3d& rgb) { return kLuminanceWeights.dot(rgb); }

Eigen::Vector3d Albedo(const AppearanceOptions& options, const Eigen::Vector3d& p) {
  if (options.texture_style == "smooth_color") return SmoothColorAlbedo(options, p);
  if (options.texture_style == "none") return Eigen::Vector3d::Constant(UniformAlbedo(options, p));
  return Eigen::Vector3d::Constant(ContrastAlbedo(options, p));
}

Eigen::Vector3d ShadePoint(const AppearanceOptions& options, const Eigen::Vector3d& p,
                           const Eigen::Vector3d& n, const Eigen::Vector3d& eye) {
  const Eigen::Vector3d to_eye = (eye - p).normalized();
  const Eigen::Vector3d light =
      options.light == "headlight" ? to_eye : options.light_direction.normalized();
  const double lambert = std::max(0.0, n.dot(light));
  const Eigen::Vector3d diffuse =
      Albedo(options, p) * (options.ambient + (1 - options.ambient) * lambert);
  if (options.specular == 0 || lambert == 0) return diffuse;
  const Eigen::Vector3d half = (light + to_eye).normalized();
  const double highlight = options.specular * std::pow(std::max(0.0, n.dot(half)), options.shininess);
  return (diffuse + Eigen::Vector3d::Constant(highlight)).cwiseMin(1.0);
}

}  // namespace mr
