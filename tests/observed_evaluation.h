#pragma once

// Accuracy of a mesh of a synthetic workspace on its observed surface (the
// ground-truth faces seen by at least two of the workspace's cameras), as
// mesh_evaluator --workspace_path measures it; for the end-to-end tests.

#include <string>
#include <vector>

#include "colmap_io/ply.h"
#include "colmap_io/workspace.h"
#include "eval/evaluator.h"

namespace mr {

struct ObservedEvaluation {
  EvaluationResult input;    // meshed-poisson.ply
  EvaluationResult refined;  // meshed-refined.ply
};

// Evaluates `dense`/meshed-poisson.ply and `dense`/meshed-refined.ply against
// `gt_path` on the observed surface (within `region`, if given, as
// mesh_evaluator --region_box).
inline ObservedEvaluation EvaluateObservedSurface(const std::string& dense,
                                                  const std::string& gt_path,
                                                  const EvaluationOptions& options,
                                                  const RegionBox* region = nullptr) {
  const TriangleMesh gt = ReadPly(gt_path);
  const TriangleMesh before = ReadPly(dense + "/meshed-poisson.ply");
  const TriangleMesh after = ReadPly(dense + "/meshed-refined.ply");
  const Workspace workspace = OpenWorkspace(dense);
  std::vector<PinholeView> views;
  for (uint32_t id : workspace.image_ids) {
    const Image& image = workspace.model.images.at(id);
    views.push_back(ViewFromColmap(workspace.model.cameras.at(image.camera_id), image));
  }
  std::vector<char> observed = ObservedFaces(gt.V, gt.F, views, 2);
  if (region != nullptr) KeepFacesInBox(gt.V, gt.F, *region, &observed);
  ObservedEvaluation result;
  result.input = EvaluateMesh(before.V, before.F, gt.V, gt.F, options, &observed);
  result.refined = EvaluateMesh(after.V, after.F, gt.V, gt.F, options, &observed);
  return result;
}

}  // namespace mr
