// mesh_denoiser: denoises a triangle mesh by moving its vertices only.
//
//   mesh_denoiser --input_path IN.ply --output_path OUT.ply
//                 [--Denoise.method lp|laplacian|bilateral_normal|l0] [--Denoise.* ...]
//
// Defaults: the content-aware L_p denoiser of DCV with every parameter
// estimated from the mesh. Input and output .ply or .obj (by extension);
// the output is written atomically. See docs/denoising.md.

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "colmap_io/mesh_io.h"
#include "denoise/denoiser.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

namespace mr {
namespace {

int Run(int argc, char** argv) {
  std::string input_path, output_path;
  bool verbose = false;
  DenoiseOptions denoise;
  OptionManager options("mesh_denoiser",
                        "Denoises a triangle mesh (vertices move, connectivity unchanged).");
  options.AddRequired("input_path", &input_path, "input mesh (.ply or .obj)");
  options.AddRequired("output_path", &output_path,
                      "output mesh (.ply or .obj, written atomically)");
  options.Add("verbose", &verbose, "verbose logging");
  RegisterDenoiseOptions(&options, &denoise, "Denoise");
  options.SetInputPaths([&] { return std::vector<std::string>{input_path}; });
  if (!options.Parse(argc, argv)) return 0;
  if (verbose) SetLogLevel(LogLevel::kVerbose);
  denoise.Check();
  if (!ExistsFile(input_path)) MR_THROW_INPUT << input_path << ": no such file";
  for (const std::string* path : {&input_path, &output_path}) {
    const std::string ext = GetExtension(*path);
    if (ext != ".ply" && ext != ".obj") {
      MR_THROW_INPUT << *path << ": unsupported extension '" << ext << "' (expected .ply or .obj)";
    }
  }
  RefuseOutputOverInput("--output_path", output_path, {input_path});
  CheckOutputFile("--output_path", output_path);
  TriangleMesh mesh = ReadMesh(input_path);
  MR_LOG(INFO) << "Read " << input_path << ": " << mesh.NumVertices() << " vertices, "
               << mesh.NumFaces() << " faces";
  if (mesh.NumFaces() == 0) {
    MR_THROW_INPUT << input_path << ": the mesh has no faces (a point cloud cannot be denoised)";
  }
  const DenoiseResult result = Denoise(mesh.V, mesh.F, denoise);
  for (size_t k = 0; k < result.iterations.size(); ++k) {
    const DenoiseIteration& it = result.iterations[k];
    MR_LOG(INFO) << "Outer iteration " << k + 1 << ": p = " << it.p << ", theta = " << it.theta
                 << ", sigma = " << it.sigma << ", lambda = " << it.lambda
                 << ", change = " << it.change << " mean edges, " << it.seconds << " s";
  }
  MR_LOG(INFO) << result.BriefReport();
  mesh.V = result.V;
  mesh.N.resize(0, 3);  // stale after moving vertices
  WriteMesh(output_path, mesh);
  MR_LOG(INFO) << "Wrote " << output_path;
  return 0;
}

}  // namespace
}  // namespace mr

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    return mr::Run(argc, argv);
  });
}
