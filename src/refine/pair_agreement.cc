// pair_agreement: how well a mesh explains a COLMAP workspace's images, pair
// by pair. For each ordered pair (i, j) it predicts image i from image j
// through the mesh (PredictImage: the pair term's warp, without resolution
// matching) and reports, over the predicted pixels at least 3 px inside the
// valid domain:
//   - the standard deviation of the difference, in grey levels of 255;
//   - the local displacement: in each 15 x 15 block (90 % of it inside), the
//     least-squares fit difference = c + u dI/dx + v dI/dy, and the median and
//     90th percentile of |(u, v)| in pixels over the blocks;
//   - the mean ZNCC (Gaussian window, --Similarity.sigma) with the
//     similarity's variance floor epsilon and with 1e-6, which tells
//     disagreement of the images from the floor's effect on weak texture.
// A development tool (docs/results.md, "What the images say at the truth"),
// not a test.
//
//   build/bin/pair_agreement --workspace_path WS --input_path mesh.ply
//       [--pairs "0:1 1:0"] [--Refine.interpolation cubic]

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/imgproc.hpp>

#include "colmap_io/ply.h"
#include "colmap_io/workspace.h"
#include "geometry/mesh.h"
#include "refine/photometric.h"
#include "refine/similarity.h"
#include "refine/view_source.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/options.h"
#include "util/program.h"
#include "util/statistics.h"

namespace {

using namespace mr;

double MeanZncc(const cv::Mat& observed, const cv::Mat& predicted, const cv::Mat& mask,
                double sigma, double epsilon) {
  SimilarityOptions options;
  options.method = "zncc";
  options.sigma = sigma;
  options.epsilon = epsilon;
  options.double_precision = true;
  const SimilarityResult result = ComputeSimilarity(observed, predicted, mask, options, false);
  return result.weight_sum > 0 ? result.zncc_sum / result.weight_sum : 0.0;
}

struct PairReport {
  long pixels = 0;
  double difference_std = 0;      // grey levels
  double displacement_median = 0;  // px
  double displacement_p90 = 0;     // px
  int blocks = 0;
  double zncc = 0, zncc_tight = 0;
};

PairReport Measure(const cv::Mat& image_i, const cv::Mat& predicted, const cv::Mat& mask,
                   double sigma, double epsilon) {
  constexpr int kBlock = 15;
  PairReport report;
  cv::Mat interior;
  cv::erode(mask, interior, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(7, 7)));
  cv::Mat observed, difference, gx, gy;
  image_i.convertTo(observed, CV_64F, 255.0);
  predicted.convertTo(difference, CV_64F, 255.0);
  difference -= observed;
  // Sobel / 8: the central difference smoothed across, in grey levels per px.
  cv::Sobel(observed, gx, CV_64F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(observed, gy, CV_64F, 0, 1, 3, 1.0 / 8);
  report.pixels = cv::countNonZero(interior);
  if (report.pixels > 1) {
    cv::Scalar mean, deviation;
    cv::meanStdDev(difference, mean, deviation, interior);
    report.difference_std = deviation[0];
  }
  std::vector<double> displacements;
  for (int y = 0; y + kBlock <= interior.rows; y += kBlock) {
    for (int x = 0; x + kBlock <= interior.cols; x += kBlock) {
      Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      int inside = 0;
      for (int r = y; r < y + kBlock; ++r) {
        for (int c = x; c < x + kBlock; ++c) {
          if (!interior.at<uint8_t>(r, c)) continue;
          const Eigen::Vector3d row(1.0, gx.at<double>(r, c), gy.at<double>(r, c));
          normal += row * row.transpose();
          rhs += row * difference.at<double>(r, c);
          ++inside;
        }
      }
      if (inside < 0.9 * kBlock * kBlock) continue;
      const Eigen::Vector3d fit = normal.ldlt().solve(rhs);
      if (!fit.allFinite()) continue;
      displacements.push_back(std::hypot(fit(1), fit(2)));
    }
  }
  report.blocks = static_cast<int>(displacements.size());
  // Quantile reorders `displacements`, which cannot change the second result:
  // they are finite and non-negative (hypot never gives -0), so values that
  // compare equal are bitwise equal.
  report.displacement_median = displacements.empty() ? 0 : Quantile(&displacements, 0.5);
  report.displacement_p90 = displacements.empty() ? 0 : Quantile(&displacements, 0.9);
  // The ZNCC on the images' own [0, 1] scale, which epsilon refers to.
  cv::Mat observed_unit, predicted_unit;
  image_i.convertTo(observed_unit, CV_64F);
  predicted.convertTo(predicted_unit, CV_64F);
  report.zncc = MeanZncc(observed_unit, predicted_unit, interior, sigma, epsilon);
  report.zncc_tight = MeanZncc(observed_unit, predicted_unit, interior, sigma, 1e-6);
  return report;
}

}  // namespace

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    std::string workspace_path, input_path, pairs_text = "0:1 1:0", interpolation = "cubic";
    SimilarityOptions similarity;
    OptionManager options("pair_agreement",
                          "how well a mesh explains the images of a COLMAP workspace, pair by pair");
    options.AddRequired("workspace_path", &workspace_path, "COLMAP dense workspace");
    options.AddRequired("input_path", &input_path, "mesh (PLY) in the workspace's frame");
    options.Add("pairs", &pairs_text, "ordered pairs \"i:j ...\" (image i predicted from j; "
                                      "indices in the workspace's image order)");
    options.Add("Refine.interpolation", &interpolation, "cubic or bilinear");
    options.Add("Similarity.sigma", &similarity.sigma, "ZNCC window, px");
    options.Add("Similarity.epsilon", &similarity.epsilon, "ZNCC variance floor");
    if (!options.Parse(argc, argv)) return 0;

    const Workspace workspace = OpenWorkspace(workspace_path);
    const WorkspaceViewSource source(workspace);
    const TriangleMesh mesh = ReadPly(input_path);
    std::vector<std::pair<int, int>> pairs;
    std::istringstream stream(pairs_text);
    for (std::string token; stream >> token;) {
      int i = -1, j = -1;
      char colon = 0;
      std::istringstream pair(token);
      if (!(pair >> i >> colon >> j) || colon != ':' || i < 0 || j < 0 ||
          i >= source.NumViews() || j >= source.NumViews() || i == j) {
        MR_THROW_INPUT << "--pairs: \"" << token << "\" is not i:j with two different views in [0, "
                       << source.NumViews() << ")";
      }
      pairs.emplace_back(i, j);
    }
    PairTermOptions pair_options;
    pair_options.interpolation = interpolation;
    pair_options.match_resolution = false;
    pair_options.Check();
    similarity.Check();

    Renderer renderer;
    renderer.SetMesh(mesh.V, mesh.F);
    MeshGeometry geometry{&mesh.V, &mesh.F, FaceNormals(mesh.V, mesh.F)};
    std::printf("pair  pixels  difference_std_grey  displacement_px(median/p90, blocks)  "
                "zncc(eps %g / 1e-6)\n", similarity.epsilon);
    for (const auto& [i, j] : pairs) {
      const RenderBuffers render_i = renderer.Render(source.View(i));
      const RenderBuffers render_j = renderer.Render(source.View(j));
      const cv::Mat image_i = source.LoadGray(i);
      cv::Mat predicted, mask;
      PredictImage(geometry, source.View(i), render_i, source.View(j), render_j,
                   source.LoadGray(j), pair_options, &predicted, &mask);
      const PairReport r = Measure(image_i, predicted, mask, similarity.sigma, similarity.epsilon);
      std::printf("%s <- %s  %ld  %.3f  %.4f/%.4f (%d)  %.4f/%.4f\n", source.Name(i).c_str(),
                  source.Name(j).c_str(), r.pixels, r.difference_std, r.displacement_median,
                  r.displacement_p90, r.blocks, r.zncc, r.zncc_tight);
    }
    return 0;
  });
}
