// workspace_synthesizer: writes a synthetic COLMAP dense workspace with its
// ground truth (see src/synth/synthesizer.h and docs/synthesizer.md).
//
//   workspace_synthesizer --output_path DIR [--model_path M]
//
// DIR/dense/ is the workspace, DIR/ground_truth.ply the normalised ground
// truth (beside the workspace, not inside it).

#include <exception>
#include <iostream>

#include "synth/synthesizer.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    mr::SynthesizerOptions o;
    bool verbose = false;
    mr::OptionManager options(
        "workspace_synthesizer",
        "Writes a synthetic COLMAP dense workspace (DIR/dense/) with ground truth "
        "(DIR/ground_truth.ply): renders, sparse model, noisy depth/normal maps, and the "
        "initial surface from the real colmap stereo_fusion + poisson_mesher.");
    options.AddRequired("output_path", &o.output_path, "output folder (DIR/dense must not exist)");
    options.Add("model_path", &o.model_path,
                "ground-truth mesh (.ply/.obj); empty: the built-in shape");
    options.Add("model_up_axis", &o.model_up_axis,
                "axis of the model that points up: x, y or z (the bunny: y)");
    options.Add("shape", &o.shape, "built-in shape when no model_path: builtin");
    options.Add("scene_diagonal", &o.scene_diagonal,
                "bounding-box diagonal of the normalised ground truth (scene units)");
    options.Add("ground_plane_radius", &o.ground_plane_radius,
                "a textured ground under the object, half-side in object radii (part of the "
                "ground truth); 0 = none, black background");
    options.Add("num_views", &o.cameras.num_views, "number of views");
    options.Add("width", &o.cameras.width, "image width (pixels)");
    options.Add("height", &o.cameras.height, "image height (pixels)");
    options.Add("layout", &o.cameras.layout, "camera layout: ring or hemisphere");
    options.Add("elevation_deg", &o.cameras.elevation_deg, "ring elevation (degrees)");
    options.Add("min_elevation_deg", &o.cameras.min_elevation_deg,
                "hemisphere layout: lowest elevation (degrees)");
    options.Add("max_elevation_deg", &o.cameras.max_elevation_deg,
                "hemisphere layout: highest elevation (degrees)");
    options.Add("focal_factor", &o.cameras.focal_factor,
                "focal length as a multiple of the image width");
    options.Add("fill_fraction", &o.cameras.fill_fraction,
                "fraction of the image height the object's bounding sphere fills");
    options.Add("alternate_fill_fraction", &o.cameras.alternate_fill_fraction,
                "the odd-numbered views at this fill fraction instead: a capture from two "
                "distances; above 1, close-ups of the object's middle (0: all at fill_fraction; "
                "at most 3)");
    options.Add("supersample", &o.supersample, "supersampling factor per axis (anti-aliasing)");
    options.Add("image_noise", &o.image_noise,
                "Gaussian image noise per pixel and channel (standard deviation, radiance in "
                "[0, 1])");
    options.Add("write_masks", &o.write_masks, "write dense/masks/<image>.png");
    options.Add("num_sparse_points", &o.num_sparse_points, "maximum number of sparse points3D");
    options.Add("seed", &o.seed, "random seed");
    options.Add("depth_noise", &o.noise.depth_noise,
                "per-pixel Gaussian depth noise (standard deviation relative to depth)");
    options.Add("correlated_noise", &o.noise.correlated_noise,
                "spatially correlated depth error (standard deviation relative to depth)");
    options.Add("correlation_px", &o.noise.correlation_px,
                "correlation length of that error (pixels)");
    options.Add("depth_blur_px", &o.noise.depth_blur_px,
                "smoothing of the true depth before the noise (pixels, PatchMatch-like)");
    options.Add("outlier_fraction", &o.noise.outlier_fraction,
                "fraction of depth pixels that are outliers");
    options.Add("normal_noise", &o.noise.normal_noise, "normal noise (radians, approx.)");
    options.Add("texture_style", &o.appearance.texture_style,
                "texture: contrast (grey, high contrast), smooth_color (colour, low luminance "
                "contrast) or none (uniform; shading only)");
    options.Add("texture_scale", &o.appearance.texture_scale,
                "finest texture period (scene units)");
    options.Add("texture_contrast", &o.appearance.texture_contrast,
                "contrast gain of the contrast texture (tanh steepness)");
    options.Add("light", &o.appearance.light,
                "light: world (fixed world direction) or headlight (at the camera)");
    options.Add("ambient", &o.appearance.ambient, "ambient share of the lighting, [0, 1]");
    options.Add("specular", &o.appearance.specular,
                "strength of a white Blinn-Phong highlight (glossy surfaces), [0, 1]; 0 = none");
    options.Add("shininess", &o.appearance.shininess,
                "Blinn-Phong exponent of the highlight (larger: sharper), [1, 10000]");
    options.Add("exposure_jitter", &o.exposure_jitter,
                "standard deviation of the log of a random per-view exposure gain, [0, 1]");
    options.Add("background", &o.background,
                "grey level of a uniform backdrop behind the object, [0, 1] (radiance; 1 = "
                "white); 0 = black");
    options.Add("vignetting", &o.vignetting,
                "lens vignetting: the corners darkened by this share, 1 - v (r / r_corner)^2, "
                "the same in every view, [0, 0.9]; 0 = none");
    options.Add("jpeg_quality", &o.jpeg_quality,
                "write the images as JPEG of this quality (1-100; view_0000.jpg, masks "
                "view_0000.jpg.png); 0 = PNG");
    options.Add("Shape.edge_length", &o.builtin.edge_length,
                "built-in shape: target edge length (scene units)");
    options.Add("Shape.relief_amplitude", &o.builtin.relief_amplitude,
                "built-in shape: relief amplitude (scene units)");
    options.Add("CameraError.pose_error_px", &o.camera_error.pose_error_px,
                "RMS reprojection error (pixels, on the surface each view sees) of a random "
                "pose error per image in the written sparse model, [0, 100]; images and depth "
                "maps keep the true cameras, the true model goes to DIR/sparse_true; 0 = exact");
    options.Add("CameraError.focal_error_percent", &o.camera_error.focal_error_percent,
                "focal length error of the written sparse model (percent, fx and fy scaled by "
                "1 +- e, sign random per camera), [0, 50]; 0 = exact");
    options.Add("run_colmap", &o.run_colmap, "run colmap stereo_fusion and poisson_mesher");
    options.Add("colmap_path", &o.colmap.colmap_path, "colmap executable (path or name on PATH)");
    options.Add("StereoFusion.min_num_pixels", &o.colmap.fusion_min_num_pixels,
                "colmap stereo_fusion min_num_pixels");
    options.Add("StereoFusion.max_image_size", &o.colmap.fusion_max_image_size,
                "colmap stereo_fusion max_image_size: longest side at which the depth maps are "
                "fused (-1: their own size)");
    options.Add("PoissonMeshing.trim", &o.colmap.poisson_trim,
                "colmap poisson_mesher trim (retried lower if the mesh comes out empty)");
    options.Add("PoissonMeshing.depth", &o.colmap.poisson_depth,
                "colmap poisson_mesher octree depth");
    options.Add("num_threads", &o.colmap.num_threads, "colmap threads (-1: all)");
    options.Add("colmap_timeout_s", &o.colmap.timeout_s,
                "seconds one colmap run may take before it is killed and the synthesis fails; "
                "0 = no limit");
    options.Add("Render.platform", &o.renderer.platform, "EGL platform: auto, device, surfaceless");
    options.Add("verbose", &verbose, "verbose logging");
    if (!options.Parse(argc, argv)) return 0;
    if (verbose) mr::SetLogLevel(mr::LogLevel::kVerbose);
    o.Check();
    mr::CheckOutputFolder("--output_path", o.output_path);
    mr::CreateDirIfNotExists(o.output_path);
    options.WriteConfig(mr::JoinPaths(o.output_path, "workspace_synthesizer.ini"));
    const mr::SynthesizerSummary summary = mr::SynthesizeWorkspace(o);
    std::cout << summary.BriefReport() << std::endl;
    std::cout << "Workspace: " << mr::JoinPaths(o.output_path, "dense")
              << "\nGround truth: " << mr::JoinPaths(o.output_path, "ground_truth.ply")
              << std::endl;
    return 0;
  });
}
