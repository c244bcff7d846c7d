// mesh_initializer: the visual hull of a workspace's masks, as a closed,
// outward-oriented PLY mesh (an initial surface where COLMAP gives none).

#include <algorithm>
#include <cmath>
#include <exception>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "colmap_io/ply.h"
#include "colmap_io/workspace.h"
#include "geometry/view.h"
#include "init/isosurface.h"
#include "init/middlebury.h"
#include "init/visual_hull.h"
#include "refine/mask_outline.h"
#include "refine/view_source.h"
#ifdef MR_HAVE_REMESH
#include "geometry/remesh.h"
#endif
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    std::string workspace_path, output_path, bbox_text;
    bool use_holdout = true, use_silhouette_list = true;
    mr::VisualHullOptions options;
    mr::OptionManager manager(
        "mesh_initializer",
        "Carves the visual hull of the masks of a COLMAP dense workspace (masks/<image>.png) "
        "and writes its surface as a watertight, outward-oriented PLY mesh.");
    manager.AddRequired("workspace_path", &workspace_path, "COLMAP dense workspace with masks/");
    manager.Add("output_path", &output_path,
                "output PLY (default: <workspace>/meshed-visualhull.ply)");
    manager.Add("resolution", &options.resolution,
                "grid cells along the longest side of the box, [4, 2048]");
    int target_faces = 0;
    double remesh_edge_length = 0;
    manager.Add("target_faces", &target_faces,
                "if > 0, decimate the hull to at most this many faces (Garland-Heckbert)");
    manager.Add("remesh_edge_length", &remesh_edge_length,
                "if > 0, isotropic remeshing to this edge length (scene units), after "
                "decimation");
    manager.Add("bbox", &bbox_text,
                "\"x0 y0 z0 x1 y1 z1\" (default: <workspace>/bbox.txt, else the cameras' "
                "common field of view)");
    manager.Add("VisualHull.padding", &options.padding,
                "box padding per side, fraction of its longest side");
    manager.Add("VisualHull.min_views", &options.min_views,
                "a point must project into at least this many images");
    manager.Add("use_holdout", &use_holdout,
                "skip the images listed in <workspace>/holdout.txt");
    manager.Add("use_silhouette_list", &use_silhouette_list,
                "use only the images listed in <workspace>/silhouette_images.txt, if present");
    manager.SetInputPaths([&] {
      std::vector<std::string> inputs = mr::WorkspaceInputPaths(workspace_path);
      inputs.push_back(mr::JoinPaths(workspace_path, "holdout.txt"));
      inputs.push_back(mr::JoinPaths(workspace_path, "silhouette_images.txt"));
      return inputs;
    });
    if (!manager.Parse(argc, argv)) return 0;
    options.Check();
    if (target_faces < 0) MR_THROW_INPUT << "--target_faces " << target_faces << ", expected >= 0";
    if (!(remesh_edge_length >= 0)) {
      MR_THROW_INPUT << "--remesh_edge_length " << remesh_edge_length << ", expected >= 0";
    }
#ifndef MR_HAVE_REMESH
    if (target_faces > 0 || remesh_edge_length > 0) {
      MR_THROW_INPUT << "--target_faces/--remesh_edge_length need mr_remesh (CGAL), which this "
                        "build lacks";
    }
#endif
    if (output_path.empty()) output_path = mr::JoinPaths(workspace_path, "meshed-visualhull.ply");
    {
      std::vector<std::string> inputs = mr::WorkspaceInputPaths(workspace_path);
      inputs.push_back(mr::JoinPaths(workspace_path, "holdout.txt"));
      inputs.push_back(mr::JoinPaths(workspace_path, "silhouette_images.txt"));
      mr::RefuseOutputOverInput("--output_path", output_path, inputs);
    }
    mr::CheckOutputFile("--output_path", output_path);

    const mr::Workspace ws = mr::OpenWorkspace(workspace_path);
    std::set<std::string> holdout, good;
    if (use_holdout) {
      for (const auto& n : mr::ReadImageNameList(mr::JoinPaths(ws.root, "holdout.txt"))) {
        holdout.insert(n);
      }
    }
    if (use_silhouette_list) {
      for (const auto& n :
           mr::ReadImageNameList(mr::JoinPaths(ws.root, "silhouette_images.txt"))) {
        good.insert(n);
      }
    }
    std::vector<mr::PinholeView> views;
    std::vector<cv::Mat> masks;
    std::vector<std::string> skipped;
    for (const uint32_t id : ws.image_ids) {
      const mr::Image& image = ws.model.images.at(id);
      if (holdout.count(image.name) || (!good.empty() && !good.count(image.name))) {
        skipped.push_back(image.name);
        continue;
      }
      cv::Mat mask = ws.ReadMask(id);
      if (mask.empty()) {
        MR_LOG(WARNING) << "No mask for " << image.name << "; it does not carve";
        continue;
      }
      views.push_back(mr::ViewFromColmap(ws.model.cameras.at(image.camera_id), image));
      masks.push_back(mask);
    }
    if (views.empty()) {
      MR_THROW_INPUT << workspace_path << ": no usable masks (expected masks/<image name>.png "
                     << "for the images not held out)";
    }
    std::string skipped_list;
    for (const auto& n : skipped) skipped_list += " " + n;
    MR_LOG(INFO) << "Carving with " << views.size() << " masks; skipped " << skipped.size()
                 << (skipped.empty() ? "" : ":" + skipped_list);
    // A mask that leaves out part of the object carves that part away: the
    // hull needs masks that cover the object, and is only conservative with
    // larger ones (mask_outline.h measures where the images' edges lie).
    const mr::MaskOutlineReport outline = mr::MeasureMaskOutline(
        mr::WorkspaceViewSource(ws, {skipped.begin(), skipped.end()}), mr::MaskOutlineOptions());
    if (outline.move && outline.edge_offset_px < 0) {
      MR_LOG(WARNING) << "WARNING: the masks are tighter than the objects in the images: "
                      << outline.Measured() << ". The visual hull cuts the object by about as "
                      << "much; grow the masks (dilate them by "
                      << static_cast<int>(std::ceil(-outline.edge_offset_px)) + 1
                      << " px) for a hull that contains it";
    } else {
      MR_LOG(INFO) << "Masks against the images' edges: " << outline.Measured();
    }

    Eigen::AlignedBox3d bbox;
    const std::string bbox_file = mr::JoinPaths(ws.root, "bbox.txt");
    if (!bbox_text.empty()) {
      bbox = mr::ParseBoundingBox(bbox_text, "--bbox");
      MR_LOG(INFO) << "Bounding box from --bbox";
    } else if (mr::ExistsFile(bbox_file)) {
      bbox = mr::ReadBoundingBoxFile(bbox_file);
      MR_LOG(INFO) << "Bounding box from " << bbox_file;
    } else {
      bbox = mr::FrustumIntersectionBox(views);
      MR_LOG(INFO) << "Bounding box from the cameras' common field of view";
    }
    MR_LOG(INFO) << "Box " << bbox.min().transpose() << " .. " << bbox.max().transpose();

    mr::TriangleMesh mesh;
    const mr::VisualHullSummary summary =
        mr::ComputeVisualHull(views, masks, bbox, options, &mesh.V, &mesh.F);
    MR_LOG(INFO) << "Visual hull: " << summary.BriefReport();
    if (summary.num_components > 1) {
      MR_LOG(INFO) << "Kept the largest of " << summary.num_components << " components";
    }
#ifdef MR_HAVE_REMESH
    if (target_faces > 0 && mesh.NumFaces() > target_faces) {
      mr::Decimate(&mesh.V, &mesh.F, target_faces);  // logs its own summary
    }
    if (remesh_edge_length > 0) {
      mr::IsotropicRemesh(&mesh.V, &mesh.F, remesh_edge_length);  // logs its own summary
    }
    if (target_faces > 0 || remesh_edge_length > 0) {
      std::string why;
      if (!mr::IsClosedAndOriented(mesh.F, &why) || mr::SignedVolume(mesh.V, mesh.F) <= 0) {
        MR_THROW_INPUT << "the decimated/remeshed hull is no longer closed and outward ("
                       << why << "); run without --target_faces/--remesh_edge_length";
      }
    }
#endif
    mr::WritePly(output_path, mesh);
    MR_LOG(INFO) << "Wrote " << output_path << " (" << mesh.NumVertices() << " vertices, "
                 << mesh.NumFaces() << " faces)";
    return 0;
  });
}
