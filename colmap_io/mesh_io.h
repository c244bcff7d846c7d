#pragma once

// Mesh files by extension: .ply (see colmap_io/ply.h) and Wavefront .obj.
//
// OBJ reading: `v x y z [w]` vertices (a trailing `r g b` in [0, 1] is read as
// vertex colours when every vertex has it), `f` faces in the v, v/vt, v//vn
// and v/vt/vn forms with 1-based or negative (relative) indices, polygons
// fan-triangulated; `vt`, `vn`, groups, materials, lines and comments are
// ignored. Bad numbers, out-of-range indices and faces with fewer than three
// corners throw mr::InputError naming the file and the line.

#include <string>

#include "colmap_io/ply.h"

namespace mr {

// Reads a .ply or .obj mesh (extension is case-insensitive).
TriangleMesh ReadMesh(const std::string& path);

// Writes a .ply (binary little-endian) or .obj mesh atomically. OBJ output
// holds positions, faces, per-vertex normals (`vn`, faces as v//vn) when
// mesh.N is non-empty, and vertex colours (`v x y z r g b`, r g b in [0, 1])
// when mesh.C is non-empty.
void WriteMesh(const std::string& path, const TriangleMesh& mesh);

TriangleMesh ReadObj(const std::string& path);
// ReadObj from the file's bytes `data`; `path` only names them in errors.
TriangleMesh ReadObjData(const std::string& path, const std::string& data);
void WriteObj(const std::string& path, const TriangleMesh& mesh);

}  // namespace mr
