#pragma once

// The synthesizer's per-view products: camera rigs, anti-aliased images,
// noisy COLMAP-style depth/normal maps and the sparse model's tracks.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "colmap_io/dense_array.h"
#include "colmap_io/sparse_model.h"
#include "geometry/view.h"
#include "render/renderer.h"
#include "synth/texture.h"

namespace mr {

struct CameraRigOptions {
  // Number of views. Range [2, 1000].
  int num_views = 16;
  // Image size in pixels. Range [16, 8192].
  int width = 640;
  int height = 480;
  // "ring": all views at `elevation_deg`, evenly spaced in azimuth (like
  // Middlebury's sparse rings). "hemisphere": a Fibonacci spiral over
  // elevations [min_elevation_deg, max_elevation_deg].
  std::string layout = "ring";
  double elevation_deg = 30;       // ring elevation above the xy plane, [-89, 89]
  double min_elevation_deg = 10;   // hemisphere band, [-89, max_elevation_deg)
  double max_elevation_deg = 75;   // hemisphere band, (min_elevation_deg, 89]
  // Fraction of the image height covered by the object's bounding sphere
  // (about the bounding-box centre; the object itself then fills ~70%). (0, 1].
  double fill_fraction = 0.8;
  // The odd-numbered views at this fill fraction instead: a capture from two
  // distances, whose views see the surface at pixel footprints up to
  // alternate_fill_fraction / fill_fraction apart. 0: every view at
  // fill_fraction. Above 1 the odd views are close-ups that see only the
  // middle of the object. [0, 3].
  double alternate_fill_fraction = 0;
  // Focal length in pixels as a multiple of the image width (0.9 ~ 58 deg
  // horizontal field of view). Range (0.1, 10].
  double focal_factor = 0.9;

  bool Check() const;
};

// Views looking at the origin (PINHOLE, principal point at the image centre,
// cam_from_world poses, world +z up), at the distance where a sphere of
// radius `bounding_radius` around the origin fills `fill_fraction` of the height.
std::vector<PinholeView> MakeCameras(const CameraRigOptions& options, double bounding_radius);

// The view whose pixel (col, row) is sampled at image point (col, row) of
// `view`: COLMAP's dense (depth-map) convention, half a pixel off the sparse one.
PinholeView DenseConventionView(const PinholeView& view);

// Ground-truth scene: mesh, unit outward face normals, and the appearance.
struct SynthScene {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Eigen::MatrixXd face_normals;
  AppearanceOptions appearance;
};

// RGB radiance of the surface seen in one render-buffer pixel of a view
// whose camera centre is `eye` (the headlight's position); nullopt for
// background.
std::optional<Eigen::Vector3d> ShadeBufferPixel(const SynthScene& scene,
                                                const RenderBuffers& buffers, size_t index,
                                                const Eigen::Vector3d& eye);
// Surface point seen in one render-buffer pixel (face_id must be >= 0).
Eigen::Vector3d BufferPoint(const SynthScene& scene, const RenderBuffers& buffers, size_t index);

// An anti-aliased RGB image: row-major, interleaved radiance in [0, 1]
// (channel c of pixel i at 3 * i + c; R = G = B for the grey texture styles)
// and, per pixel, the fraction of sub-pixels that saw the object.
struct SynthImage {
  int width = 0;
  int height = 0;
  std::vector<float> radiance;  // 3 * width * height
  std::vector<float> coverage;  // width * height
};

// Renders `view` at `supersample` times its resolution (the renderer must
// hold scene.V/F) and box-filters down to the view's resolution.
SynthImage RenderImage(Renderer& renderer, const SynthScene& scene, const PinholeView& view,
                       int supersample);

// Adds white Gaussian noise of standard deviation `sigma` to every channel of
// every pixel (background too, like a camera's read noise) and clamps to
// [0, 1]. The noise depends only on (seed, view_index). sigma in [0, 0.5].
void AddImageNoise(double sigma, uint32_t seed, uint32_t view_index, SynthImage* image);

// Multiplies every channel of every pixel by the view's exposure gain
// exp(N(0, sigma)) and clips at 1; returns the gain. The gain depends only on
// (seed, view_index). sigma in [0, 1]; 0 leaves the image as it is (gain 1).
double ApplyExposureJitter(double sigma, uint32_t seed, uint32_t view_index, SynthImage* image);

// Puts the object in front of a uniform grey backdrop of radiance `grey`:
// every pixel gets (1 - coverage) * grey added, so the anti-aliased outline
// blends the two as a camera's pixel does. grey in [0, 1]; 0 leaves the
// image as it is (a black background).
void ApplyBackground(double grey, SynthImage* image);

// Darkens the image towards its corners as a lens does (vignetting): every
// channel of the pixel at distance r from the image centre is multiplied by
// 1 - strength * (r / r_corner)^2, r_corner the distance to a corner, so the
// centre keeps its value and the corners keep 1 - strength. The same for
// every view: the fall-off is fixed in the image, not on the surface.
// strength in [0, 0.9]; 0 leaves the image as it is.
void ApplyVignetting(double strength, SynthImage* image);

struct DepthNoiseOptions {
  // Standard deviation of the per-pixel Gaussian depth noise, relative to
  // the depth. Range [0, 0.1].
  double depth_noise = 0.0025;
  // Standard deviation of a spatially correlated depth error (relative to
  // the depth), independent per view: PatchMatch's errors come in patches,
  // which fusion does not average away within a view. Range [0, 0.1].
  double correlated_noise = 0.004;
  // Correlation length (pixels, Gaussian sigma) of that error. Range [0.5, 100].
  double correlation_px = 6;
  // Gaussian smoothing (pixels, sigma) of the true depth inside the object
  // before the noise, like PatchMatch's window; 0 = none. Range [0, 20].
  double depth_blur_px = 3;
  // Fraction of valid pixels replaced by outliers (depth scaled by a uniform
  // factor in [0.85, 1.15]). Range [0, 0.5].
  double outlier_fraction = 0.002;
  // Standard deviation (radians, approximately, per axis) of the normal
  // noise. stereo_fusion's max_normal_error (10 deg) rejects much more. [0, 1].
  double normal_noise = 0.05;
  // Pixels whose surface is seen at a grazing angle (cosine between normal
  // and viewing ray below this) are left empty, as PatchMatch leaves them. [0, 1).
  double min_cos_incidence = 0.1;

  bool Check() const;
};

// COLMAP geometric depth map (1 channel, z-depth, 0 = empty) and normal map
// (3 channels, camera frame, pointing towards the camera), plus the exact
// render they came from (dense convention).
struct DenseMaps {
  DenseArray depth;
  DenseArray normal;
  RenderBuffers exact;
};
DenseMaps RenderDenseMaps(Renderer& renderer, const SynthScene& scene, const PinholeView& view,
                          const DepthNoiseOptions& options, uint32_t seed);

// Sparse model: one PINHOLE camera (id 1), images 1..n named `names`, and up
// to `num_points` surface points (area-uniform samples) that are visible in
// at least two views, with tracks and matching points2D. Visibility uses the
// exact dense-convention renders (`exact[i]` for view i). Colours (RGB) are
// the mean over the track of the pixels of `images` that the point projects into.
Reconstruction MakeSparseModel(const SynthScene& scene, const std::vector<PinholeView>& views,
                               const std::vector<std::string>& names,
                               const std::vector<RenderBuffers>& exact,
                               const std::vector<SynthImage>& images, int num_points,
                               uint32_t seed);

}  // namespace mr
