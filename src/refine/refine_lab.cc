// refine_lab: runs the refiner on the built-in in-memory test scene (bumpy
// sphere, ring of views) and prints accuracy before and after. A development
// tool for quick experiments with options; not a test.
//
//   build/bin/refine_lab [--start smooth|truth|noisy] [--Refine.* ...]

#include <cstdio>
#include <random>

#include "eval/evaluator.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "refine/refiner.h"
#include "refine/test_scene.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/options.h"
#include "util/program.h"

int main(int argc, char** argv) {
  using namespace mr;
  return mr::RunProgram([&]() -> int {
    std::string start = "smooth";
    int subdivisions = 5, width = 160, height = 120, views = 8;
    double relief = 0.06, noise = 0.01;
    RefineOptions refine;
    OptionManager options("refine_lab", "refiner experiments on the built-in test scene");
    options.Add("start", &start, "initial mesh: smooth (sphere), truth, noisy (truth + noise)");
    options.Add("Scene.subdivisions", &subdivisions, "icosphere subdivisions of the truth");
    options.Add("Scene.relief", &relief, "relief amplitude (object radius 1)");
    options.Add("Scene.noise", &noise, "noise of --start noisy (object radius 1)");
    options.Add("Scene.width", &width, "image width");
    options.Add("Scene.height", &height, "image height");
    options.Add("Scene.views", &views, "number of views");
    RegisterRefineOptions(&options, &refine);
    if (!options.Parse(argc, argv)) return 0;
    Renderer renderer;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    MakeBumpySphere(subdivisions, relief, &V, &F);
    TestSceneOptions scene;
    scene.width = width;
    scene.height = height;
    scene.num_views = views;
    const InMemoryViewSource source = MakeTestScene(V, F, scene, {}, &renderer);
    TriangleMesh mesh;
    if (start == "smooth") {
      MakeIcosphere(4, 1.0, &mesh.V, &mesh.F);
    } else {
      mesh.V = V;
      mesh.F = F;
      if (start == "noisy") {
        std::mt19937 rng(1);
        std::normal_distribution<double> normal(0.0, noise);
        const Eigen::MatrixXd N = VertexNormals(V, F);
        for (int i = 0; i < V.rows(); ++i) mesh.V.row(i) += normal(rng) * N.row(i);
      }
    }
    EvaluationOptions eval;
    eval.threshold = 0.02;
    eval.num_samples = 50000;
    const EvaluationResult before = EvaluateMesh(mesh.V, mesh.F, V, F, eval);
    const RefineSummary summary = RefineMesh(source, refine, &mesh, &renderer);
    const EvaluationResult after = EvaluateMesh(mesh.V, mesh.F, V, F, eval);
    std::printf("%s", summary.FullReport().c_str());
    std::printf("before %s\nafter  %s\n", before.ToJson().c_str(), after.ToJson().c_str());
    return 0;
  });
}
