#pragma once

// PLY triangle meshes: binary little/big-endian and ASCII.
//
// Reads the properties COLMAP writes (vertex x y z, optional nx ny nz, value,
// red green blue; faces as `vertex_indices` or `vertex_index` with uchar/int
// counts) and skips any other property or element. Polygons with more than
// three corners are fan-triangulated. Every field is checked: truncated data,
// a wrong magic, NaN/Inf coordinates or an out-of-range index throw
// mr::InputError naming the file and what was wrong.

#include <cstdint>
#include <string>

#include <Eigen/Core>

namespace mr {

// A triangle mesh with optional per-vertex attributes (libigl-style shapes).
struct TriangleMesh {
  Eigen::MatrixXd V;  // #V by 3 positions
  Eigen::MatrixXi F;  // #F by 3 vertex indices (counter-clockwise = outward)
  Eigen::MatrixXd N;  // #V by 3 normals, or empty
  Eigen::Matrix<uint8_t, Eigen::Dynamic, 3> C;  // #V by 3 RGB colours, or empty
  Eigen::VectorXd values;                        // #V per-vertex `value` (Poisson density), or empty

  int NumVertices() const { return static_cast<int>(V.rows()); }
  int NumFaces() const { return static_cast<int>(F.rows()); }
};

enum class PlyFormat { kBinaryLittleEndian, kBinaryBigEndian, kAscii };

// Reads a mesh (a point cloud reads as a mesh with no faces).
TriangleMesh ReadPly(const std::string& path);
// The same from the file's bytes `data`; `path` only names them in errors
// (in-memory data, the fuzz harnesses).
TriangleMesh ReadPlyData(const std::string& path, const std::string& data);

// Writes `mesh` atomically (temporary file in the same folder, then rename).
// N, C and values are written when non-empty. Faces are written as
// `list uchar int vertex_indices`, like COLMAP; positions, normals and values
// as float (again like COLMAP), so a round trip rounds them to float.
void WritePly(const std::string& path, const TriangleMesh& mesh,
              PlyFormat format = PlyFormat::kBinaryLittleEndian);

}  // namespace mr
