#include "denoise/lp_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Geometry>

#include "util/error.h"

namespace mr {

EdgeQuads BuildEdgeQuads(const Eigen::MatrixXi& F, int num_vertices) {
  EdgeQuads out;
  // Half-edges keyed by (min, max) vertex; sorting groups each edge's faces.
  struct HalfEdge {
    int64_t key;
    int opposite;
  };
  std::vector<HalfEdge> half;
  half.reserve(static_cast<size_t>(F.rows()) * 3);
  for (int f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      if (v < 0 || v >= num_vertices) {
        MR_THROW_INPUT << "face " << f << " has vertex index " << v << " (expected 0.."
                       << num_vertices - 1 << ")";
      }
    }
    // A face with a repeated vertex (collapsed) contributes no edge.
    if (F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 2) == F(f, 0)) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
      const int lo = std::min(a, b), hi = std::max(a, b);
      half.push_back({(static_cast<int64_t>(lo) << 32) | static_cast<int64_t>(hi), F(f, k)});
    }
  }
  std::sort(half.begin(), half.end(),
            [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; });
  std::vector<Eigen::Vector4i> rows;
  rows.reserve(half.size() / 2 + 1);
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const size_t count = j - i;
    if (count == 1) {
      ++out.num_boundary;
    } else if (count > 2) {
      ++out.num_non_manifold;
    } else {
      const int lo = static_cast<int>(half[i].key >> 32);
      const int hi = static_cast<int>(half[i].key & 0xffffffff);
      const int o1 = half[i].opposite, o2 = half[i + 1].opposite;
      if (o1 != o2 && o1 != lo && o1 != hi && o2 != lo && o2 != hi) {
        rows.emplace_back(lo, hi, o1, o2);
      } else {
        ++out.num_non_manifold;  // doubled face or folded onto itself
      }
    }
    i = j;
  }
  out.quads.resize(static_cast<int>(rows.size()), 4);
  for (size_t r = 0; r < rows.size(); ++r) out.quads.row(r) = rows[r].transpose();
  return out;
}

Eigen::MatrixXd EdgeWeights(const Eigen::MatrixXd& V, const Eigen::MatrixXi& quads,
                            int* num_degenerate) {
  const int m = static_cast<int>(quads.rows());
  Eigen::MatrixXd W(m, 4);
  int degenerate = 0;
#pragma omp parallel for reduction(+ : degenerate) schedule(static) if (m > 50000)
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector3d x1 = V.row(quads(i, 0)), x3 = V.row(quads(i, 1));
    const Eigen::Vector3d x2 = V.row(quads(i, 2)), x4 = V.row(quads(i, 3));
    const Eigen::Vector3d e = x3 - x1;
    const double l2 = e.squaredNorm();
    const double a123 = e.cross(x2 - x1).norm();  // 2 * area
    const double a134 = e.cross(x4 - x1).norm();
    const double asum = a123 + a134;
    bool ok = l2 > 0 && asum > 1e-12 * l2 && std::isfinite(asum);
    double w2 = 0, w4 = 0, t = 0;
    if (ok) {
      w2 = a134 / asum;
      w4 = a123 / asum;
      const Eigen::Vector3d q = w2 * x2 + w4 * x4;
      t = (q - x1).dot(e) / l2;
      ok = std::isfinite(t) && t > -2.0 && t < 3.0;
    }
    if (ok) {
      W.row(i) << -(1.0 - t), -t, w2, w4;
    } else {
      W.row(i).setZero();
      ++degenerate;
    }
  }
  if (num_degenerate != nullptr) *num_degenerate = degenerate;
  return W;
}

Eigen::SparseMatrix<double> AssembleEdgeOperator(const Eigen::MatrixXi& quads,
                                                 const Eigen::MatrixXd& weights,
                                                 int num_vertices) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<size_t>(quads.rows()) * 4);
  for (int i = 0; i < quads.rows(); ++i) {
    for (int k = 0; k < 4; ++k) triplets.emplace_back(i, quads(i, k), weights(i, k));
  }
  Eigen::SparseMatrix<double> D(quads.rows(), num_vertices);
  D.setFromTriplets(triplets.begin(), triplets.end());
  return D;
}

Eigen::MatrixXd ApplyEdgeOperator(const Eigen::MatrixXi& quads, const Eigen::MatrixXd& weights,
                                  const Eigen::MatrixXd& X) {
  const int m = static_cast<int>(quads.rows());
  Eigen::MatrixXd R(m, 3);
#pragma omp parallel for schedule(static) if (m > 50000)
  for (int i = 0; i < m; ++i) {
    R.row(i) = weights(i, 0) * X.row(quads(i, 0)) + weights(i, 1) * X.row(quads(i, 1)) +
               weights(i, 2) * X.row(quads(i, 2)) + weights(i, 3) * X.row(quads(i, 3));
  }
  return R;
}

double GstThreshold(double lambda, double p) {
  if (lambda <= 0) return 0;
  if (p > 1.0) return 0;  // convex: only y = 0 maps to 0
  if (p == 1.0) return lambda;
  const double a = 2.0 * lambda * (1.0 - p);
  return std::pow(a, 1.0 / (2.0 - p)) + lambda * p * std::pow(a, (p - 1.0) / (2.0 - p));
}

double GstShrink(double y, double lambda, double p) {
  const double ay = std::abs(y);
  if (lambda <= 0) return y;
  if (p == 1.0) return ay <= lambda ? 0.0 : std::copysign(ay - lambda, y);
  if (p > 1.0) {
    // Convex case: the minimiser x in (0, |y|) solves g(x) = x + lambda p
    // x^(p-1) - |y| = 0 (g increasing, no threshold). Safeguarded Newton on
    // the bracket [lo, hi].
    if (p >= 2.0) return y / (1.0 + 2.0 * lambda);
    double lo = 0, hi = ay, x = ay / (1.0 + lambda * p * std::pow(ay, p - 2.0));
    for (int it = 0; it < 100; ++it) {
      const double g = x + lambda * p * std::pow(x, p - 1.0) - ay;
      if (g > 0) hi = x; else lo = x;
      const double dg = 1.0 + lambda * p * (p - 1.0) * std::pow(x, p - 2.0);
      double next = x - g / dg;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::abs(next - x) <= 1e-13 * ay || hi - lo <= 1e-13 * ay) {
        x = next;
        break;
      }
      x = next;
    }
    return std::copysign(x, y);
  }
  if (ay <= GstThreshold(lambda, p)) return 0.0;
  // Fixed point x = |y| - lambda p x^(p-1) from x = |y| (Zuo et al., Alg. 1).
  // It converges monotonically above the threshold; iterate to convergence.
  double x = ay;
  for (int it = 0; it < 50; ++it) {
    const double next = ay - lambda * p * std::pow(x, p - 1.0);
    if (std::abs(next - x) <= 1e-12 * ay) {
      x = next;
      break;
    }
    x = next;
  }
  return std::copysign(std::max(x, 0.0), y);
}

Eigen::Vector3d GstShrinkVector(const Eigen::Vector3d& y, double lambda, double p) {
  const double len = y.norm();
  if (len == 0) return y;
  return y * (GstShrink(len, lambda, p) / len);
}

double HyperLaplacianNll(const Eigen::VectorXd& row_norms, double p, double theta) {
  const double m = static_cast<double>(row_norms.size());
  double sum = 0;
  for (int i = 0; i < row_norms.size(); ++i) sum += std::pow(row_norms(i), p);
  return 0.5 * theta * sum +
         m * (std::lgamma(1.0 / p) - std::log(0.5 * p) - (1.0 / p) * std::log(0.5 * theta));
}

double ThetaClosedForm(const Eigen::VectorXd& row_norms, double p) {
  double sum = 0;
  for (int i = 0; i < row_norms.size(); ++i) sum += std::pow(row_norms(i), p);
  if (sum <= 0) return std::numeric_limits<double>::infinity();
  return 2.0 * static_cast<double>(row_norms.size()) / (p * sum);
}

double SigmaSquaredClosedForm(const Eigen::MatrixXd& X, const Eigen::MatrixXd& X0) {
  if (X.rows() == 0) return 0;
  return (X - X0).squaredNorm() / static_cast<double>(X.rows());
}

double EstimateP(const Eigen::VectorXd& row_norms, double p_min, double p_max, double p_step,
                 double* theta) {
  double best_p = p_max, best_theta = 0, best_nll = std::numeric_limits<double>::infinity();
  const int steps = static_cast<int>(std::floor((p_max - p_min) / p_step + 1e-9));
  for (int s = 0; s <= steps; ++s) {
    const double p = std::min(p_max, p_min + s * p_step);
    const double th = ThetaClosedForm(row_norms, p);
    if (!std::isfinite(th)) continue;
    const double nll = HyperLaplacianNll(row_norms, p, th);
    if (nll < best_nll) {
      best_nll = nll;
      best_p = p;
      best_theta = th;
    }
  }
  if (theta != nullptr) *theta = best_theta;
  return best_p;
}

}  // namespace mr
