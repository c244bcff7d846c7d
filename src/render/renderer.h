#pragma once

// Headless rasterisation of a triangle mesh through EGL + OpenGL.
//
// The GPU resolves visibility (which face is seen at each pixel centre); the
// depth and barycentric coordinates of that face are then computed exactly
// (double-precision ray/triangle intersection at the pixel centre), so the
// buffers do not depend on the driver's depth precision.
//
// Context creation prefers an EGL device (an NVIDIA GPU when present) and
// falls back to Mesa (llvmpipe) through the surfaceless or device platform.
// The choice is logged and reported by Description(). The context is desktop
// OpenGL 3.3 core (or newer) and renders into an FBO; no display is needed.
//
// Threading: a Renderer (its EGL context) must be used from the thread that
// created it; several Renderers may share a thread. Render() parallelises its
// CPU part with OpenMP.
//
// Precision: the mesh is uploaded once per SetMesh as float positions relative
// to its centroid (the centroid is folded into the transform in double).
// The GPU only decides which face is seen at each pixel centre (reverse-Z
// 32-bit float depth when GL 4.5 / ARB_clip_control is available); depth
// and barycentrics come from a double-precision ray/triangle intersection.
// On silhouette pixels where the pixel-centre ray misses the rasterised face
// numerically (the GPU snaps vertices to 1/2^SubpixelBits() px, so it may
// disagree with the exact test within ~2^-SubpixelBits() px of an edge), the
// barycentrics are clamped to the triangle and the depth is
// that of the clamped point.
//
// Memory: SetMesh keeps a copy of (V, F) for the exact CPU step, besides the
// GPU buffers (12 bytes per vertex, 12 per face).
//
// Near plane: 0.9 x the smallest camera z of the mesh's bounding box when it
// is in front of the camera; otherwise 1e-5 x the scene depth (see
// render_internal.h). RenderCpu uses the same plane.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geometry/view.h"

namespace mr {

// Per-pixel outputs of one render, row-major (index row * width + col).
// Pixel (col, row) is sampled at image point (col + 0.5, row + 0.5).
struct RenderBuffers {
  int width = 0;
  int height = 0;
  std::vector<int32_t> face_id;  // visible face, -1 where the background is seen
  std::vector<float> depth;      // camera-frame z of the surface point, 0 where none
  // Barycentric coordinates (u, v) of the surface point in its face: the point
  // is (1 - u - v) * V(F(f,0)) + u * V(F(f,1)) + v * V(F(f,2)). 2 per pixel.
  std::vector<float> bary;

  // Bytes of the buffers of a width x height render: a face id, a depth and
  // two barycentric coordinates per pixel.
  static size_t Bytes(int width, int height) {
    return static_cast<size_t>(width) * height * (sizeof(int32_t) + 3 * sizeof(float));
  }

  int FaceAt(int row, int col) const { return face_id[static_cast<size_t>(row) * width + col]; }
  float DepthAt(int row, int col) const { return depth[static_cast<size_t>(row) * width + col]; }
};

struct RendererOptions {
  // "auto": an EGL device first, then Mesa surfaceless; "device": EGL devices
  // only; "surfaceless": Mesa's surfaceless platform only.
  std::string platform = "auto";
  // Largest side of the offscreen framebuffer (pixels, >= 0; 0 = the driver's
  // limit, at most 4096). Larger views are rendered in tiles.
  int max_tile_size = 0;
  // Reverse-Z depth (depth = near / z, float precision uniform in z) when the
  // context has GL 4.5 or ARB_clip_control; false forces the classic
  // [-1, 1] perspective depth (near/far from the mesh bounds).
  bool reverse_z = true;
  bool Check() const;
};

class Renderer {
 public:
  // Creates the EGL context; throws mr::InputError (with what was tried) if
  // none can be created.
  explicit Renderer(const RendererOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // "EGL device 0: NVIDIA ...", "Mesa llvmpipe (surfaceless)", ...
  std::string Description() const;

  // GL_SUBPIXEL_BITS of the rasteriser (8 on llvmpipe and NVIDIA): vertices
  // are snapped to 1/2^bits px, so the face seen at a pixel whose centre lies
  // within ~2^-bits px of an edge may be either neighbour.
  int SubpixelBits() const;

  // Uploads a mesh; it is used by all following Render calls.
  void SetMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F);

  // Renders the current mesh into `view` at its resolution. Faces behind the
  // camera or closer than a small near plane are clipped. Views larger than
  // the framebuffer limit are rendered in tiles. Without a mesh (or with an
  // empty one) every pixel is background.
  RenderBuffers Render(const PinholeView& view);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// CPU reference implementation with the same output (slow; for tests and
// for machines with no EGL at all).
RenderBuffers RenderCpu(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                        const PinholeView& view);

}  // namespace mr
