// Timing of the mr_remesh functions on a ~200k-face mesh (a benchmark, not a
// test). Usage: remesh_benchmark [mesh.obj] (default: the Stanford bunny in
// MR_SHARED_DIR). The OBJ is cleaned, midpoint-subdivided once (x4) and
// decimated to 200k faces; then each operation is timed on that mesh.

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/mesh.h"
#include "geometry/remesh.h"
#include "util/error.h"
#include "util/logging.h"

namespace {

// Minimal OBJ reader: `v x y z` and triangular `f a b c` (a/b/c forms allowed).
void ReadObj(const std::string& path, Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  std::ifstream in(path);
  if (!in) MR_THROW_INPUT << path << ": cannot open";
  std::vector<double> v;
  std::vector<int> f;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      double x, y, z;
      s >> x >> y >> z;
      v.insert(v.end(), {x, y, z});
    } else if (tag == "f") {
      std::string tok;
      std::vector<int> idx;
      while (s >> tok) idx.push_back(std::stoi(tok.substr(0, tok.find('/'))) - 1);
      for (size_t k = 1; k + 1 < idx.size(); ++k) f.insert(f.end(), {idx[0], idx[k], idx[k + 1]});
    }
  }
  *V = Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(v.data(), v.size() / 3, 3);
  *F = Eigen::Map<Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>>(f.data(), f.size() / 3, 3);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string path =
        argc > 1 ? argv[1] : std::string(MR_SHARED_DIR) + "/data/models/stanford-bunny.obj";
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    ReadObj(path, &V, &F);
    MR_LOG(INFO) << path << ": " << V.rows() << " vertices, " << F.rows() << " faces";
    mr::CleanMesh(&V, &F);
    mr::SubdivideMidpoint(&V, &F);
    mr::Decimate(&V, &F, 200000);
    const Eigen::MatrixXd V200 = V;
    const Eigen::MatrixXi F200 = F;
    const double edge = mr::MeanEdgeLength(V, F);

    mr::SetLogLevel(mr::LogLevel::kVerbose);
    mr::CleanMesh(&V, &F);
    mr::SetLogLevel(mr::LogLevel::kInfo);
    MR_LOG(INFO) << "CountSelfIntersections: " << mr::CountSelfIntersections(V, F).BriefReport();

    V = V200, F = F200;
    mr::Decimate(&V, &F, 50000);
    V = V200, F = F200;
    mr::DecimateOptions lt;
    lt.policy = "lindstrom_turk";
    mr::Decimate(&V, &F, 50000, lt);

    V = V200, F = F200;
    mr::IsotropicRemesh(&V, &F, edge);  // same resolution, 3 iterations
    V = V200, F = F200;
    mr::IsotropicRemesh(&V, &F, 2 * edge);  // coarser

    V = V200, F = F200;
    mr::SubdivideSqrt3(&V, &F);
    V = V200, F = F200;
    mr::SubdivideMidpoint(&V, &F);

    // Self-intersection repair: push one vertex through the model.
    for (const bool cgal : {false, true}) {
      V = V200, F = F200;
      const Eigen::RowVector3d c = V.colwise().mean();
      V.row(0) = c + 1.5 * (c - V.row(0));
      mr::RemoveSelfIntersectionsOptions options;
      options.use_cgal_repair = cgal;
      mr::RemoveSelfIntersections(&V, &F, options);
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ERROR: %s\n", e.what());
    return 1;
  }
}
