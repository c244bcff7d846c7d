// mesh_evaluator: accuracy and completeness of a mesh against a ground-truth
// mesh (Middlebury-style), printed as one JSON line on stdout.
//
//   mesh_evaluator --input_path meshed-refined.ply --gt_path gt.ply
//       [--threshold 1.25] [--num_samples 200000] [--seed 1]

#include <exception>
#include <iostream>
#include <string>

#include "colmap_io/mesh_io.h"
#include "eval/evaluator.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"

int main(int argc, char** argv) {
  try {
    std::string input_path;
    std::string gt_path;
    mr::EvaluationOptions options;
    mr::OptionManager manager(
        "mesh_evaluator",
        "Evaluates a mesh (.ply/.obj) against a ground-truth mesh and prints one JSON line: "
        "accuracy90, completeness (%), chamfer, normal_deg, mean_accuracy, faces.");
    manager.AddRequired("input_path", &input_path, "mesh to evaluate (.ply or .obj)");
    manager.AddRequired("gt_path", &gt_path, "ground-truth mesh (.ply or .obj)");
    manager.Add("threshold", &options.threshold,
                "completeness threshold in scene units (> 0)");
    manager.Add("num_samples", &options.num_samples,
                "area-uniform samples drawn on each mesh (>= 1)");
    manager.Add("seed", &options.seed, "sampler seed (>= 0)");
    if (!manager.Parse(argc, argv)) return 0;
    options.Check();
    for (const std::string& path : {input_path, gt_path}) {
      if (!mr::ExistsFile(path)) MR_THROW_INPUT << path << ": file does not exist";
    }
    const mr::TriangleMesh mesh = mr::ReadMesh(input_path);
    const mr::TriangleMesh gt = mr::ReadMesh(gt_path);
    if (mesh.NumFaces() == 0) MR_THROW_INPUT << input_path << ": mesh has no faces";
    if (gt.NumFaces() == 0) MR_THROW_INPUT << gt_path << ": mesh has no faces";
    const mr::EvaluationResult result = mr::EvaluateMesh(mesh.V, mesh.F, gt.V, gt.F, options);
    std::cout << result.ToJson() << std::endl;
    return 0;
  } catch (const mr::InputError& e) {
    std::cerr << "ERROR: " << e.what() << std::endl;
  } catch (const std::exception& e) {
    std::cerr << "ERROR: " << e.what() << std::endl;
  }
  return 1;
}
