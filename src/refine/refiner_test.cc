#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "eval/evaluator.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "geometry/remesh.h"
#include "denoise/denoiser.h"
#include "refine/background_mask.h"
#include "refine/photometric.h"
#include "refine/refiner.h"
#include "refine/silhouette.h"
#include "refine/test_scene.h"
#include "refine/view_selection.h"
#include "render/renderer.h"
#include "util/error.h"

namespace mr {
namespace {

class RefinerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { renderer_ = new Renderer(); }
  static void TearDownTestSuite() {
    delete renderer_;
    renderer_ = nullptr;
  }
  static RefineOptions FastOptions() {
    RefineOptions options;
    options.num_levels = 2;
    options.iterations_per_level = 6;
    options.target_edge_px = 3.0;
    return options;
  }
  // FastOptions at full resolution only.
  static RefineOptions OneLevelOptions() {
    RefineOptions options = FastOptions();
    options.num_levels = 1;
    return options;
  }
  // The smooth unit sphere (4 subdivisions) that refinements of the bumpy
  // sphere start from.
  static TriangleMesh SmoothSphere() {
    TriangleMesh sphere;
    MakeIcosphere(4, 1.0, &sphere.V, &sphere.F);
    return sphere;
  }
  // The bumpy sphere (5 subdivisions) and the ring of views of it at
  // 160x120 and at 320x240, the larger rendered with `large_supersample`.
  struct TwoSizes {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    InMemoryViewSource small, large;
  };
  static TwoSizes BumpySphereAtTwoSizes(int large_supersample) {
    TwoSizes scene;
    MakeBumpySphere(5, 0.06, &scene.V, &scene.F);
    TestSceneOptions large;
    large.width = 320;
    large.height = 240;
    large.supersample = large_supersample;
    scene.small = MakeTestScene(scene.V, scene.F, {}, {}, renderer_);
    scene.large = MakeTestScene(scene.V, scene.F, large, {}, renderer_);
    return scene;
  }
  static Renderer* renderer_;
};
Renderer* RefinerTest::renderer_ = nullptr;

EvaluationResult Evaluate(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                          const Eigen::MatrixXd& gV, const Eigen::MatrixXi& gF) {
  EvaluationOptions options;
  options.threshold = 0.02;
  options.num_samples = 20000;
  return EvaluateMesh(V, F, gV, gF, options);
}

// RMS of the radial relief |x| - mean |x| over the vertices (bumpy sphere).
double ReliefRms(const Eigen::MatrixXd& V) {
  const Eigen::VectorXd r = V.rowwise().norm();
  return std::sqrt((r.array() - r.mean()).square().mean());
}

// The ground truth given as input stays close to what it was, with the
// defaults: compared with the input after the refiner's remeshing alone, the
// flow and the proximal steps may add at most a quarter of a pixel footprint
// to accuracy90 and one degree to the normal error. Not "no worse": the data
// term's optimum is not exactly the ground truth (bilinear warps, windows at
// occlusions), and the flow moves it by a fifth of a pixel (measured here:
// accuracy90 6e-5 -> 0.0027 with footprint 0.015, normals 0.17 -> 0.88 deg,
// with the earlier L_p step;
// without the proximal step 0.0035 and 3.2 deg). Detail preservation: the
// noise-free bump field keeps at least 95 % of its RMS (measured 97.7 %
// with the bilateral-normal step).
// The decision of best_iterate_giveback on the similarity sequences of the
// corpus's default runs (docs/results.md): the open shell that fell back
// after its 5th iterate ends there; fandisk's early dip and bunny's slight
// late fall do not move the result.
// A unit sphere carrying a noise-free bump field of wavelength `edges`
// triangle edges and amplitude half an edge (icosphere of 5 subdivisions,
// edge about 0.038).
void MakeFineRelief(double edges, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  MakeIcosphere(5, 1.0, V, F);
  const double edge = (V->row((*F)(0, 0)) - V->row((*F)(0, 1))).norm();
  MakeBumpySphere(5, 0.5 * edge, V, F, Eigen::Vector3d::Constant(2.0 * M_PI / (edges * edge)));
}

// The refiner's proximal step on a noise-free surface with fine relief, with
// no data term to put the relief back: the share of the bump field's RMS
// that one step, and the ten of a level, leave. Measured (4 December 2026),
// wavelength 8 / 16 edges (20 / 40 pixels at the default 2.5-pixel edges):
//   bilateral_normal (the default): one step 0.656 / 0.933, ten 0.267 / 0.592
//   laplacian (the baseline):       one step 0.856 / 0.962, ten 0.355 / 0.703
//   lp (noise taken from the step): 1.000 / 1.000 (no step, no noise, no change)
// The default's fairing step (DenoiseOptions::fairing_weight 0.3, added 7
// December 2026) leaves these to every printed digit: the relief's faces
// differ by less than the range sigma, so it does not act on them.
// The default does not leave fine relief "nearly unchanged": a third of a
// 20-pixel bump field goes in one step, and the data term must put it back
// every iteration (docs/results.md, "Where the energy settles"). The bounds
// sit a few points under the measurements: they state what the regulariser
// costs and fail if a change makes it erode faster.
TEST(ProximalStep, ShareOfAFineBumpFieldLeft) {
  struct Bound {
    const char* method;
    double edges, one, ten;
  };
  for (const Bound& b : {Bound{"bilateral_normal", 8, 0.62, 0.24},
                         Bound{"bilateral_normal", 16, 0.91, 0.55},
                         Bound{"laplacian", 8, 0.82, 0.32}, Bound{"laplacian", 16, 0.94, 0.66},
                         Bound{"lp", 8, 0.999, 0.999}, Bound{"lp", 16, 0.999, 0.999}}) {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    MakeFineRelief(b.edges, &V, &F);
    const double before = ReliefRms(V);
    DenoiseOptions denoise = RefineOptions().denoise;
    denoise.method = b.method;
    Eigen::MatrixXd W = V;
    double after_one = 0;
    for (int it = 0; it < 10; ++it) {
      // As in the refiner: the surface before the (here empty) gradient step
      // is the reference the step's noise is measured against.
      W = Denoise(W, F, denoise, &W).V;
      if (it == 0) after_one = ReliefRms(W) / before;
    }
    const double after_ten = ReliefRms(W) / before;
    const std::string key = std::string(b.method) + "_" + std::to_string(int(b.edges)) + "_edges";
    RecordProperty(key + "_one_step", std::to_string(after_one));
    RecordProperty(key + "_ten_steps", std::to_string(after_ten));
    EXPECT_GT(after_one, b.one) << key;
    EXPECT_GT(after_ten, b.ten) << key;
  }
}

TEST(BestIterateToKeep, KeepsTheBestOnlyWhenMuchOfTheGainWasGivenBack) {
  const std::vector<double> beetle = {0.307487, 0.341489, 0.358888, 0.364248, 0.364904,
                                      0.361673, 0.356749, 0.349604, 0.341615, 0.334489};
  EXPECT_EQ(BestIterateToKeep(beetle, 0.25), 4);   // gave back 53 % of 0.057
  EXPECT_EQ(BestIterateToKeep(beetle, 0.5), 4);
  EXPECT_EQ(BestIterateToKeep(beetle, 0.6), -1);
  const std::vector<double> fandisk = {0.186598, 0.240612, 0.221486, 0.234129, 0.234969,
                                       0.237643, 0.237235, 0.237863, 0.235878, 0.23653};
  EXPECT_EQ(BestIterateToKeep(fandisk, 0.25), -1);  // 8 %
  EXPECT_EQ(BestIterateToKeep(fandisk, 0.05), 1);
  const std::vector<double> bunny = {0.666392, 0.687826, 0.693559, 0.694107, 0.69399,
                                     0.693109, 0.692835, 0.692633, 0.691764, 0.691621};
  EXPECT_EQ(BestIterateToKeep(bunny, 0.25), -1);  // 9 %
  const std::vector<double> rising = {0.74, 0.80, 0.83, 0.84, 0.85};
  EXPECT_EQ(BestIterateToKeep(rising, 0.0), -1);  // the last is the best
  // Below the start: every setting returns the start.
  const std::vector<double> falling = {0.5, 0.49, 0.48};
  EXPECT_EQ(BestIterateToKeep(falling, 1.0), 0);
  EXPECT_EQ(BestIterateToKeep(falling, 0.25), 0);
  EXPECT_EQ(BestIterateToKeep({0.5}, 0.25), -1);
  EXPECT_EQ(BestIterateToKeep({}, 0.25), -1);
}

// The guard condition of the best-iterate rule on the corpus's runs: the
// open shell's guard reset 24-36 % of its 37,470 vertices per iteration
// after its best iterate; the baseline on fandisk-shading, whose similarity
// also gave back half its gain while the surface kept improving, 0.2 % of
// 29,791.
// camera_rounds: round k after k (k + 1) / 2 iterations of the finest
// level, never before its first iteration; rounds that would fall at or
// after its last iteration are not made.
TEST(CameraRoundIterations, EachRoundOneIterationLaterThanTheGapBefore) {
  using Rounds = std::vector<int>;
  EXPECT_EQ(CameraRoundIterations(14, 1), Rounds({1}));
  EXPECT_EQ(CameraRoundIterations(14, 2), Rounds({1, 3}));
  EXPECT_EQ(CameraRoundIterations(14, 3), Rounds({1, 3, 6}));
  EXPECT_EQ(CameraRoundIterations(14, 4), Rounds({1, 3, 6, 10}));
  EXPECT_EQ(CameraRoundIterations(14, 5), Rounds({1, 3, 6, 10}));  // 15 is past the last
  EXPECT_EQ(CameraRoundIterations(6, 3), Rounds({1, 3}));           // 6 is past the last
  EXPECT_EQ(CameraRoundIterations(14, 0), Rounds());
  EXPECT_EQ(CameraRoundIterations(1, 3), Rounds());
}

// The cameras are refined at the surface's level when all its grey images fit
// the budget, else at the next coarser level if its images do (sizes halved
// rounding up, as the pyramid's; kMaxCameraLevelsCoarser is 1), else not.
TEST(CameraRefinementLevel, TheFinestLevelWhoseImagesFit) {
  ASSERT_EQ(kMaxCameraLevelsCoarser, 1);
  PinholeView view;
  view.width = 1281;  // odd: level 1 rounds up to 641 x 480
  view.height = 960;
  const std::vector<PinholeView> views(10, view);
  const size_t level0 = 10 * 1281 * 960 * 4, level1 = 10 * 641 * 480 * 4;
  EXPECT_EQ(CameraRefinementLevel(views, 0, level0), 0);
  EXPECT_EQ(CameraRefinementLevel(views, 0, level0 - 1), 1);
  EXPECT_EQ(CameraRefinementLevel(views, 0, level1), 1);
  EXPECT_EQ(CameraRefinementLevel(views, 0, level1 - 1), -1);
  // Given the views of level 1 (here the same sizes), the levels count from 1.
  EXPECT_EQ(CameraRefinementLevel(views, 1, level0), 1);
  EXPECT_EQ(CameraRefinementLevel(views, 1, level0 - 1), 2);
  EXPECT_EQ(CameraRefinementLevel(views, 1, level1 - 1), -1);
  EXPECT_EQ(CameraRefinementLevel({}, 0, 0), 0);
}

// The defaults' 14 iterations average the last 8; after a camera round the
// surface first follows the new cameras for kCameraSettlingIterations (4).
TEST(FirstAveragedIteration, LastIteratesAfterTheSurfaceSettled) {
  EXPECT_EQ(kCameraSettlingIterations, 4);
  const std::vector<int> none;
  EXPECT_EQ(FirstAveragedIteration(14, 8, none), 6);
  EXPECT_EQ(FirstAveragedIteration(14, 1, none), 14);  // one iterate: no mean
  EXPECT_EQ(FirstAveragedIteration(4, 8, none), 0);    // at most all of them
  EXPECT_EQ(FirstAveragedIteration(14, 8, {1}), 6);    // round at 1: settled by 5
  EXPECT_EQ(FirstAveragedIteration(14, 8, {1, 3, 6}), 10);
  EXPECT_EQ(FirstAveragedIteration(14, 8, {1, 3, 6, 10}), 14);  // none left
  EXPECT_EQ(FirstAveragedIteration(11, 8, {1, 3, 6}), 11);  // 10 alone after 6: no mean
}

TEST(MeanResetFraction, SeparatesTheShellFromAPlateau) {
  const std::vector<int> beetle = {9156, 10514, 11157, 12497, 13085, 13673};
  EXPECT_GT(MeanResetFraction(beetle, 37470), kGuardOverrideFraction);
  EXPECT_NEAR(MeanResetFraction(beetle, 37470), 0.312, 0.001);
  const std::vector<int> fandisk_baseline = {15, 43, 31, 35, 77, 102, 104, 128, 0};
  EXPECT_LT(MeanResetFraction(fandisk_baseline, 29791), 0.1 * kGuardOverrideFraction);
  EXPECT_EQ(MeanResetFraction({}, 100), 0.0);
  EXPECT_EQ(MeanResetFraction({5}, 0), 0.0);
  EXPECT_DOUBLE_EQ(MeanResetFraction({10, 30}, 100), 0.2);
}

// A seen band vertex counts as contradicted below 0.5 on a textured surface,
// whose vertices score near 0.92, and on a shaded one, whose vertices score
// anywhere in [-0.2, 0.4], only well below all of them. The sums are per
// vertex, Σ w m and Σ w; unseen vertices (w = 0) are left out.
TEST(ContradictedSimilarity, AnOutlierOfItsOwnSurface) {
  const int n = 1001;
  Eigen::VectorXd weight(n), textured(n), shaded(n);
  for (int v = 0; v < n; ++v) {
    weight(v) = 1 + v % 5;
    textured(v) = weight(v) * (0.92 + 0.03 * ((v % 7) - 3) / 3.0);
    shaded(v) = weight(v) * (-0.2 + 0.6 * v / (n - 1.0));
  }
  EXPECT_EQ(ContradictedSimilarity(textured, weight), kOpenBorderMaxSimilarity);
  // Median 0.1, median absolute deviation 0.15.
  const double shaded_bound = 0.1 - kOpenBorderOutlierSigmas * 1.4826 * 0.15;
  EXPECT_NEAR(ContradictedSimilarity(shaded, weight), shaded_bound, 1e-3);
  EXPECT_LT(shaded_bound, -0.2);  // no vertex of the shaded surface counts

  // Unseen vertices do not count, whatever their sums say.
  Eigen::VectorXd weight_unseen = weight, shaded_unseen = shaded;
  for (int v = 0; v < n; v += 2) {
    weight_unseen(v) = 0;
    shaded_unseen(v) = 0.9;
  }
  EXPECT_NEAR(ContradictedSimilarity(shaded_unseen, weight_unseen), shaded_bound, 0.01);
  EXPECT_EQ(ContradictedSimilarity(shaded, Eigen::VectorXd::Zero(n)),
            -std::numeric_limits<double>::infinity());
}

TEST_F(RefinerTest, GroundTruthStaysGroundTruth) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  TriangleMesh mesh;
  mesh.V = V;
  mesh.F = F;
  RefineOptions options;  // defaults
  options.iterations_per_level = 6;
  // Without masks made from the black background: at 160x120 their outline
  // differs from the exact one by a pixel here and there (anti-aliased edge
  // pixels), and the silhouette term follows it. With them the normal error
  // ends at 1.27 degrees (input 0.17; with masks rendered from the true mesh
  // 0.90, with none 0.85): over this test's 1-degree bound. A known cost,
  // measured and documented in docs/results.md, not hidden by a wider bound.
  options.masks_from_background = false;
  RefineOptions remesh_only = options;
  remesh_only.iterations_per_level = 0;
  TriangleMesh remeshed = mesh;
  RefineMesh(source, remesh_only, &remeshed, renderer_);
  const EvaluationResult input = Evaluate(remeshed.V, remeshed.F, V, F);

  const RefineSummary summary = RefineMesh(source, options, &mesh, renderer_);
  const EvaluationResult after = Evaluate(mesh.V, mesh.F, V, F);
  const double footprint = MedianFootprint(source.Views(), V, VertexNormals(V, F));
  ASSERT_GT(footprint, 0);
  EXPECT_LT(after.accuracy90, input.accuracy90 + 0.25 * footprint)
      << "remeshed input " << input.accuracy90 << ", footprint " << footprint << "\n"
      << summary.FullReport();
  EXPECT_LT(after.normal_deg, input.normal_deg + 1.0) << summary.FullReport();
  EXPECT_GT(summary.final_similarity, 0.8) << summary.FullReport();
  const double relief_before = ReliefRms(remeshed.V), relief_after = ReliefRms(mesh.V);
  RecordProperty("relief_rms_before", std::to_string(relief_before));
  RecordProperty("relief_rms_after", std::to_string(relief_after));
  EXPECT_GT(relief_after, 0.95 * relief_before)
      << "relief RMS " << relief_before << " -> " << relief_after;
}

// --Refine.light auto tells a light at the camera from one fixed in the
// world by the input's similarity, on the same object: a ring of views lit
// by a light fixed in the world, and the same views lit from each camera.
TEST_F(RefinerTest, LightAutoTellsAHeadlightFromAFixedLight) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(4, 0.06, &V, &F);
  RefineOptions options;
  options.light = "auto";
  options.iterations_per_level = 1;
  options.masks_from_background = false;
  for (const bool headlight : {false, true}) {
    TestSceneOptions scene;
    scene.headlight = headlight;
    const InMemoryViewSource source = MakeTestScene(V, F, scene, {}, renderer_);
    TriangleMesh mesh;
    mesh.V = V;
    mesh.F = F;
    const RefineSummary summary = RefineMesh(source, options, &mesh, renderer_);
    std::printf("headlight %d: %s\n", headlight, summary.light.c_str());
    EXPECT_EQ(summary.light.rfind(headlight ? "at the camera" : "fixed in the world", 0), 0u)
        << summary.light;
  }
}

// The bumpy sphere (V, F) that the test scene shows, and the smooth sphere
// (V0, F0) to start from: the relief must be recovered from the images.
void MakeBumpyAndSmoothSpheres(Eigen::MatrixXd* V, Eigen::MatrixXi* F, Eigen::MatrixXd* V0,
                               Eigen::MatrixXi* F0) {
  MakeBumpySphere(5, 0.06, V, F);
  MakeIcosphere(4, 1.0, V0, F0);
}

TEST_F(RefinerTest, NoisyMeshGetsCloserToGroundTruth) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  TriangleMesh mesh;
  mesh.V = V0;
  mesh.F = F0;
  const EvaluationResult before = Evaluate(V0, F0, V, F);
  const RefineSummary summary = RefineMesh(source, FastOptions(), &mesh, renderer_);
  const EvaluationResult after = Evaluate(mesh.V, mesh.F, V, F);
  EXPECT_LT(after.accuracy90, 0.6 * before.accuracy90) << summary.FullReport();
  EXPECT_LT(after.normal_deg, before.normal_deg) << summary.FullReport();
  EXPECT_GT(summary.final_similarity, summary.initial_similarity);
  // The time split accounts for the whole run.
  double iterating = 0;
  for (const auto& it : summary.iterations) iterating += it.seconds;
  EXPECT_NEAR(summary.setup_seconds + summary.remesh_seconds + iterating + summary.final_seconds,
              summary.seconds, 0.02 * summary.seconds + 0.05)
      << summary.FullReport();
  EXPECT_NE(summary.FullReport().find("  time: setup "), std::string::npos);
}

// average_last_iterates: the finest level ends on the mean of its last
// iterates, exactly those that runs of fewer iterations end on, and not on
// the last alone. (With kappa 0: dcv's kappa grows over the whole run, so a
// shorter run's iterates differ.)
TEST_F(RefinerTest, FinestLevelEndsOnTheMeanOfItsLastIterates) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  RefineOptions options = OneLevelOptions();
  options.kappa = 0;
  options.average_pair_halves = false;  // the shorter runs' iterates take all pairs
  options.output_subdivisions = 0;  // the iterates themselves
  const auto refine = [&](int iterations, int average, RefineSummary* summary) {
    TriangleMesh mesh;
    mesh.V = V0;
    mesh.F = F0;
    RefineOptions o = options;
    o.iterations_per_level = iterations;
    o.average_last_iterates = average;
    *summary = RefineMesh(source, o, &mesh, renderer_);
    return mesh;
  };
  RefineSummary summary;
  const TriangleMesh second = refine(2, 1, &summary);
  EXPECT_EQ(summary.iterates_averaged, 0);
  const TriangleMesh third = refine(3, 1, &summary);
  const TriangleMesh averaged = refine(3, 2, &summary);
  EXPECT_EQ(summary.iterates_averaged, 2) << summary.FullReport();
  ASSERT_EQ(averaged.F, third.F);
  const double to_mean = (averaged.V - (second.V + third.V) / 2).rowwise().norm().maxCoeff();
  const double to_last = (averaged.V - third.V).rowwise().norm().maxCoeff();
  EXPECT_LT(to_mean, 1e-9) << "furthest from the mean of iterates 2 and 3: " << to_mean;
  EXPECT_GT(to_last, 1e-4) << "furthest from the 3rd iterate: " << to_last;
}

// --Refine.pair_halves_min_views: the middle iterations of each level take
// alternate halves of the pairs, the first and last two all of them, and the
// relief is recovered as well as with all pairs in every iteration.
TEST_F(RefinerTest, PairHalvesInTheMiddleIterations) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  RefineOptions options = OneLevelOptions();
  options.average_last_iterates = 1;  // no averaged iterations, which take halves too
  RefineOptions halves = options;
  halves.pair_halves_min_views = source.NumViews();
  options.pair_halves_min_views = source.NumViews() + 1;  // off
  EvaluationResult result[2];
  for (int k = 0; k < 2; ++k) {
    TriangleMesh mesh;
    mesh.V = V0;
    mesh.F = F0;
    const RefineSummary summary = RefineMesh(source, k ? halves : options, &mesh, renderer_);
    result[k] = Evaluate(mesh.V, mesh.F, V, F);
    EXPECT_EQ(summary.FullReport().find("h: the similarity over half") != std::string::npos,
              k == 1);
    ASSERT_EQ(summary.iterations.size(), 6u);
    for (int it = 0; it < 6; ++it) {
      const bool all = k == 0 || it == 0 || it >= 4;
      if (all) {
        EXPECT_EQ(summary.iterations[it].num_pairs, summary.num_pairs) << it;
      } else {
        EXPECT_LT(summary.iterations[it].num_pairs, summary.num_pairs) << it;
        EXPECT_GE(summary.iterations[it].num_pairs, summary.num_pairs / 2 - 1) << it;
      }
    }
  }
  RecordProperty("accuracy90_all_pairs", std::to_string(result[0].accuracy90));
  RecordProperty("accuracy90_halves", std::to_string(result[1].accuracy90));
  EXPECT_LT(result[1].accuracy90, 1.1 * result[0].accuracy90);
  EXPECT_LT(result[1].normal_deg, 1.1 * result[0].normal_deg);
}

// --Refine.average_pair_halves: the averaged iterations take alternate
// halves of the pairs (each half in turn), the settling ones all of them,
// and the relief is recovered as well as with all pairs.
TEST_F(RefinerTest, AveragedIterationsTakeAlternateHalvesOfThePairs) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  RefineOptions options = OneLevelOptions();
  options.iterations_per_level = 8;
  options.average_last_iterates = 4;
  RefineOptions all_pairs = options;
  all_pairs.average_pair_halves = false;
  EvaluationResult result[2];
  for (int k = 0; k < 2; ++k) {
    TriangleMesh mesh;
    mesh.V = V0;
    mesh.F = F0;
    const RefineSummary summary =
        RefineMesh(source, k ? options : all_pairs, &mesh, renderer_);
    result[k] = Evaluate(mesh.V, mesh.F, V, F);
    EXPECT_EQ(summary.iterates_averaged, 4);
    ASSERT_EQ(summary.iterations.size(), 8u);
    std::set<int> sizes;
    for (int it = 0; it < 8; ++it) {
      const int num_pairs = summary.iterations[it].num_pairs;
      if (k == 0 || it < 4) {
        EXPECT_EQ(num_pairs, summary.num_pairs) << it;
      } else {
        EXPECT_LT(num_pairs, summary.num_pairs) << it;
        sizes.insert(num_pairs);
        if (it >= 5) {
          EXPECT_EQ(num_pairs + summary.iterations[it - 1].num_pairs, summary.num_pairs) << it;
        }
      }
    }
    if (k == 1) {
      EXPECT_EQ(sizes.size(), summary.num_pairs % 2 == 0 ? 1u : 2u);
    }
  }
  RecordProperty("accuracy90_all_pairs", std::to_string(result[0].accuracy90));
  RecordProperty("accuracy90_halves", std::to_string(result[1].accuracy90));
  EXPECT_LT(result[1].accuracy90, 1.1 * result[0].accuracy90);
  EXPECT_LT(result[1].normal_deg, 1.1 * result[0].normal_deg);
}

// --Refine.max_image_size: images and cameras scaled down together. The same
// scene rendered at twice the size and refined at max_image_size 160 ends
// where the 160x120 scene ends (a camera scaled wrongly by half a pixel
// would leave every pair misaligned and the result far off).
TEST_F(RefinerTest, MaxImageSizeWorksAtTheWorkingResolution) {
  const TwoSizes scene = BumpySphereAtTwoSizes(1);
  const Eigen::MatrixXd& V = scene.V;
  const Eigen::MatrixXi& F = scene.F;
  const InMemoryViewSource& small_source = scene.small;
  const InMemoryViewSource& large_source = scene.large;
  TriangleMesh at_small = SmoothSphere(), at_large = SmoothSphere();
  const EvaluationResult before = Evaluate(at_small.V, at_small.F, V, F);
  RefineMesh(small_source, FastOptions(), &at_small, renderer_);
  RefineOptions options = FastOptions();
  options.max_image_size = 160;
  const RefineSummary summary = RefineMesh(large_source, options, &at_large, renderer_);
  const EvaluationResult small_result = Evaluate(at_small.V, at_small.F, V, F);
  const EvaluationResult large_result = Evaluate(at_large.V, at_large.F, V, F);
  std::printf("accuracy90 %.4f -> %.4f at 160x120, %.4f at 320x240 scaled to 160; faces %d, %d\n",
              before.accuracy90, small_result.accuracy90, large_result.accuracy90,
              static_cast<int>(at_small.F.rows()), static_cast<int>(at_large.F.rows()));
  EXPECT_LT(large_result.accuracy90, 0.6 * before.accuracy90) << summary.FullReport();
  EXPECT_NEAR(large_result.accuracy90, small_result.accuracy90, 0.15 * small_result.accuracy90);
  EXPECT_NEAR(large_result.normal_deg, small_result.normal_deg, 0.15 * small_result.normal_deg);
  // The mesh follows the working resolution: as many faces as at 160x120.
  EXPECT_NEAR(at_large.F.rows(), at_small.F.rows(), 0.1 * at_small.F.rows());
}

// Photographs from two cameras of different resolutions in one workspace
// (two phones; COLMAP's image_undistorter gives every camera its own size):
// the views of the ring alternate between 160x120 and 320x240 images, so
// each pair compares images whose pixels cover the surface at footprints a
// factor 2 apart. The mesh is sized by the sharper views, as for the ring of
// 320x240 views alone, and must end about where that run ends (a camera or
// pyramid level scaled wrongly for one size would leave half of the pairs
// misaligned and the result far off). Measured: accuracy90 0.0391 -> 0.0213
// mixed, 0.0214 all 320x240 (0.0180 all 160x120, on a mesh of 19k faces
// instead of 46k-71k; FastOptions' 12 iterations leave the finer meshes
// rougher: normal error 4.65, 4.29 and 3.56 degrees).
TEST_F(RefinerTest, ViewsOfDifferentSizesRefineTogether) {
  const TwoSizes scene = BumpySphereAtTwoSizes(TestSceneOptions().supersample);
  const Eigen::MatrixXd& V = scene.V;
  const Eigen::MatrixXi& F = scene.F;
  const InMemoryViewSource& small_source = scene.small;
  const InMemoryViewSource& large_source = scene.large;
  InMemoryViewSource mixed;
  for (int i = 0; i < small_source.NumViews(); ++i) {
    const InMemoryViewSource& from = i % 2 == 0 ? small_source : large_source;
    mixed.Add(from.Name(i), from.View(i), from.LoadGray(i));
  }
  ASSERT_EQ(mixed.View(1).width, 320);
  ASSERT_EQ(mixed.View(2).width, 160);
  TriangleMesh at_large = SmoothSphere(), at_mixed = SmoothSphere();
  const EvaluationResult before = Evaluate(at_large.V, at_large.F, V, F);
  RefineMesh(large_source, FastOptions(), &at_large, renderer_);
  const RefineSummary summary = RefineMesh(mixed, FastOptions(), &at_mixed, renderer_);
  const EvaluationResult large_result = Evaluate(at_large.V, at_large.F, V, F);
  const EvaluationResult mixed_result = Evaluate(at_mixed.V, at_mixed.F, V, F);
  std::printf("accuracy90 %.4f -> %.4f all 320x240, %.4f mixed; normal %.2f -> %.2f, %.2f; "
              "faces %d, %d\n",
              before.accuracy90, large_result.accuracy90, mixed_result.accuracy90,
              before.normal_deg, large_result.normal_deg, mixed_result.normal_deg,
              static_cast<int>(at_large.F.rows()), static_cast<int>(at_mixed.F.rows()));
  EXPECT_LT(mixed_result.accuracy90, 0.6 * before.accuracy90) << summary.FullReport();
  EXPECT_LT(mixed_result.accuracy90, 1.15 * large_result.accuracy90);
  EXPECT_LT(mixed_result.normal_deg, 1.15 * large_result.normal_deg);
}

// RefineOptions::output_subdivisions: the refined vertices are kept as they
// are, every face is split in four, every vertex has a colour, and the new
// vertices on the edges' curves bring the surface nearer the truth than the
// refined triangles' facets.
TEST_F(RefinerTest, OutputSubdivisionKeepsTheRefinedVerticesAndSmoothsTheFacets) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  RefineOptions options = OneLevelOptions();
  options.output_subdivisions = 0;
  TriangleMesh plain, split;
  plain.V = split.V = V0;
  plain.F = split.F = F0;
  RefineMesh(source, options, &plain, renderer_);
  options.output_subdivisions = 1;
  const RefineSummary summary = RefineMesh(source, options, &split, renderer_);
  ASSERT_EQ(split.F.rows(), 4 * plain.F.rows());
  EXPECT_EQ(summary.final_faces, split.F.rows());
  ASSERT_EQ(split.V.rows(), plain.V.rows() + ComputeEdgeTopology(plain.F, plain.V.rows()).E.rows());
  EXPECT_EQ(split.V.topRows(plain.V.rows()), plain.V);
  ASSERT_EQ(split.C.rows(), split.V.rows());
  EXPECT_EQ(split.C.topRows(plain.C.rows()), plain.C);
  EXPECT_EQ(CountSelfIntersections(split.V, split.F).intersecting_pairs, 0);
  const EvaluationResult a = Evaluate(plain.V, plain.F, V, F);
  const EvaluationResult b = Evaluate(split.V, split.F, V, F);
  std::printf("accuracy90 %.5f -> %.5f, normal %.3f -> %.3f deg, faces %d -> %d\n", a.accuracy90,
              b.accuracy90, a.normal_deg, b.normal_deg, static_cast<int>(plain.F.rows()),
              static_cast<int>(split.F.rows()));
  // Here the bumps are a few edges wide and the data term, not the facets,
  // limits the result (measured 0.02346 -> 0.02352, 4.230 -> 4.222 deg); a
  // split that bulged would show. The corpus's gains: docs/results.md.
  EXPECT_LT(b.normal_deg, a.normal_deg + 0.05);
  EXPECT_LT(b.accuracy90, 1.02 * a.accuracy90);
}

// RMS distance, in pixels, between the projections of the vertices V through
// two sets of cameras (vertices in front of both and inside the image).
double ReprojectionRmsPx(const std::vector<PinholeView>& a, const std::vector<PinholeView>& b,
                         const Eigen::MatrixXd& V) {
  double sum = 0;
  long n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    for (int v = 0; v < V.rows(); ++v) {
      const Eigen::Vector3d x = V.row(v);
      if (a[i].WorldToCamera(x).z() <= 0 || b[i].WorldToCamera(x).z() <= 0) continue;
      const Eigen::Vector2d p = a[i].Project(x);
      if (!a[i].InImage(p)) continue;
      sum += (p - b[i].Project(x)).squaredNorm();
      ++n;
    }
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

// max_faces holds even where the remesher's edges come out shorter than its
// target: with a budget far below what 1.5-pixel edges would need, the level
// mesh has at most max_faces faces, and not far fewer.
TEST_F(RefinerTest, FaceBudgetIsRespected) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  for (const int max_faces : {3000, 7000}) {
    TriangleMesh mesh;
    mesh.V = V;
    mesh.F = F;
    RefineOptions options;
    options.num_levels = 1;
    options.iterations_per_level = 0;
    options.target_edge_px = 1.5;
    options.max_faces = max_faces;
    options.output_subdivisions = 0;  // the budget is the refinement's; the split comes after
    RefineMesh(source, options, &mesh, renderer_);
    EXPECT_LE(mesh.F.rows(), max_faces);
    EXPECT_GE(mesh.F.rows(), 0.8 * max_faces);
  }
}

// A scene in depth: a bumpy sphere on a ground that reaches 8 radii out.
// The far ground is remeshed with longer edges than the sphere (its pixels
// cover more), where one length for the whole mesh gave both the same.
TEST_F(RefinerTest, EdgesFollowTheFootprintInDepth) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(4, 0.03, &V, &F);
  const int sphere_faces = static_cast<int>(F.rows()), base = static_cast<int>(V.rows());
  AppendGrid(Eigen::Vector3d(-8, -8, -1.05), Eigen::Vector3d(16, 0, 0), Eigen::Vector3d(0, 16, 0),
             32, &V, &F);  // facing up
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  TriangleMesh mesh;
  mesh.V = V;
  mesh.F = F;
  RefineOptions options;
  options.num_levels = 1;
  options.iterations_per_level = 0;
  options.max_faces = 1000000;
  options.output_subdivisions = 0;  // the edges of the refinement's mesh
  RefineMesh(source, options, &mesh, renderer_);
  // Mean edge length of the faces on the sphere and on the ground beyond 5
  // radii.
  double sum[2] = {0, 0};
  int count[2] = {0, 0};
  for (int f = 0; f < mesh.F.rows(); ++f) {
    const Eigen::Vector3d a = mesh.V.row(mesh.F(f, 0)), b = mesh.V.row(mesh.F(f, 1)),
                          c = mesh.V.row(mesh.F(f, 2));
    const Eigen::Vector3d centre = (a + b + c) / 3;
    const int where = centre.norm() < 1.2 ? 0 : centre.head<2>().norm() > 5 ? 1 : -1;
    if (where < 0) continue;
    sum[where] += ((a - b).norm() + (b - c).norm() + (c - a).norm()) / 3;
    ++count[where];
  }
  ASSERT_GT(count[0], 100);
  ASSERT_GT(count[1], 100);
  const double sphere_edge = sum[0] / count[0], far_edge = sum[1] / count[1];
  EXPECT_GT(far_edge, 1.8 * sphere_edge) << sphere_edge << " " << far_edge;
  // The sphere keeps the length its own footprint asks for.
  const std::vector<PinholeView> views = source.Views();
  Eigen::MatrixXd sphere_V = V.topRows(base);
  Eigen::MatrixXi sphere_F = F.topRows(sphere_faces);
  const double footprint = MedianFootprint(views, sphere_V, VertexNormals(sphere_V, sphere_F));
  EXPECT_NEAR(sphere_edge, options.target_edge_px * footprint,
              0.35 * options.target_edge_px * footprint);
}

// Images without texture carry no information, also when they are not
// exactly constant: a textureless region scaled by a non-dyadic factor holds
// rounding noise of ~1e-7 (here a fixed pattern in each image). The flow must
// not follow it: before the information floor, -G / (H + mu) of that noise
// sent vertices to the step limit every iteration.
TEST_F(RefinerTest, RoundingNoiseOfATexturelessImageMovesNothing) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  const InMemoryViewSource textured = MakeTestScene(V, F, {}, {}, renderer_);
  InMemoryViewSource source;
  for (int i = 0; i < textured.NumViews(); ++i) {
    const PinholeView& view = textured.View(i);
    cv::Mat gray(view.height, view.width, CV_32F);
    for (int y = 0; y < gray.rows; ++y) {
      for (int x = 0; x < gray.cols; ++x) {
        gray.at<float>(y, x) = 0.5f + 1e-7f * static_cast<float>((7 * x + 13 * y + 3 * i) % 5);
      }
    }
    source.Add(textured.Name(i), view, gray);
  }
  TriangleMesh mesh;
  mesh.V = V;
  mesh.F = F;
  RefineOptions options;
  options.num_levels = 1;
  options.iterations_per_level = 3;
  options.regularizer = "none";
  TriangleMesh remeshed = mesh;
  RefineOptions remesh_only = options;
  remesh_only.iterations_per_level = 0;
  RefineMesh(source, remesh_only, &remeshed, renderer_);
  const RefineSummary summary = RefineMesh(source, options, &mesh, renderer_);
  ASSERT_EQ(mesh.V.rows(), remeshed.V.rows());
  const double moved = (mesh.V - remeshed.V).rowwise().norm().maxCoeff();
  const double footprint = MedianFootprint(source.Views(), V, VertexNormals(V, F));
  EXPECT_LT(moved, 0.01 * footprint) << summary.FullReport();
}

// --Refine.refine_cameras: the images are true, the cameras carry about a
// pixel of pose error (as after SfM). Without camera refinement the flow
// bends the (true) start mesh to fit the wrong cameras; with it the cameras
// move most of the way back and the mesh stays closer to the truth.
TEST_F(RefinerTest, CameraRefinementUndoesPoseError) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(4, 0.06, &V, &F);
  const InMemoryViewSource truth = MakeTestScene(V, F, {}, {}, renderer_);
  InMemoryViewSource wrong;
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  std::vector<PinholeView> true_views, wrong_views;
  for (int i = 0; i < truth.NumViews(); ++i) {
    PinholeView view = truth.View(i);
    true_views.push_back(view);
    const Eigen::Vector3d axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    const Eigen::Vector3d shift = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const Eigen::Vector3d center = view.Center() + 0.004 * shift;
    view.R = Eigen::AngleAxisd(0.25 * M_PI / 180, axis).toRotationMatrix() * view.R;
    view.t = -view.R * center;
    wrong_views.push_back(view);
    wrong.Add(truth.Name(i), view, truth.LoadGray(i), truth.LoadMask(i));
  }
  const double error_before = ReprojectionRmsPx(true_views, wrong_views, V);
  RefineOptions options = OneLevelOptions();
  // The photometric term alone: masks made from the true images' background
  // pull the surface towards the wrong cameras' outlines, as given masks
  // would (with them the cameras end 0.454 px from the truth, not 0.343).
  options.masks_from_background = false;
  TriangleMesh fixed, refined;
  fixed.V = refined.V = V;
  fixed.F = refined.F = F;
  const RefineSummary without = RefineMesh(wrong, options, &fixed, renderer_);
  options.refine_cameras = "poses";
  const RefineSummary with = RefineMesh(wrong, options, &refined, renderer_);
  ASSERT_EQ(with.cameras.size(), true_views.size()) << with.FullReport();
  EXPECT_TRUE(without.cameras.empty());
  // One level of 6 iterations: the default's two rounds, after 1 and 3
  // iterations, never against the start mesh.
  ASSERT_EQ(with.camera_reports.size(), 2u) << with.FullReport();
  const double error_after = ReprojectionRmsPx(true_views, with.cameras, V);
  const EvaluationResult a = Evaluate(fixed.V, fixed.F, V, F), b = Evaluate(refined.V, refined.F, V, F);
  std::printf("pose error %.3f -> %.3f px; accuracy90 %.4f without, %.4f with camera refinement; "
              "similarity %.4f, %.4f\n",
              error_before, error_after, a.accuracy90, b.accuracy90, without.final_similarity,
              with.final_similarity);
  EXPECT_GT(error_before, 0.7);
  EXPECT_LT(error_after, 0.4 * error_before) << with.camera_reports[0];
  EXPECT_LT(b.accuracy90, a.accuracy90);
  EXPECT_GT(with.final_similarity, without.final_similarity);

  // The true mesh refined on the wrong cameras with `o`, into `mesh`.
  const auto refine_truth = [&](const RefineOptions& o, TriangleMesh* mesh) {
    mesh->V = V;
    mesh->F = F;
    return RefineMesh(wrong, o, mesh, renderer_);
  };

  // camera_rounds 1: a single refinement, after the first iteration. It
  // undoes as much here (0.230 px against the default's 0.241; its second
  // round starts from where the first left the cameras, its priors still
  // centred on the input ones); the corpus's cases at 1 px gain from the
  // later rounds (docs/camera_refinement.md).
  options.camera_rounds = 1;
  TriangleMesh once;
  const RefineSummary one = refine_truth(options, &once);
  ASSERT_EQ(one.camera_reports.size(), 1u) << one.FullReport();
  const double error_one = ReprojectionRmsPx(true_views, one.cameras, V);
  std::printf("one camera round: pose error %.3f -> %.3f px, accuracy90 %.4f\n", error_before,
              error_one, Evaluate(once.V, once.F, V, F).accuracy90);
  EXPECT_LT(error_one, 0.4 * error_before) << one.camera_reports[0];
  // The round's time is its own, not the data term's of the iteration it
  // comes before.
  ASSERT_EQ(CameraRoundIterations(options.iterations_per_level, 1), std::vector<int>{1});
  ASSERT_GT(one.iterations.size(), 2u);
  for (const RefineIteration& it : one.iterations) {
    if (it.iteration == 1) {
      EXPECT_GT(it.camera_seconds, 0);
      EXPECT_LT(it.data_seconds + it.camera_seconds, it.seconds);
    } else {
      EXPECT_EQ(it.camera_seconds, 0) << it.iteration;
    }
  }

  // A memory budget smaller than the views' images (8 of 160 x 120, 600 KiB,
  // against half of a 1 MiB cache): the cameras are refined at pyramid level
  // 1 (80 x 60) while the surface is at level 0, and carried back to it.
  RefineOptions small_cache = options;
  small_cache.cache_mb = 1;
  TriangleMesh coarse_cameras;
  const RefineSummary coarser = refine_truth(small_cache, &coarse_cameras);
  ASSERT_EQ(coarser.camera_reports.size(), 1u) << coarser.FullReport();
  EXPECT_EQ(coarser.camera_reports[0].rfind("level 0 (at pyramid level 1: ", 0), 0u)
      << coarser.camera_reports[0];
  const double error_coarser = ReprojectionRmsPx(true_views, coarser.cameras, V);
  std::printf("cameras at level 1: pose error %.3f -> %.3f px, accuracy90 %.4f\n", error_before,
              error_coarser, Evaluate(coarse_cameras.V, coarse_cameras.F, V, F).accuracy90);
  EXPECT_LT(error_coarser, 0.4 * error_before) << coarser.camera_reports[0];

  // Two levels: still only within the finest one, never at the coarse
  // level's surface.
  options.num_levels = 2;
  TriangleMesh levels;
  const RefineSummary coarse = refine_truth(options, &levels);
  ASSERT_FALSE(coarse.iterations.empty());
  EXPECT_EQ(coarse.iterations.front().level, 1) << coarse.FullReport();
  ASSERT_EQ(coarse.camera_reports.size(), 1u) << coarse.FullReport();
  EXPECT_EQ(coarse.camera_reports[0].rfind("level 0: ", 0), 0u) << coarse.camera_reports[0];
}

TEST(ResizedViewSource, ImagesAndCamerasScaleTogether) {
  InMemoryViewSource base;
  PinholeView view = LookAtView(Eigen::Vector3d(0, -4, 0), Eigen::Vector3d::Zero(),
                                Eigen::Vector3d::UnitZ(), 401, 301, 500);
  view.cx = 190.3;  // off centre
  // A linear ramp in continuous image coordinates survives INTER_AREA exactly.
  cv::Mat gray(301, 401, CV_32F), mask(301, 401, CV_8U, cv::Scalar(0));
  for (int r = 0; r < 301; ++r) {
    for (int c = 0; c < 401; ++c) gray.at<float>(r, c) = 0.001f * (c + 0.5f) + 0.002f * (r + 0.5f);
  }
  mask(cv::Rect(100, 100, 200, 100)).setTo(255);
  base.Add("a", view, gray, mask);
  base.Add("b", view.Scaled(0.25), cv::Mat(76, 101, CV_32F, cv::Scalar(0.5)));

  const ResizedViewSource resized(base, 200);
  const PinholeView& v = resized.View(0);
  EXPECT_EQ(v.width, 200);  // 401 * 200 / 401
  EXPECT_EQ(v.height, 150);  // round(301 * 200 / 401) = round(150.1)
  EXPECT_TRUE(resized.Resized(0));
  EXPECT_FALSE(resized.Resized(1));  // 101 x 76 is within the limit
  EXPECT_EQ(resized.View(1).width, 101);
  // A 3D point projects to the scaled image point, per axis.
  const Eigen::Vector3d X(0.3, 0.2, -0.4);
  const Eigen::Vector2d p = view.Project(X), q = v.Project(X);
  EXPECT_NEAR(q.x(), p.x() * 200.0 / 401.0, 1e-9);
  EXPECT_NEAR(q.y(), p.y() * 150.0 / 301.0, 1e-9);
  // The image content follows: the ramp at a scaled pixel centre is the ramp
  // at the corresponding full-resolution point.
  const cv::Mat g = resized.LoadGray(0);
  ASSERT_EQ(g.cols, 200);
  ASSERT_EQ(g.rows, 150);
  for (const auto& [r, c] : std::vector<std::pair<int, int>>{{10, 10}, {75, 100}, {140, 190}}) {
    const double x = (c + 0.5) * 401.0 / 200.0, y = (r + 0.5) * 301.0 / 150.0;
    EXPECT_NEAR(g.at<float>(r, c), 0.001 * x + 0.002 * y, 1e-4) << r << " " << c;
  }
  // Masks stay binary.
  const cv::Mat m = resized.LoadMask(0);
  ASSERT_EQ(m.size(), g.size());
  EXPECT_EQ(cv::countNonZero((m > 0) & (m < 255)), 0);
  EXPECT_NEAR(cv::countNonZero(m), 200 * 100 * (200.0 / 401) * (150.0 / 301), 150);
  // No limit: everything passes through.
  const ResizedViewSource unlimited(base, -1);
  EXPECT_EQ(unlimited.View(0).width, 401);
  EXPECT_EQ(unlimited.LoadGray(0).cols, 401);
}

// Outside its mask every grey pixel becomes 0 where the backdrop is not dark;
// inside, in a view without a mask, in a view on a dark backdrop, and in
// the colour images, nothing changes.
TEST(BlackOutsideMasksViewSource, BlackensWhatTheMaskLeavesOut) {
  InMemoryViewSource base;
  const PinholeView view = LookAtView(Eigen::Vector3d(0, -4, 0), Eigen::Vector3d::Zero(),
                                      Eigen::Vector3d::UnitZ(), 40, 30, 50);
  cv::Mat gray(30, 40, CV_32F), mask(30, 40, CV_8U, cv::Scalar(0));
  cv::randu(gray, 0.1, 0.9);
  mask(cv::Rect(5, 8, 20, 12)).setTo(255);
  base.Add("masked", view, gray, mask);
  base.Add("whole", view, gray, cv::Mat(30, 40, CV_8U, cv::Scalar(255)));
  base.Add("none", view, gray);
  cv::Mat dark = gray.clone();
  dark.setTo(0.04, mask == 0);  // a backdrop of 10 grey levels
  base.Add("dark", view, dark, mask);
  EXPECT_NEAR(BackdropLevel(gray, mask), 0.5, 0.1);
  EXPECT_FLOAT_EQ(BackdropLevel(dark, mask), 0.04f);
  EXPECT_EQ(BackdropLevel(gray, cv::Mat(30, 40, CV_8U, cv::Scalar(255))), -1);
  const BlackOutsideMasksViewSource black(base);
  EXPECT_EQ(black.Report(), "");  // nothing loaded yet
  const cv::Mat g = black.LoadGray(0);
  ASSERT_EQ(g.size(), gray.size());
  long kept = 0, blackened = 0;
  for (int r = 0; r < 30; ++r) {
    for (int c = 0; c < 40; ++c) {
      if (mask.at<uint8_t>(r, c)) {
        EXPECT_EQ(g.at<float>(r, c), gray.at<float>(r, c));
        ++kept;
      } else {
        EXPECT_EQ(g.at<float>(r, c), 0.f);
        ++blackened;
      }
    }
  }
  EXPECT_EQ(kept, 240);
  EXPECT_EQ(blackened, 1200 - 240);
  EXPECT_EQ(cv::norm(base.LoadGray(0), gray, cv::NORM_INF), 0);  // the base is untouched
  EXPECT_EQ(cv::norm(black.LoadGray(1), gray, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(black.LoadGray(2), gray, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(black.LoadGray(3), dark, cv::NORM_INF), 0);
  // The view whose mask covers it all has no backdrop to measure.
  EXPECT_NE(black.Report().find("not dark in 1 of 2 views"), std::string::npos) << black.Report();
  EXPECT_EQ(cv::norm(black.LoadColor(0), base.LoadColor(0), cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(black.LoadMask(0), mask, cv::NORM_INF), 0);
}

// The schedule chooses itself: no coarse level for a start that is already
// close (the truth), coarse levels for a far-off one (a sphere 12 % too big,
// several pixels off in every view).
// The silhouette term moves contour vertices by the gap between the observed
// outline and the rendered one: none where the mask is the mesh's own
// outline (before: every contour vertex a little inside the drawn outline
// was pushed outward, and textureless scenes inflated, accuracy90 1.39x the
// input on the corpus's builtin-shading-40), and outward by the gap where
// the mask comes from a larger sphere.
// A fine, slightly rough unit sphere (edges ~1.5 px, radial noise 0.4 px)
// seen from 5 units by a 320x240 view: its contour generator is jagged, as a
// real mesh's is.
void RoughSphereInView(Eigen::MatrixXd* V, Eigen::MatrixXi* F, PinholeView* view) {
  MakeIcosphere(5, 1.0, V, F);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (int v = 0; v < V->rows(); ++v) V->row(v) *= 1.0 + noise(rng);
  *view = PinholeView();
  view->width = 320;
  view->height = 240;
  view->fx = view->fy = 400;
  view->cx = 160;
  view->cy = 120;
  view->t = Eigen::Vector3d(0, 0, 5);
}

TEST_F(RefinerTest, SilhouetteTermFollowsTheGapBetweenOutlines) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PinholeView view;
  RoughSphereInView(&V, &F, &view);
  const Eigen::MatrixXd big_V = 1.03 * V;
  renderer_->SetMesh(V, F);
  const RenderBuffers render = renderer_->Render(view);
  renderer_->SetMesh(big_V, F);
  const RenderBuffers big_render = renderer_->Render(view);
  const Eigen::MatrixXd N = VertexNormals(V, F);
  const double footprint = 5.0 / view.fx;
  for (const bool larger : {false, true}) {
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(V.rows(), 3);
    Eigen::VectorXd count = Eigen::VectorXd::Zero(V.rows());
    AccumulateSilhouetteTerm(V, F, N, view, render,
                             RenderedCoverage(larger ? big_render : render), 3.0,
                             /*hull_margin_px=*/-1, &d, &count);
    double radial_sum = 0;
    int contour = 0;
    for (int v = 0; v < V.rows(); ++v) {
      if (count(v) == 0) continue;
      radial_sum += d.row(v).dot(V.row(v).normalized()) / footprint;
      ++contour;
    }
    ASSERT_GT(contour, 50);
    const double mean_px = radial_sum / contour;
    std::printf("mask of the %s sphere: %d contour vertices, mean radial move %.3f px\n",
                larger ? "larger" : "same", contour, mean_px);
    // The larger sphere's outline lies 0.03 * f * r / sqrt(d^2 - r^2) = 2.45
    // px further out.
    if (larger) {
      EXPECT_NEAR(mean_px, 2.45, 0.5);
    } else {
      EXPECT_NEAR(mean_px, 0.0, 0.15);
    }
  }
}

// The visual hull: with a mask smaller than the mesh (a sphere 10 % smaller,
// its outline about 8 px inside), every vertex off the contour that projects
// outside the mask is pulled toward it across the image plane, by its
// distance beyond the mask's edge, at most max_px; with the mesh's own mask
// nothing off the contour moves by more than the pixel grid allows.
TEST_F(RefinerTest, HullPullRetractsWhatLiesOutsideTheMask) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PinholeView view;
  RoughSphereInView(&V, &F, &view);
  renderer_->SetMesh(V, F);
  const RenderBuffers render = renderer_->Render(view);
  const cv::Mat own_mask = RenderedCoverage(render);
  renderer_->SetMesh(0.9 * V, F);
  const cv::Mat small_mask = RenderedCoverage(renderer_->Render(view));
  const Eigen::MatrixXd N = VertexNormals(V, F);
  // Off the contour: no face of the vertex turns its back on the camera, or
  // none faces it.
  std::vector<char> front(V.rows(), 0), back(V.rows(), 0);
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const bool faces = (b - a).cross(c - a).dot(view.Center() - a) > 0;
    for (int k = 0; k < 3; ++k) (faces ? front : back)[F(f, k)] = 1;
  }
  const double margin = 0, max_px = 3.0;
  for (const bool small : {false, true}) {
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(V.rows(), 3);
    Eigen::VectorXd count = Eigen::VectorXd::Zero(V.rows());
    AccumulateSilhouetteTerm(V, F, N, view, render, small ? small_mask : own_mask, max_px, margin,
                             &d, &count);
    int pulled = 0, capped = 0;
    double largest_px = 0;
    for (int v = 0; v < V.rows(); ++v) {
      if ((front[v] && back[v]) || count(v) == 0) continue;
      ++pulled;
      const Eigen::Vector3d x = V.row(v);
      const double footprint = view.WorldToCamera(x).z() / view.fx;
      const double px = d.row(v).norm() / footprint;
      largest_px = std::max(largest_px, px);
      if (px > max_px - 1e-6) ++capped;
      EXPECT_LE(px, max_px + 1e-6);
      // Across the image plane (the view looks along +z) and, from well
      // outside, toward the image centre (near the edge the nearest inside
      // pixel may lie to the side).
      EXPECT_NEAR(d(v, 2), 0, 1e-9 * d.row(v).norm()) << v;
      if (px > 1) {
        EXPECT_LT(d(v, 0) * x.x() + d(v, 1) * x.y(), 0) << v;
      }
    }
    std::printf("%s mask: %d vertices off the contour pulled, %d by the full %.0f px; largest "
                "%.3f px\n", small ? "smaller sphere's" : "own", pulled, capped, max_px,
                largest_px);
    if (small) {
      EXPECT_GT(pulled, 200);
      EXPECT_GT(capped, 100);  // most of the 8-px band
    } else {
      EXPECT_LT(largest_px, 0.75);  // the pixel grid's share only (<= sqrt(2)/2)
    }
  }
  // A negative margin: only the contour term (the test above).
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(V.rows(), 3);
  Eigen::VectorXd count = Eigen::VectorXd::Zero(V.rows());
  AccumulateSilhouetteTerm(V, F, N, view, render, small_mask, max_px, -1, &d, &count);
  for (int v = 0; v < V.rows(); ++v) {
    if (!(front[v] && back[v])) {
      EXPECT_EQ(count(v), 0) << v;
    }
  }
}

// (V, F) without the faces whose centroid satisfies `cut`, and without the
// vertices no face uses any more: an open mesh.
TriangleMesh FacesExcept(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                         const std::function<bool(const Eigen::RowVector3d&)>& cut) {
  std::vector<int> kept;
  for (int f = 0; f < F.rows(); ++f) {
    if (!cut(FaceCentroid(V, F, f).transpose())) kept.push_back(f);
  }
  TriangleMesh mesh;
  mesh.V = V;
  mesh.F.resize(kept.size(), 3);
  for (size_t i = 0; i < kept.size(); ++i) mesh.F.row(i) = F.row(kept[i]);
  RemoveUnreferencedVertices(&mesh.V, &mesh.F);
  return mesh;
}

// The open border's membrane step moves only what the images see and
// contradict. A bumpy sphere cut open at the top, where the ring of views
// (elevation 25 degrees) sees the border and the surface around it: the rim
// stays where it was. Cut open at the bottom, with the last rings flared out
// and down as a trimmed Poisson mesh's skirt, which the views see at a
// slant against the images of the true surface: the step pulls it in. No
// masks, so that the silhouette term does not pull the skirt in as well.
// Measured (6 December 2026): the rim 0.0060 lower with the step (0.0145
// with the step on every band vertex), the skirt's mean error 0.0720 in the
// input, 0.0665 without the step and 0.0604 with it (0.0587 on every band
// vertex). An edge is about 0.04 long.
TEST_F(RefinerTest, OpenBorderMembraneMovesOnlyWhatTheImagesContradict) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  ASSERT_FALSE(source.HasMasks());
  RefineOptions options = OneLevelOptions();
  options.masks_from_background = false;
  auto refine = [&](const Eigen::MatrixXd& V_in, const Eigen::MatrixXi& F_in, int rings) {
    TriangleMesh mesh;
    mesh.V = V_in;
    mesh.F = F_in;
    RefineOptions o = options;
    o.open_border_rings = rings;
    RefineMesh(source, o, &mesh, renderer_);
    return mesh;
  };

  // Open at the top.
  const TriangleMesh top =
      FacesExcept(V, F, [](const Eigen::RowVector3d& c) { return c.z() > 0.7; });
  const TriangleMesh top_off = refine(top.V, top.F, 0), top_on = refine(top.V, top.F, 3);
  // Where the hole's rim ends: the mean height of the border vertices.
  auto rim_height = [](const TriangleMesh& mesh) {
    const VertexBand border = OpenBorderBand(mesh.F, static_cast<int>(mesh.V.rows()), 1);
    double sum = 0;
    for (const int v : border.vertices) sum += mesh.V(v, 2);
    return border.vertices.empty() ? 0.0 : sum / border.vertices.size();
  };
  const double rim_off = rim_height(top_off), rim_on = rim_height(top_on);
  std::printf("open at the top: the rim at z = %.4f without the step, %.4f with it\n", rim_off,
              rim_on);
  EXPECT_GT(rim_on, rim_off - 0.01);  // measured 0.006 lower; without the gate 0.015

  // Open at the bottom, with a skirt: the vertices below z = -0.45 pushed
  // out and down, the more the lower they are.
  Eigen::MatrixXd V_skirt = V;
  for (int v = 0; v < V.rows(); ++v) {
    const double depth = -0.45 - V(v, 2);
    if (depth <= 0) continue;
    const Eigen::RowVector3d outward(V(v, 0), V(v, 1), 0);
    V_skirt.row(v) += depth * (0.8 * outward.normalized() + Eigen::RowVector3d(0, 0, -0.4));
  }
  const TriangleMesh skirt =
      FacesExcept(V_skirt, F, [](const Eigen::RowVector3d& c) { return c.z() < -0.6; });
  // The mean distance to the truth of the vertices below z = -0.5.
  auto skirt_error = [&](const TriangleMesh& mesh) {
    const VertexErrors errors = MeasureVertexErrors(mesh.V, V, F);
    double sum = 0;
    int n = 0;
    for (int v = 0; v < mesh.V.rows(); ++v) {
      if (mesh.V(v, 2) < -0.5) {
        sum += errors.distance(v);
        ++n;
      }
    }
    return n > 0 ? sum / n : 0.0;
  };
  const double error_input = skirt_error(skirt);
  const double error_off = skirt_error(refine(skirt.V, skirt.F, 0));
  const double error_on = skirt_error(refine(skirt.V, skirt.F, 3));
  std::printf("skirt: mean error below z = -0.5 %.4f in the input, %.4f without the step, %.4f "
              "with it\n", error_input, error_off, error_on);
  EXPECT_LT(error_on, 0.95 * error_off);
}

// Masks grown by 3 px, as those made for a visual hull are: the silhouette
// term pulls the surface out onto them, unless they are moved back onto the
// images' edges first (align_masks, mask_outline.h). Refined from the ground
// truth, which the exact masks keep where it is.
TEST_F(RefinerTest, GrownMasksAreMovedOntoTheImageEdges) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  const InMemoryViewSource images = MakeTestScene(V, F, {}, {}, renderer_);
  renderer_->SetMesh(V, F);
  const cv::Mat disc = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7));
  InMemoryViewSource exact, grown;
  for (int i = 0; i < images.NumViews(); ++i) {
    const PinholeView& view = images.View(i);
    const cv::Mat mask = RenderedCoverage(renderer_->Render(view));
    cv::Mat larger;
    cv::dilate(mask, larger, disc);
    exact.Add(images.Name(i), view, images.LoadGray(i), mask);
    grown.Add(images.Name(i), view, images.LoadGray(i), larger);
  }
  auto refine = [&](const InMemoryViewSource& source, bool align) {
    TriangleMesh mesh;
    mesh.V = V;
    mesh.F = F;
    RefineOptions options;
    options.iterations_per_level = 4;
    options.align_masks = align;
    const RefineSummary summary = RefineMesh(source, options, &mesh, renderer_);
    const EvaluationResult result = Evaluate(mesh.V, mesh.F, V, F);
    std::printf("%s masks, align_masks %d: accuracy90 %.5f, normal %.2f deg\n  masks: %s\n",
                &source == &exact ? "exact" : "grown", align ? 1 : 0, result.accuracy90,
                result.normal_deg, summary.masks.c_str());
    return std::make_pair(result, summary);
  };
  const auto [as_exact, exact_summary] = refine(exact, true);
  const auto [as_given, given_summary] = refine(grown, false);
  const auto [moved, moved_summary] = refine(grown, true);
  EXPECT_NE(exact_summary.masks.find("used as given"), std::string::npos) << exact_summary.masks;
  EXPECT_EQ(given_summary.masks.find("image edge"), std::string::npos)  // not measured
      << given_summary.masks;
  EXPECT_NE(moved_summary.masks.find("moved onto it"), std::string::npos) << moved_summary.masks;
  // Moving the masks wins back at least 85 % of what growing them cost.
  EXPECT_LT(moved.accuracy90 - as_exact.accuracy90,
            0.15 * (as_given.accuracy90 - as_exact.accuracy90));
  EXPECT_LT(moved.normal_deg - as_exact.normal_deg,
            0.15 * (as_given.normal_deg - as_exact.normal_deg));
}

// The bumpy sphere shot against black and against a grey backdrop, with exact
// masks, refined from the smooth sphere: compared as if shot against black
// (black_outside_masks, the default), the grey backdrop refines as the black
// one does; compared as it is, its outline blends the object with grey in
// each view, and the result is worse. Images on black are left as they are.
TEST_F(RefinerTest, GreyBackdropRefinesAsBlackWithMasks) {
  Eigen::MatrixXd V, V0;
  Eigen::MatrixXi F, F0;
  MakeBumpyAndSmoothSpheres(&V, &F, &V0, &F0);
  auto scene = [&](double background) {
    TestSceneOptions scene_options;
    scene_options.background = background;
    const InMemoryViewSource images = MakeTestScene(V, F, scene_options, {}, renderer_);
    InMemoryViewSource masked;
    for (int i = 0; i < images.NumViews(); ++i) {
      masked.Add(images.Name(i), images.View(i), images.LoadGray(i),
                 RenderedCoverage(renderer_->Render(images.View(i))));
    }
    return masked;
  };
  const InMemoryViewSource black = scene(0), grey = scene(0.6);
  auto refine = [&](const InMemoryViewSource& source, bool black_outside) {
    TriangleMesh mesh;
    mesh.V = V0;
    mesh.F = F0;
    RefineOptions options = FastOptions();
    options.black_outside_masks = black_outside;
    RefineMesh(source, options, &mesh, renderer_);
    const EvaluationResult result = Evaluate(mesh.V, mesh.F, V, F);
    std::printf("%s backdrop, black_outside_masks %d: accuracy90 %.5f, normal %.2f deg\n",
                &source == &black ? "black" : "grey", black_outside ? 1 : 0, result.accuracy90,
                result.normal_deg);
    return result;
  };
  const EvaluationResult on_black = refine(black, true);
  const EvaluationResult on_black_as_is = refine(black, false);
  EXPECT_EQ(on_black.accuracy90, on_black_as_is.accuracy90);
  const EvaluationResult grey_as_black = refine(grey, true);
  const EvaluationResult grey_as_is = refine(grey, false);
  EXPECT_LT(grey_as_black.accuracy90, 1.05 * on_black.accuracy90);
  EXPECT_LT(grey_as_black.normal_deg, 1.05 * on_black.normal_deg);
  EXPECT_GT(grey_as_is.accuracy90, grey_as_black.accuracy90);
}

// The silhouette term's distances are searched near each contour vertex,
// not transformed over the whole image: within the search radius they are
// OpenCV's exact Euclidean distance transform, interpolated; beyond it they
// keep their sign and a magnitude of at least the radius. A mask of random
// discs, some cut by the image border.
TEST(SilhouetteTest, SignedDistanceNearTheBoundaryMatchesTheDistanceTransform) {
  const int width = 160, height = 120, radius = 7;
  cv::Mat mask = cv::Mat::zeros(height, width, CV_8U);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 12; ++k) {
    cv::circle(mask, cv::Point(static_cast<int>(unit(rng) * width), static_cast<int>(unit(rng) * height)),
               static_cast<int>(3 + unit(rng) * 25), cv::Scalar(255), cv::FILLED);
  }
  // The reference: each pixel's distance between centres to the nearest
  // pixel on the other side, less half a pixel, positive inside.
  cv::Mat d_in, d_out;
  cv::distanceTransform(mask > 0, d_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(mask == 0, d_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  auto reference = [&](int r, int c) {
    const float in = d_in.at<float>(r, c);
    return in > 0 ? in - 0.5 : 0.5 - d_out.at<float>(r, c);
  };
  int exact = 0, far = 0;
  for (int k = 0; k < 20000; ++k) {
    const double x = 0.5 + unit(rng) * (width - 1.001), y = 0.5 + unit(rng) * (height - 1.001);
    const int c0 = static_cast<int>(std::floor(x - 0.5)), r0 = static_cast<int>(std::floor(y - 0.5));
    const double fu = x - 0.5 - c0, fv = y - 0.5 - r0;
    const double p00 = reference(r0, c0), p01 = reference(r0, c0 + 1),
                 p10 = reference(r0 + 1, c0), p11 = reference(r0 + 1, c0 + 1);
    const double expected = (1 - fv) * (p00 + fu * (p01 - p00)) + fv * (p10 + fu * (p11 - p10));
    const double got = SignedDistanceToMaskAt(mask, x, y, radius);
    const double largest = std::max({std::abs(p00), std::abs(p01), std::abs(p10), std::abs(p11)});
    if (largest <= radius - 0.5) {
      ASSERT_NEAR(got, expected, 1e-4) << "at (" << x << ", " << y << ")";
      ++exact;
    } else {
      ASSERT_GT(got * expected, 0) << "at (" << x << ", " << y << ")";
      ASSERT_GE(std::abs(got), radius - 2.0) << "at (" << x << ", " << y << ")";
      ++far;
    }
  }
  EXPECT_GT(exact, 5000);
  EXPECT_GT(far, 1000);
}

TEST_F(RefinerTest, ScheduleFollowsTheStart) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  TestSceneOptions scene;
  scene.width = 320;
  scene.height = 240;
  const InMemoryViewSource source = MakeTestScene(V, F, scene, {}, renderer_);
  RefineOptions options;  // num_levels 0: chosen from the input
  options.iterations_per_level = 1;
  TriangleMesh close;
  close.V = V;
  close.F = F;
  const RefineSummary close_summary = RefineMesh(source, options, &close, renderer_);
  EXPECT_EQ(close_summary.iterations.front().level, 0) << close_summary.schedule;
  // The chosen one-level schedule starts from the remeshing done on the
  // second thread while the schedule was measured; it must be the surface
  // the sequential path makes when one level is given.
  RefineOptions one_level = options;
  one_level.num_levels = 1;
  TriangleMesh given;
  given.V = V;
  given.F = F;
  RefineMesh(source, one_level, &given, renderer_);
  EXPECT_EQ(close.F, given.F);
  EXPECT_EQ(close.V, given.V);
  TriangleMesh far;
  MakeIcosphere(4, 1.12, &far.V, &far.F);
  const RefineSummary far_summary = RefineMesh(source, options, &far, renderer_);
  EXPECT_GE(far_summary.iterations.front().level, 1) << far_summary.schedule;
  EXPECT_NE(far_summary.schedule.find("levels"), std::string::npos) << far_summary.schedule;
}

TEST_F(RefinerTest, InvariantToRotationAndScale) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(5, 0.06, &V, &F);
  RefineOptions options = OneLevelOptions();
  options.iterations_per_level = 4;

  TriangleMesh plain = SmoothSphere();
  RefineMesh(MakeTestScene(V, F, {}, {}, renderer_), options, &plain, renderer_);

  SceneTransform moved;
  moved.scale = 37.0;
  moved.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  moved.translation = Eigen::Vector3d(100, -20, 5);
  TriangleMesh transformed = SmoothSphere();
  transformed.V = moved.Apply(transformed.V);
  RefineMesh(MakeTestScene(V, F, {}, moved, renderer_), options, &transformed, renderer_);

  // Compare in the canonical frame, as surfaces (remeshing may pick different
  // vertices after floating-point differences).
  Eigen::MatrixXd back(transformed.V.rows(), 3);
  for (int i = 0; i < back.rows(); ++i) back.row(i) = moved.Inverse(transformed.V.row(i)).transpose();
  const EvaluationResult diff = Evaluate(back, transformed.F, plain.V, plain.F);
  EXPECT_LT(diff.accuracy90, 1e-3);
}

TEST_F(RefinerTest, EmptyMeshIsRefused) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(3, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  TriangleMesh empty;
  empty.V.resize(0, 3);
  empty.F.resize(0, 3);
  EXPECT_THROW(RefineMesh(source, FastOptions(), &empty, renderer_), InputError);
}

TEST_F(RefinerTest, MeshBehindCamerasIsRefused) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(3, 0.06, &V, &F);
  const InMemoryViewSource source = MakeTestScene(V, F, {}, {}, renderer_);
  TriangleMesh far_away;
  far_away.V = V.rowwise() + Eigen::RowVector3d(0, 0, 1000);
  far_away.F = F;
  EXPECT_THROW(RefineMesh(source, FastOptions(), &far_away, renderer_), InputError);
}

TEST_F(RefinerTest, ViewsWithoutOverlapAreRefused) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeBumpySphere(3, 0.06, &V, &F);
  TestSceneOptions opposite;
  opposite.num_views = 2;  // two cameras on opposite sides see disjoint halves
  opposite.elevation_deg = 0;
  const InMemoryViewSource source = MakeTestScene(V, F, opposite, {}, renderer_);
  TriangleMesh mesh;
  mesh.V = V;
  mesh.F = F;
  EXPECT_THROW(RefineMesh(source, FastOptions(), &mesh, renderer_), InputError);
}

// A sphere of radius r seen from distance d projects to a disc of radius
// f r / sqrt(d^2 - r^2) pixels; the faces that face the camera cover it once.
TEST(BestViewCoverage, SphereCoversItsProjectedDisc) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  MakeIcosphere(4, 1.0, &V, &F);
  const int w = 640, h = 480;
  const double f = 300;
  const auto view_at = [&](double d) {
    return LookAtView(Eigen::Vector3d(0, -d, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(),
                      w, h, f);
  };
  const auto disc = [&](double d) { return M_PI * f * f / (d * d - 1) / (w * h); };
  EXPECT_NEAR(BestViewCoverage({view_at(4)}, V, F), disc(4), 0.02 * disc(4));
  // The best of the views counts, not their sum.
  EXPECT_NEAR(BestViewCoverage({view_at(40), view_at(4), view_at(8)}, V, F), disc(4),
              0.02 * disc(4));
  EXPECT_LT(BestViewCoverage({view_at(40)}, V, F), 0.001);
  // Behind the camera, or wholly outside the image: nothing.
  const PinholeView away = LookAtView(Eigen::Vector3d(0, -4, 0), Eigen::Vector3d(0, -8, 0),
                                     Eigen::Vector3d::UnitZ(), w, h, f);
  EXPECT_EQ(BestViewCoverage({away}, V, F), 0.0);
  const Eigen::MatrixXd aside = V.rowwise() + Eigen::RowVector3d(30, 0, 0);
  EXPECT_EQ(BestViewCoverage({view_at(4)}, aside, F), 0.0);
  // Filling the whole image is capped at 1.
  EXPECT_EQ(BestViewCoverage({view_at(1.05)}, V, F), 1.0);
}

TEST(RefineOptions, DefaultsAreValid) { EXPECT_TRUE(RefineOptions().Check()); }

TEST(RefineOptions, BadValuesNameTheField) {
  RefineOptions options;
  options.similarity = "ssd";
  try {
    options.Check();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("similarity"), std::string::npos);
  }
  options = RefineOptions();
  options.open_border_rings = -1;
  try {
    options.Check();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("open_border_rings"), std::string::npos);
  }
}

}  // namespace
}  // namespace mr
