#pragma once

// workspace_synthesizer: a synthetic COLMAP dense workspace with ground truth.
//
// Writes, for a ground-truth mesh (loaded, or the built-in shape) normalised
// to a bounding-box diagonal of `scene_diagonal` units centred at the origin:
//   output_path/ground_truth.ply          the normalised ground truth
//   output_path/dense/images/view_NNNN.png   anti-aliased RGB renders
//   output_path/dense/masks/view_NNNN.png.png  (write_masks) 255 = object
//   output_path/dense/sparse/{cameras,images,points3D}.bin  (with camera_error:
//                                          the perturbed model)
//   output_path/sparse_true/{cameras,images,points3D}.bin  (only with
//                                          camera_error: the true model)
//   output_path/dense/stereo/{depth_maps,normal_maps}/<name>.geometric.bin
//   output_path/dense/stereo/{fusion,patch-match}.cfg
//   output_path/dense/fused.ply, meshed-poisson.ply  (run_colmap: real colmap)
//   output_path/logs/*.log                 colmap's output

#include <string>

#include "render/renderer.h"
#include "synth/camera_error.h"
#include "synth/colmap_runner.h"
#include "synth/scene.h"
#include "synth/shape.h"
#include "synth/texture.h"

namespace mr {

struct SynthesizerOptions {
  // Output folder (created; its dense/ must not exist yet). Required.
  std::string output_path;
  // Ground-truth mesh (.ply or .obj); empty: the built-in `shape`.
  std::string model_path;
  // Axis of the loaded model that points up ("x", "y" or "z"); it is rotated
  // onto the world +z axis that the cameras treat as up. Scanned models such
  // as the Stanford bunny are often "y".
  std::string model_up_axis = "z";
  // Built-in shape when model_path is empty: "builtin".
  std::string shape = "builtin";
  // Bounding-box diagonal of the normalised ground truth (scene units). (0, 1e6].
  double scene_diagonal = 100;
  // A flat ground under the object, as in photographs of a thing on a table:
  // a square of half-side ground_plane_radius x the object's bounding radius
  // at the object's lowest point, textured like the object and part of the
  // ground truth (the cameras still frame the object). 0 = none (a black
  // background). [0, 100]. Masks, if written, then cover the ground too.
  double ground_plane_radius = 0;
  // Image supersampling factor per axis for anti-aliasing. Range [1, 8].
  int supersample = 3;
  // Standard deviation of the white Gaussian noise added to every pixel and
  // channel of the images (radiance in [0, 1], before 8-bit quantisation),
  // seeded by `seed` and the view index; 0 = none. Range [0, 0.5].
  double image_noise = 0;
  // Standard deviation of the log of a per-view exposure gain: each view's
  // radiance is multiplied by exp(N(0, exposure_jitter)) (seeded by `seed`
  // and the view index) and clipped at 1, before the noise, as auto-exposure
  // varies between photos. 0 = every view exposed alike. Range [0, 1].
  double exposure_jitter = 0;
  // Grey level of a uniform backdrop behind the object (ApplyBackground),
  // before vignetting and exposure; 0 = black. Range [0, 1].
  double background = 0;
  // Vignetting of the lens: radiance times 1 - vignetting * (r / r_corner)^2
  // (ApplyVignetting), before the exposure gain; the same in every view.
  // 0 = none. Range [0, 0.9].
  double vignetting = 0;
  // 0: the images are written as PNG ("view_0000.png"). 1-100: as JPEG of
  // this quality ("view_0000.jpg", masks "view_0000.jpg.png"), with the
  // compression's blocks and ringing, as photographs and COLMAP's undistorted
  // images of them are stored.
  int jpeg_quality = 0;
  // Write COLMAP masks (dense/masks/<image name>.png).
  bool write_masks = true;
  // Maximum number of sparse points3D (each seen in >= 2 views). [0, 1e7].
  int num_sparse_points = 5000;
  // Seed of all random numbers (noise, sparse samples). >= 0.
  int seed = 0;
  // Run colmap stereo_fusion + poisson_mesher at the end.
  bool run_colmap = true;

  BuiltinShapeOptions builtin;
  CameraRigOptions cameras;
  AppearanceOptions appearance;
  DepthNoiseOptions noise;
  ColmapRunOptions colmap;
  RendererOptions renderer;
  // Error of the written sparse model (poses, focal lengths) as from SfM; the
  // images and depth maps stay rendered with the true cameras, the true model
  // goes to output_path/sparse_true/. Seeded by `seed`.
  CameraErrorOptions camera_error;

  bool Check() const;
};

struct SynthesizerSummary {
  int num_gt_vertices = 0;
  int num_gt_faces = 0;
  int num_views = 0;
  int num_points3D = 0;
  double mean_track_length = 0;
  double mean_coverage = 0;  // mean fraction of image pixels showing the object
  bool perturbed_cameras = false;  // camera_error applied to dense/sparse
  CameraErrorSummary camera_error;
  bool ran_colmap = false;
  ColmapRunSummary colmap;
  double render_seconds = 0;
  double total_seconds = 0;
  std::string renderer;

  std::string BriefReport() const;
};

SynthesizerSummary SynthesizeWorkspace(const SynthesizerOptions& options);

// Name of view i: "view_0000.png", ... ("view_0000.jpg", ... with
// `extension` ".jpg").
std::string SynthViewName(int i, const std::string& extension = ".png");

// Writes an 8-bit RGB image of `image` (radiance * 255, rounded; grey styles
// give R = G = B) in the format of the path's extension (WriteImageFile):
// PNG for ".png", JPEG of `jpeg_quality` (1-100) for ".jpg".
void WriteSynthImage(const std::string& path, const SynthImage& image, int jpeg_quality = 95);

}  // namespace mr
