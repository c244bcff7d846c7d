#include "refine/step_filter.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include "geometry/mesh.h"
#include "util/error.h"

namespace mr {
namespace {

// RMS over vertices with confidence > 0 of |x_v - mean of its neighbours' x|.
double Jitter(const Eigen::MatrixXd& X, const Eigen::VectorXd& confidence,
              const std::vector<std::vector<int>>& adjacency) {
  double sum = 0;
  long count = 0;
  for (int v = 0; v < X.rows(); ++v) {
    if (!(confidence(v) > 0) || adjacency[v].empty()) continue;
    Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
    for (int j : adjacency[v]) mean += X.row(j);
    mean /= static_cast<double>(adjacency[v].size());
    sum += (X.row(v) - mean).squaredNorm();
    ++count;
  }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

}  // namespace

Eigen::MatrixXd FilterStep(const Eigen::MatrixXd& gradient, const Eigen::VectorXd& confidence,
                           const Eigen::MatrixXi& F, const StepFilterOptions& options,
                           StepFilterSummary* summary) {
  const int n = static_cast<int>(gradient.rows());
  MR_CHECK_EQ(confidence.size(), n);
  MR_CHECK_EQ(gradient.cols(), 3);
  MR_CHECK(options.smoothing > 0 && options.tolerance > 0 && options.max_iterations >= 1);
  StepFilterSummary local;
  StepFilterSummary& s = summary != nullptr ? *summary : local;
  s = StepFilterSummary();
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(n, 3);
  std::vector<double> seen;
  for (int v = 0; v < n; ++v) {
    if (confidence(v) > 0) seen.push_back(confidence(v));
  }
  if (seen.empty()) return X;
  std::nth_element(seen.begin(), seen.begin() + seen.size() / 2, seen.end());
  s.median_confidence = seen[seen.size() / 2];
  const double w = options.smoothing * s.median_confidence;
  s.edge_weight = w;

  const std::vector<std::vector<int>> adjacency = VertexAdjacency(F, n);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<size_t>(n) * 7);
  for (int v = 0; v < n; ++v) {
    const double c = std::max(0.0, confidence(v));
    triplets.emplace_back(v, v, c + w * (adjacency[v].size() + 1e-6));
    for (int j : adjacency[v]) triplets.emplace_back(v, j, -w);
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(options.tolerance);
  cg.setMaxIterations(options.max_iterations);
  cg.compute(A);
  // Start from the unfiltered step where it is defined.
  Eigen::MatrixXd raw = Eigen::MatrixXd::Zero(n, 3);
  for (int v = 0; v < n; ++v) {
    if (confidence(v) > 0) raw.row(v) = -gradient.row(v) / confidence(v);
  }
  for (int k = 0; k < 3; ++k) {
    const Eigen::VectorXd b = -gradient.col(k);
    X.col(k) = cg.solveWithGuess(b, Eigen::VectorXd(raw.col(k)));
    s.cg_iterations += static_cast<int>(cg.iterations());
  }
  s.jitter_before = Jitter(raw, confidence, adjacency);
  s.jitter_after = Jitter(X, confidence, adjacency);
  return X;
}

}  // namespace mr
