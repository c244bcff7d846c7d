#include "init/isosurface.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include <Eigen/Geometry>

#include "geometry/mesh.h"
#include "util/error.h"

namespace mr {

ScalarGrid::ScalarGrid(int nx_, int ny_, int nz_, const Eigen::Vector3d& origin_, double spacing_,
                       float fill)
    : nx(nx_), ny(ny_), nz(nz_), origin(origin_), spacing(spacing_) {
  MR_CHECK(nx >= 0 && ny >= 0 && nz >= 0) << "grid size " << nx << " " << ny << " " << nz;
  values.assign(static_cast<size_t>(nx) * ny * nz, fill);
}

namespace {

// The six tetrahedra of the Freudenthal subdivision, as cube-corner indices
// (bit 0: +x, bit 1: +y, bit 2: +z). Each walks from corner 0 to corner 7
// along the axes in one of the six orders.
constexpr int kTets[6][4] = {
    {0, 1, 3, 7},  // x, y, z
    {0, 1, 5, 7},  // x, z, y
    {0, 2, 3, 7},  // y, x, z
    {0, 2, 6, 7},  // y, z, x
    {0, 4, 5, 7},  // z, x, y
    {0, 4, 6, 7},  // z, y, x
};

class Extractor {
 public:
  Extractor(const ScalarGrid& grid, double iso) : grid_(grid), iso_(iso) {}

  void Run(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
    const int nx = grid_.nx, ny = grid_.ny, nz = grid_.nz;
    if (nx >= 2 && ny >= 2 && nz >= 2) {
      for (int k = 0; k + 1 < nz; ++k) {
        for (int j = 0; j + 1 < ny; ++j) {
          for (int i = 0; i + 1 < nx; ++i) Cube(i, j, k);
        }
      }
    }
    V->resize(static_cast<Eigen::Index>(positions_.size()), 3);
    for (size_t v = 0; v < positions_.size(); ++v) V->row(v) = positions_[v].transpose();
    F->resize(static_cast<Eigen::Index>(faces_.size()), 3);
    for (size_t f = 0; f < faces_.size(); ++f) F->row(f) = faces_[f].transpose();
  }

 private:
  bool Boundary(int i, int j, int k) const {
    return i == 0 || j == 0 || k == 0 || i == grid_.nx - 1 || j == grid_.ny - 1 ||
           k == grid_.nz - 1;
  }

  // Value at a node, with boundary nodes forced outside.
  double Value(int i, int j, int k) const {
    const double v = grid_.At(i, j, k);
    return Boundary(i, j, k) ? std::min(v, iso_) : v;
  }

  void Cube(int i, int j, int k) {
    size_t node[8];
    double val[8];
    Eigen::Vector3d pos[8];
    int num_inside = 0;
    for (int c = 0; c < 8; ++c) {
      const int ci = i + (c & 1), cj = j + ((c >> 1) & 1), ck = k + ((c >> 2) & 1);
      node[c] = grid_.Index(ci, cj, ck);
      val[c] = Value(ci, cj, ck);
      num_inside += val[c] > iso_;
    }
    if (num_inside == 0 || num_inside == 8) return;
    for (int c = 0; c < 8; ++c) {
      pos[c] = grid_.Position(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
    }
    for (const auto& tet : kTets) {
      int in[4], out[4];
      int ni = 0, no = 0;
      for (int c : tet) {
        if (val[c] > iso_) {
          in[ni++] = c;
        } else {
          out[no++] = c;
        }
      }
      if (ni == 0 || no == 0) continue;
      // Direction from the inside corners to the outside corners.
      Eigen::Vector3d cin = Eigen::Vector3d::Zero(), cout = Eigen::Vector3d::Zero();
      for (int a = 0; a < ni; ++a) cin += pos[in[a]] / ni;
      for (int a = 0; a < no; ++a) cout += pos[out[a]] / no;
      const Eigen::Vector3d outward = cout - cin;
      // Polygon on the crossed edges (3 or 4 corners), as (inside, outside)
      // corner pairs in cyclic order.
      std::vector<std::pair<int, int>> poly;
      if (ni == 1) {
        poly = {{in[0], out[0]}, {in[0], out[1]}, {in[0], out[2]}};
      } else if (no == 1) {
        poly = {{in[0], out[0]}, {in[1], out[0]}, {in[2], out[0]}};
      } else {
        poly = {{in[0], out[0]}, {in[0], out[1]}, {in[1], out[1]}, {in[1], out[0]}};
      }
      // Orientation from the edge midpoints (never degenerate), so it does
      // not depend on where the crossings are interpolated.
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      const size_t m = poly.size();
      for (size_t a = 0; a < m; ++a) {
        const auto& p = poly[a];
        const auto& q = poly[(a + 1) % m];
        const Eigen::Vector3d mp = 0.5 * (pos[p.first] + pos[p.second]);
        const Eigen::Vector3d mq = 0.5 * (pos[q.first] + pos[q.second]);
        normal += mp.cross(mq);  // Newell's method
      }
      if (normal.dot(outward) < 0) std::reverse(poly.begin(), poly.end());
      int ids[4];
      for (size_t a = 0; a < m; ++a) {
        ids[a] = Vertex(node[poly[a].first], node[poly[a].second], pos[poly[a].first],
                        pos[poly[a].second], val[poly[a].first], val[poly[a].second]);
      }
      faces_.emplace_back(ids[0], ids[1], ids[2]);
      if (m == 4) faces_.emplace_back(ids[0], ids[2], ids[3]);
    }
  }

  int Vertex(size_t a, size_t b, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb,
             double va, double vb) {
    const uint64_t key = static_cast<uint64_t>(std::min(a, b)) * grid_.NumNodes() + std::max(a, b);
    const auto it = index_.find(key);
    if (it != index_.end()) return it->second;
    double t = (va - iso_) / (va - vb);
    t = std::clamp(t, 1e-3, 1 - 1e-3);
    positions_.push_back(pa + t * (pb - pa));
    const int id = static_cast<int>(positions_.size()) - 1;
    index_.emplace(key, id);
    return id;
  }

  const ScalarGrid& grid_;
  const double iso_;
  std::unordered_map<uint64_t, int> index_;
  std::vector<Eigen::Vector3d> positions_;
  std::vector<Eigen::Vector3i> faces_;
};

int Find(std::vector<int>& parent, int x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

void ExtractIsosurface(const ScalarGrid& grid, double iso, Eigen::MatrixXd* V,
                       Eigen::MatrixXi* F) {
  MR_CHECK_EQ(grid.values.size(), static_cast<size_t>(grid.nx) * grid.ny * grid.nz);
  Extractor(grid, iso).Run(V, F);
}

int KeepLargestComponent(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
  const int nv = static_cast<int>(V->rows());
  if (F->rows() == 0) return 0;
  std::vector<int> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  for (Eigen::Index f = 0; f < F->rows(); ++f) {
    for (int c = 1; c < 3; ++c) {
      const int a = Find(parent, (*F)(f, 0)), b = Find(parent, (*F)(f, c));
      if (a != b) parent[a] = b;
    }
  }
  std::vector<int> count(nv, 0);
  for (Eigen::Index f = 0; f < F->rows(); ++f) ++count[Find(parent, (*F)(f, 0))];
  int num_components = 0;
  for (int v = 0; v < nv; ++v) num_components += count[v] > 0;
  const int best = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  Eigen::MatrixXi kept(count[best], 3);
  int n = 0;
  for (Eigen::Index f = 0; f < F->rows(); ++f) {
    if (Find(parent, (*F)(f, 0)) == best) kept.row(n++) = F->row(f);
  }
  *F = kept;
  RemoveUnreferencedVertices(V, F);
  return num_components;
}

bool IsClosedAndOriented(const Eigen::MatrixXi& F, std::string* why) {
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(static_cast<size_t>(F.rows()) * 3);
  auto key = [](int a, int b) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
  };
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    for (int c = 0; c < 3; ++c) ++directed[key(F(f, c), F(f, (c + 1) % 3))];
  }
  for (const auto& [k, n] : directed) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    const auto rev = directed.find(key(b, a));
    const int nrev = rev == directed.end() ? 0 : rev->second;
    if (n != 1 || nrev != 1) {
      if (why != nullptr) {
        std::ostringstream s;
        s << "directed edge (" << a << ", " << b << ") appears " << n << " times, its reverse "
          << nrev << " times";
        *why = s.str();
      }
      return false;
    }
  }
  return true;
}

double SignedVolume(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  double vol = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    vol += a.dot(b.cross(c));
  }
  return vol / 6.0;
}

}  // namespace mr
