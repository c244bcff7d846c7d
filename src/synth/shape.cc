#include "synth/shape.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "util/error.h"

namespace mr {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSphereRadius = 32.0;  // scene units; the diagonal ends near 100

double SmoothStep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Relief height (scene units, roughly in [-1, 1] * amplitude) at a point p of
// the undisplaced sphere. A solid function of p, so there is no seam.
double Relief(const Eigen::Vector3d& p, double amplitude) {
  const double k1 = 2 * kPi / 8.0;   // egg-crate bumps, wavelength 8
  const double k2 = 2 * kPi / 6.0;   // finer ripples, wavelength 6
  const double k3 = 2 * kPi / 9.0;   // groove spacing 9
  const Eigen::Vector3d a1 = Eigen::Vector3d(1, 0.3, 0.2).normalized();
  const Eigen::Vector3d a2 = Eigen::Vector3d(-0.2, 1, 0.4).normalized();
  const Eigen::Vector3d a3 = Eigen::Vector3d(0.3, -0.5, 1).normalized();
  const Eigen::Vector3d a4 = Eigen::Vector3d(0.7, 0.7, -0.1).normalized();
  const double bumps = std::sin(k1 * p.dot(a1)) * std::sin(k1 * p.dot(a2));
  const double ripples = std::sin(k2 * p.dot(a3) + 0.8 * std::sin(k1 * p.dot(a1)));
  // Narrow grooves: a dip of width ~1/4 of the spacing.
  const double s = std::abs(std::sin(0.5 * k3 * p.dot(a4)));
  const double groove = -std::pow(1.0 - s, 4.0);
  return amplitude * (0.55 * bumps + 0.25 * ripples + 0.9 * groove);
}

// A ring of vertices around the local z axis: `n` vertex indices at angles
// 2 pi (k + offset) / n.
struct Ring {
  std::vector<int> ids;
  double offset = 0;
  double Angle(int k) const { return 2 * kPi * (k + offset) / static_cast<double>(ids.size()); }
};

// Triangulates the band between two rings. Orientation: the triangles are
// (a_i, b_j, b_j+1) and (a_i, b_j, a_i+1), outward when ring `a` is "above"
// ring `b` as seen from outside with angles increasing to the right.
void StitchRings(const Ring& a, const Ring& b, std::vector<Eigen::Vector3i>* faces) {
  const int na = static_cast<int>(a.ids.size());
  const int nb = static_cast<int>(b.ids.size());
  int i = 0, j = 0;
  while (i < na || j < nb) {
    const bool advance_b = j < nb && (i == na || b.Angle(j + 1) < a.Angle(i + 1));
    const int ai = a.ids[i % na], bj = b.ids[j % nb];
    Eigen::Vector3i f;
    if (advance_b) {
      f = Eigen::Vector3i(ai, bj, b.ids[(j + 1) % nb]);
      ++j;
    } else {
      f = Eigen::Vector3i(ai, bj, a.ids[(i + 1) % na]);
      ++i;
    }
    if (f(0) != f(1) && f(1) != f(2) && f(0) != f(2)) faces->push_back(f);
  }
}

int RingCount(double radius, double edge) {
  return std::max(3, static_cast<int>(std::lround(2 * kPi * radius / edge)));
}

}  // namespace

bool BuiltinShapeOptions::Check() const {
  if (!(edge_length > 0 && edge_length <= 10)) {
    MR_THROW_INPUT << "BuiltinShapeOptions::edge_length = " << edge_length
                   << ". Violated constraint: 0 < edge_length <= 10";
  }
  if (!(relief_amplitude >= 0 && relief_amplitude <= 5)) {
    MR_THROW_INPUT << "BuiltinShapeOptions::relief_amplitude = " << relief_amplitude
                   << ". Violated constraint: 0 <= relief_amplitude <= 5";
  }
  if (!(cut_angle_deg >= 20 && cut_angle_deg <= 90)) {
    MR_THROW_INPUT << "BuiltinShapeOptions::cut_angle_deg = " << cut_angle_deg
                   << ". Violated constraint: 20 <= cut_angle_deg <= 90";
  }
  if (!(tilt_deg >= 0 && tilt_deg <= 90)) {
    MR_THROW_INPUT << "BuiltinShapeOptions::tilt_deg = " << tilt_deg
                   << ". Violated constraint: 0 <= tilt_deg <= 90";
  }
  return true;
}

TriangleMesh MakeBuiltinShape(const BuiltinShapeOptions& options) {
  options.Check();
  const double R = kSphereRadius;
  const double e = options.edge_length;
  const double theta_c = options.cut_angle_deg * kPi / 180;
  const double fade = 3.0;  // relief fades to 0 over this distance from the crease

  std::vector<Eigen::Vector3d> verts;
  std::vector<Eigen::Vector3i> faces;
  auto add_ring = [&](double radius, double z_or_theta, bool on_sphere, double offset,
                      int count) {
    Ring ring;
    ring.offset = offset;
    for (int k = 0; k < count; ++k) {
      const double phi = 2 * kPi * (k + offset) / count;
      Eigen::Vector3d p;
      if (on_sphere) {
        const double th = z_or_theta;
        const Eigen::Vector3d u(std::sin(th) * std::cos(phi), std::sin(th) * std::sin(phi),
                                std::cos(th));
        const double taper = SmoothStep(0, fade, R * (th - theta_c));
        p = (R + (taper > 0 ? taper * Relief(R * u, options.relief_amplitude) : 0.0)) * u;
      } else {
        p = Eigen::Vector3d(radius * std::cos(phi), radius * std::sin(phi), z_or_theta);
      }
      ring.ids.push_back(static_cast<int>(verts.size()));
      verts.push_back(p);
    }
    return ring;
  };

  // Curved body: rings from the crease (theta_c) down to the pole (pi).
  const double ring_step = 0.866 * e;
  const int n_curved = std::max(2, static_cast<int>(std::ceil(R * (kPi - theta_c) / ring_step)));
  std::vector<Ring> curved;
  for (int i = 0; i <= n_curved; ++i) {
    const double th = theta_c + (kPi - theta_c) * i / n_curved;
    const int count = (i == n_curved) ? 1 : RingCount(R * std::sin(th), e);
    // The crease ring has offset 0 so the cap shares it exactly.
    curved.push_back(add_ring(0, th, true, 0.5 * (i % 2), count));
  }
  for (int i = 0; i < n_curved; ++i) StitchRings(curved[i], curved[i + 1], &faces);

  // Flat cap: concentric rings from the crease to the centre, in the plane
  // z = R cos(theta_c). The crease ring (curved[0]) is shared.
  const double rc = R * std::sin(theta_c);
  const double zc = R * std::cos(theta_c);
  const int n_cap = std::max(1, static_cast<int>(std::ceil(rc / ring_step)));
  std::vector<Ring> cap = {curved[0]};
  for (int j = 1; j <= n_cap; ++j) {
    const double r = rc * (1.0 - static_cast<double>(j) / n_cap);
    const int count = (j == n_cap) ? 1 : RingCount(r, e);
    cap.push_back(add_ring(r, zc, false, 0.5 * (j % 2), count));
  }
  // Inner ring first: seen from outside (+z) this orientation is outward.
  for (int j = 0; j < n_cap; ++j) StitchRings(cap[j + 1], cap[j], &faces);

  const Eigen::Matrix3d tilt =
      Eigen::AngleAxisd(options.tilt_deg * kPi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  TriangleMesh mesh;
  mesh.V.resize(static_cast<Eigen::Index>(verts.size()), 3);
  for (size_t v = 0; v < verts.size(); ++v) mesh.V.row(v) = (tilt * verts[v]).transpose();
  mesh.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) mesh.F.row(f) = faces[f].transpose();
  return mesh;
}

double NormalizeMesh(double diagonal, Eigen::MatrixXd* V) {
  MR_CHECK(V != nullptr);
  if (V->rows() == 0) MR_THROW_INPUT << "ground-truth mesh has no vertices";
  const Eigen::RowVector3d lo = V->colwise().minCoeff();
  const Eigen::RowVector3d hi = V->colwise().maxCoeff();
  const double d = (hi - lo).norm();
  if (!(d > 0) || !std::isfinite(d)) {
    MR_THROW_INPUT << "ground-truth mesh has a degenerate bounding box (diagonal " << d
                   << ", expected > 0)";
  }
  const Eigen::RowVector3d centre = 0.5 * (lo + hi);
  const double scale = diagonal / d;
  *V = ((V->rowwise() - centre) * scale).eval();
  return scale;
}

double MaxDihedralAngleDeg(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const Eigen::MatrixXd N = FaceNormals(V, F);
  const EdgeTopology topo = ComputeEdgeTopology(F, static_cast<int>(V.rows()));
  double best = 0;
  for (const IndexLists::List faces : topo.edge_faces) {
    if (faces.size() != 2) continue;
    const double c = std::clamp(N.row(faces[0]).dot(N.row(faces[1])), -1.0, 1.0);
    best = std::max(best, std::acos(c) * 180 / kPi);
  }
  return best;
}

}  // namespace mr
