// GPU visibility through EGL + OpenGL 3.3 core; exact depth and barycentrics
// on the CPU. See renderer.h.
//
// GL entry points come from GLVND's libOpenGL (GL_GLEXT_PROTOTYPES), which
// dispatches to the vendor of the current EGL context.

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <thread>
#include <vector>

#include "render/egl_context.h"
#include "render/render_internal.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"

namespace mr {
namespace {

// The mesh is drawn unindexed, three vertices of its own per face, each
// carrying the face's id + 1 (0 is the background) as a flat integer. The
// indexed draw with gl_PrimitiveID took 33 ms a view on llvmpipe for the
// example's 159k faces at 640x480, this 26 ms (the same ids: the triangles
// and their float corners are the same; Mesa's draw stage appears to
// re-assemble the triangles to supply gl_PrimitiveID).
const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in int face;
uniform mat4 clip_from_local;
flat out int v_face;
void main() { v_face = face; gl_Position = clip_from_local * vec4(position, 1.0); }
)";

const char* kFragmentShader = R"(#version 330 core
flat in int v_face;
layout(location = 0) out int face_id;
void main() { face_id = v_face; }
)";

GLuint CompileShader(GLenum type, const char* source) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetShaderInfoLog(shader, sizeof(log), nullptr, log);
    glDeleteShader(shader);
    MR_CHECK(false) << "renderer shader does not compile: " << log;
  }
  return shader;
}

std::string GlString(GLenum name) {
  const GLubyte* s = glGetString(name);
  return s == nullptr ? std::string("?") : std::string(reinterpret_cast<const char*>(s));
}

}  // namespace

bool RendererOptions::Check() const {
  if (platform != "auto" && platform != "device" && platform != "surfaceless") {
    MR_THROW_INPUT << "RendererOptions::platform = \"" << platform
                   << "\". Violated constraint: platform in {auto, device, surfaceless}";
  }
  if (max_tile_size < 0) {
    MR_THROW_INPUT << "RendererOptions::max_tile_size = " << max_tile_size
                   << ". Violated constraint: max_tile_size >= 0";
  }
  return true;
}

struct Renderer::Impl {
  std::unique_ptr<internal::EglContext> egl;
  std::thread::id owner;
  std::string description;
  bool clip_control = false;  // reverse-Z with a [0, 1] depth range
  int max_tile = 0;           // largest FBO side
  int subpixel_bits = 0;

  GLuint program = 0, vao = 0, vbo = 0, face_vbo = 0;  // corners, their face ids
  GLint clip_from_local_loc = -1;
  GLuint fbo = 0, color_rb = 0, depth_rb = 0;
  int fbo_width = 0, fbo_height = 0;

  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();

  void MakeCurrent() {
    MR_CHECK(std::this_thread::get_id() == owner)
        << "a Renderer must be used from the thread that created it";
    egl->MakeCurrent();
  }

  void CheckGl(const char* what) {
    const GLenum e = glGetError();
    if (e == GL_OUT_OF_MEMORY) {
      MR_THROW_INPUT << "OpenGL out of memory during " << what << " (" << description << ")";
    }
    MR_CHECK(e == GL_NO_ERROR) << "OpenGL error 0x" << std::hex << e << " during " << what;
  }

  void EnsureFbo(int width, int height) {
    if (fbo != 0 && fbo_width == width && fbo_height == height) return;
    if (fbo == 0) {
      glGenFramebuffers(1, &fbo);
      glGenRenderbuffers(1, &color_rb);
      glGenRenderbuffers(1, &depth_rb);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, color_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_R32I, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
    CheckGl("framebuffer allocation");
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    MR_CHECK(status == GL_FRAMEBUFFER_COMPLETE)
        << "framebuffer " << width << "x" << height << " incomplete: 0x" << std::hex << status;
    fbo_width = width;
    fbo_height = height;
  }

  // Clip-space transform of the centred positions (V - centroid) for the
  // sub-view `view` (a tile). Computed in double, rounded to float once.
  Eigen::Matrix4f ClipFromLocal(const PinholeView& view, double near, double far) const {
    Eigen::Matrix4d cam_from_local = Eigen::Matrix4d::Identity();
    cam_from_local.topLeftCorner<3, 3>() = view.R;
    cam_from_local.topRightCorner<3, 1>() = view.R * centroid + view.t;
    // Image point (x, y) maps to window (x, y) (no flip: window row r, which
    // glReadPixels returns as memory row r, is image row r).
    const double W = view.width, H = view.height;
    Eigen::Matrix4d clip_from_cam = Eigen::Matrix4d::Zero();
    clip_from_cam(0, 0) = 2 * view.fx / W;
    clip_from_cam(0, 2) = 2 * view.cx / W - 1;
    clip_from_cam(1, 1) = 2 * view.fy / H;
    clip_from_cam(1, 2) = 2 * view.cy / H - 1;
    if (clip_control) {
      // Reverse-Z: depth = near / z in (0, 1]; clipped where z < near.
      clip_from_cam(2, 3) = near;
    } else {
      clip_from_cam(2, 2) = (far + near) / (far - near);
      clip_from_cam(2, 3) = -2 * far * near / (far - near);
    }
    clip_from_cam(3, 2) = 1;
    return (clip_from_cam * cam_from_local).cast<float>();
  }
};

Renderer::Renderer(const RendererOptions& options) : impl_(new Impl) {
  options.Check();
  Impl& m = *impl_;
  m.egl.reset(new internal::EglContext(options.platform));
  m.owner = std::this_thread::get_id();

  const std::string version = GlString(GL_VERSION);
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33) {
    MR_THROW_INPUT << "OpenGL " << version << " via " << m.egl->path()
                   << " is older than the 3.3 core profile the renderer needs";
  }
  m.clip_control = major * 10 + minor >= 45;
  if (!m.clip_control && options.reverse_z) {
    GLint num_ext = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &num_ext);
    for (GLint i = 0; i < num_ext; ++i) {
      const GLubyte* e = glGetStringi(GL_EXTENSIONS, i);
      if (e && std::strcmp(reinterpret_cast<const char*>(e), "GL_ARB_clip_control") == 0) {
        m.clip_control = true;
      }
    }
  }
  if (!options.reverse_z) m.clip_control = false;
  GLint max_rb = 0, max_vp[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_vp);
  glGetIntegerv(GL_SUBPIXEL_BITS, &m.subpixel_bits);
  // Tiles of at most 4096 pixels a side bound the FBO memory (2 x 64 MiB).
  m.max_tile = std::min({max_rb, max_vp[0], max_vp[1], 4096});
  MR_CHECK_GE(m.max_tile, 64) << "GL_MAX_RENDERBUFFER_SIZE / GL_MAX_VIEWPORT_DIMS";
  if (options.max_tile_size > 0) m.max_tile = std::min(m.max_tile, options.max_tile_size);

  std::ostringstream desc;
  desc << GlString(GL_VENDOR) << " " << GlString(GL_RENDERER) << ", OpenGL " << version << " via "
       << m.egl->path();
  if (!m.clip_control) desc << " (standard depth, no reverse-Z)";
  m.description = desc.str();
  MR_LOG(INFO) << "Renderer: " << m.description;

  const GLuint vs = CompileShader(GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = CompileShader(GL_FRAGMENT_SHADER, kFragmentShader);
  m.program = glCreateProgram();
  glAttachShader(m.program, vs);
  glAttachShader(m.program, fs);
  glLinkProgram(m.program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(m.program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetProgramInfoLog(m.program, sizeof(log), nullptr, log);
    MR_CHECK(false) << "renderer program does not link: " << log;
  }
  m.clip_from_local_loc = glGetUniformLocation(m.program, "clip_from_local");
  glGenVertexArrays(1, &m.vao);
  glGenBuffers(1, &m.vbo);
  glGenBuffers(1, &m.face_vbo);
  m.CheckGl("renderer setup");
}

Renderer::~Renderer() {
  if (!impl_ || !impl_->egl) return;
  Impl& m = *impl_;
  // GL objects die with the context; delete them explicitly only when the
  // context can be made current here (the owner thread).
  if (std::this_thread::get_id() == m.owner) {
    try {
      m.egl->MakeCurrent();
      glDeleteFramebuffers(1, &m.fbo);
      glDeleteRenderbuffers(1, &m.color_rb);
      glDeleteRenderbuffers(1, &m.depth_rb);
      glDeleteBuffers(1, &m.vbo);
      glDeleteBuffers(1, &m.face_vbo);
      glDeleteVertexArrays(1, &m.vao);
      glDeleteProgram(m.program);
    } catch (const std::exception&) {
    }
  }
  m.egl.reset();
}

std::string Renderer::Description() const { return impl_->description; }

int Renderer::SubpixelBits() const { return impl_->subpixel_bits; }

void Renderer::SetMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  Impl& m = *impl_;
  m.MakeCurrent();  // also checks the calling thread
  PinholeView dummy;
  dummy.width = dummy.height = 1;
  internal::CheckViewAndMesh(V, F, dummy);
  m.V = V;
  m.F = F;
  m.centroid = V.rows() > 0 ? Eigen::Vector3d(V.colwise().mean().transpose())
                            : Eigen::Vector3d::Zero();
  // Positions relative to the centroid: float keeps ~7 digits of the offset
  // to the centroid instead of the absolute (possibly geo-referenced)
  // coordinates; the centroid is folded into the transform in double.
  std::vector<float> positions(static_cast<size_t>(F.rows()) * 9);
  std::vector<int32_t> ids(static_cast<size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        positions[9 * f + 3 * c + k] = static_cast<float>(V(F(f, c), k) - m.centroid[k]);
      }
      ids[3 * f + c] = static_cast<int32_t>(f + 1);
    }
  }
  glBindVertexArray(m.vao);
  glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
  glBufferData(GL_ARRAY_BUFFER, positions.size() * sizeof(float), positions.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 3 * sizeof(float), nullptr);
  glBindBuffer(GL_ARRAY_BUFFER, m.face_vbo);
  glBufferData(GL_ARRAY_BUFFER, ids.size() * sizeof(int32_t), ids.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(1);
  glVertexAttribIPointer(1, 1, GL_INT, sizeof(int32_t), nullptr);
  glBindVertexArray(0);
  m.CheckGl("mesh upload");
}

RenderBuffers Renderer::Render(const PinholeView& view) {
  Impl& m = *impl_;
  m.MakeCurrent();  // also checks the calling thread
  internal::CheckViewAndMesh(m.V, m.F, view);
  const int W = view.width, H = view.height;
  RenderBuffers out = internal::EmptyBuffers(W, H);
  double far = 0;
  const double near = internal::NearPlane(m.V, view, &far);
  if (m.F.rows() == 0 || !(near > 0)) return out;
  const double start_s = ElapsedSeconds();

  // 1. Visibility on the GPU, tile by tile (a tile is the view with the
  //    principal point shifted by the tile's origin).
  const int tile_w = std::min(W, m.max_tile), tile_h = std::min(H, m.max_tile);
  m.EnsureFbo(tile_w, tile_h);
  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  glUseProgram(m.program);
  glBindVertexArray(m.vao);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glDisable(GL_DITHER);
  glEnable(GL_DEPTH_TEST);
  if (m.clip_control) {
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    glDepthFunc(GL_GREATER);
  } else {
    glDepthFunc(GL_LESS);
  }
  glDepthMask(GL_TRUE);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  std::vector<int32_t> tile_ids(static_cast<size_t>(tile_w) * tile_h);
  std::vector<int32_t> ids(static_cast<size_t>(W) * H);
  double draw_s = 0;  // clear + draw (measured only when logging verbosely)
  for (int y0 = 0; y0 < H; y0 += tile_h) {
    for (int x0 = 0; x0 < W; x0 += tile_w) {
      const int tw = std::min(tile_w, W - x0), th = std::min(tile_h, H - y0);
      PinholeView tile = view;
      tile.width = tw;
      tile.height = th;
      tile.cx -= x0;
      tile.cy -= y0;
      const double tile_s = ElapsedSeconds();
      glViewport(0, 0, tw, th);
      const GLint zero[4] = {0, 0, 0, 0};
      glClearBufferiv(GL_COLOR, 0, zero);
      const GLfloat clear_depth = m.clip_control ? 0.0f : 1.0f;
      glClearBufferfv(GL_DEPTH, 0, &clear_depth);
      const Eigen::Matrix4f M = m.ClipFromLocal(tile, near, far);
      glUniformMatrix4fv(m.clip_from_local_loc, 1, GL_FALSE, M.data());  // column-major
      glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(m.F.rows() * 3));
      if (LogEnabled(LogLevel::kVerbose)) {
        glFinish();
        draw_s += ElapsedSeconds() - tile_s;
      }
      glReadPixels(0, 0, tw, th, GL_RED_INTEGER, GL_INT, tile_ids.data());
      m.CheckGl("render");
      for (int r = 0; r < th; ++r) {
        std::copy_n(tile_ids.data() + static_cast<size_t>(r) * tw, tw,
                    ids.data() + static_cast<size_t>(y0 + r) * W + x0);
      }
    }
  }
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  const double gpu_s = ElapsedSeconds();

  // 2. Exact depth and barycentrics on the CPU: intersect the pixel-centre ray
  //    with the visible face in double precision. Where the ray misses the
  //    face numerically (pixels on its silhouette, where the GPU's
  //    fixed-point rasterisation and the exact test disagree), the
  //    barycentrics are clamped to the triangle (u, v >= 0, then scaled so
  //    that u + v <= 1) and the depth is that of the clamped point; for a face
  //    exactly parallel to the ray, the centroid is used.
  const int num_faces = static_cast<int>(m.F.rows());
  const Eigen::MatrixXd& V = m.V;
  const Eigen::MatrixXi& F = m.F;
  bool bad_id = false;
#pragma omp parallel for schedule(static) reduction(|| : bad_id)
  for (int row = 0; row < H; ++row) {
    const double dy = (row + 0.5 - view.cy) / view.fy;
    for (int col = 0; col < W; ++col) {
      const size_t i = static_cast<size_t>(row) * W + col;
      const int id = ids[i];
      if (id <= 0) continue;
      if (id > num_faces) {
        bad_id = true;
        continue;
      }
      const int f = id - 1;
      const Eigen::Vector3d P0 = view.WorldToCamera(V.row(F(f, 0)).transpose());
      const Eigen::Vector3d P1 = view.WorldToCamera(V.row(F(f, 1)).transpose());
      const Eigen::Vector3d P2 = view.WorldToCamera(V.row(F(f, 2)).transpose());
      const Eigen::Vector3d d((col + 0.5 - view.cx) / view.fx, dy, 1.0);
      double t = 0, u = 1.0 / 3, v = 1.0 / 3;
      const bool hit = internal::IntersectRay(d, P0, P1, P2, &t, &u, &v);
      if (!hit) u = v = 1.0 / 3;
      if (!hit || u < 0 || v < 0 || u + v > 1) {
        u = std::max(u, 0.0);
        v = std::max(v, 0.0);
        if (u + v > 1) {
          const double s = u + v;
          u /= s;
          v /= s;
        }
        t = ((1 - u - v) * P0 + u * P1 + v * P2).z();
      }
      out.face_id[i] = f;
      out.depth[i] = static_cast<float>(t);
      out.bary[2 * i] = static_cast<float>(u);
      out.bary[2 * i + 1] = static_cast<float>(v);
    }
  }
  MR_CHECK(!bad_id) << "GPU returned a face id beyond the mesh's " << num_faces << " faces";
  MR_LOG(VERBOSE) << "Render " << W << "x" << H << ": visibility (GL) "
                  << 1e3 * (gpu_s - start_s) << " ms (draw " << 1e3 * draw_s
                  << " ms), exact depth (CPU) "
                  << 1e3 * (ElapsedSeconds() - gpu_s) << " ms";
  return out;
}

}  // namespace mr
