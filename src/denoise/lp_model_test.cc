#include "denoise/lp_model.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "util/error.h"

namespace mr {
namespace {

double GstObjective(double x, double y, double lambda, double p) {
  return 0.5 * (x - y) * (x - y) + lambda * std::pow(std::abs(x), p);
}

TEST(Gst, MatchesBruteForce) {
  for (double p : {0.1, 0.3, 0.5, 0.8, 1.0, 1.2, 1.5, 1.9, 2.0}) {
    for (double lambda : {0.05, 0.4, 1.5}) {
      for (double y = -4.0; y <= 4.0; y += 0.173) {
        const double x = GstShrink(y, lambda, p);
        // Brute force over a fine grid (0 included exactly).
        double best_x = 0, best_f = GstObjective(0, y, lambda, p);
        for (double t = -5.0; t <= 5.0; t += 1e-4) {
          const double f = GstObjective(t, y, lambda, p);
          if (f < best_f) best_f = f, best_x = t;
        }
        const double fx = GstObjective(x, y, lambda, p);
        EXPECT_LE(fx, best_f + 1e-7) << "p=" << p << " lambda=" << lambda << " y=" << y;
        // Away from the threshold the minimiser is unique: compare positions.
        if (std::abs(std::abs(y) - GstThreshold(lambda, p)) > 1e-2) {
          EXPECT_NEAR(x, best_x, 2e-4) << "p=" << p << " lambda=" << lambda << " y=" << y;
        }
      }
    }
  }
}

TEST(Gst, ConvexRangeHasNoThreshold) {
  // For p in (1, 2] the problem is strictly convex: only y = 0 maps to 0, the
  // map is odd and monotone, and p = 2 is the linear shrink y / (1 + 2 lambda).
  for (double p : {1.01, 1.3, 1.7, 2.0}) {
    EXPECT_EQ(GstThreshold(0.7, p), 0.0);
    EXPECT_EQ(GstShrink(0.0, 0.7, p), 0.0);
    double prev = 0;
    for (double y = 1e-6; y < 10; y *= 1.7) {
      const double x = GstShrink(y, 0.7, p);
      EXPECT_GT(x, 0) << "p=" << p << " y=" << y;
      EXPECT_LT(x, y);
      EXPECT_GE(x, prev);
      EXPECT_NEAR(GstShrink(-y, 0.7, p), -x, 1e-15);
      // Against a 400-step bisection of x + lambda p x^(p-1) = y on [0, y]: the
      // same to 1e-12 |y| (absolute: for p near 1 and small y the root can be
      // below the double range, e.g. 1e-590 at p = 1.01, y = 1e-6).
      double lo = 0, hi = y;
      for (int i = 0; i < 400; ++i) {
        const double mid = 0.5 * (lo + hi);
        (mid + 0.7 * p * std::pow(mid, p - 1.0) > y ? hi : lo) = mid;
      }
      EXPECT_NEAR(x, 0.5 * (lo + hi), 1e-12 * y) << "p=" << p << " y=" << y;
      prev = x;
    }
  }
  EXPECT_NEAR(GstShrink(3.0, 0.25, 2.0), 2.0, 1e-15);
}

TEST(Gst, VectorIsRotationInvariant) {
  const Eigen::Vector3d y(0.3, -1.2, 0.7);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (double p : {0.3, 1.0, 1.5}) {
    const Eigen::Vector3d a = R * GstShrinkVector(y, 0.5, p);
    const Eigen::Vector3d b = GstShrinkVector(R * y, 0.5, p);
    EXPECT_LT((a - b).norm(), 1e-12);
    // Equals the 1-D GST of the length, along y.
    EXPECT_NEAR(GstShrinkVector(y, 0.5, p).norm(), GstShrink(y.norm(), 0.5, p), 1e-12);
  }
}

// A triangulated grid of (nx+1) x (ny+1) vertices, x in [-nx/2, nx/2].
void Grid(int nx, int ny, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  V->resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) V->row(j * (nx + 1) + i) << i - nx / 2, j, 0;
  }
  F->resize(2 * nx * ny, 3);
  int f = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 2, d = a + nx + 1;
      if ((i + j) % 2 == 0) {
        F->row(f++) << a, b, c;
        F->row(f++) << a, c, d;
      } else {
        F->row(f++) << a, b, d;
        F->row(f++) << b, c, d;
      }
    }
  }
}

TEST(EdgeOperator, ZeroOnPlanarPatch) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Grid(6, 5, &V, &F);
  // Jitter in the plane, then put the plane in a general position.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int v = 0; v < V.rows(); ++v) V.row(v) += Eigen::RowVector3d(u(rng), u(rng), 0);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  V = (V * R.transpose()).rowwise() + Eigen::RowVector3d(3, -1, 2);
  const EdgeQuads eq = BuildEdgeQuads(F, static_cast<int>(V.rows()));
  EXPECT_GT(eq.quads.rows(), 50);
  EXPECT_EQ(eq.num_boundary, 2 * (6 + 5));
  int degenerate = -1;
  const Eigen::MatrixXd W = EdgeWeights(V, eq.quads, &degenerate);
  EXPECT_EQ(degenerate, 0);
  const Eigen::MatrixXd R2 = ApplyEdgeOperator(eq.quads, W, V);
  EXPECT_LT(R2.cwiseAbs().maxCoeff(), 1e-12);
  // The sparse D agrees with the matrix-free product.
  const Eigen::SparseMatrix<double> D = AssembleEdgeOperator(eq.quads, W, V.rows());
  EXPECT_LT((D * V - R2).cwiseAbs().maxCoeff(), 1e-12);
  // Weights: opposite vertices sum to 1, edge ends to -1.
  for (int i = 0; i < W.rows(); ++i) {
    EXPECT_NEAR(W(i, 2) + W(i, 3), 1.0, 1e-12);
    EXPECT_NEAR(W(i, 0) + W(i, 1), -1.0, 1e-12);
  }
}

TEST(EdgeOperator, NonZeroOnlyOnCrease) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  Grid(6, 5, &V, &F);
  for (int v = 0; v < V.rows(); ++v) V(v, 2) = 0.7 * std::max(V(v, 0), 0.0);  // fold at x = 0
  const EdgeQuads eq = BuildEdgeQuads(F, static_cast<int>(V.rows()));
  const Eigen::MatrixXd W = EdgeWeights(V, eq.quads);
  const Eigen::MatrixXd R = ApplyEdgeOperator(eq.quads, W, V);
  int crease = 0;
  for (int i = 0; i < R.rows(); ++i) {
    const bool on_crease = V(eq.quads(i, 0), 0) == 0 && V(eq.quads(i, 1), 0) == 0;
    if (on_crease) {
      ++crease;
      EXPECT_GT(R.row(i).norm(), 0.1) << "crease row " << i;
    } else {
      EXPECT_LT(R.row(i).norm(), 1e-12) << "row " << i;
    }
  }
  EXPECT_EQ(crease, 5);
}

TEST(EdgeOperator, BoundaryNonManifoldAndDegenerate) {
  // Three triangles on one edge (non-manifold), one collapsed face.
  Eigen::MatrixXi F(4, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4, 2, 2, 3;
  const EdgeQuads eq = BuildEdgeQuads(F, 5);
  EXPECT_EQ(eq.quads.rows(), 0);
  EXPECT_EQ(eq.num_non_manifold, 1);
  Eigen::MatrixXi bad(1, 3);
  bad << 0, 1, 7;
  EXPECT_THROW(BuildEdgeQuads(bad, 3), InputError);
  // Two collinear (zero-area) triangles: a degenerate row with zero weights.
  Eigen::MatrixXd V(4, 3);
  V << 0, 0, 0, 2, 0, 0, 1, 0, 0, 3, 0, 0;
  Eigen::MatrixXi quads(1, 4);
  quads << 0, 1, 2, 3;
  int degenerate = 0;
  const Eigen::MatrixXd W = EdgeWeights(V, quads, &degenerate);
  EXPECT_EQ(degenerate, 1);
  EXPECT_EQ(W.squaredNorm(), 0.0);
}

// Samples m row lengths from the hyper-Laplacian exp(-theta/2 |r|^p):
// u = theta/2 |r|^p is Gamma(1/p, 1).
Eigen::VectorXd SampleRows(int m, double p, double theta, int seed) {
  std::mt19937 rng(seed);
  std::gamma_distribution<double> gamma(1.0 / p, 1.0);
  Eigen::VectorXd r(m);
  for (int i = 0; i < m; ++i) r(i) = std::pow(2.0 * gamma(rng) / theta, 1.0 / p);
  return r;
}

TEST(LpModel, ThetaClosedFormMinimisesNll) {
  const Eigen::VectorXd r = SampleRows(2000, 0.5, 20.0, 1);
  for (double p : {0.2, 0.5, 0.9}) {
    const double theta = ThetaClosedForm(r, p);
    // Numeric minimisation over log theta (golden section).
    double a = std::log(theta) - 3, b = std::log(theta) + 3;
    const double g = (std::sqrt(5.0) - 1) / 2;
    for (int it = 0; it < 200; ++it) {
      const double c = b - g * (b - a), d = a + g * (b - a);
      if (HyperLaplacianNll(r, p, std::exp(c)) < HyperLaplacianNll(r, p, std::exp(d))) {
        b = d;
      } else {
        a = c;
      }
    }
    EXPECT_NEAR(std::exp(0.5 * (a + b)) / theta, 1.0, 1e-6) << "p = " << p;
  }
}

TEST(LpModel, EstimatePRecoversSampledParameters) {
  for (double p_true : {0.3, 0.5, 0.8}) {
    const Eigen::VectorXd r = SampleRows(20000, p_true, 10.0, 2);
    double theta = 0;
    const double p = EstimateP(r, 0.1, 1.0, 0.05, &theta);
    EXPECT_NEAR(p, p_true, 0.051);
    // theta is only comparable at the same p.
    EXPECT_NEAR(ThetaClosedForm(r, p_true) / 10.0, 1.0, 0.05);
  }
}

TEST(LpModel, SigmaClosedFormMinimisesNll) {
  std::mt19937 rng(4);
  std::normal_distribution<double> gauss(0, 0.3);
  Eigen::MatrixXd X0 = Eigen::MatrixXd::Zero(500, 3), X(500, 3);
  for (int i = 0; i < X.rows(); ++i) X.row(i) << gauss(rng), gauss(rng), gauss(rng);
  const double s2 = SigmaSquaredClosedForm(X, X0);
  const double ss = (X - X0).squaredNorm();
  auto nll = [&](double v) { return 0.5 * X.rows() * std::log(v) + ss / (2 * v); };
  double best = 0, best_f = 1e300;
  for (double v = 0.01; v < 1.0; v += 1e-5) {
    if (nll(v) < best_f) best_f = nll(v), best = v;
  }
  EXPECT_NEAR(best, s2, 2e-5);
  EXPECT_NEAR(std::sqrt(s2 / 3), 0.3, 0.03);  // the sampled sigma per coordinate
}

}  // namespace
}  // namespace mr
