#pragma once

// Pictures of meshes for the documentation: flat Lambertian grey shading of
// the faces seen through a PinholeView, rendered with mr::Renderer (face ids)
// and shaded on the CPU. Back faces (seen from behind: wrong orientation or
// holes) are tinted red so that they stand out.

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "geometry/view.h"
#include "render/renderer.h"

namespace mr {

struct MeshPictureOptions {
  // Render at this many times the resolution and average down (1..4).
  int supersample = 2;
  // "key": a fixed light above-left of the camera; "headlight": from the camera.
  std::string lighting = "key";
  // Ambient term in [0, 1): intensity = ambient + (1 - ambient) * max(0, n.l).
  double ambient = 0.12;
  // Background grey level in [0, 255].
  int background = 255;
  bool Check() const;
};

// A view of `bounds` from the direction (azimuth, elevation) in degrees around
// the box centre: azimuth turns about `up` starting from `front` (the
// direction from the centre toward the camera at azimuth 0, elevation 0),
// elevation lifts toward `up`. The box's bounding sphere fills the image.
PinholeView OrbitView(const Eigen::AlignedBox3d& bounds, double azimuth_deg,
                      double elevation_deg, int width, int height, const Eigen::Vector3d& up,
                      const Eigen::Vector3d& front);

// Per-vertex RGB colours (as TriangleMesh::C).
using VertexColors = Eigen::Matrix<uint8_t, Eigen::Dynamic, 3>;

// Shades rendered buffers: 8-bit BGR image of the view's size. Front faces
// are grey, or with `colors` (and the faces F they index) take the colour
// interpolated at each pixel's surface point (an error map, a COLMAP mesh's
// colours); back faces stay red.
cv::Mat ShadeBuffers(const RenderBuffers& buffers, const Eigen::MatrixXd& face_normals,
                     const PinholeView& view, const MeshPictureOptions& options,
                     const Eigen::MatrixXi* F = nullptr, const VertexColors* colors = nullptr);

// Renders and shades a mesh (through `renderer`, or RenderCpu if null), in
// `colors` if given (one row per vertex of V).
cv::Mat RenderMeshPicture(Renderer* renderer, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                          const PinholeView& view, const MeshPictureOptions& options,
                          const VertexColors* colors = nullptr);

// Writes an image as PNG, atomically. Throws InputError if it cannot.
void WritePng(const std::string& path, const cv::Mat& image);

}  // namespace mr
