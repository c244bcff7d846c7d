// mesh_render: a flat-shaded grey picture of a mesh (or two side by side),
// seen from a workspace camera or from an orbit around the mesh, for docs.

#include <cmath>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>

#include "colmap_io/mesh_io.h"
#include "colmap_io/workspace.h"
#include "init/mesh_picture.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

namespace {

std::vector<double> ParseNumbers(const std::string& text, size_t count, const std::string& flag) {
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  if (!in.eof() || v.size() != count) {
    MR_THROW_INPUT << "--" << flag << " \"" << text << "\": expected " << count << " numbers";
  }
  for (double d : v) {
    if (!std::isfinite(d)) MR_THROW_INPUT << "--" << flag << " \"" << text << "\": not finite";
  }
  return v;
}

mr::TriangleMesh LoadMesh(const std::string& path) {
  mr::TriangleMesh mesh = mr::ReadMesh(path);
  if (mesh.NumFaces() == 0) MR_THROW_INPUT << path << ": the mesh has no faces";
  return mesh;
}

Eigen::AlignedBox3d Bounds(const Eigen::MatrixXd& V) {
  return Eigen::AlignedBox3d(V.colwise().minCoeff().transpose(),
                             V.colwise().maxCoeff().transpose());
}

}  // namespace

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    std::string input_path, output_path, workspace_path, image_name, view_text, side_by_side,
        up_text, front_text;
    int width = 0, height = 0;
    mr::MeshPictureOptions options;
    mr::OptionManager manager(
        "mesh_render",
        "Renders a mesh with flat grey Lambertian shading (back faces red) to a PNG, from a "
        "workspace camera (--image_name) or an orbit viewpoint (--view \"azimuth elevation\").");
    manager.AddRequired("input_path", &input_path, "mesh (.ply or .obj)");
    manager.AddRequired("output_path", &output_path, "PNG to write");
    manager.Add("workspace_path", &workspace_path,
                "COLMAP workspace (cameras for --image_name; up and front for --view)");
    manager.Add("image_name", &image_name, "render from this workspace image's camera");
    manager.Add("view", &view_text, "\"azimuth elevation\" in degrees around the mesh centre");
    manager.Add("width", &width, "image width (default: camera's, or 800 for --view)");
    manager.Add("height", &height, "image height (default: keeps the camera's aspect, or 600)");
    manager.Add("side_by_side", &side_by_side, "second mesh drawn to the right, same view");
    manager.Add("up", &up_text,
                "\"x y z\" world up for --view (default: the workspace cameras' up, else +y)");
    manager.Add("front", &front_text,
                "\"x y z\" direction of azimuth 0 (default: toward the first camera, else +z)");
    manager.Add("supersample", &options.supersample, "render at k times the size, 1..4");
    manager.Add("lighting", &options.lighting, "key or headlight");
    manager.Add("ambient", &options.ambient, "ambient term in [0, 1)");
    manager.Add("background", &options.background, "background grey level 0..255");
    bool vertex_colors = false;
    manager.Add("vertex_colors", &vertex_colors,
                "shade front faces in the meshes' vertex colours (e.g. mesh_evaluator's "
                "--output_error_path map, or a COLMAP mesh's colours) instead of grey; a mesh "
                "without colours is refused");
    manager.SetInputPaths([&] {
      mr::WorkspaceOptions ws_options;
      ws_options.use_masks = false;
      std::vector<std::string> inputs = mr::WorkspaceInputPaths(workspace_path, ws_options);
      inputs.insert(inputs.end(), {input_path, side_by_side});
      return inputs;
    });
    if (!manager.Parse(argc, argv)) return 0;
    options.Check();
    if (image_name.empty() == view_text.empty()) {
      MR_THROW_INPUT << "give exactly one of --image_name and --view";
    }
    if (!image_name.empty() && workspace_path.empty()) {
      MR_THROW_INPUT << "--image_name needs --workspace_path";
    }
    if (width < 0 || height < 0) MR_THROW_INPUT << "--width/--height must be positive";
    mr::RefuseOutputOverInput("--output_path", output_path, {input_path, side_by_side});
    mr::CheckOutputFile("--output_path", output_path);

    const mr::TriangleMesh mesh = LoadMesh(input_path);
    mr::TriangleMesh second;
    if (!side_by_side.empty()) second = LoadMesh(side_by_side);

    std::unique_ptr<mr::Workspace> ws;
    if (!workspace_path.empty()) {
      mr::WorkspaceOptions ws_options;
      ws_options.use_masks = false;  // only the cameras are used
      ws = std::make_unique<mr::Workspace>(mr::OpenWorkspace(workspace_path, ws_options));
    }
    mr::PinholeView view;
    if (!image_name.empty()) {
      bool found = false;
      for (const uint32_t id : ws->image_ids) {
        const mr::Image& image = ws->model.images.at(id);
        if (image.name != image_name) continue;
        view = mr::ViewFromColmap(ws->model.cameras.at(image.camera_id), image);
        found = true;
      }
      if (!found) MR_THROW_INPUT << workspace_path << ": no image named " << image_name;
      if (width > 0) {
        const double s = static_cast<double>(width) / view.width;
        view = view.Scaled(s);
        if (height > 0 && height != view.height) {
          MR_THROW_INPUT << "--height " << height << " does not keep the camera's aspect (expected "
                         << view.height << ")";
        }
      }
    } else {
      const std::vector<double> ae = ParseNumbers(view_text, 2, "view");
      Eigen::Vector3d up = Eigen::Vector3d::UnitY(), front = Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d centre = Bounds(mesh.V).center();
      if (ws != nullptr && !ws->image_ids.empty()) {
        // World up: the cameras' mean image-up direction; for a planar ring
        // of cameras (some may be upside down, as in Middlebury), the ring's
        // normal signed by that mean.
        Eigen::Vector3d mean_up = Eigen::Vector3d::Zero(), mean_c = Eigen::Vector3d::Zero();
        for (const uint32_t id : ws->image_ids) {
          mean_up -= ws->model.images.at(id).Rotation().row(1).transpose();
          mean_c += ws->model.images.at(id).ProjectionCenter();
        }
        mean_c /= static_cast<double>(ws->image_ids.size());
        up = mean_up;
        if (ws->image_ids.size() >= 3) {
          Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
          for (const uint32_t id : ws->image_ids) {
            const Eigen::Vector3d d = ws->model.images.at(id).ProjectionCenter() - mean_c;
            cov += d * d.transpose();
          }
          const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
          if (eig.eigenvalues()(0) < 0.1 * eig.eigenvalues()(1)) {
            up = eig.eigenvectors().col(0);
            if (up.dot(mean_up) < 0) up = -up;
          }
        }
        front = ws->model.images.at(ws->image_ids.front()).ProjectionCenter() - centre;
      }
      if (!up_text.empty()) {
        const auto u = ParseNumbers(up_text, 3, "up");
        up = Eigen::Vector3d(u[0], u[1], u[2]);
      }
      if (!front_text.empty()) {
        const auto f = ParseNumbers(front_text, 3, "front");
        front = Eigen::Vector3d(f[0], f[1], f[2]);
      }
      if (up.norm() < 1e-12) MR_THROW_INPUT << "--up: zero vector";
      Eigen::AlignedBox3d bounds = Bounds(mesh.V);
      if (second.NumFaces() > 0) bounds.extend(Bounds(second.V));
      view = mr::OrbitView(bounds, ae[0], ae[1], width > 0 ? width : 800,
                           height > 0 ? height : 600, up, front);
    }

    std::unique_ptr<mr::Renderer> renderer;
    try {
      renderer = std::make_unique<mr::Renderer>();  // logs its description
    } catch (const mr::InputError& e) {
      MR_LOG(WARNING) << "No EGL renderer (" << e.what() << "); using the slow CPU renderer";
    }
    auto colors_of = [&](const mr::TriangleMesh& m, const std::string& path) {
      if (!vertex_colors) return static_cast<const mr::VertexColors*>(nullptr);
      if (m.C.rows() != m.V.rows()) {
        MR_THROW_INPUT << path << ": --vertex_colors 1 but the mesh has no vertex colours";
      }
      return &m.C;
    };
    const mr::VertexColors* colors = colors_of(mesh, input_path);
    const mr::VertexColors* second_colors =
        second.NumFaces() > 0 ? colors_of(second, side_by_side) : nullptr;
    cv::Mat picture =
        mr::RenderMeshPicture(renderer.get(), mesh.V, mesh.F, view, options, colors);
    if (second.NumFaces() > 0) {
      const cv::Mat right = mr::RenderMeshPicture(renderer.get(), second.V, second.F, view,
                                                  options, second_colors);
      cv::hconcat(picture, right, picture);
    }
    mr::WritePng(output_path, picture);
    MR_LOG(INFO) << "Wrote " << output_path << " (" << picture.cols << "x" << picture.rows
                 << ", " << mesh.NumFaces() << " faces"
                 << (second.NumFaces() > 0 ? " + " + std::to_string(second.NumFaces()) : "")
                 << ")";
    return 0;
  });
}
