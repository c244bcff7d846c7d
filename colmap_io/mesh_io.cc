#include "colmap_io/mesh_io.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ostream>
#include <vector>

#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Splits [begin, end) into whitespace-separated tokens.
void Tokenize(const char* begin, const char* end, std::vector<std::pair<const char*, const char*>>* tokens) {
  tokens->clear();
  const char* p = begin;
  while (p < end) {
    while (p < end && IsBlank(*p)) ++p;
    if (p == end) break;
    const char* q = p;
    while (q < end && !IsBlank(*q)) ++q;
    tokens->emplace_back(p, q);
    p = q;
  }
}

bool TokenIs(const std::pair<const char*, const char*>& token, const char* word) {
  const size_t n = std::strlen(word);
  return static_cast<size_t>(token.second - token.first) == n &&
         std::memcmp(token.first, word, n) == 0;
}

}  // namespace

TriangleMesh ReadObj(const std::string& path) { return ReadObjData(path, ReadFileToString(path)); }

TriangleMesh ReadObjData(const std::string& path, const std::string& data) {
  std::vector<double> positions;
  std::vector<double> colors;
  std::vector<int> triangles;
  std::vector<std::pair<const char*, const char*>> tokens;
  std::vector<int> corners;
  std::string text;
  int64_t line_number = 0;
  bool all_colored = true;
  const char* p = data.data();
  const char* end = p + data.size();
  while (p < end) {
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', end - p));
    if (eol == nullptr) eol = end;
    ++line_number;
    const char* line_end = eol;
    const char* hash = static_cast<const char*>(std::memchr(p, '#', line_end - p));
    if (hash != nullptr) line_end = hash;
    Tokenize(p, line_end, &tokens);
    p = eol + 1;
    if (tokens.empty()) continue;
    if (TokenIs(tokens[0], "v")) {
      if (tokens.size() < 4) {
        MR_THROW_INPUT << path << ":" << line_number << ": vertex with " << tokens.size() - 1
                       << " coordinates (expected at least 3)";
      }
      double values[6];
      const size_t n = std::min<size_t>(tokens.size() - 1, 6);
      for (size_t k = 0; k < n; ++k) {
        text.assign(tokens[k + 1].first, tokens[k + 1].second);
        char* parse_end = nullptr;
        values[k] = std::strtod(text.c_str(), &parse_end);
        if (*parse_end != '\0') {
          MR_THROW_INPUT << path << ":" << line_number << ": invalid number '" << text
                         << "' in vertex";
        }
      }
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(values[k])) {
          MR_THROW_INPUT << path << ":" << line_number << ": non-finite vertex coordinate "
                         << values[k];
        }
        positions.push_back(values[k]);
      }
      if (n >= 6) {
        for (int k = 3; k < 6; ++k) colors.push_back(values[k]);
      } else {
        all_colored = false;
      }
    } else if (TokenIs(tokens[0], "f")) {
      const int64_t num_vertices = static_cast<int64_t>(positions.size() / 3);
      corners.clear();
      for (size_t k = 1; k < tokens.size(); ++k) {
        // Only the position index (before the first '/') is used.
        const char* slash =
            static_cast<const char*>(std::memchr(tokens[k].first, '/', tokens[k].second - tokens[k].first));
        text.assign(tokens[k].first, slash != nullptr ? slash : tokens[k].second);
        char* parse_end = nullptr;
        const long long index = std::strtoll(text.c_str(), &parse_end, 10);
        if (text.empty() || *parse_end != '\0') {
          MR_THROW_INPUT << path << ":" << line_number << ": invalid face corner '"
                         << std::string(tokens[k].first, tokens[k].second) << "'";
        }
        const long long resolved = index > 0 ? index - 1 : num_vertices + index;
        if (index == 0 || resolved < 0 || resolved >= num_vertices) {
          MR_THROW_INPUT << path << ":" << line_number << ": face vertex index " << index
                         << " out of range (" << num_vertices << " vertices defined so far)";
        }
        corners.push_back(static_cast<int>(resolved));
      }
      if (corners.size() < 3) {
        MR_THROW_INPUT << path << ":" << line_number << ": face with " << corners.size()
                       << " corners (expected at least 3)";
      }
      for (size_t k = 2; k < corners.size(); ++k) {
        triangles.push_back(corners[0]);
        triangles.push_back(corners[k - 1]);
        triangles.push_back(corners[k]);
      }
    }
    // vt, vn, vp, g, o, s, usemtl, mtllib, l, p, ...: not needed.
  }

  TriangleMesh mesh;
  const Eigen::Index nv = static_cast<Eigen::Index>(positions.size() / 3);
  mesh.V.resize(nv, 3);
  for (Eigen::Index i = 0; i < nv; ++i) {
    mesh.V.row(i) << positions[3 * i], positions[3 * i + 1], positions[3 * i + 2];
  }
  if (all_colored && nv > 0) {
    mesh.C.resize(nv, 3);
    for (Eigen::Index i = 0; i < nv; ++i) {
      for (int k = 0; k < 3; ++k) {
        const double c = colors[3 * i + k];
        mesh.C(i, k) = static_cast<uint8_t>(std::lround(std::min(1.0, std::max(0.0, c)) * 255));
      }
    }
  }
  mesh.F.resize(static_cast<Eigen::Index>(triangles.size() / 3), 3);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    mesh.F.row(f) << triangles[3 * f], triangles[3 * f + 1], triangles[3 * f + 2];
  }
  return mesh;
}

void WriteObj(const std::string& path, const TriangleMesh& mesh) {
  const Eigen::Index nv = mesh.V.rows();
  const bool has_normals = mesh.N.rows() == nv && mesh.N.cols() == 3 && nv > 0;
  const bool has_colors = mesh.C.rows() == nv && nv > 0;
  std::string body;
  body.reserve(nv * 48 + mesh.F.rows() * 32);
  body += "# written by mesh_refiner\n";
  char line[160];
  for (Eigen::Index i = 0; i < nv; ++i) {
    const int n =
        has_colors
            ? std::snprintf(line, sizeof(line), "v %.17g %.17g %.17g %.9g %.9g %.9g\n",
                            mesh.V(i, 0), mesh.V(i, 1), mesh.V(i, 2), mesh.C(i, 0) / 255.0,
                            mesh.C(i, 1) / 255.0, mesh.C(i, 2) / 255.0)
            : std::snprintf(line, sizeof(line), "v %.17g %.17g %.17g\n", mesh.V(i, 0),
                            mesh.V(i, 1), mesh.V(i, 2));
    body.append(line, n);
  }
  if (has_normals) {
    for (Eigen::Index i = 0; i < nv; ++i) {
      const int n = std::snprintf(line, sizeof(line), "vn %.9g %.9g %.9g\n", mesh.N(i, 0),
                                  mesh.N(i, 1), mesh.N(i, 2));
      body.append(line, n);
    }
  }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      MR_CHECK(mesh.F(f, k) >= 0 && mesh.F(f, k) < nv)
          << path << ": face " << f << " has vertex index " << mesh.F(f, k) << " of " << nv;
    }
    const int a = mesh.F(f, 0) + 1, b = mesh.F(f, 1) + 1, c = mesh.F(f, 2) + 1;
    const int n = has_normals ? std::snprintf(line, sizeof(line), "f %d//%d %d//%d %d//%d\n", a,
                                              a, b, b, c, c)
                              : std::snprintf(line, sizeof(line), "f %d %d %d\n", a, b, c);
    body.append(line, n);
  }
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

TriangleMesh ReadMesh(const std::string& path) {
  const std::string ext = GetExtension(path);
  if (ext == ".ply") return ReadPly(path);
  if (ext == ".obj") return ReadObj(path);
  MR_THROW_INPUT << path << ": unsupported mesh extension '" << ext << "' (expected .ply or .obj)";
}

void WriteMesh(const std::string& path, const TriangleMesh& mesh) {
  const std::string ext = GetExtension(path);
  if (ext == ".ply") {
    WritePly(path, mesh, PlyFormat::kBinaryLittleEndian);
  } else if (ext == ".obj") {
    WriteObj(path, mesh);
  } else {
    MR_THROW_INPUT << path << ": unsupported mesh extension '" << ext
                   << "' (expected .ply or .obj)";
  }
}

}  // namespace mr
