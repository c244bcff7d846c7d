#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh.h"
#include "refine/photometric.h"
#include "render/renderer.h"

namespace mr {
namespace {

// A smooth test image: sinusoids, values in [0.1, 0.9].
cv::Mat SmoothImage(int width, int height, double phase) {
  cv::Mat image(height, width, CV_32F);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      image.at<float>(r, c) = static_cast<float>(
          0.5 + 0.2 * std::sin(0.31 * c + phase) * std::cos(0.23 * r) +
          0.15 * std::sin(0.17 * (c + r) + 2 * phase));
    }
  }
  return image;
}

// Total similarity cost C over both orderings of the pair, with exact CPU renders.
double PairCost(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const PinholeView& a,
                const PinholeView& b, const cv::Mat& image_a, const cv::Mat& image_b,
                const SimilarityOptions& similarity, DataTerm* term,
                const PairTermOptions& options = PairTermOptions()) {
  MeshGeometry mesh{&V, &F, FaceNormals(V, F)};
  const RenderBuffers ra = RenderCpu(V, F, a), rb = RenderCpu(V, F, b);
  DataTermAccumulator accumulator(static_cast<int>(V.rows()));
  accumulator.AddPair(mesh, a, ra, image_a, b, rb, image_b, similarity, options);
  accumulator.AddPair(mesh, b, rb, image_b, a, ra, image_a, similarity, options);
  *term = accumulator.Sum();
  return term->cost;
}

// A bumpy height field z = h(x, y) seen by two cameras from above; it covers
// both images entirely so that no pixel changes visibility under tiny moves.
void HeightField(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int n = 9;
  V->resize(n * n, 3);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = -2.0 + 4.0 * j / (n - 1), y = -2.0 + 4.0 * i / (n - 1);
      V->row(i * n + j) << x, y, 0.15 * std::sin(1.3 * x) * std::cos(0.9 * y);
    }
  }
  F->resize(2 * (n - 1) * (n - 1), 3);
  int f = 0;
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const int v00 = i * n + j, v01 = v00 + 1, v10 = v00 + n, v11 = v10 + 1;
      F->row(f++) << v00, v01, v11;
      F->row(f++) << v00, v11, v10;
    }
  }
}

// The height field seen by two cameras from above, with a smooth image each.
struct TwoViewScene {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  PinholeView a = LookAtView(Eigen::Vector3d(-0.3, 0, 4), Eigen::Vector3d::Zero(),
                             Eigen::Vector3d(0, 1, 0), 40, 32, 40);
  PinholeView b = LookAtView(Eigen::Vector3d(0.4, 0.2, 4), Eigen::Vector3d::Zero(),
                             Eigen::Vector3d(0, 1, 0), 40, 32, 40);
  cv::Mat image_a = SmoothImage(40, 32, 0.0), image_b = SmoothImage(40, 32, 0.7);
  TwoViewScene() { HeightField(&V, &F); }
};

TEST(PairTerm, VertexGradientMatchesFiniteDifferences) {
  TwoViewScene scene;
  Eigen::MatrixXd& V = scene.V;
  const Eigen::MatrixXi& F = scene.F;
  const PinholeView &a = scene.a, &b = scene.b;
  const cv::Mat &image_a = scene.image_a, &image_b = scene.image_b;
  // Resolution matching holds its blur fixed in the derivative
  // (photometric.h), so the exact derivative is checked without it.
  const std::vector<std::pair<std::string, std::string>> variants = {
      {"zncc", "cubic"}, {"zncc", "bilinear"}, {"dcv", "cubic"}, {"dcv", "bilinear"}};
  for (const auto& [method, interpolation] : variants) {
    SimilarityOptions similarity;
    similarity.method = method;
    similarity.kappa = 0.0;  // with κ = 0 the dcv direction is the exact gradient
    similarity.double_precision = true;
    PairTermOptions options;
    options.interpolation = interpolation;
    options.match_resolution = false;
    DataTerm term;
    PairCost(V, F, a, b, image_a, image_b, similarity, &term, options);
    const Eigen::MatrixXd analytic = term.gradient;
    std::mt19937 rng(3);
    std::normal_distribution<double> normal;
    int checked = 0;
    for (int v : {30, 31, 40, 41, 49, 50}) {
      ASSERT_GT(term.weight(v), 0) << "vertex " << v << " is not seen";
      const Eigen::Vector3d dir = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
      const double h = 1e-6;
      Eigen::MatrixXd Vp = V, Vm = V;
      Vp.row(v) += h * dir.transpose();
      Vm.row(v) -= h * dir.transpose();
      DataTerm tp, tm;
      const double fd = (PairCost(Vp, F, a, b, image_a, image_b, similarity, &tp, options) -
                         PairCost(Vm, F, a, b, image_a, image_b, similarity, &tm, options)) /
                        (2 * h);
      const double an = analytic.row(v).dot(dir);
      EXPECT_NEAR(an, fd, 2e-3 * std::max(1.0, std::abs(fd)))
          << method << " " << interpolation << " vertex " << v << " analytic " << an << " fd "
          << fd;
      ++checked;
    }
    EXPECT_EQ(checked, 6);
  }
}

// The accumulator's sum over two pairs equals the two pair terms added one by
// one (the per-thread buffers are reused, not reset, between pairs).
TEST(PairTerm, AccumulatorEqualsSumOfPairTerms) {
  TwoViewScene scene;
  Eigen::MatrixXd& V = scene.V;
  const Eigen::MatrixXi& F = scene.F;
  const PinholeView &a = scene.a, &b = scene.b;
  const cv::Mat &image_a = scene.image_a, &image_b = scene.image_b;
  SimilarityOptions similarity;
  DataTerm summed;
  PairCost(V, F, a, b, image_a, image_b, similarity, &summed);

  MeshGeometry mesh{&V, &F, FaceNormals(V, F)};
  const RenderBuffers ra = RenderCpu(V, F, a), rb = RenderCpu(V, F, b);
  DataTerm one_by_one;
  one_by_one.Reset(static_cast<int>(V.rows()));
  const PairTermOptions options;
  const long valid_ab =
      AccumulatePairTerm(mesh, a, ra, image_a, b, rb, image_b, similarity, options, &one_by_one);
  const long valid_ba =
      AccumulatePairTerm(mesh, b, rb, image_b, a, ra, image_a, similarity, options, &one_by_one);
  ASSERT_GT(valid_ab, 100);
  ASSERT_GT(valid_ba, 100);
  EXPECT_EQ(summed.valid_pixels, valid_ab + valid_ba);
  EXPECT_EQ(one_by_one.valid_pixels, valid_ab + valid_ba);
  EXPECT_NEAR(summed.cost, one_by_one.cost, 1e-9 * std::abs(one_by_one.cost));
  EXPECT_GT(one_by_one.gradient.norm(), 0);
  EXPECT_LT((summed.gradient - one_by_one.gradient).norm(), 1e-9 * one_by_one.gradient.norm());
  EXPECT_LT((summed.curvature - one_by_one.curvature).norm(), 1e-9 * one_by_one.curvature.norm());
  EXPECT_LT((summed.weight - one_by_one.weight).norm(), 1e-9 * one_by_one.weight.norm());
  EXPECT_LT((summed.footprint - one_by_one.footprint).norm(),
            1e-9 * one_by_one.footprint.norm());
  EXPECT_LT((summed.similarity - one_by_one.similarity).norm(),
            1e-9 * one_by_one.similarity.norm());
}

// The per-vertex similarity spreads each valid pixel's m(p) over the
// vertices of its face, as the weight spreads the pixel: over the mesh the
// two sum to sum_p m(p) and to the valid pixels. Where the images agree
// (the same image predicted from itself) every seen vertex's mean is 1; an
// unrelated image brings the means down.
TEST(PairTerm, PerVertexSimilaritySpreadsThePixels) {
  TwoViewScene scene;
  SimilarityOptions similarity;
  similarity.method = "zncc";
  DataTerm term;
  PairCost(scene.V, scene.F, scene.a, scene.b, scene.image_a, scene.image_b, similarity, &term);
  ASSERT_GT(term.valid_pixels, 200);
  EXPECT_NEAR(term.weight.sum(), static_cast<double>(term.valid_pixels), 1e-6 * term.valid_pixels);
  EXPECT_NEAR(term.similarity.sum(), term.zncc_sum, 1e-6 * term.weight.sum());

  // One view, twice: the prediction is the image itself.
  PairCost(scene.V, scene.F, scene.a, scene.a, scene.image_a, scene.image_a, similarity, &term);
  // (Less than 1 by the variance regulariser: m = v / (v + eps) for equal
  // windows of variance v, about 0.97 for these smooth images; a pixel whose
  // window lies mostly outside the valid domain counts with m = 0.)
  std::vector<double> means;
  for (int v = 0; v < scene.V.rows(); ++v) {
    if (term.weight(v) < 1) continue;
    means.push_back(term.similarity(v) / term.weight(v));
    EXPECT_GT(means.back(), 0.9) << v;
  }
  ASSERT_GT(means.size(), 20u);
  std::sort(means.begin(), means.end());
  EXPECT_GT(means[means.size() / 2], 0.95);
  const double agreeing = term.similarity.sum() / term.weight.sum();
  cv::Mat unrelated(32, 40, CV_32F);
  cv::RNG rng(7);
  rng.fill(unrelated, cv::RNG::UNIFORM, 0.1, 0.9);
  PairCost(scene.V, scene.F, scene.a, scene.b, scene.image_a, unrelated, similarity, &term);
  EXPECT_LT(term.similarity.sum() / term.weight.sum(), agreeing - 0.3);
}

// Without the gradient the accumulator adds the same scalars and nothing
// else (the final similarity is measured this way).
TEST(PairTerm, MeasurementAddsTheSameScalars) {
  TwoViewScene scene;
  const Eigen::MatrixXd& V = scene.V;
  const Eigen::MatrixXi& F = scene.F;
  MeshGeometry mesh{&V, &F, FaceNormals(V, F)};
  const RenderBuffers ra = RenderCpu(V, F, scene.a), rb = RenderCpu(V, F, scene.b);
  SimilarityOptions similarity;
  const PairTermOptions options;
  DataTermAccumulator full(static_cast<int>(V.rows())), measured(static_cast<int>(V.rows()));
  const long valid = full.AddPair(mesh, scene.a, ra, scene.image_a, scene.b, rb, scene.image_b,
                                  similarity, options);
  EXPECT_EQ(measured.AddPair(mesh, scene.a, ra, scene.image_a, scene.b, rb, scene.image_b,
                             similarity, options, /*with_gradient=*/false),
            valid);
  ASSERT_GT(valid, 100);
  const DataTerm a = full.Sum(), b = measured.Sum();
  EXPECT_EQ(a.valid_pixels, b.valid_pixels);
  EXPECT_DOUBLE_EQ(a.cost, b.cost);
  EXPECT_DOUBLE_EQ(a.MeanSimilarity(), b.MeanSimilarity());
  EXPECT_GT(a.gradient.norm(), 0);
  EXPECT_EQ(b.gradient.norm(), 0);
  EXPECT_EQ(b.weight.sum(), 0);
}

// A textured plane z = 0 rendered into `view` by averaging 5x5 rays per pixel
// (what a camera's pixel integrates): a coarse and a fine sinusoid, the fine
// one of period 0.19 (3 pixels at distance 4, 6 at distance 2).
cv::Mat PlaneImage(const PinholeView& view) {
  auto texture = [](double x, double y) {
    return 0.5 + 0.2 * std::sin(2 * M_PI * x / 0.75) * std::cos(2 * M_PI * y / 0.9) +
           0.15 * std::sin(2 * M_PI * (x + 0.6 * y) / 0.19);
  };
  const int S = 5;
  cv::Mat image(view.height, view.width, CV_32F);
  for (int r = 0; r < view.height; ++r) {
    for (int c = 0; c < view.width; ++c) {
      double sum = 0;
      for (int i = 0; i < S; ++i) {
        for (int k = 0; k < S; ++k) {
          const Eigen::Vector3d ray = view.RayDirection(c + (k + 0.5) / S, r + (i + 0.5) / S);
          const Eigen::Vector3d x = view.Center() - view.Center().z() / ray.z() * ray;
          sum += texture(x.x(), x.y());
        }
      }
      image.at<float>(r, c) = static_cast<float>(sum / (S * S));
    }
  }
  return image;
}

// Two views of a textured plane, one at twice the other's distance: one
// pixel of the far view covers 2 x 2 of the near one, so point sampling
// compares a sharp image with a blurred one. Matching the resolution raises
// the similarity of both orderings on these exact images.
TEST(PairTerm, ResolutionMatchingComparesAtTheCoarserFootprint) {
  Eigen::MatrixXd V(4, 3);
  V << -3, -3, 0, 3, -3, 0, 3, 3, 0, -3, 3, 0;
  Eigen::MatrixXi F(2, 3);
  F << 0, 1, 2, 0, 2, 3;
  const PinholeView far = LookAtView(Eigen::Vector3d(-0.2, 0, 4), Eigen::Vector3d::Zero(),
                                     Eigen::Vector3d(0, 1, 0), 64, 64, 64);
  const PinholeView near = LookAtView(Eigen::Vector3d(0.2, 0.1, 2), Eigen::Vector3d::Zero(),
                                      Eigen::Vector3d(0, 1, 0), 64, 64, 64);
  const cv::Mat image_far = PlaneImage(far), image_near = PlaneImage(near);
  MeshGeometry mesh{&V, &F, FaceNormals(V, F)};
  const RenderBuffers r_far = RenderCpu(V, F, far), r_near = RenderCpu(V, F, near);
  SimilarityOptions similarity;
  similarity.method = "zncc";
  auto similarity_of = [&](const std::string& interpolation, bool match, bool far_is_i) {
    PairTermOptions options;
    options.interpolation = interpolation;
    options.match_resolution = match;
    DataTermAccumulator accumulator(static_cast<int>(V.rows()));
    if (far_is_i) {
      accumulator.AddPair(mesh, far, r_far, image_far, near, r_near, image_near, similarity,
                          options, false);
    } else {
      accumulator.AddPair(mesh, near, r_near, image_near, far, r_far, image_far, similarity,
                          options, false);
    }
    return accumulator.Sum().MeanSimilarity();
  };
  // Cubic interpolation (the default) adds little blur of its own. (With
  // bilinear interpolation, which does, matching raised the near view's
  // ordering from 0.926 to 0.959 and lowered the far view's from 0.993 to
  // 0.991.)
  for (const bool far_is_i : {true, false}) {
    const double plain = similarity_of("cubic", false, far_is_i);
    const double matched = similarity_of("cubic", true, far_is_i);
    std::printf("far view is i: %d, mean ZNCC %.4f -> %.4f with resolution matching\n", far_is_i,
                plain, matched);
    EXPECT_GT(matched, plain + (far_is_i ? 0.001 : 0.005)) << far_is_i;
  }
}

// The relighting factor of a light at the camera: the ratio of the two
// views' shading, 1 with only ambient light, and 1 where the point faces
// neither camera.
TEST(HeadlightRelighting, RatioOfTheTwoViewsShading) {
  const Eigen::Vector3d n(0, 0, 1), x(0, 0, 0);
  const Eigen::Vector3d head_on(0, 0, 5), oblique(3, 0, 3);  // cosines 1 and 1/sqrt(2)
  const double c = 1 / std::sqrt(2.0);
  EXPECT_NEAR(HeadlightRelighting(0.3, n, x, head_on, oblique), (0.3 + 0.7) / (0.3 + 0.7 * c),
              1e-12);
  EXPECT_NEAR(HeadlightRelighting(0.3, n, x, oblique, head_on), (0.3 + 0.7 * c) / 1.0, 1e-12);
  EXPECT_NEAR(HeadlightRelighting(0.0, n, x, oblique, head_on), c, 1e-12);
  EXPECT_EQ(HeadlightRelighting(1.0, n, x, oblique, head_on), 1.0);
  EXPECT_EQ(HeadlightRelighting(0.0, n, x, head_on, Eigen::Vector3d(0, 0, -5)), 1.0);
  EXPECT_NEAR(HeadlightRelighting(0.2, n, Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(1, 1, 2),
                                  Eigen::Vector3d(1, 1, 7)),
              1.0, 1e-12);  // the same direction from the point
}

// Two views of a bumpy height field lit by a light at each camera (ambient
// share 0.3), rendered exactly: through the true surface, image j relit to
// view i predicts image i several times better than image j as it is.
TEST(PairTerm, HeadlightRelightingPredictsAViewLitFromItsCamera) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  HeightField(&V, &F);
  const Eigen::MatrixXd N = FaceNormals(V, F);
  const PinholeView a = LookAtView(Eigen::Vector3d(-1.4, 0, 3), Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d(0, 1, 0), 40, 32, 40);
  const PinholeView b = LookAtView(Eigen::Vector3d(1.2, 0.6, 3), Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d(0, 1, 0), 40, 32, 40);
  const double ambient = 0.3;
  auto headlit = [&](const PinholeView& view, const RenderBuffers& render) {
    cv::Mat image(view.height, view.width, CV_32F, cv::Scalar(0));
    for (int r = 0; r < view.height; ++r) {
      for (int c = 0; c < view.width; ++c) {
        const int f = render.FaceAt(r, c);
        if (f < 0) continue;
        const Eigen::Vector3d x = view.Center() + render.DepthAt(r, c) * view.RayDirection(c + 0.5, r + 0.5);
        const double albedo = 0.5 + 0.3 * std::sin(3.1 * x.x()) * std::cos(2.3 * x.y());
        const double lit = std::max(0.0, N.row(f).dot((view.Center() - x).normalized()));
        image.at<float>(r, c) = static_cast<float>(albedo * (ambient + (1 - ambient) * lit));
      }
    }
    return image;
  };
  const RenderBuffers ra = RenderCpu(V, F, a), rb = RenderCpu(V, F, b);
  const cv::Mat image_a = headlit(a, ra), image_b = headlit(b, rb);
  MeshGeometry mesh{&V, &F, N};
  auto mean_error = [&](double headlight_ambient) {
    PairTermOptions options;
    options.match_resolution = false;
    options.headlight_ambient = headlight_ambient;
    cv::Mat predicted, mask;
    PredictImage(mesh, a, ra, b, rb, image_b, options, &predicted, &mask);
    double sum = 0;
    int n = 0;
    for (int r = 2; r < a.height - 2; ++r) {
      for (int c = 2; c < a.width - 2; ++c) {
        if (mask.at<uint8_t>(r, c) == 0) continue;
        sum += std::abs(predicted.at<double>(r, c) - image_a.at<float>(r, c));
        ++n;
      }
    }
    EXPECT_GT(n, 300);
    return sum / std::max(1, n);
  };
  const double as_is = mean_error(-1), relit = mean_error(ambient);
  std::printf("mean |prediction - image i|: %.4f as it is, %.4f relit\n", as_is, relit);
  EXPECT_LT(relit, 0.4 * as_is);
  EXPECT_GT(mean_error(0.9), relit);  // the wrong ambient share relights less well
}

}  // namespace
}  // namespace mr
