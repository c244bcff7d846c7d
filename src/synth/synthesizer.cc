#include "synth/synthesizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include <opencv2/core.hpp>

#include "colmap_io/dense_array.h"
#include "colmap_io/image_file.h"
#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {
namespace {

TriangleMesh LoadGroundTruth(const SynthesizerOptions& options) {
  TriangleMesh mesh;
  if (!options.model_path.empty()) {
    if (!ExistsFile(options.model_path)) {
      MR_THROW_INPUT << options.model_path << ": ground-truth mesh not found";
    }
    mesh = ReadMesh(options.model_path);
    if (mesh.NumFaces() == 0) {
      MR_THROW_INPUT << options.model_path << ": ground-truth mesh has no faces";
    }
    RemoveUnreferencedVertices(&mesh.V, &mesh.F);
    // Rotate the up axis onto +z (proper rotations, so faces keep their orientation).
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    if (options.model_up_axis == "y") {
      R << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // y -> z, z -> -y
    } else if (options.model_up_axis == "x") {
      R << 0, 0, -1, 0, 1, 0, 1, 0, 0;  // x -> z, z -> -x
    }
    mesh.V = (mesh.V * R.transpose()).eval();
  } else {
    mesh = MakeBuiltinShape(options.builtin);
  }
  mesh.N.resize(0, 3);
  mesh.C.resize(0, 3);
  mesh.values.resize(0);
  NormalizeMesh(options.scene_diagonal, &mesh.V);
  return mesh;
}

// Appends to `mesh` a square ground of half-side `half_side` centred under
// the origin at the mesh's lowest point, facing +z: a grid of `cells` x
// `cells` squares, so that no triangle is much larger than the object's
// screen (the evaluator samples faces, the renderer clips them).
void AppendGroundPlane(double half_side, int cells, TriangleMesh* mesh) {
  const double z = mesh->V.col(2).minCoeff();
  AppendGrid(Eigen::Vector3d(-half_side, -half_side, z), Eigen::Vector3d(2 * half_side, 0, 0),
             Eigen::Vector3d(0, 2 * half_side, 0), cells, &mesh->V, &mesh->F);
}

}  // namespace

bool SynthesizerOptions::Check() const {
  if (output_path.empty()) {
    MR_THROW_INPUT << "SynthesizerOptions::output_path is empty. Violated constraint: non-empty";
  }
  if (model_path.empty() && shape != "builtin") {
    MR_THROW_INPUT << "SynthesizerOptions::shape = " << shape
                   << ". Violated constraint: shape is builtin (or give model_path)";
  }
  if (model_up_axis != "x" && model_up_axis != "y" && model_up_axis != "z") {
    MR_THROW_INPUT << "SynthesizerOptions::model_up_axis = " << model_up_axis
                   << ". Violated constraint: model_up_axis is x, y or z";
  }
  if (!(scene_diagonal > 0 && scene_diagonal <= 1e6)) {
    MR_THROW_INPUT << "SynthesizerOptions::scene_diagonal = " << scene_diagonal
                   << ". Violated constraint: 0 < scene_diagonal <= 1e6";
  }
  if (!(ground_plane_radius == 0 || (ground_plane_radius >= 1 && ground_plane_radius <= 100))) {
    MR_THROW_INPUT << "SynthesizerOptions::ground_plane_radius = " << ground_plane_radius
                   << ". Violated constraint: 0 (none) or 1 <= ground_plane_radius <= 100";
  }
  if (supersample < 1 || supersample > 8) {
    MR_THROW_INPUT << "SynthesizerOptions::supersample = " << supersample
                   << ". Violated constraint: 1 <= supersample <= 8";
  }
  if (!(exposure_jitter >= 0 && exposure_jitter <= 1)) {
    MR_THROW_INPUT << "SynthesizerOptions::exposure_jitter = " << exposure_jitter
                   << ". Violated constraint: 0 <= exposure_jitter <= 1";
  }
  if (!(background >= 0 && background <= 1)) {
    MR_THROW_INPUT << "SynthesizerOptions::background = " << background
                   << ". Violated constraint: 0 <= background <= 1";
  }
  if (!(vignetting >= 0 && vignetting <= 0.9)) {
    MR_THROW_INPUT << "SynthesizerOptions::vignetting = " << vignetting
                   << ". Violated constraint: 0 <= vignetting <= 0.9";
  }
  if (jpeg_quality < 0 || jpeg_quality > 100) {
    MR_THROW_INPUT << "SynthesizerOptions::jpeg_quality = " << jpeg_quality
                   << ". Violated constraint: 0 (PNG) or 1 <= jpeg_quality <= 100";
  }
  if (!(image_noise >= 0 && image_noise <= 0.5)) {
    MR_THROW_INPUT << "SynthesizerOptions::image_noise = " << image_noise
                   << ". Violated constraint: 0 <= image_noise <= 0.5";
  }
  if (num_sparse_points < 0 || num_sparse_points > 10000000) {
    MR_THROW_INPUT << "SynthesizerOptions::num_sparse_points = " << num_sparse_points
                   << ". Violated constraint: 0 <= num_sparse_points <= 1e7";
  }
  if (seed < 0) {
    MR_THROW_INPUT << "SynthesizerOptions::seed = " << seed << ". Violated constraint: seed >= 0";
  }
  builtin.Check();
  cameras.Check();
  appearance.Check();
  noise.Check();
  if (run_colmap) colmap.Check();
  renderer.Check();
  camera_error.Check();
  return true;
}

std::string SynthesizerSummary::BriefReport() const {
  std::ostringstream s;
  s << "Synthesized " << num_views << " views of a ground truth with " << num_gt_vertices
    << " vertices / " << num_gt_faces << " faces; " << num_points3D
    << " sparse points (mean track " << mean_track_length << "); object covers "
    << 100 * mean_coverage << "% of the pixels";
  if (perturbed_cameras) s << "; " << camera_error.BriefReport();
  if (ran_colmap) {
    s << "; fused " << colmap.fused_points << " points; Poisson mesh " << colmap.poisson_vertices
      << " vertices / " << colmap.poisson_faces << " faces (trim " << colmap.trim_used << ")";
  }
  s << "; " << total_seconds << " s";
  return s.str();
}

std::string SynthViewName(int i, const std::string& extension) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "view_%04d", i);
  return buffer + extension;
}

void WriteSynthImage(const std::string& path, const SynthImage& image, int jpeg_quality) {
  MR_CHECK_EQ(image.radiance.size(), 3 * static_cast<size_t>(image.width) * image.height);
  cv::Mat mat(image.height, image.width, CV_8UC3);
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      const size_t pixel = static_cast<size_t>(row) * image.width + col;
      uchar rgb[3];
      for (int c = 0; c < 3; ++c) {
        const double v = image.radiance[3 * pixel + c];
        rgb[c] = static_cast<uchar>(std::clamp(std::lround(255.0 * v), 0L, 255L));
      }
      mat.at<cv::Vec3b>(row, col) = cv::Vec3b(rgb[2], rgb[1], rgb[0]);  // OpenCV is BGR
    }
  }
  WriteImageFile(path, mat, jpeg_quality);
}

SynthesizerSummary SynthesizeWorkspace(const SynthesizerOptions& options) {
  options.Check();
  const double t_start = ElapsedSeconds();
  SynthesizerSummary summary;

  const std::string dense = JoinPaths(options.output_path, "dense");
  if (ExistsDir(dense)) {
    MR_THROW_INPUT << dense
                   << ": already exists; choose a new --output_path or remove the old workspace";
  }

  // Ground truth.
  double t0 = ElapsedSeconds();
  TriangleMesh gt = LoadGroundTruth(options);
  // The cameras frame the object, not the ground.
  const double radius = gt.V.rowwise().norm().maxCoeff();
  if (options.ground_plane_radius > 0) {
    AppendGroundPlane(options.ground_plane_radius * radius, 64, &gt);
  }
  summary.num_gt_vertices = gt.NumVertices();
  summary.num_gt_faces = gt.NumFaces();
  CreateDirIfNotExists(options.output_path);
  WritePly(JoinPaths(options.output_path, "ground_truth.ply"), gt);
  MR_LOG(INFO) << "Ground truth: " << gt.NumVertices() << " vertices, " << gt.NumFaces()
               << " faces ("
               << (options.model_path.empty() ? "built-in shape" : options.model_path)
               << ", bounding-box diagonal " << options.scene_diagonal << ")"
               << (options.ground_plane_radius > 0 ? ", with a ground plane" : "") << " in "
               << ElapsedSeconds() - t0 << " s";

  SynthScene scene;
  scene.V = gt.V;
  scene.F = gt.F;
  scene.face_normals = FaceNormals(gt.V, gt.F);
  scene.appearance = options.appearance;
  const std::vector<PinholeView> views = MakeCameras(options.cameras, radius);
  summary.num_views = static_cast<int>(views.size());

  // Folders.
  const std::string images_dir = JoinPaths(dense, "images");
  const std::string masks_dir = JoinPaths(dense, "masks");
  const std::string sparse_dir = JoinPaths(dense, "sparse");
  const std::string stereo_dir = JoinPaths(dense, "stereo");
  const std::string depth_dir = JoinPaths(stereo_dir, "depth_maps");
  const std::string normal_dir = JoinPaths(stereo_dir, "normal_maps");
  for (const auto& d : {images_dir, sparse_dir, depth_dir, normal_dir,
                        JoinPaths(stereo_dir, "consistency_graphs")}) {
    CreateDirIfNotExists(d);
  }
  if (options.write_masks) CreateDirIfNotExists(masks_dir);

  // Rendering.
  t0 = ElapsedSeconds();
  Renderer renderer(options.renderer);
  summary.renderer = renderer.Description();
  renderer.SetMesh(scene.V, scene.F);
  std::vector<std::string> names;
  std::vector<SynthImage> images;
  std::vector<RenderBuffers> exact;
  Progress progress("Rendering views", static_cast<long>(views.size()));
  double coverage_sum = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const std::string name =
        SynthViewName(static_cast<int>(i), options.jpeg_quality > 0 ? ".jpg" : ".png");
    names.push_back(name);
    SynthImage image = RenderImage(renderer, scene, views[i], options.supersample);
    ApplyBackground(options.background, &image);
    ApplyVignetting(options.vignetting, &image);
    ApplyExposureJitter(options.exposure_jitter, static_cast<uint32_t>(options.seed),
                        static_cast<uint32_t>(i), &image);
    AddImageNoise(options.image_noise, static_cast<uint32_t>(options.seed),
                  static_cast<uint32_t>(i), &image);
    WriteSynthImage(JoinPaths(images_dir, name), image, options.jpeg_quality);
    if (options.write_masks) {
      cv::Mat mask(image.height, image.width, CV_8UC1);
      for (int row = 0; row < image.height; ++row) {
        for (int col = 0; col < image.width; ++col) {
          mask.at<uchar>(row, col) =
              image.coverage[static_cast<size_t>(row) * image.width + col] >= 0.5f ? 255 : 0;
        }
      }
      WriteImageFile(JoinPaths(masks_dir, name + ".png"), mask);
    }
    double covered = 0;
    for (float c : image.coverage) covered += c;
    coverage_sum += covered / image.coverage.size();

    DenseMaps maps = RenderDenseMaps(renderer, scene, views[i], options.noise,
                                     static_cast<uint32_t>(options.seed * 1000003 + i));
    WriteDenseArray(JoinPaths(depth_dir, name + ".geometric.bin"), maps.depth);
    WriteDenseArray(JoinPaths(normal_dir, name + ".geometric.bin"), maps.normal);
    exact.push_back(std::move(maps.exact));
    images.push_back(std::move(image));
    progress.Update(static_cast<long>(i + 1));
  }
  progress.Done();
  summary.mean_coverage = coverage_sum / views.size();
  summary.render_seconds = ElapsedSeconds() - t0;
  MR_LOG(INFO) << "Rendered " << views.size() << " views (" << options.cameras.width << "x"
               << options.cameras.height << ", supersample " << options.supersample
               << ", texture " << options.appearance.texture_style << ", light "
               << options.appearance.light << ", specular " << options.appearance.specular
               << ", background " << options.background << ", vignetting " << options.vignetting
               << ", exposure jitter " << options.exposure_jitter << ", image noise "
               << options.image_noise
               << (options.jpeg_quality > 0
                       ? ", JPEG quality " + std::to_string(options.jpeg_quality)
                       : std::string(", PNG"))
               << ") with depth and normal maps in " << summary.render_seconds << " s";

  // Sparse model.
  t0 = ElapsedSeconds();
  Reconstruction model =
      MakeSparseModel(scene, views, names, exact, images, options.num_sparse_points,
                      static_cast<uint32_t>(options.seed * 7919 + 17));
  if (options.camera_error.pose_error_px > 0 || options.camera_error.focal_error_percent > 0) {
    // The true model beside dense/, where nothing reads it by accident; the
    // workspace gets the wrong one, to be fused with the true depth maps.
    const std::string true_dir = JoinPaths(options.output_path, "sparse_true");
    CreateDirIfNotExists(true_dir);
    WriteSparseModelBinary(true_dir, model);
    summary.camera_error = PerturbCameras(options.camera_error, gt.V,
                                          static_cast<uint32_t>(options.seed) * 104729u + 101u,
                                          &model);
    summary.perturbed_cameras = true;
    MR_LOG(INFO) << "Sparse model perturbed (pose_error_px " << options.camera_error.pose_error_px
                 << ", focal_error_percent " << options.camera_error.focal_error_percent
                 << "; true model in " << true_dir << "): "
                 << summary.camera_error.BriefReport();
  }
  WriteSparseModelBinary(sparse_dir, model);
  summary.num_points3D = static_cast<int>(model.points3D.size());
  size_t track_sum = 0;
  for (const auto& [id, p] : model.points3D) track_sum += p.track.size();
  summary.mean_track_length =
      model.points3D.empty() ? 0.0 : static_cast<double>(track_sum) / model.points3D.size();
  MR_LOG(INFO) << "Sparse model: " << model.images.size() << " images, "
               << summary.num_points3D << " points3D (mean track length "
               << summary.mean_track_length << ") in " << ElapsedSeconds() - t0 << " s";
  if (summary.num_points3D == 0) {
    MR_LOG(WARNING) << "no surface point is seen by two views; colmap stereo_fusion will fuse "
                       "nothing";
  }

  // Configuration files as COLMAP's image_undistorter writes them.
  WriteFileAtomically(JoinPaths(stereo_dir, "fusion.cfg"), [&](std::ostream& out) {
    for (const auto& name : names) out << name << "\n";
  });
  WriteFileAtomically(JoinPaths(stereo_dir, "patch-match.cfg"), [&](std::ostream& out) {
    for (const auto& name : names) out << name << "\n__auto__, 20\n";
  });

  if (options.run_colmap) {
    summary.colmap = RunColmapFusionAndPoisson(dense, JoinPaths(options.output_path, "logs"),
                                               options.colmap);
    summary.ran_colmap = true;
  }
  summary.total_seconds = ElapsedSeconds() - t_start;
  MR_LOG(INFO) << summary.BriefReport();
  return summary;
}

}  // namespace mr
