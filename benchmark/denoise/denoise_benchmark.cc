// Denoising benchmark (not a test): quality on the standard protocol and speed.
//
//   denoise_benchmark quality [MODELS_DIR]   markdown table on stdout
//   denoise_benchmark speed NUM_FACES [cg|cholesky] [lp|l0]
//                                            time + peak memory on a noisy cube
//   denoise_benchmark one MODEL [METHOD]     one model, one method, per-iteration log
//                                            (METHOD lp | laplacian | bilateral_normal | l0)
//
// Protocol: Gaussian noise along the vertex normals with sigma = 0.3 x mean
// edge length (seed 1) added to a clean mesh. E_a: mean angle (degrees)
// between corresponding face normals of the result and the clean mesh. E_v:
// mean distance from the result's vertices to the clean surface (exact, AABB
// tree) divided by the clean mesh's bounding-box diagonal.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include "colmap_io/mesh_io.h"
#include "denoise/denoiser.h"
#include "denoise/lp_model.h"
#include "denoise/synthetic_meshes.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/program.h"

namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

void ReadObj(const std::string& path, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const mr::TriangleMesh mesh = mr::ReadMesh(path);
  *V = mesh.V;
  *F = mesh.F;
}

struct Errors {
  double ea = 0, ev = 0;
};

class Metric {
 public:
  Metric(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) : N_(mr::FaceNormals(V, F)) {
    for (int f = 0; f < F.rows(); ++f) {
      auto p = [&](int k) { return K::Point_3(V(F(f, k), 0), V(F(f, k), 1), V(F(f, k), 2)); };
      tris_.emplace_back(p(0), p(1), p(2));
    }
    tree_.insert(tris_.begin(), tris_.end());
    tree_.accelerate_distance_queries();
    diag_ = mr::BoundingBoxDiagonal(V);
  }
  Errors Evaluate(const Eigen::MatrixXd& X, const Eigen::MatrixXi& F) const {
    Errors e;
    const Eigen::MatrixXd N = mr::FaceNormals(X, F);
    for (int f = 0; f < F.rows(); ++f) {
      const double c = std::max(-1.0, std::min(1.0, N.row(f).dot(N_.row(f))));
      e.ea += std::acos(c) * 180.0 / M_PI;
    }
    e.ea /= F.rows();
    for (int v = 0; v < X.rows(); ++v) {
      e.ev += std::sqrt(tree_.squared_distance(K::Point_3(X(v, 0), X(v, 1), X(v, 2))));
    }
    e.ev /= X.rows() * diag_;
    return e;
  }

 private:
  Eigen::MatrixXd N_;
  std::vector<Triangle> tris_;
  Tree tree_;
  double diag_ = 1;
};

// Experiment-only overrides of the lp options from the environment (MAXIT,
// FIXP, PMIN, PMAX, ELEXP, LSCALE, BMAX, B0, FIXL, BF, UPDOP, ESTIT, INNER, CGTOL, SOLVER) and of
// the l0 options (L0LF, L0B0, L0BMAX, L0K, L0AF, L0AD, L0UPD) and of the
// bilateral_normal ones (BNOUT, BNNI, BNVI, BNSR, BNFAIR); unset =
// defaults. Results in docs/ use none.
void ApplyEnvOverrides(mr::DenoiseOptions* o) {
  auto env = [](const char* name, double fallback) {
    const char* v = std::getenv(name);
    return v != nullptr ? std::atof(v) : fallback;
  };
  o->max_iterations = static_cast<int>(env("MAXIT", o->max_iterations));
  o->fixed_p = env("FIXP", o->fixed_p);
  o->p_min = env("PMIN", o->p_min);
  o->p_max = env("PMAX", o->p_max);
  o->edge_length_exponent = env("ELEXP", o->edge_length_exponent);
  o->lambda_scale = env("LSCALE", o->lambda_scale);
  o->beta_max = env("BMAX", o->beta_max);
  o->beta_initial = env("B0", o->beta_initial);
  o->fixed_lambda = env("FIXL", o->fixed_lambda);
  o->beta_factor = env("BF", o->beta_factor);
  o->estimate_iterations = static_cast<int>(env("ESTIT", o->estimate_iterations));
  o->inner_iterations = static_cast<int>(env("INNER", o->inner_iterations));
  o->update_operator = env("UPDOP", o->update_operator ? 1 : 0) != 0;
  o->cg_tolerance = env("CGTOL", o->cg_tolerance);
  if (const char* v = std::getenv("SOLVER")) o->linear_solver = v;
  o->l0_lambda_factor = env("L0LF", o->l0_lambda_factor);
  o->l0_beta_initial = env("L0B0", o->l0_beta_initial);
  o->l0_beta_max = env("L0BMAX", o->l0_beta_max);
  o->l0_beta_factor = env("L0K", o->l0_beta_factor);
  o->l0_alpha_factor = env("L0AF", o->l0_alpha_factor);
  o->l0_alpha_decay = env("L0AD", o->l0_alpha_decay);
  o->outer_iterations = static_cast<int>(env("BNOUT", o->outer_iterations));
  o->normal_iterations = static_cast<int>(env("BNNI", o->normal_iterations));
  o->vertex_iterations = static_cast<int>(env("BNVI", o->vertex_iterations));
  o->normal_sigma = env("BNSR", o->normal_sigma);
  o->fairing_weight = env("BNFAIR", o->fairing_weight);
  o->l0_update_operator = env("L0UPD", o->l0_update_operator ? 1 : 0) != 0;
}

double PeakMemoryMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0;
}

// The Laplacian's iteration counts over which the oracle column takes the best.
constexpr int kLaplacianIterationCounts[] = {1, 2, 3, 4, 6, 8, 10, 15, 20, 30, 50, 80};

int Quality(const std::string& models_dir, const std::string& only, const std::string& method) {
  struct Model {
    std::string name;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
  };
  std::vector<Model> models;
  for (const char* name : {"fandisk", "rocker-arm", "stanford-bunny", "beast", "igea"}) {
    Model m{name, {}, {}};
    const std::string obj = models_dir + "/" + name + ".obj";
    if (std::ifstream(obj).good()) {
      ReadObj(obj, &m.V, &m.F);
    } else {
      const mr::TriangleMesh mesh = mr::ReadMesh(models_dir + "/" + name + ".ply");
      m.V = mesh.V;
      m.F = mesh.F;
    }
    models.push_back(m);
  }
  {
    Model m{"cube-40", {}, {}};
    mr::SubdividedCube(40, &m.V, &m.F);
    models.push_back(m);
    Model o{"octahedron-5", {}, {}};
    mr::SubdividedOctahedron(5, &o.V, &o.F);
    models.push_back(o);
  }
  if (only == "icosphere-4" || only == "icosphere-5") {
    // Regular spheres, `one` mode only (not in the table): where more
    // smoothing is always better.
    Model ico{only, {}, {}};
    mr::MakeIcosphere(only == "icosphere-4" ? 4 : 5, 1.0, &ico.V, &ico.F);
    models.push_back(ico);
  }
  std::printf(
      "| model | faces | noisy E_a | noisy E_v | lp E_a | lp E_v | lp s | laplacian(10) E_a | "
      "laplacian best E_a (iters) | laplacian best E_v (iters) | bilateral E_a | bilateral E_v "
      "| l0 E_a | l0 E_v | l0 s | lp p/theta/sigma/lambda (last) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Model& m : models) {
    if (!only.empty() && m.name != only) continue;
    const Metric metric(m.V, m.F);
    if (!only.empty()) {
      // One model, one method, verbose: for studying the behaviour.
      const double h = mr::MeanEdgeLength(m.V, m.F);
      // SEED: the noise seed of this one-model run (default 1, as in the table).
      const int seed = std::getenv("SEED") != nullptr ? std::atoi(std::getenv("SEED")) : 1;
      const Eigen::MatrixXd noisy = mr::AddNormalNoise(m.V, m.F, 0.3 * h, seed);
      mr::DenoiseOptions o;
      o.method = method;
      o.verbose = true;
      ApplyEnvOverrides(&o);
      if (std::getenv("XCLEANFIT") != nullptr) {
        // Experiment: the prior fitted on the clean mesh's rows (unit mean edge).
        const mr::EdgeQuads eq = mr::BuildEdgeQuads(m.F, static_cast<int>(m.V.rows()));
        const Eigen::MatrixXd Xc = m.V / h;
        const Eigen::MatrixXd W = mr::EdgeWeights(Xc, eq.quads);
        const Eigen::MatrixXd R = mr::ApplyEdgeOperator(eq.quads, W, Xc);
        std::vector<double> nr;
        for (int i = 0; i < R.rows(); ++i) {
          if (W.row(i).squaredNorm() > 0) nr.push_back(std::max(R.row(i).norm(), 1e-12));
        }
        const Eigen::VectorXd rn = Eigen::Map<Eigen::VectorXd>(nr.data(), nr.size());
        double th1 = 0, th2 = 0;
        const double p1 = mr::EstimateP(rn, 0.1, 1.0, 0.05, &th1);
        const double p2 = mr::EstimateP(rn, 0.1, 2.0, 0.05, &th2);
        std::vector<double> sorted = nr;
        std::sort(sorted.begin(), sorted.end());
        std::printf("clean rows: %zu, median %.4g, p90 %.4g, mean %.4g; fit [0.1,1]: p %.2f theta "
                    "%.4g; fit [0.1,2]: p %.2f theta %.4g\n",
                    nr.size(), sorted[sorted.size() / 2], sorted[sorted.size() * 9 / 10],
                    rn.mean(), p1, th1, p2, th2);
      }
      const Errors en = metric.Evaluate(noisy, m.F);
      if (method == "laplacian_best") {
        // The oracle column of the table for this seed: the best E_a over the
        // Laplacian's iteration counts.
        std::printf("%s laplacian_best: noisy E_a %.2f E_v %.2e ->", m.name.c_str(), en.ea, en.ev);
        std::pair<double, int> best{1e9, 0};
        o.method = "laplacian";
        for (int iters : kLaplacianIterationCounts) {
          o.laplacian_iterations = iters;
          best = std::min(best, {metric.Evaluate(mr::Denoise(noisy, m.F, o).V, m.F).ea, iters});
        }
        std::printf(" E_a %.2f (%d iterations)\n", best.first, best.second);
        continue;
      }
      const Errors e = metric.Evaluate(mr::Denoise(noisy, m.F, o).V, m.F);
      std::printf("%s %s: noisy E_a %.2f E_v %.2e -> E_a %.2f E_v %.2e (mean edge %.4g, "
                  "noise sigma %.4g)\n",
                  m.name.c_str(), method.c_str(), en.ea, en.ev, e.ea, e.ev, h, 0.3 * h);
      continue;
    }
    const double h = mr::MeanEdgeLength(m.V, m.F);
    const Eigen::MatrixXd noisy = mr::AddNormalNoise(m.V, m.F, 0.3 * h, 1);
    const Errors en = metric.Evaluate(noisy, m.F);
    mr::DenoiseOptions lp;
    ApplyEnvOverrides(&lp);
    const mr::DenoiseResult rlp = mr::Denoise(noisy, m.F, lp);
    const Errors elp = metric.Evaluate(rlp.V, m.F);
    mr::DenoiseOptions lap;
    lap.method = "laplacian";
    const Errors elap10 = metric.Evaluate(mr::Denoise(noisy, m.F, lap).V, m.F);
    Errors best_a{1e9, 1e9}, best_v{1e9, 1e9};
    int best_a_it = 0, best_v_it = 0;
    for (int iters : kLaplacianIterationCounts) {
      lap.laplacian_iterations = iters;
      const Errors e = metric.Evaluate(mr::Denoise(noisy, m.F, lap).V, m.F);
      if (e.ea < best_a.ea) best_a = e, best_a_it = iters;
      if (e.ev < best_v.ev) best_v = e, best_v_it = iters;
    }
    mr::DenoiseOptions bil;
    bil.method = "bilateral_normal";
    const Errors ebil = metric.Evaluate(mr::Denoise(noisy, m.F, bil).V, m.F);
    mr::DenoiseOptions l0;
    l0.method = "l0";
    ApplyEnvOverrides(&l0);
    const mr::DenoiseResult rl0 = mr::Denoise(noisy, m.F, l0);
    const Errors el0 = metric.Evaluate(rl0.V, m.F);
    const mr::DenoiseIteration& last = rlp.iterations.back();
    // Bold: the lowest E_a of the methods run with their defaults (not the
    // oracle Laplacian column).
    const double best = std::min(std::min(elp.ea, elap10.ea), std::min(ebil.ea, el0.ea));
    auto ea = [&](double v) {
      char buf[32];
      std::snprintf(buf, sizeof(buf), v == best ? "**%.2f**" : "%.2f", v);
      return std::string(buf);
    };
    std::printf(
        "| %s | %d | %.2f | %.2e | %s | %.2e | %.2f | %s | %.2f (%d) | %.2e (%d) | %s | "
        "%.2e | %s | %.2e | %.2f | %.2f / %.3g / %.3g / %.3g (%zu it) |\n",
        m.name.c_str(), static_cast<int>(m.F.rows()), en.ea, en.ev, ea(elp.ea).c_str(), elp.ev,
        rlp.total_seconds, ea(elap10.ea).c_str(), best_a.ea, best_a_it, best_v.ev, best_v_it,
        ea(ebil.ea).c_str(), ebil.ev, ea(el0.ea).c_str(), el0.ev, rl0.total_seconds, last.p,
        last.theta, last.sigma, last.lambda, rlp.iterations.size());
    std::fflush(stdout);
  }
  return 0;
}

int Speed(long faces, const std::string& linear_solver, const std::string& method) {
  const int n = static_cast<int>(std::lround(std::sqrt(faces / 12.0)));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  mr::SubdividedCube(n, &V, &F);
  const Eigen::MatrixXd noisy = mr::AddNormalNoise(V, F, 0.3 * 2.0 / n, 1);
  const double before = PeakMemoryMiB();
  mr::DenoiseOptions options;
  options.method = method;
  options.linear_solver = linear_solver;
  const mr::DenoiseResult r = mr::Denoise(noisy, F, options);
  int factorizations = 0, cg_iterations = 0;
  for (const auto& it : r.iterations) {
    factorizations += it.num_factorizations;
    cg_iterations += it.num_cg_iterations;
  }
  for (const auto& step : r.l0_steps) {
    if (linear_solver == "cholesky") ++factorizations;
    cg_iterations += step.num_cg_iterations;
  }
  const size_t outer = method == "l0" ? r.l0_steps.size() : r.iterations.size();
  // faces | vertices | method | solver | total s | setup s | solve s | outer
  // iterations (l0: beta steps) | factorisations | cg iterations | peak MiB
  // before | peak MiB after
  std::printf("| %ld | %ld | %s | %s | %.2f | %.2f | %.2f | %zu | %d | %d | %.0f | %.0f |\n",
              F.rows(), V.rows(), method.c_str(), linear_solver.c_str(), r.total_seconds,
              r.setup_seconds, r.solve_seconds, outer, factorizations, cg_iterations, before,
              PeakMemoryMiB());
  return 0;
}

}  // namespace

// Through RunProgram, like mesh_denoiser, so that the allocator settings are
// those the programs run with (util/program.h).
int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    const std::string mode = argc > 1 ? argv[1] : "quality";
    if (std::getenv("MR_VERBOSE") != nullptr) mr::SetLogLevel(mr::LogLevel::kVerbose);
    if (mode == "quality") return Quality(argc > 2 ? argv[2] : MR_SHARED_DIR "/data/models", "", "");
    if (mode == "one" && argc > 2) {
      return Quality(MR_SHARED_DIR "/data/models", argv[2], argc > 3 ? argv[3] : "lp");
    }
    if (mode == "speed" && argc > 2) {
      return Speed(std::stol(argv[2]), argc > 3 ? argv[3] : "cg", argc > 4 ? argv[4] : "lp");
    }
    std::fprintf(stderr,
                 "usage: denoise_benchmark quality [MODELS_DIR] | speed NUM_FACES [cg|cholesky] "
                 "[lp|l0] | one MODEL [METHOD]\n");
    return 1;
  });
}
