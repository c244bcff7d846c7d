// render_probe: creates the headless renderer, prints which EGL path it took
// and times renders of an icosphere.
//
//   render_probe [--Render.platform auto|device|surfaceless]
//                [--Probe.subdivisions 7] [--Probe.width 640] [--Probe.height 480]
//                [--Probe.num_renders 10] [--Probe.cpu 1]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

#include <Eigen/Geometry>

#include "geometry/primitives.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

int Run(int argc, char** argv) {
  mr::RendererOptions render_options;
  int subdivisions = 7;
  int width = 640, height = 480, num_renders = 10;
  bool cpu = true;
  bool verbose = false;
  mr::OptionManager options("render_probe",
                            "Creates the headless EGL renderer and times icosphere renders.");
  options.Add("Render.platform", &render_options.platform, "auto, device or surfaceless");
  options.Add("Render.max_tile_size", &render_options.max_tile_size,
              "largest framebuffer side (px, 0 = driver limit)");
  options.Add("Probe.subdivisions", &subdivisions,
              "icosphere subdivisions (20 * 4^s faces; 7 = 327,680), 0..9");
  options.Add("Probe.width", &width, "image width (px)");
  options.Add("Probe.height", &height, "image height (px)");
  options.Add("Probe.num_renders", &num_renders, "timed renders (>= 1)");
  options.Add("Probe.cpu", &cpu, "also time the CPU reference RenderCpu and compare");
  options.Add("Probe.verbose", &verbose, "log the time of each render's phases");
  if (!options.Parse(argc, argv)) return 0;
  if (verbose) mr::SetLogLevel(mr::LogLevel::kVerbose);
  render_options.Check();
  if (subdivisions < 0 || subdivisions > 9) {
    MR_THROW_INPUT << "Probe.subdivisions = " << subdivisions
                   << ". Violated constraint: 0 <= subdivisions <= 9";
  }
  if (width < 1 || height < 1 || num_renders < 1) {
    MR_THROW_INPUT << "Probe.width/height/num_renders = " << width << "/" << height << "/"
                   << num_renders << ". Violated constraint: all >= 1";
  }

  double t0 = Now();
  mr::Renderer renderer(render_options);
  std::cout << "Renderer: " << renderer.Description() << std::endl;
  std::printf("context creation: %.1f ms\n", 1e3 * (Now() - t0));

  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  mr::MakeIcosphere(subdivisions, 1.0, Eigen::Vector3d(0.1, -0.2, 0.3), &V, &F);
  mr::PinholeView view;
  view.width = width;
  view.height = height;
  view.fx = view.fy = 0.9 * width;
  view.cx = 0.5 * width;
  view.cy = 0.5 * height;
  view.R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  view.t = Eigen::Vector3d(0, 0, 2.6) - view.R * Eigen::Vector3d(0.1, -0.2, 0.3);

  t0 = Now();
  renderer.SetMesh(V, F);
  std::printf("mesh: %ld vertices, %ld faces; SetMesh %.1f ms\n", static_cast<long>(V.rows()),
              static_cast<long>(F.rows()), 1e3 * (Now() - t0));

  mr::RenderBuffers buffers = renderer.Render(view);  // warm-up
  double total = 0, best = 1e30;
  for (int i = 0; i < num_renders; ++i) {
    t0 = Now();
    buffers = renderer.Render(view);
    const double dt = Now() - t0;
    total += dt;
    best = std::min(best, dt);
  }
  long covered = 0;
  for (int id : buffers.face_id) covered += id >= 0;
  std::printf("Render %dx%d: %.2f ms mean, %.2f ms min over %d renders; %.1f%% pixels covered\n",
              width, height, 1e3 * total / num_renders, 1e3 * best, num_renders,
              100.0 * covered / buffers.face_id.size());
  if (cpu) {
    t0 = Now();
    const mr::RenderBuffers ref = mr::RenderCpu(V, F, view);
    const double dt = Now() - t0;
    long agree = 0;
    for (size_t i = 0; i < ref.face_id.size(); ++i) agree += ref.face_id[i] == buffers.face_id[i];
    std::printf("RenderCpu %dx%d: %.2f ms; face ids agree with the GPU on %.3f%% of pixels\n",
                width, height, 1e3 * dt, 100.0 * agree / ref.face_id.size());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    return Run(argc, argv);
  });
}
