#pragma once

// A small COLMAP workspace written with the project's own writers, for the
// command-line tests: images of a bumpy sphere rendered in memory
// (refine/test_scene.h, 8 views of 160x120) and their PINHOLE sparse model.

#include <filesystem>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colmap_io/sparse_model.h"
#include "refine/test_scene.h"
#include "render/renderer.h"

namespace mr {

// Writes `workspace`/images/<view>.png and `workspace`/sparse/*.bin (the
// folders are created).
inline void WriteRenderedTestWorkspace(const std::string& workspace) {
  std::filesystem::create_directories(workspace + "/images");
  std::filesystem::create_directories(workspace + "/sparse");
  Renderer renderer;
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(4, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, &renderer);
  Reconstruction model;
  for (int i = 0; i < source.NumViews(); ++i) {
    const PinholeView& view = source.View(i);
    Camera camera;
    camera.camera_id = i + 1;
    camera.model = CameraModel::kPinhole;
    camera.width = view.width;
    camera.height = view.height;
    camera.params = {view.fx, view.fy, view.cx, view.cy};
    model.cameras[camera.camera_id] = camera;
    Image image;
    image.image_id = i + 1;
    image.camera_id = camera.camera_id;
    image.name = source.Name(i) + ".png";
    image.qvec = RotationToQuaternion(view.R);
    image.tvec = view.t;
    model.images[image.image_id] = image;
    cv::Mat u8;
    source.LoadGray(i).convertTo(u8, CV_8U, 255.0);
    cv::imwrite(workspace + "/images/" + image.name, u8);
  }
  WriteSparseModelBinary(workspace + "/sparse", model);
}

}  // namespace mr
