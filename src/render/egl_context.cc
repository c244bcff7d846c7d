#include "render/egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <cstring>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "util/error.h"
#include "util/logging.h"

#if defined(__SANITIZE_ADDRESS__)
#define MR_ASAN_BUILD 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MR_ASAN_BUILD 1
#endif
#endif
#ifdef MR_ASAN_BUILD
#include <dlfcn.h>
#include <link.h>
#endif

// Older eglext.h versions lack these.
#ifndef EGL_PLATFORM_SURFACELESS_MESA
#define EGL_PLATFORM_SURFACELESS_MESA 0x31DD
#endif
#ifndef EGL_NO_CONFIG_KHR
#define EGL_NO_CONFIG_KHR ((EGLConfig)0)
#endif

namespace mr {
namespace internal {
namespace {

bool HasExtension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    const bool starts = p == list || p[-1] == ' ';
    const bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

std::string EglErrorString(EGLint code) {
  switch (code) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    default: {
      std::ostringstream s;
      s << "EGL error 0x" << std::hex << code;
      return s.str();
    }
  }
}

// eglInitialize/eglTerminate are per display, and EGL returns the same
// display handle for the same device: count users so that destroying one
// Renderer does not terminate another's display.
std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_users;

#ifdef MR_ASAN_BUILD
// AddressSanitizer builds only (scripts/sanitize.sh). At exit libEGL unloads
// Mesa's DRI driver before LeakSanitizer looks; blocks the driver still holds
// from its own globals (2 x 56 bytes with llvmpipe, Mesa 22.3) then count as
// leaked, allocated by code in no mapped library, which no suppression can
// name. Marking the loaded driver RTLD_NODELETE keeps its globals mapped: the
// blocks stay reachable, and a real leak in the driver is still reported and
// attributed to it (scripts/lsan.supp).
void KeepDriversMapped() {
  std::vector<std::string> drivers;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        const std::string name = info->dlpi_name != nullptr ? info->dlpi_name : "";
        if (name.find("_dri.so") != std::string::npos) {
          static_cast<std::vector<std::string>*>(data)->push_back(name);
        }
        return 0;
      },
      &drivers);
  for (const std::string& driver : drivers) {
    dlopen(driver.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
  }
}
#endif

bool AcquireDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  int& users = g_display_users[display];
  if (users == 0) {
    EGLint major = 0, minor = 0;
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
      g_display_users.erase(display);
      return false;
    }
#ifdef MR_ASAN_BUILD
    KeepDriversMapped();
#endif
  }
  ++users;
  return true;
}

void ReleaseDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(g_display_mutex);
  auto it = g_display_users.find(display);
  if (it == g_display_users.end()) return;
  if (--it->second == 0) {
    eglTerminate(display);
    g_display_users.erase(it);
  }
}

struct Candidate {
  std::string name;
  EGLenum platform;
  void* native;
};

}  // namespace

EglContext::EglContext(const std::string& platform) {
  if (platform != "auto" && platform != "device" && platform != "surfaceless") {
    MR_THROW_INPUT << "RendererOptions::platform = \"" << platform
                   << "\". Violated constraint: one of auto, device, surfaceless";
  }
  std::vector<std::string> tried;
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client_ext == nullptr) {
    MR_THROW_INPUT << "Cannot create an EGL context: EGL client extensions unavailable ("
                   << EglErrorString(eglGetError()) << "); is libEGL (GLVND) installed?";
  }
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  auto query_devices =
      reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
  auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
      eglGetProcAddress("eglQueryDeviceStringEXT"));

  std::vector<Candidate> hardware, software, surfaceless;
  const bool want_devices = platform == "auto" || platform == "device";
  const bool want_surfaceless = platform == "auto" || platform == "surfaceless";
  if (get_platform_display == nullptr || !HasExtension(client_ext, "EGL_EXT_platform_base")) {
    tried.push_back("all platforms: EGL_EXT_platform_base (eglGetPlatformDisplayEXT) missing");
  } else {
    if (want_devices) {
      const bool enumeration = HasExtension(client_ext, "EGL_EXT_device_enumeration") ||
                               HasExtension(client_ext, "EGL_EXT_device_base");
      if (!enumeration || !HasExtension(client_ext, "EGL_EXT_platform_device") ||
          query_devices == nullptr || query_device_string == nullptr) {
        tried.push_back("EGL devices: EGL_EXT_device_enumeration/EGL_EXT_platform_device missing");
      } else {
        EGLint num = 0;
        if (query_devices(0, nullptr, &num) != EGL_TRUE || num <= 0) {
          tried.push_back("EGL devices: eglQueryDevicesEXT found none");
        } else {
          std::vector<EGLDeviceEXT> devices(num);
          query_devices(num, devices.data(), &num);
          std::vector<Candidate> nvidia;
          for (int i = 0; i < num; ++i) {
            const char* ext = query_device_string(devices[i], EGL_EXTENSIONS);
            std::ostringstream name;
            name << "EGL device " << i;
            if (HasExtension(ext, "EGL_MESA_device_software")) {
              name << " (software)";
              software.push_back({name.str(), EGL_PLATFORM_DEVICE_EXT, devices[i]});
              continue;
            }
            if (HasExtension(ext, "EGL_EXT_device_drm")) {
              const char* file = query_device_string(devices[i], EGL_DRM_DEVICE_FILE_EXT);
              if (file != nullptr) name << " (" << file << ")";
            }
            if (HasExtension(ext, "EGL_NV_device_cuda")) {
              nvidia.push_back({name.str() + " NVIDIA", EGL_PLATFORM_DEVICE_EXT, devices[i]});
            } else {
              hardware.push_back({name.str(), EGL_PLATFORM_DEVICE_EXT, devices[i]});
            }
          }
          hardware.insert(hardware.begin(), nvidia.begin(), nvidia.end());
        }
      }
    }
    if (want_surfaceless) {
      if (!HasExtension(client_ext, "EGL_MESA_platform_surfaceless")) {
        tried.push_back("Mesa surfaceless platform: EGL_MESA_platform_surfaceless missing");
      } else {
        surfaceless.push_back(
            {"Mesa surfaceless platform", EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY});
      }
    }
  }
  std::vector<Candidate> candidates = hardware;
  candidates.insert(candidates.end(), surfaceless.begin(), surfaceless.end());
  candidates.insert(candidates.end(), software.begin(), software.end());

  for (const Candidate& c : candidates) {
    EGLDisplay display = get_platform_display(c.platform, c.native, nullptr);
    if (display == EGL_NO_DISPLAY) {
      tried.push_back(c.name + ": eglGetPlatformDisplayEXT failed (" +
                      EglErrorString(eglGetError()) + ")");
      continue;
    }
    if (!AcquireDisplay(display)) {
      tried.push_back(c.name + ": eglInitialize failed (" + EglErrorString(eglGetError()) + ")");
      continue;
    }
    auto fail = [&](const std::string& why) {
      tried.push_back(c.name + ": " + why);
      ReleaseDisplay(display);
    };
    const char* ext = eglQueryString(display, EGL_EXTENSIONS);
    if (!HasExtension(ext, "EGL_KHR_surfaceless_context")) {
      fail("EGL_KHR_surfaceless_context missing");
      continue;
    }
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
      fail("eglBindAPI(EGL_OPENGL_API) failed (" + EglErrorString(eglGetError()) + ")");
      continue;
    }
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!HasExtension(ext, "EGL_KHR_no_config_context")) {
      const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0,
                                       EGL_NONE};
      EGLint num_configs = 0;
      if (eglChooseConfig(display, config_attribs, &config, 1, &num_configs) != EGL_TRUE ||
          num_configs < 1) {
        fail("no EGLConfig with EGL_OPENGL_BIT");
        continue;
      }
    }
    const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                      3,
                                      EGL_CONTEXT_MINOR_VERSION,
                                      3,
                                      EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                      EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                      EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attribs);
    if (context == EGL_NO_CONTEXT) {
      fail("eglCreateContext(OpenGL 3.3 core) failed (" + EglErrorString(eglGetError()) + ")");
      continue;
    }
    if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
      const std::string why = EglErrorString(eglGetError());
      eglDestroyContext(display, context);
      fail("eglMakeCurrent without surface failed (" + why + ")");
      continue;
    }
    display_ = display;
    context_ = context;
    path_ = c.name;
    for (const std::string& t : tried) MR_LOG(VERBOSE) << "EGL: skipped " << t;
    return;
  }
  std::ostringstream msg;
  msg << "Cannot create a headless EGL OpenGL 3.3 core context (platform \"" << platform
      << "\"). Tried:";
  if (tried.empty()) msg << " nothing (no candidate found)";
  for (const std::string& t : tried) msg << " [" << t << "]";
  msg << ". Install Mesa's EGL (libegl-mesa0, libgl1-mesa-dri) or the NVIDIA driver; "
         "EGL_LOG_LEVEL=debug shows Mesa's reasons.";
  MR_THROW_INPUT << msg.str();
}

EglContext::~EglContext() {
  if (context_ == nullptr) return;
  if (eglGetCurrentContext() == context_) {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  eglDestroyContext(display_, context_);
  ReleaseDisplay(display_);
}

void EglContext::MakeCurrent() {
  // eglGetCurrentContext() and eglMakeCurrent() act on the thread's bound API.
  if (eglQueryAPI() != EGL_OPENGL_API) eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == context_) return;
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) != EGL_TRUE) {
    MR_THROW_INPUT << "eglMakeCurrent failed for " << path_ << " ("
                   << EglErrorString(eglGetError())
                   << "); a Renderer must be used from the thread that created it";
  }
}

}  // namespace internal
}  // namespace mr
