// mesh_refiner: refines a COLMAP mesh with DCV (Li et al., TIP 2016).
//
//   mesh_refiner --workspace_path dense/ [--input_path mesh.ply]
//                [--output_path dense/meshed-refined.ply] [--Refine.* ...]
//
// See docs/mesh_refiner.md for every option.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>

#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "colmap_io/workspace.h"
#include "geometry/mesh.h"
#include "refine/camera_refinement.h"
#include "refine/refiner.h"
#include "refine/view_selection.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

namespace mr {
namespace {

// Fewer input faces than this are refused: a handful of triangles cannot
// stand for a surface seen in images (a one-triangle "mesh" refines to
// similarity -0.01).
constexpr int kMinInputFaces = 20;

// A final mean similarity (plain ZNCC of all view pairs through the mesh) at
// or below this is reported as a result that probably means nothing. The
// lowest input similarities in docs/results.md are about 0.2 (fandisk-shading
// 0.19, the dino's visual hull 0.21); wrong distortion parameters, a mesh of
// another scene or a collapsed mesh score about 0.
constexpr double kMeaninglessSimilarity = 0.05;

// A mesh that covers less than this fraction of every image is refined from
// a few hundred pixels at best (1 % of a 640x480 image is a disc 62 pixels
// across): the refinement can do little, and the mesh is often the wrong
// one or the cameras' scale is off.
constexpr double kMinImageCoverage = 0.01;

void WarnIfMeaningless(const RefineSummary& summary) {
  if (summary.final_similarity > kMeaninglessSimilarity) return;
  MR_LOG(WARNING) << "WARNING: the final mean similarity is " << summary.final_similarity
                  << " (initial " << summary.initial_similarity << ", " << summary.final_faces
                  << " faces), at most " << kMeaninglessSimilarity
                  << ": the images do not agree with each other through the mesh, so the result "
                     "is probably meaningless. Check the cameras (distortion parameters), that "
                     "the mesh belongs to these images, and --Refine.num_levels";
}

// The workspace's model with the refined cameras of `source`'s views (same
// ids; intrinsics of a camera from its first view; SIMPLE_PINHOLE gets the
// mean of fx and fy). Images not in `source` (held out) keep their poses.
Reconstruction RefinedModel(const Workspace& workspace, const WorkspaceViewSource& source,
                            const std::vector<PinholeView>& cameras) {
  Reconstruction model = workspace.model;
  std::set<uint32_t> cameras_done;
  for (int i = 0; i < source.NumViews(); ++i) {
    const PinholeView& view = cameras.at(i);
    Image& image = model.images.at(source.ImageId(i));
    image.qvec = RotationToQuaternion(view.R);
    image.tvec = view.t;
    if (!cameras_done.insert(image.camera_id).second) continue;
    Camera& camera = model.cameras.at(image.camera_id);
    if (camera.model == CameraModel::kSimplePinhole) {
      camera.params = {0.5 * (view.fx + view.fy), view.cx, view.cy};
    } else {
      camera.params = {view.fx, view.fy, view.cx, view.cy};
    }
  }
  return model;
}

// The views of `source` registered against the mesh (V, F), held fixed:
// every view not in `fixed` gets its pose refined against its neighbours,
// which keep theirs (as new images are registered to a model). Returns the
// workspace's model with the registered poses and logs one line.
Reconstruction RegisterViews(const Workspace& workspace, const WorkspaceViewSource& source,
                             const std::vector<char>& fixed, const Eigen::MatrixXd& V,
                             const Eigen::MatrixXi& F, const CameraRefinementOptions& options,
                             Renderer* renderer) {
  std::vector<PinholeView> views = source.Views();
  const std::vector<std::vector<int>> neighbors =
      SelectNeighbors(views, V, VertexNormals(V, F), ViewSelectionOptions());
  std::vector<std::pair<int, int>> pairs;
  std::vector<cv::Mat> images(views.size());
  std::vector<int> camera_of_view;
  for (int i = 0; i < source.NumViews(); ++i) {
    const Image& image = workspace.model.images.at(source.ImageId(i));
    camera_of_view.push_back(static_cast<int>(image.camera_id));
    if (fixed[i]) continue;
    for (int j : neighbors[i]) {
      if (fixed[j]) pairs.emplace_back(i, j);
    }
  }
  for (const auto& [i, j] : pairs) {
    for (int k : {i, j}) {
      if (images[k].empty()) images[k] = source.LoadGray(k);
    }
  }
  // The mesh is what is judged: held fixed.
  CameraRefinementOptions register_options = options;
  register_options.mode = "poses";
  register_options.surface_sigma_px = 0;
  const CameraRefinementSummary summary = RefineCameras(
      images, pairs, V, F, renderer, camera_of_view, register_options, &views, nullptr, &fixed);
  MR_LOG(INFO) << "Held-out views registered to the refined model: " << summary.BriefReport();
  return RefinedModel(workspace, source, views);
}

// Prints the dry-run summary of a workspace and mesh.
void PrintSummary(const Workspace& workspace, const ViewSource& source, const TriangleMesh& mesh,
                  const std::string& input_path, const RefineOptions& refine) {
  const Eigen::Vector3d lo = mesh.V.colwise().minCoeff(), hi = mesh.V.colwise().maxCoeff();
  const std::vector<PinholeView> views = source.Views();
  const double footprint = MedianFootprint(views, mesh.V, VertexNormals(mesh.V, mesh.F));
  const double edge = MeanEdgeLength(mesh.V, mesh.F);
  std::printf("Workspace:   %s\n", workspace.root.c_str());
  std::printf("Images:      %d registered, %zu used\n", static_cast<int>(workspace.image_ids.size()),
              views.size());
  std::printf("Cameras:     %zu\n", workspace.model.cameras.size());
  std::printf("Masks:       %s\n", workspace.mask_dir.empty() ? "none" : workspace.mask_dir.c_str());
  if (!workspace.undistortion.empty()) std::printf("Undistorted: %s\n", workspace.undistortion.c_str());
  std::printf("Mesh:        %s\n", input_path.c_str());
  std::printf("Vertices:    %d\nFaces:       %d\n", mesh.NumVertices(), mesh.NumFaces());
  std::printf("Bounding box: [%g, %g, %g] - [%g, %g, %g]\n", lo.x(), lo.y(), lo.z(), hi.x(), hi.y(),
              hi.z());
  if (footprint > 0) {
    std::printf("Mean edge:   %g (%.2f px at full resolution)\n", edge, edge / footprint);
  } else {
    std::printf("Mean edge:   %g (the mesh is not visible in any view)\n", edge);
  }
  // The resolution the refinement works at, and the finest level's mesh.
  const ResizedViewSource working(source, refine.max_image_size);
  int largest = 0, resized = 0;
  for (int i = 0; i < working.NumViews(); ++i) {
    if (working.View(i).width * working.View(i).height >
        working.View(largest).width * working.View(largest).height) {
      largest = i;
    }
    resized += working.Resized(i) ? 1 : 0;
  }
  std::printf("Working resolution: %dx%d (largest view; %d of %d views scaled down to "
              "--Refine.max_image_size %d)\n",
              working.View(largest).width, working.View(largest).height, resized,
              working.NumViews(), refine.max_image_size);
  if (working.HasMasks()) {
    std::printf("Masks: %s%s\n", MeasureMaskOutline(working, refine.mask_outline).BriefReport().c_str(),
                refine.align_masks ? "" : " (--Refine.align_masks 0: used as given)");
  }
  const int max_faces = refine.FaceBudget(mesh.NumFaces());
  const EdgeSizing sizing(working.Views(), mesh.V, mesh.F, refine.target_edge_px, max_faces);
  std::printf("Faces at the finest level: about %d (%.2g px edges%s, at most %d)\n",
              sizing.visible() ? sizing.expected_faces() : 0,
              sizing.visible() ? sizing.edge_px() : refine.target_edge_px,
              sizing.uniform() ? ""
                               : (" in " + std::to_string(sizing.band_edges().size()) +
                                  " depth bands")
                                     .c_str(),
              max_faces);
}

int Run(int argc, char** argv) {
  std::string workspace_path, input_path, output_path, mask_path, image_path, holdout_path;
  bool dry_run = false, verbose = false;
  RefineOptions refine;
  OptionManager options("mesh_refiner",
                        "refines a COLMAP mesh (meshed-poisson.ply) with DCV and writes "
                        "meshed-refined.ply");
  options.AddRequired("workspace_path", &workspace_path,
                      "COLMAP dense workspace (images/, sparse/), or a project with sparse/0");
  options.Add("input_path", &input_path,
              "input mesh (default: <workspace>/meshed-poisson.ply, else meshed-delaunay.ply)");
  options.Add("output_path", &output_path, "output mesh (default: <workspace>/meshed-refined.ply)");
  options.Add("mask_path", &mask_path, "folder of masks <image name>.png (default: <workspace>/masks if present)");
  options.Add("image_path", &image_path, "folder of images (default: <workspace>/images)");
  options.Add("holdout_path", &holdout_path,
              "text file of image names to leave out of refinement; their photo-consistency is "
              "reported before and after");
  options.Add("dry_run", &dry_run, "load and validate the workspace and mesh, print a summary, exit");
  options.Add("verbose", &verbose, "per-iteration details");
  RegisterRefineOptions(&options, &refine);
  // Everything the run reads: no output may replace it or write into it.
  const auto input_paths = [&] {
    WorkspaceOptions ws_options;
    ws_options.mask_path = mask_path;
    ws_options.image_path = image_path;
    std::vector<std::string> paths = WorkspaceInputPaths(workspace_path, ws_options);
    paths.insert(paths.end(), {input_path, holdout_path});
    return paths;
  };
  options.SetInputPaths(input_paths);
  if (!options.Parse(argc, argv)) return 0;
  if (verbose) SetLogLevel(LogLevel::kVerbose);
  refine.Check();
  // Before the output checks, which would otherwise blame the default output.
  if (!ExistsDir(workspace_path)) {
    MR_THROW_INPUT << workspace_path
                   << (ExistsFile(workspace_path) ? ": is a file; expected a workspace folder"
                                                  : ": workspace folder does not exist");
  }
  if (output_path.empty()) output_path = JoinPaths(workspace_path, "meshed-refined.ply");
  RefuseOutputOverInput("--output_path", output_path, input_paths());
  const std::string output_ext = GetExtension(output_path);
  if (output_ext != ".ply" && output_ext != ".obj") {
    MR_THROW_INPUT << "--output_path " << output_path << ": unsupported extension '" << output_ext
                   << "' (expected .ply or .obj)";
  }
  CheckOutputFile("--output_path", output_path);

  WorkspaceOptions ws_options;
  ws_options.mask_path = mask_path;
  ws_options.image_path = image_path;
  const Workspace workspace = OpenWorkspace(workspace_path, ws_options);
  if (input_path.empty()) {
    input_path = workspace.DefaultMeshPath();
    if (input_path.empty()) {
      MR_THROW_INPUT << workspace_path
                     << ": no meshed-poisson.ply or meshed-delaunay.ply; run colmap poisson_mesher "
                        "first or give --input_path";
    }
  }
  RefuseOutputOverInput("--output_path", output_path, {input_path});
  if (ExistsDir(input_path)) MR_THROW_INPUT << input_path << ": is a folder; expected a PLY mesh";
  // Camera refinement writes the refined model next to the mesh, never over sparse/.
  const std::string refined_model_path = JoinPaths(workspace.root, "sparse_refined");
  if (refine.refine_cameras != "none") {
    RefuseOutputOverInput("the refined model", refined_model_path,
                          {workspace.sparse_dir, input_path, output_path});
    CheckOutputFolder("the refined model", refined_model_path);
  }

  const std::set<std::string> holdout =
      holdout_path.empty() ? std::set<std::string>{} : [&] {
        const std::vector<std::string> names = ReadNameList(holdout_path);
        return std::set<std::string>(names.begin(), names.end());
      }();
  CheckImageNamesInModel(workspace, {holdout.begin(), holdout.end()}, holdout_path);
  WorkspaceViewSource source(workspace, holdout);
  TriangleMesh mesh = ReadPly(input_path);
  MR_LOG(INFO) << "Read " << input_path << ": " << mesh.NumVertices() << " vertices, "
               << mesh.NumFaces() << " faces";
  if (mesh.NumFaces() == 0) {
    MR_THROW_INPUT << input_path << ": the mesh has no faces (a point cloud cannot be refined)";
  }
  if (mesh.NumFaces() < kMinInputFaces) {
    MR_THROW_INPUT << input_path << ": the mesh has " << mesh.NumFaces()
                   << (mesh.NumFaces() == 1 ? " face" : " faces") << "; at least "
                   << kMinInputFaces
                   << " are needed for a refinement to mean anything (is it the right file?)";
  }
  if (dry_run) {
    PrintSummary(workspace, source, mesh, input_path, refine);
    return 0;
  }
  if (!(MedianFootprint(source.Views(), mesh.V, VertexNormals(mesh.V, mesh.F)) > 0)) {
    MR_THROW_INPUT << input_path
                   << ": the mesh is not visible in any view: no vertex faces a camera inside its "
                      "image (is the mesh in the same coordinate frame as the sparse model?)";
  }
  const double coverage = BestViewCoverage(source.Views(), mesh.V, mesh.F);
  if (coverage < kMinImageCoverage) {
    MR_LOG(WARNING) << "WARNING: " << input_path << " covers only " << 100 * coverage
                    << " % of the image in the view that sees most of it (expected at least "
                    << 100 * kMinImageCoverage
                    << " %): too few pixels to refine from. Is it the mesh of these images, in "
                       "the sparse model's frame and scale?";
  }
  if (refine.color == "principal") {
    const Eigen::Vector3d w = PrincipalTextureColor(source);
    source.SetGrayWeights(w);
    MR_LOG(INFO) << "Images compared along the colour direction of most texture (R, G, B) = ("
                 << w(0) << ", " << w(1) << ", " << w(2) << ")";
  }

  Renderer renderer;  // logs "Renderer: <GL vendor, renderer, EGL path>"

  // Held-out views: photo-consistency before and after, through all views.
  std::vector<int> holdout_views;
  const WorkspaceViewSource all_views(workspace);
  for (int i = 0; i < all_views.NumViews(); ++i) {
    if (holdout.count(all_views.Name(i))) holdout_views.push_back(i);
  }
  double holdout_before = 0;
  if (!holdout_views.empty()) {
    holdout_before = PhotoConsistency(all_views, holdout_views, mesh.V, mesh.F, &renderer);
  }

  const RefineSummary summary = RefineMesh(source, refine, &mesh, &renderer);
  WriteMesh(output_path, mesh);
  MR_LOG(INFO) << "Wrote " << output_path;
  // With refined cameras, the held-out views are compared with the used
  // views through the cameras the mesh was refined with.
  Workspace refined = workspace;
  if (!summary.cameras.empty()) {
    refined.model = RefinedModel(workspace, source, summary.cameras);
    CreateDirIfNotExists(refined_model_path);
    WriteSparseModelBinary(refined_model_path, refined.model);
    MR_LOG(INFO) << "Wrote the refined cameras to " << refined_model_path << " ("
                 << summary.cameras.size() << " images"
                 << (holdout.empty() ? "" : "; held-out images keep their poses") << ")";
  }
  std::cout << summary.FullReport();
  WarnIfMeaningless(summary);
  if (!holdout_views.empty()) {
    const WorkspaceViewSource refined_views(refined);
    const double after =
        PhotoConsistency(refined_views, holdout_views, mesh.V, mesh.F, &renderer);
    std::printf("Held-out photo-consistency (mean ZNCC, %zu views): %.4f -> %.4f\n",
                holdout_views.size(), holdout_before, after);
    // The held-out views carry the SfM model's errors (and, when the used
    // cameras were refined, the old datum). Registered against the refined
    // model, as a new image would be, they judge the surface rather than the
    // cameras.
    std::vector<char> fixed(refined_views.NumViews(), 1);
    for (int i : holdout_views) fixed[i] = 0;
    Workspace registered = refined;
    registered.model = RegisterViews(refined, refined_views, fixed, mesh.V, mesh.F,
                                     refine.camera_refinement, &renderer);
    const double registered_after = PhotoConsistency(WorkspaceViewSource(registered),
                                                     holdout_views, mesh.V, mesh.F, &renderer);
    std::printf("Held-out photo-consistency with the held-out views registered to the refined "
                "model (their poses refined against the mesh and the used views): %.4f\n",
                registered_after);
  }
  return 0;
}

}  // namespace
}  // namespace mr

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    return mr::Run(argc, argv);
  });
}
