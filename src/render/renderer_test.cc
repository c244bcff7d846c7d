#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include <Eigen/Geometry>

#include "geometry/primitives.h"
#include "util/error.h"

namespace mr {
namespace {

// GPU tests fail loudly when no EGL context can be created, unless
// MR_ALLOW_NO_EGL=1 (then they are skipped).
bool AllowNoEgl() {
  const char* e = std::getenv("MR_ALLOW_NO_EGL");
  return e != nullptr && std::string(e) == "1";
}

// One renderer for the whole suite (created on the main thread, which runs
// every test).
Renderer* SharedRenderer(std::string* error) {
  static std::unique_ptr<Renderer> renderer;
  static std::string failure;
  static bool tried = false;
  if (!tried) {
    tried = true;
    try {
      renderer.reset(new Renderer());
    } catch (const InputError& e) {
      failure = e.what();
    }
  }
  *error = failure;
  return renderer.get();
}

#define GET_RENDERER(r)                                              \
  std::string egl_error_;                                            \
  Renderer* r = SharedRenderer(&egl_error_);                         \
  if (r == nullptr) {                                                \
    if (AllowNoEgl()) GTEST_SKIP() << "MR_ALLOW_NO_EGL=1: " << egl_error_; \
    FAIL() << "no EGL context (set MR_ALLOW_NO_EGL=1 to skip): " << egl_error_; \
  }

PinholeView MakeView(int width, int height, double fx, double fy, double cx, double cy) {
  PinholeView v;
  v.width = width;
  v.height = height;
  v.fx = fx;
  v.fy = fy;
  v.cx = cx;
  v.cy = cy;
  return v;
}

// World point (identity pose) that projects to image point (x, y) at depth z.
Eigen::Vector3d Unproject(const PinholeView& v, double x, double y, double z) {
  return Eigen::Vector3d((x - v.cx) / v.fx * z, (y - v.cy) / v.fy * z, z);
}

// Checks a render of a single fronto-parallel triangle with image corners
// `p` at depth `z` against the analytic answer: coverage by the
// point-in-triangle test of pixel centres (pixels within `edge_tol` px of an
// edge are not judged), depth z and image-space barycentrics (exact for a
// fronto-parallel triangle), both to 1e-5.
void ExpectAnalyticTriangle(const RenderBuffers& buf, const PinholeView& view,
                            const Eigen::Vector2d p[3], double z, double edge_tol,
                            const std::string& what) {
  ASSERT_EQ(buf.width, view.width) << what;
  ASSERT_EQ(buf.height, view.height) << what;
  ASSERT_EQ(buf.face_id.size(), static_cast<size_t>(view.width * view.height)) << what;
  ASSERT_EQ(buf.bary.size(), 2 * buf.face_id.size()) << what;
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() * b.y() - a.y() * b.x();
  };
  const double area2 = cross(p[1] - p[0], p[2] - p[0]);
  int inside = 0, judged = 0, wrong = 0;
  for (int row = 0; row < view.height; ++row) {
    for (int col = 0; col < view.width; ++col) {
      const Eigen::Vector2d q(col + 0.5, row + 0.5);
      // Barycentrics of q: weight of p[1] is u, of p[2] is v.
      const double u = cross(p[0] - q, p[2] - q) / -area2;
      const double v = cross(p[0] - q, p[1] - q) / area2;
      const double w = 1 - u - v;
      // Distances (px) to the edges opposite p[0], p[1], p[2].
      const double d0 = std::abs(w * area2) / (p[2] - p[1]).norm();
      const double d1 = std::abs(u * area2) / (p[2] - p[0]).norm();
      const double d2 = std::abs(v * area2) / (p[1] - p[0]).norm();
      if (std::min({d0, d1, d2}) < edge_tol) continue;
      ++judged;
      const bool expect = u > 0 && v > 0 && w > 0;
      const int id = buf.FaceAt(row, col);
      if (expect != (id == 0)) {
        ++wrong;
        ADD_FAILURE() << what << ": pixel (" << col << ", " << row << ") face " << id
                      << ", expected " << (expect ? 0 : -1);
        continue;
      }
      const size_t i = static_cast<size_t>(row) * view.width + col;
      if (!expect) {
        EXPECT_EQ(buf.depth[i], 0.0f);
        continue;
      }
      ++inside;
      EXPECT_NEAR(buf.depth[i], z, 1e-5 * z) << what << " at (" << col << ", " << row << ")";
      EXPECT_NEAR(buf.bary[2 * i], u, 1e-5) << what << " at (" << col << ", " << row << ")";
      EXPECT_NEAR(buf.bary[2 * i + 1], v, 1e-5) << what << " at (" << col << ", " << row << ")";
    }
    if (wrong > 10) break;
  }
  EXPECT_GT(inside, 20) << what << ": the triangle should cover pixels";
  EXPECT_GT(judged, view.width * view.height * 9 / 10) << what;
}

// `renderer` may be null: then only the CPU reference is checked.
void CheckAnalyticTriangle(Renderer* renderer, const PinholeView& view, const Eigen::Vector2d p[3],
                           double z) {
  Eigen::MatrixXd V(3, 3);
  for (int k = 0; k < 3; ++k) V.row(k) = Unproject(view, p[k].x(), p[k].y(), z).transpose();
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 2;
  ExpectAnalyticTriangle(RenderCpu(V, F, view), view, p, z, 1e-3, "CPU");
  if (renderer == nullptr) return;
  renderer->SetMesh(V, F);
  // The GPU snaps vertices to 1/2^SubpixelBits() px (1/256 on llvmpipe and
  // NVIDIA), which moves edges by up to ~0.7 of that: pixels that close to an
  // edge may go either way. The CPU reference is exact (1e-3 px).
  const double gpu_tol = std::ldexp(1.0, -std::max(renderer->SubpixelBits(), 4));
  ExpectAnalyticTriangle(renderer->Render(view), view, p, z, gpu_tol, "GPU");
}

TEST(RendererOptions, DefaultsAreValid) { EXPECT_TRUE(RendererOptions().Check()); }

TEST(RendererOptions, BadValuesThrow) {
  RendererOptions o;
  o.platform = "x11";
  EXPECT_THROW(o.Check(), InputError);
  o = RendererOptions();
  o.max_tile_size = -1;
  EXPECT_THROW(o.Check(), InputError);
}

// The CPU reference alone (runs without EGL too).
TEST(RenderCpu, SingleTriangleMatchesAnalytic) {
  const Eigen::Vector2d p[3] = {{20.3, 15.2}, {130.7, 30.1}, {60.2, 100.9}};
  CheckAnalyticTriangle(nullptr, MakeView(160, 120, 100, 100, 80, 60), p, 5.0);
  const Eigen::Vector2d q[3] = {{5.5, 3.3}, {40.6, 115.2}, {150.1, 60.4}};
  CheckAnalyticTriangle(nullptr, MakeView(160, 120, 90, 110, 31.5, 92.25), q, 3.0);
}

TEST(RenderCpu, EmptyAndBadInput) {
  const PinholeView view = MakeView(64, 48, 50, 50, 32, 24);
  const RenderBuffers buf = RenderCpu(Eigen::MatrixXd(0, 3), Eigen::MatrixXi(0, 3), view);
  ASSERT_EQ(buf.face_id.size(), 64u * 48u);
  for (int id : buf.face_id) EXPECT_EQ(id, -1);
  Eigen::MatrixXd V = Eigen::MatrixXd::Random(3, 3);
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 3;
  EXPECT_THROW(RenderCpu(V, F, view), InputError);
}

TEST(Renderer, DescriptionNamesThePath) {
  GET_RENDERER(r);
  const std::string d = r->Description();
  std::cout << "Renderer: " << d << ", subpixel bits " << r->SubpixelBits() << std::endl;
  EXPECT_GE(r->SubpixelBits(), 4);  // the GL minimum
  EXPECT_NE(d.find(" via "), std::string::npos) << d;
}

TEST(Renderer, SingleTriangleMatchesAnalytic) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(160, 120, 100, 100, 80, 60);
  const Eigen::Vector2d p[3] = {{20.3, 15.2}, {130.7, 30.1}, {60.2, 100.9}};
  CheckAnalyticTriangle(r, view, p, 5.0);
  // Opposite orientation (clockwise in the image) is visible too.
  const Eigen::Vector2d q[3] = {p[0], p[2], p[1]};
  CheckAnalyticTriangle(r, view, q, 2.5);
}

TEST(Renderer, OffCentrePrincipalPoint) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(160, 120, 90, 110, 31.5, 92.25);
  const Eigen::Vector2d p[3] = {{5.5, 3.3}, {150.1, 60.4}, {40.6, 115.2}};
  CheckAnalyticTriangle(r, view, p, 3.0);
}

TEST(Renderer, NonSquareImage) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(48, 150, 60, 75, 24, 75);
  const Eigen::Vector2d p[3] = {{2.2, 10.7}, {45.1, 80.3}, {10.4, 140.6}};
  CheckAnalyticTriangle(r, view, p, 7.0);
}

// A tilted triangle seen by a rotated, translated camera: every covered pixel's
// surface point (from depth and barycentrics) must project to the pixel centre.
TEST(Renderer, TiltedTriangleIsExact) {
  GET_RENDERER(r);
  PinholeView view = MakeView(120, 90, 100, 100, 60, 45);
  view.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  view.t = Eigen::Vector3d(0.2, -0.1, 1.0);
  const Eigen::Vector3d C = view.Center();
  Eigen::MatrixXd V(3, 3);
  // Camera-frame corners, tilted (depth varies from 3 to 6), mapped to world.
  const Eigen::Vector3d Pc[3] = {{-1.2, -0.9, 3.0}, {1.5, -0.5, 6.0}, {-0.3, 1.3, 4.0}};
  for (int k = 0; k < 3; ++k) V.row(k) = (view.R.transpose() * (Pc[k] - view.t)).transpose();
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 2;
  r->SetMesh(V, F);
  for (const RenderBuffers& buf : {r->Render(view), RenderCpu(V, F, view)}) {
    int covered = 0;
    for (int row = 0; row < view.height; ++row) {
      for (int col = 0; col < view.width; ++col) {
        const size_t i = static_cast<size_t>(row) * view.width + col;
        if (buf.face_id[i] < 0) continue;
        ++covered;
        const double u = buf.bary[2 * i], v = buf.bary[2 * i + 1];
        const Eigen::Vector3d X = (1 - u - v) * V.row(0) + u * V.row(1) + v * V.row(2);
        const Eigen::Vector3d Xc = view.WorldToCamera(X);
        EXPECT_NEAR(Xc.z(), buf.depth[i], 1e-5 * Xc.z());
        const Eigen::Vector2d x = view.Project(X);
        // Silhouette pixels are clamped to the triangle (within ~1 px).
        const bool interior = u > 1e-3 && v > 1e-3 && u + v < 1 - 1e-3;
        const double tol = interior ? 1e-3 : 1.0;
        EXPECT_NEAR(x.x(), col + 0.5, tol) << col << ", " << row;
        EXPECT_NEAR(x.y(), row + 0.5, tol) << col << ", " << row;
        // The ray through the pixel centre hits depth * direction.
        if (interior) {
          const Eigen::Vector3d hit = C + buf.depth[i] * view.RayDirection(col + 0.5, row + 0.5);
          EXPECT_LT((hit - X).norm(), 1e-4);
        }
      }
    }
    EXPECT_GT(covered, 500);
  }
}

TEST(Renderer, IcosphereMatchesCpu) {
  GET_RENDERER(r);
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, Eigen::Vector3d(0.1, -0.2, 0.3), &V, &F);
  PinholeView view = MakeView(160, 120, 140, 150, 83.0, 57.5);
  view.R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  view.t = Eigen::Vector3d(0.05, 0.1, 3.5) - view.R * Eigen::Vector3d(0.1, -0.2, 0.3);
  r->SetMesh(V, F);
  const RenderBuffers gpu = r->Render(view);
  const RenderBuffers cpu = RenderCpu(V, F, view);
  int agree = 0, both = 0, hit = 0;
  for (size_t i = 0; i < gpu.face_id.size(); ++i) {
    agree += gpu.face_id[i] == cpu.face_id[i];
    hit += cpu.face_id[i] >= 0;
    if (gpu.face_id[i] >= 0 && cpu.face_id[i] >= 0) {
      ++both;
      EXPECT_NEAR(gpu.depth[i], cpu.depth[i], 1e-4 * cpu.depth[i]) << i;
    }
  }
  const double n = static_cast<double>(gpu.face_id.size());
  EXPECT_GT(agree / n, 0.995);
  EXPECT_GT(hit / n, 0.2);
  EXPECT_GT(both, hit * 99 / 100);
}

// Geo-referenced coordinates (1e6 m offsets, a 1 m sphere): float positions
// are only accurate because the centroid is subtracted before upload.
TEST(Renderer, LargeCoordinatesMatchCpu) {
  GET_RENDERER(r);
  const Eigen::Vector3d offset(3.2e6, -1.7e6, 2.5e5);
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, offset, &V, &F);
  PinholeView view = MakeView(120, 90, 110, 110, 61, 44);
  view.R = Eigen::AngleAxisd(-0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  view.t = Eigen::Vector3d(0, 0, 3) - view.R * offset;
  r->SetMesh(V, F);
  const RenderBuffers gpu = r->Render(view);
  const RenderBuffers cpu = RenderCpu(V, F, view);
  int agree = 0, hit = 0;
  for (size_t i = 0; i < gpu.face_id.size(); ++i) {
    agree += gpu.face_id[i] == cpu.face_id[i];
    hit += cpu.face_id[i] >= 0;
    if (gpu.face_id[i] >= 0 && cpu.face_id[i] >= 0) {
      EXPECT_NEAR(gpu.depth[i], cpu.depth[i], 1e-4 * cpu.depth[i]);
    }
  }
  EXPECT_GT(hit, static_cast<int>(gpu.face_id.size() / 5));
  EXPECT_GT(agree, static_cast<int>(gpu.face_id.size() * 995 / 1000));
}

// The classic [-1, 1] depth path (used where GL 4.5 / ARB_clip_control is
// missing) resolves occlusion like reverse-Z.
TEST(Renderer, StandardDepthMatchesCpu) {
  GET_RENDERER(r);
  RendererOptions options;
  options.reverse_z = false;
  Renderer classic(options);
  EXPECT_NE(classic.Description().find("standard depth"), std::string::npos);
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, Eigen::Vector3d::Zero(), &V, &F);
  PinholeView view = MakeView(120, 90, 100, 100, 60, 45);
  view.t = Eigen::Vector3d(0.1, 0, 3);
  classic.SetMesh(V, F);
  const RenderBuffers gpu = classic.Render(view);
  const RenderBuffers cpu = RenderCpu(V, F, view);
  int agree = 0;
  for (size_t i = 0; i < gpu.face_id.size(); ++i) agree += gpu.face_id[i] == cpu.face_id[i];
  EXPECT_GT(agree, static_cast<int>(gpu.face_id.size() * 995 / 1000));
}

TEST(Renderer, TiledRenderMatchesUntiled) {
  GET_RENDERER(r);
  RendererOptions options;
  options.max_tile_size = 64;
  std::unique_ptr<Renderer> tiled;
  ASSERT_NO_THROW(tiled.reset(new Renderer(options)));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(3, 1.0, Eigen::Vector3d::Zero(), &V, &F);
  PinholeView view = MakeView(150, 100, 120, 120, 70, 55);
  view.t = Eigen::Vector3d(0, 0, 3);
  r->SetMesh(V, F);
  tiled->SetMesh(V, F);  // two renderers alternating on one thread
  const RenderBuffers a = r->Render(view);
  const RenderBuffers b = tiled->Render(view);
  int agree = 0;
  for (size_t i = 0; i < a.face_id.size(); ++i) agree += a.face_id[i] == b.face_id[i];
  EXPECT_GT(agree, static_cast<int>(a.face_id.size() * 998 / 1000));
}

TEST(Renderer, NearerTriangleWins) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(80, 60, 60, 60, 40, 30);
  for (int order = 0; order < 2; ++order) {
    const double z_a = order == 0 ? 3.0 : 5.0;  // face 0
    const double z_b = order == 0 ? 5.0 : 3.0;  // face 1
    Eigen::MatrixXd V(6, 3);
    V.row(0) = Unproject(view, 5, 5, z_a).transpose();
    V.row(1) = Unproject(view, 60, 8, z_a).transpose();
    V.row(2) = Unproject(view, 10, 55, z_a).transpose();
    V.row(3) = Unproject(view, 75, 50, z_b).transpose();
    V.row(4) = Unproject(view, 20, 10, z_b).transpose();
    V.row(5) = Unproject(view, 70, 5, z_b).transpose();
    Eigen::MatrixXi F(2, 3);
    F << 0, 1, 2, 3, 4, 5;
    r->SetMesh(V, F);
    const int nearer = order == 0 ? 0 : 1;
    for (const RenderBuffers& buf : {r->Render(view), RenderCpu(V, F, view)}) {
      // Pixel (40, 15) lies inside both triangles.
      EXPECT_EQ(buf.FaceAt(15, 40), nearer) << "order " << order;
      EXPECT_NEAR(buf.DepthAt(15, 40), 3.0, 1e-5);
      int seen[2] = {0, 0};
      for (int id : buf.face_id) {
        if (id >= 0) ++seen[id];
      }
      EXPECT_GT(seen[0], 50);
      EXPECT_GT(seen[1], 50);
    }
  }
}

TEST(Renderer, FaceBehindCamera) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(80, 60, 60, 60, 40, 30);
  Eigen::MatrixXd V(9, 3);
  // Face 0: visible, upper left corner.
  V.row(0) = Unproject(view, 2, 2, 4).transpose();
  V.row(1) = Unproject(view, 20, 2, 4).transpose();
  V.row(2) = Unproject(view, 2, 20, 4).transpose();
  // Face 1: behind the camera (z = -4); with the sign of z lost it would
  // cover the image centre.
  V.row(3) = Unproject(view, 10, 10, -4).transpose();
  V.row(4) = Unproject(view, 70, 15, -4).transpose();
  V.row(5) = Unproject(view, 40, 55, -4).transpose();
  // Face 2: crosses the camera plane (one corner behind): only its front part
  // is rendered; compared with the CPU reference below.
  V.row(6) = Eigen::Vector3d(0.5, 0.2, 3);
  V.row(7) = Eigen::Vector3d(1.0, -0.3, 2);
  V.row(8) = Eigen::Vector3d(0.8, 0.4, -1);
  Eigen::MatrixXi F(3, 3);
  F << 0, 1, 2, 3, 4, 5, 6, 7, 8;
  r->SetMesh(V, F);
  const RenderBuffers gpu = r->Render(view);
  const RenderBuffers cpu = RenderCpu(V, F, view);
  int count[3] = {0, 0, 0}, agree = 0;
  for (size_t i = 0; i < gpu.face_id.size(); ++i) {
    if (gpu.face_id[i] >= 0) ++count[gpu.face_id[i]];
    agree += gpu.face_id[i] == cpu.face_id[i];
    EXPECT_NE(cpu.face_id[i], 1);
    if (gpu.face_id[i] == 2 && cpu.face_id[i] == 2) {
      EXPECT_NEAR(gpu.depth[i], cpu.depth[i], 1e-4 * cpu.depth[i]);
    }
  }
  EXPECT_GT(count[0], 50);
  EXPECT_EQ(count[1], 0);
  EXPECT_GT(count[2], 50);
  EXPECT_GT(agree, static_cast<int>(gpu.face_id.size() * 99 / 100));
}

TEST(Renderer, NoVisiblePixels) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(64, 48, 50, 50, 32, 24);
  Eigen::MatrixXd V(3, 3);
  V.row(0) = Unproject(view, 100, 10, 3).transpose();  // right of the image
  V.row(1) = Unproject(view, 150, 20, 3).transpose();
  V.row(2) = Unproject(view, 120, 40, 3).transpose();
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 2;
  r->SetMesh(V, F);
  for (const RenderBuffers& buf : {r->Render(view), RenderCpu(V, F, view)}) {
    ASSERT_EQ(buf.face_id.size(), 64u * 48u);
    for (size_t i = 0; i < buf.face_id.size(); ++i) {
      EXPECT_EQ(buf.face_id[i], -1);
      EXPECT_EQ(buf.depth[i], 0.0f);
    }
  }
}

TEST(Renderer, EmptyMesh) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(64, 48, 50, 50, 32, 24);
  Eigen::MatrixXd V(0, 3);
  Eigen::MatrixXi F(0, 3);
  r->SetMesh(V, F);
  Eigen::MatrixXd V3 = Eigen::MatrixXd::Random(3, 3);
  for (const RenderBuffers& buf : {r->Render(view), RenderCpu(V, F, view), RenderCpu(V3, F, view)}) {
    ASSERT_EQ(buf.face_id.size(), 64u * 48u);
    ASSERT_EQ(buf.bary.size(), 2u * 64u * 48u);
    for (int id : buf.face_id) EXPECT_EQ(id, -1);
  }
}

TEST(Renderer, BadMeshThrows) {
  GET_RENDERER(r);
  Eigen::MatrixXd V = Eigen::MatrixXd::Random(3, 3);
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 3;
  EXPECT_THROW(r->SetMesh(V, F), InputError);
  F << 0, 1, 2;
  V(1, 1) = std::nan("");
  EXPECT_THROW(r->SetMesh(V, F), InputError);
  const PinholeView bad = MakeView(0, 48, 50, 50, 32, 24);
  EXPECT_THROW(RenderCpu(V, F, bad), InputError);
}

// The EGL context belongs to the creating thread: use from another thread is
// refused with an error, not undefined behaviour.
TEST(Renderer, OtherThreadIsRefused) {
  GET_RENDERER(r);
  bool threw = false;
  std::thread other([&] {
    try {
      r->Render(MakeView(8, 8, 10, 10, 4, 4));
    } catch (const InternalError&) {
      threw = true;
    }
  });
  other.join();
  EXPECT_TRUE(threw);
}

// A triangle in the upper left of the image (small x and y) must appear in
// low row and column indices (catches a flipped y or x).
TEST(Renderer, YDirection) {
  GET_RENDERER(r);
  const PinholeView view = MakeView(96, 72, 80, 80, 48, 36);
  Eigen::MatrixXd V(3, 3);
  V.row(0) = Unproject(view, 4, 3, 2).transpose();
  V.row(1) = Unproject(view, 30, 5, 2).transpose();
  V.row(2) = Unproject(view, 8, 18, 2).transpose();
  // World y of the corners is negative (above the optical axis).
  ASSERT_LT(V.col(1).maxCoeff(), 0);
  Eigen::MatrixXi F(1, 3);
  F << 0, 1, 2;
  r->SetMesh(V, F);
  for (const RenderBuffers& buf : {r->Render(view), RenderCpu(V, F, view)}) {
    int covered = 0;
    for (int row = 0; row < view.height; ++row) {
      for (int col = 0; col < view.width; ++col) {
        if (buf.FaceAt(row, col) < 0) continue;
        ++covered;
        EXPECT_LT(row, 19);
        EXPECT_LT(col, 31);
      }
    }
    EXPECT_GT(covered, 100);
    EXPECT_EQ(buf.FaceAt(6, 10), 0);
  }
}

}  // namespace
}  // namespace mr
