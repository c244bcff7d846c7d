#include "eval/evaluator.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include "geometry/mesh.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/statistics.h"

namespace mr {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// A point sampled on a mesh and the face it lies on.
struct Sample {
  Eigen::Vector3d point;
  int face;
};

// Uniform double in [0, 1) from 53 random bits (the same on every platform,
// unlike std::uniform_real_distribution).
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  double Uniform() { return static_cast<double>(Next() >> 11) * (1.0 / 9007199254740992.0); }

 private:
  // SplitMix64.
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  uint64_t state_;
};

// The vertex indices of face f in increasing order: what is computed from a
// face in this order does not depend on its winding (or on which vertex is
// listed first), down to the last bit.
Eigen::Vector3i SortedFace(const Eigen::MatrixXi& F, Eigen::Index f) {
  Eigen::Vector3i face = F.row(f).transpose();
  std::sort(face.data(), face.data() + 3);
  return face;
}

// Area-uniform samples on the mesh (faces chosen with probability
// proportional to their area, uniform barycentric position inside). The
// samples do not depend on the faces' winding.
std::vector<Sample> SampleMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                               const Eigen::VectorXd& areas, int num_samples, uint64_t seed) {
  std::vector<double> cumulative(F.rows());
  double total = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    total += areas(f);
    cumulative[f] = total;
  }
  Random random(seed);
  std::vector<Sample> samples(num_samples);
  for (int i = 0; i < num_samples; ++i) {
    const double target = random.Uniform() * total;
    int f = static_cast<int>(std::upper_bound(cumulative.begin(), cumulative.end(), target) -
                             cumulative.begin());
    f = std::min(f, static_cast<int>(F.rows()) - 1);
    while (areas(f) <= 0 && f > 0) --f;  // never a zero-area face
    const double r1 = std::sqrt(random.Uniform());
    const double r2 = random.Uniform();
    const Eigen::Vector3i face = SortedFace(F, f);
    const Eigen::Vector3d a = V.row(face(0)), b = V.row(face(1)), c = V.row(face(2));
    samples[i].point = (1 - r1) * a + r1 * (1 - r2) * b + r1 * r2 * c;
    samples[i].face = f;
  }
  return samples;
}

void CheckMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const char* name,
               Eigen::VectorXd* areas) {
  if (F.rows() == 0) MR_THROW_INPUT << name << " mesh has no faces";
  if (V.cols() != 3 || F.cols() != 3) {
    MR_THROW_INPUT << name << " mesh must be #V by 3 and #F by 3 (got " << V.cols() << " and "
                   << F.cols() << " columns)";
  }
  if (F.minCoeff() < 0 || F.maxCoeff() >= V.rows()) {
    MR_THROW_INPUT << name << " mesh has a face index out of range [0, " << V.rows() << ")";
  }
  if (!V.allFinite()) MR_THROW_INPUT << name << " mesh has non-finite vertex coordinates";
  *areas = FaceAreas(V, F);
  if (!(areas->sum() > 0)) MR_THROW_INPUT << name << " mesh has zero total area";
}

struct Distances {
  std::vector<double> distance;   // per sample
  std::vector<double> angle_deg;  // per sample; NaN where a normal is undefined
  std::vector<int> target_face;   // per sample: the closest target triangle
};

// The angle in degrees between two unit normals as unoriented lines,
// min(theta, 180 - theta) in [0, 90]; NaN where either is undefined (a
// degenerate face's zero normal).
double UnorientedAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  if (a.squaredNorm() < 0.5 || b.squaredNorm() < 0.5) return std::nan("");
  return std::acos(std::min(1.0, std::abs(a.dot(b)))) * 180.0 / M_PI;
}

// Distance from every sample to the target mesh, and the angle between the
// sample's face normal and the normal of the closest target triangle as
// unoriented lines, min(theta, 180 - theta) in [0, 90] degrees: neither
// mesh's face winding (inward or outward, or mixed) changes it.
Distances Query(const std::vector<Sample>& samples, const Eigen::MatrixXd& sample_normals,
                const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  const Eigen::MatrixXd target_normals = FaceNormals(V, F);
  const ClosestPointQuery tree(V, F);
  Distances result;
  const int n = static_cast<int>(samples.size());
  result.distance.resize(n);
  result.angle_deg.resize(n);
  result.target_face.resize(n);
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1024)
#endif
  for (int i = 0; i < n; ++i) {
    int target_face = 0;
    result.distance[i] = tree.Distance(samples[i].point, &target_face);
    result.target_face[i] = target_face;
    result.angle_deg[i] = UnorientedAngleDeg(sample_normals.row(samples[i].face).transpose(),
                                             target_normals.row(target_face).transpose());
  }
  return result;
}

// The rank of the nearest-rank q-quantile of n > 0 values, ceil(q n) - 1,
// which is not QuantileRank's floor(q n) (one higher whenever q n is whole).
size_t NearestRank(size_t n, double q) {
  return std::max<size_t>(1, static_cast<size_t>(std::ceil(q * n))) - 1;
}

double Mean(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += v;
  return values.empty() ? 0 : sum / values.size();
}

}  // namespace

struct ClosestPointQuery::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
};

ClosestPointQuery::ClosestPointQuery(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
    : impl_(new Impl) {
  MR_CHECK(F.rows() > 0) << "ClosestPointQuery on an empty mesh";
  impl_->triangles.reserve(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    // Vertices in index order: the computed distances, and so the closest
    // face where two are equally close (over a shared edge), do not depend on
    // the winding.
    const Eigen::Vector3i face = SortedFace(F, f);
    const auto p = [&](int k) { return Point(V(face(k), 0), V(face(k), 1), V(face(k), 2)); };
    impl_->triangles.emplace_back(p(0), p(1), p(2));
  }
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

ClosestPointQuery::~ClosestPointQuery() = default;

double ClosestPointQuery::Distance(const Eigen::Vector3d& q, int* face) const {
  const auto closest = impl_->tree.closest_point_and_primitive(Point(q.x(), q.y(), q.z()));
  if (face != nullptr) *face = static_cast<int>(closest.second - impl_->triangles.cbegin());
  return (Eigen::Vector3d(closest.first.x(), closest.first.y(), closest.first.z()) - q).norm();
}

SurfaceDisplacement MeasureSurfaceDisplacement(const Eigen::MatrixXd& V,
                                               const Eigen::MatrixXd& V0,
                                               const Eigen::MatrixXi& F0) {
  SurfaceDisplacement d;
  if (V.rows() == 0 || F0.rows() == 0) return d;
  const ClosestPointQuery tree(V0, F0);
  double sum = 0, max = 0;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : sum) reduction(max : max)
#endif
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const double dist = tree.Distance(V.row(v).transpose());
    sum += dist;
    max = std::max(max, dist);
  }
  d.mean = sum / V.rows();
  d.max = max;
  return d;
}

VertexErrors MeasureVertexErrors(const Eigen::MatrixXd& V, const Eigen::MatrixXd& gt_V,
                                 const Eigen::MatrixXi& gt_F,
                                 const std::vector<char>* gt_observed) {
  MR_CHECK(gt_F.rows() > 0) << "ground truth without faces";
  MR_CHECK(gt_observed == nullptr || static_cast<Eigen::Index>(gt_observed->size()) == gt_F.rows())
      << "observed flags: " << gt_observed->size() << " for " << gt_F.rows() << " faces";
  VertexErrors errors;
  errors.distance.resize(V.rows());
  errors.observed.assign(V.rows(), 1);
  errors.closest_face.resize(V.rows());
  const ClosestPointQuery tree(gt_V, gt_F);
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1024)
#endif
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    int face = -1;
    errors.distance(v) = tree.Distance(V.row(v).transpose(), &face);
    errors.closest_face[v] = face;
    if (gt_observed != nullptr) errors.observed[v] = (*gt_observed)[face];
  }
  return errors;
}

Eigen::VectorXd MeasureVertexNormalErrors(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                          const Eigen::MatrixXd& gt_V, const Eigen::MatrixXi& gt_F,
                                          const VertexErrors& errors) {
  MR_CHECK(static_cast<Eigen::Index>(errors.closest_face.size()) == V.rows())
      << errors.closest_face.size() << " closest faces for " << V.rows() << " vertices";
  const Eigen::MatrixXd normals = FaceNormals(V, F);
  const Eigen::MatrixXd gt_normals = FaceNormals(gt_V, gt_F);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(V.rows());
  Eigen::VectorXi count = Eigen::VectorXi::Zero(V.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = F(f, k);
      const double angle = UnorientedAngleDeg(normals.row(f).transpose(),
                                              gt_normals.row(errors.closest_face[v]).transpose());
      if (std::isnan(angle)) continue;
      sum(v) += angle;
      ++count(v);
    }
  }
  Eigen::VectorXd angles(V.rows());
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    angles(v) = count(v) > 0 ? sum(v) / count(v) : std::nan("");
  }
  return angles;
}

Eigen::Matrix<uint8_t, Eigen::Dynamic, 3> ErrorColors(const Eigen::VectorXd& values,
                                                      const std::vector<char>& observed,
                                                      double max_value) {
  MR_CHECK(max_value > 0) << "max_value " << max_value;
  MR_CHECK(static_cast<Eigen::Index>(observed.size()) == values.size())
      << observed.size() << " observed flags for " << values.size() << " values";
  // Five stops of the viridis scale (its values at 0, 1/4, 1/2, 3/4, 1).
  static const double kStops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  Eigen::Matrix<uint8_t, Eigen::Dynamic, 3> colors(values.size(), 3);
  for (Eigen::Index v = 0; v < values.size(); ++v) {
    if (!observed[v] || !std::isfinite(values(v))) {
      colors.row(v).setConstant(128);
      continue;
    }
    const double t = 4 * std::clamp(values(v) / max_value, 0.0, 1.0);
    const int k = std::min(3, static_cast<int>(t));
    const double w = t - k;
    for (int c = 0; c < 3; ++c) {
      colors(v, c) = static_cast<uint8_t>(std::lround((1 - w) * kStops[k][c] + w * kStops[k + 1][c]));
    }
  }
  return colors;
}

bool EvaluationOptions::Check() const {
  if (!(threshold > 0) || !std::isfinite(threshold)) {
    MR_THROW_INPUT << "EvaluationOptions::threshold = " << threshold
                   << ". Violated constraint: threshold > 0";
  }
  if (num_samples < 1) {
    MR_THROW_INPUT << "EvaluationOptions::num_samples = " << num_samples
                   << ". Violated constraint: num_samples >= 1";
  }
  if (seed < 0) {
    MR_THROW_INPUT << "EvaluationOptions::seed = " << seed << ". Violated constraint: seed >= 0";
  }
  return true;
}

std::string EvaluationResult::ToJson() const {
  char text[512];
  std::snprintf(text, sizeof(text),
                "{\"accuracy90\": %.9g, \"completeness\": %.6f, \"chamfer\": %.9g, "
                "\"normal_deg\": %.6f, \"normal_deg_median\": %.6f, \"normal_deg_p90\": %.6f, "
                "\"mean_accuracy\": %.9g, \"faces\": %d",
                accuracy90, completeness, chamfer, normal_deg, normal_deg_median, normal_deg_p90,
                mean_accuracy, faces);
  std::string json = text;
  if (observed_percent >= 0) {
    std::snprintf(text, sizeof(text), ", \"observed_percent\": %.3f", observed_percent);
    json += text;
  }
  return json + "}";
}

EvaluationResult EvaluateMesh(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                              const Eigen::MatrixXd& gt_V, const Eigen::MatrixXi& gt_F,
                              const EvaluationOptions& options,
                              const std::vector<char>* gt_observed) {
  options.Check();
  Eigen::VectorXd areas, gt_areas;
  CheckMesh(V, F, "Evaluated", &areas);
  CheckMesh(gt_V, gt_F, "Ground-truth", &gt_areas);
  if (gt_observed != nullptr) {
    MR_CHECK_EQ(static_cast<long>(gt_observed->size()), static_cast<long>(gt_F.rows()));
  }
  const auto observed = [&](int gt_face) {
    return gt_observed == nullptr || (*gt_observed)[gt_face] != 0;
  };

  const uint64_t seed = static_cast<uint64_t>(options.seed);
  const std::vector<Sample> samples = SampleMesh(V, F, areas, options.num_samples, 2 * seed);
  const std::vector<Sample> gt_samples =
      SampleMesh(gt_V, gt_F, gt_areas, options.num_samples, 2 * seed + 1);

  Distances to_gt = Query(samples, FaceNormals(V, F), gt_V, gt_F);
  Distances to_recon = Query(gt_samples, FaceNormals(gt_V, gt_F), V, F);

  EvaluationResult result;
  result.faces = static_cast<int>(F.rows());
  if (gt_observed != nullptr) {
    // Keep reconstruction samples whose closest ground truth is observed, and
    // ground-truth samples on observed faces.
    Distances kept;
    for (size_t i = 0; i < to_gt.distance.size(); ++i) {
      if (!observed(to_gt.target_face[i])) continue;
      kept.distance.push_back(to_gt.distance[i]);
      kept.angle_deg.push_back(to_gt.angle_deg[i]);
    }
    std::vector<double> kept_recon;
    double observed_area = 0;
    for (int f = 0; f < gt_F.rows(); ++f) observed_area += observed(f) ? gt_areas(f) : 0.0;
    for (size_t i = 0; i < gt_samples.size(); ++i) {
      if (observed(gt_samples[i].face)) kept_recon.push_back(to_recon.distance[i]);
    }
    result.observed_percent = 100.0 * observed_area / gt_areas.sum();
    if (kept.distance.empty() || kept_recon.empty()) {
      MR_THROW_INPUT << "no sample lies on the observed part of the ground truth ("
                     << result.observed_percent << "% of its area is observed)";
    }
    to_gt.distance = std::move(kept.distance);
    to_gt.angle_deg = std::move(kept.angle_deg);
    to_recon.distance = std::move(kept_recon);
  }
  result.mean_accuracy = Mean(to_gt.distance);
  result.chamfer = result.mean_accuracy + Mean(to_recon.distance);

  std::vector<double> distances = to_gt.distance;
  result.accuracy90 = NthSmallest(&distances, NearestRank(distances.size(), 0.9));

  size_t within = 0;
  for (double d : to_recon.distance) within += d <= options.threshold ? 1 : 0;
  result.completeness = 100.0 * within / to_recon.distance.size();

  std::vector<double> angles;
  angles.reserve(to_gt.angle_deg.size());
  for (double a : to_gt.angle_deg) {
    if (std::isfinite(a)) angles.push_back(a);
  }
  if (!angles.empty()) {
    result.normal_deg = Mean(angles);
    result.normal_deg_median = Median(&angles);
    result.normal_deg_p90 = NthSmallest(&angles, NearestRank(angles.size(), 0.9));
  }
  MR_LOG(VERBOSE) << "Evaluated " << F.rows() << " faces against " << gt_F.rows()
                  << " ground-truth faces with " << options.num_samples << " samples each";
  return result;
}

std::vector<char> ObservedFaces(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                                const std::vector<PinholeView>& views, int min_views) {
  MR_CHECK_GE(min_views, 1);
  // A face is seen by a view if its centroid projects into the image in
  // front of the camera and is not hidden: its depth matches the rendered
  // depth at that pixel within two pixel footprints. Testing the centroid (not
  // pixel coverage) counts faces smaller than a pixel too. No back-face test:
  // the renderer draws both sides, so the depth test alone decides, and the
  // result does not depend on the faces' winding (a ground truth wound inward
  // is observed like one wound outward).
  std::vector<int> count(F.rows(), 0);
  Renderer renderer;
  renderer.SetMesh(V, F);
  for (const PinholeView& view : views) {
    const RenderBuffers render = renderer.Render(view);
#pragma omp parallel for schedule(static)
    for (int f = 0; f < static_cast<int>(F.rows()); ++f) {
      const Eigen::Vector3i face = SortedFace(F, f);
      const Eigen::Vector3d x = (V.row(face(0)) + V.row(face(1)) + V.row(face(2))) / 3.0;
      const Eigen::Vector3d xc = view.WorldToCamera(x);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d p = view.CameraToImage(xc);
      if (!view.InImage(p)) continue;
      const int col = static_cast<int>(p.x()), row = static_cast<int>(p.y());
      if (render.FaceAt(row, col) < 0) continue;
      if (std::abs(render.DepthAt(row, col) - xc.z()) > 2.0 * xc.z() / view.fx) continue;
      ++count[f];
    }
  }
  std::vector<char> observed(F.rows());
  for (int f = 0; f < F.rows(); ++f) observed[f] = count[f] >= min_views ? 1 : 0;
  return observed;
}

RegionBox RegionBox::Parse(const std::string& text) {
  std::string numbers = text;
  std::replace(numbers.begin(), numbers.end(), ',', ' ');
  std::istringstream in(numbers);
  RegionBox box;
  if (!(in >> box.lo.x() >> box.lo.y() >> box.lo.z() >> box.hi.x() >> box.hi.y() >> box.hi.z()) ||
      !(in >> std::ws).eof() || !(box.lo.array() < box.hi.array()).all()) {
    MR_THROW_INPUT << "region box \"" << text
                   << "\": expected six numbers \"x0 y0 z0 x1 y1 z1\" with x0 < x1, y0 < y1, "
                      "z0 < z1";
  }
  return box;
}

long KeepFacesInBox(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const RegionBox& box,
                    std::vector<char>* flags) {
  if (flags->empty()) flags->assign(F.rows(), 1);
  MR_CHECK_EQ(static_cast<long>(flags->size()), static_cast<long>(F.rows()));
  long kept = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = FaceCentroid(V, F, f);
    if (!box.Contains(c)) (*flags)[f] = 0;
    kept += (*flags)[f] != 0;
  }
  return kept;
}

}  // namespace mr
