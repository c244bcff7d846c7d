#pragma once

// Headless EGL + desktop OpenGL (3.3 core or newer) context creation, with no
// window system. Internal to mr_render.
//
// Order for platform "auto":
//   1. EGL devices (EGL_EXT_device_enumeration + EGL_EXT_platform_device) that
//      are not software renderers, NVIDIA ones (EGL_NV_device_cuda) first;
//   2. Mesa's surfaceless platform (EGL_MESA_platform_surfaceless), which uses
//      a DRM render node when there is one and llvmpipe otherwise;
//   3. software EGL devices (EGL_MESA_device_software, i.e. llvmpipe).
// "device" tries 1 then 3; "surfaceless" tries 2 only.
//
// The context renders into framebuffer objects only (EGL_KHR_surfaceless_context);
// no window or pbuffer surface is created.
//
// Threading: a context is made current on the thread that calls
// MakeCurrent(); an EGL context can be current on one thread at a time, so an
// EglContext must be used from the thread that created it (Renderer checks
// this). Several contexts may live in one thread (MakeCurrent switches).

#include <string>

namespace mr {
namespace internal {

class EglContext {
 public:
  // Throws mr::InputError listing every candidate tried and why it failed.
  explicit EglContext(const std::string& platform);
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // Makes this context current on the calling thread if it is not already.
  void MakeCurrent();

  // e.g. "EGL device 0 (/dev/dri/renderD128)", "Mesa surfaceless platform".
  const std::string& path() const { return path_; }

 private:
  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string path_;
};

}  // namespace internal
}  // namespace mr
