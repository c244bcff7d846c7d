// mesh_evaluator: accuracy and completeness of a mesh against a ground-truth
// mesh (Middlebury-style), printed as one JSON line on stdout.
//
//   mesh_evaluator --input_path meshed-refined.ply --gt_path gt.ply
//       [--threshold 1.25] [--num_samples 200000] [--seed 1]
//       [--workspace_path dense/] [--sparse_path dense/sparse_refined
//        --true_sparse_path sparse_true [--align_cameras 1]]

#include <cmath>
#include <exception>
#include <sstream>
#include <iostream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "eval/evaluator.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "colmap_io/workspace.h"
#include "geometry/view.h"
#include "synth/camera_error.h"
#include "util/program.h"

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    std::string input_path;
    std::string gt_path;
    mr::EvaluationOptions options;
    mr::OptionManager manager(
        "mesh_evaluator",
        "Evaluates a mesh (.ply/.obj) against a ground-truth mesh and prints one JSON line: "
        "accuracy90, completeness (%), chamfer, normal_deg, mean_accuracy, faces; with "
        "--sparse_path and --true_sparse_path also how far the model's cameras are from the true "
        "ones.");
    manager.AddRequired("input_path", &input_path, "mesh to evaluate (.ply or .obj)");
    manager.AddRequired("gt_path", &gt_path, "ground-truth mesh (.ply or .obj)");
    manager.Add("threshold", &options.threshold,
                "completeness threshold in scene units (> 0)");
    manager.Add("num_samples", &options.num_samples,
                "area-uniform samples drawn on each mesh (>= 1)");
    manager.Add("seed", &options.seed, "sampler seed (>= 0)");
    std::string workspace_path;
    int min_views = 2;
    manager.Add("workspace_path", &workspace_path,
                "COLMAP workspace: measure only the ground truth seen by >= min_views of its "
                "cameras (Middlebury-style observed surface)");
    manager.Add("min_views", &min_views, "with --workspace_path: views that must see a face (>= 1)");
    std::string region_box;
    manager.Add("region_box", &region_box,
                "\"x0 y0 z0 x1 y1 z1\" (or with commas): measure only the ground truth whose "
                "faces' centroids lie in this box (a region of interest, e.g. the object without "
                "the ground it stands on); with --workspace_path, only its observed part");
    std::string sparse_path, true_sparse_path;
    manager.Add("sparse_path", &sparse_path,
                "COLMAP model (e.g. sparse_refined/) whose cameras are compared with "
                "--true_sparse_path: camera_rms_px is the RMS reprojection displacement of the "
                "ground-truth vertices each true view sees, camera_max_focal_percent the worst "
                "focal error");
    manager.Add("true_sparse_path", &true_sparse_path,
                "the true COLMAP model (e.g. workspace_synthesizer's sparse_true/); images "
                "matched by name");
    bool align_cameras = false;
    manager.Add("align_cameras", &align_cameras,
                "with --sparse_path: first carry the mesh and the model's cameras into the true "
                "world by the similarity that best aligns the cameras with the true ones (the "
                "gauge an SfM model leaves free; alignment_* in the JSON)");
    std::string output_error_path;
    double error_max = 0;
    manager.Add("output_error_path", &output_error_path,
                "also write the evaluated mesh here (.ply) as an error map: each vertex's "
                "distance to the ground truth as its `value` and as a colour (viridis, dark blue "
                "0 to yellow at --error_max; mid grey where the closest ground truth is not "
                "observed); after --align_cameras, in the true world");
    std::string error_map = "distance";
    manager.Add("error_map", &error_map,
                "with --output_error_path: what the map shows, `distance` (to the ground truth) "
                "or `normal` (the normal error at each vertex: the mean over its faces of the "
                "angle between the face's normal and that of the closest ground truth, "
                "normal_deg's measure, in degrees)");
    manager.Add("error_max", &error_max,
                "with --output_error_path: the value drawn yellow, in scene units or degrees "
                "(> 0; 0 = this mesh's accuracy90, or its normal_deg_p90 for --error_map "
                "normal). Give two meshes the same value to compare their maps");
    manager.SetInputPaths([&] {
      mr::WorkspaceOptions ws_options;
      ws_options.use_masks = false;
      std::vector<std::string> inputs = mr::WorkspaceInputPaths(workspace_path, ws_options);
      inputs.push_back(input_path);
      inputs.push_back(gt_path);
      for (const std::string& dir : {sparse_path, true_sparse_path}) {
        if (dir.empty()) continue;
        for (const char* file : {"cameras", "images", "points3D"}) {
          for (const char* ext : {".bin", ".txt"}) {
            inputs.push_back(mr::JoinPaths(dir, std::string(file) + ext));
          }
        }
      }
      return inputs;
    });
    if (!manager.Parse(argc, argv)) return 0;
    options.Check();
    for (const std::string& path : {input_path, gt_path}) {
      if (mr::ExistsDir(path)) MR_THROW_INPUT << path << ": is a folder; expected a mesh file";
      if (!mr::ExistsFile(path)) MR_THROW_INPUT << path << ": file does not exist";
    }
    if (sparse_path.empty() != true_sparse_path.empty()) {
      MR_THROW_INPUT << "--sparse_path and --true_sparse_path go together (got only "
                     << (sparse_path.empty() ? "--true_sparse_path" : "--sparse_path") << ")";
    }
    for (const std::string& dir : {sparse_path, true_sparse_path}) {
      if (!dir.empty() && !mr::ExistsDir(dir)) MR_THROW_INPUT << dir << ": folder does not exist";
    }
    if (align_cameras && sparse_path.empty()) {
      MR_THROW_INPUT << "--align_cameras needs --sparse_path and --true_sparse_path";
    }
    if (!output_error_path.empty()) {
      mr::RefuseOutputOverInput("--output_error_path", output_error_path,
                                {input_path, gt_path});
      if (mr::GetExtension(output_error_path) != ".ply") {
        MR_THROW_INPUT << "--output_error_path " << output_error_path
                       << ": expected a .ply file (the map is stored as vertex colours and values)";
      }
      mr::CheckOutputFile("--output_error_path", output_error_path);
      if (!(error_max >= 0) || !std::isfinite(error_max)) {
        MR_THROW_INPUT << "--error_max " << error_max << ": expected >= 0 (0: the accuracy90)";
      }
      if (error_map != "distance" && error_map != "normal") {
        MR_THROW_INPUT << "--error_map " << error_map << ": expected distance or normal";
      }
    }
    mr::TriangleMesh mesh = mr::ReadMesh(input_path);
    const mr::TriangleMesh gt = mr::ReadMesh(gt_path);
    if (mesh.NumFaces() == 0) MR_THROW_INPUT << input_path << ": mesh has no faces";
    if (gt.NumFaces() == 0) MR_THROW_INPUT << gt_path << ": mesh has no faces";
    std::vector<char> observed;
    if (!workspace_path.empty()) {
      if (min_views < 1) MR_THROW_INPUT << "--min_views " << min_views << ": expected >= 1";
      mr::WorkspaceOptions ws_options;
      ws_options.use_masks = false;  // only the cameras are used
      const mr::Workspace workspace = mr::OpenWorkspace(workspace_path, ws_options);
      std::vector<mr::PinholeView> views;
      for (uint32_t id : workspace.image_ids) {
        const mr::Image& image = workspace.model.images.at(id);
        views.push_back(mr::ViewFromColmap(workspace.model.cameras.at(image.camera_id), image));
      }
      observed = mr::ObservedFaces(gt.V, gt.F, views, min_views);
    }
    if (!region_box.empty()) {
      const mr::RegionBox box = mr::RegionBox::Parse(region_box);
      if (mr::KeepFacesInBox(gt.V, gt.F, box, &observed) == 0) {
        MR_THROW_INPUT << "--region_box \"" << region_box
                       << "\": no (observed) ground-truth face has its centroid in the box";
      }
    }
    mr::Reconstruction model, truth;
    mr::Similarity3 model_to_truth;
    if (!sparse_path.empty()) {
      model = mr::ReadSparseModel(sparse_path);
      truth = mr::ReadSparseModel(true_sparse_path);
      if (align_cameras) {
        model_to_truth = mr::AlignCamerasToTruth(model, truth, gt.V);
        mesh.V = model_to_truth.Apply(mesh.V);
      }
    }
    const mr::EvaluationResult result = mr::EvaluateMesh(mesh.V, mesh.F, gt.V, gt.F, options,
                                                         observed.empty() ? nullptr : &observed);
    std::string json = result.ToJson();
    if (!sparse_path.empty()) {
      const mr::CameraComparison cameras =
          mr::CompareCameras(model, truth, gt.V, align_cameras ? &model_to_truth : nullptr);
      json.insert(json.size() - 1, ", " + cameras.JsonMembers());
      if (align_cameras) {
        const Eigen::AngleAxisd angle(model_to_truth.rotation);
        std::ostringstream s;
        s.precision(6);
        s << ", \"alignment_scale\": " << model_to_truth.scale
          << ", \"alignment_rotation_deg\": " << angle.angle() * 180 / M_PI
          << ", \"alignment_shift\": " << model_to_truth.translation.norm();
        json.insert(json.size() - 1, s.str());
      }
    }
    if (!output_error_path.empty()) {
      const mr::VertexErrors errors = mr::MeasureVertexErrors(
          mesh.V, gt.V, gt.F, observed.empty() ? nullptr : &observed);
      const bool normal = error_map == "normal";
      // The scale's top: given, else the accuracy90 or the normal error's
      // 90th percentile (1 for a perfect mesh).
      const double automatic = normal ? result.normal_deg_p90 : result.accuracy90;
      const double max_value = error_max > 0 ? error_max : (automatic > 0 ? automatic : 1.0);
      mr::TriangleMesh map;
      map.V = mesh.V;
      map.F = mesh.F;
      map.values = normal ? mr::MeasureVertexNormalErrors(mesh.V, mesh.F, gt.V, gt.F, errors)
                          : errors.distance;
      map.C = mr::ErrorColors(map.values, errors.observed, max_value);
      mr::WritePly(output_error_path, map);
      MR_LOG(INFO) << "Wrote the " << error_map << " error map " << output_error_path << " ("
                   << map.NumVertices() << " vertices; yellow at " << max_value
                   << (normal ? " degrees)" : ")");
    }
    std::cout << json << std::endl;
    return 0;
  });
}
