#include "colmap_io/mesh_io.h"

#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

std::string TempPath(const std::string& name) { return JoinPaths(TestScratchDir(), name); }

void WriteRaw(const std::string& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << data;
}

TriangleMesh Tetrahedron() {
  TriangleMesh mesh;
  mesh.V.resize(4, 3);
  mesh.V << 0.1, 0.2, 0.3, 1.0 / 3.0, 0, 0, 0, 1e-7, 0, 0, 0, 12345.678901234;
  mesh.F.resize(4, 3);
  mesh.F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  return mesh;
}

TEST(MeshIo, ObjRoundTripIsExact) {
  const TriangleMesh mesh = Tetrahedron();
  const std::string path = TempPath("tet.obj");
  WriteMesh(path, mesh);
  const TriangleMesh read = ReadMesh(path);
  EXPECT_TRUE(read.V == mesh.V);  // %.17g round-trips doubles
  EXPECT_TRUE(read.F == mesh.F);
}

TEST(MeshIo, ObjRoundTripWithNormals) {
  TriangleMesh mesh = Tetrahedron();
  mesh.N = Eigen::MatrixXd::Identity(4, 3);
  const std::string path = TempPath("tet_normals.obj");
  WriteMesh(path, mesh);
  EXPECT_NE(ReadFileToString(path).find("f 1//1 3//3 2//2"), std::string::npos);
  const TriangleMesh read = ReadMesh(path);
  EXPECT_TRUE(read.V == mesh.V);
  EXPECT_TRUE(read.F == mesh.F);
}

// Vertex colours (mesh_refiner's output has them) survive an OBJ round trip.
TEST(MeshIo, ObjRoundTripWithColors) {
  TriangleMesh mesh = Tetrahedron();
  mesh.C.resize(4, 3);
  mesh.C << 0, 1, 2, 127, 128, 129, 253, 254, 255, 10, 200, 30;
  const std::string path = TempPath("tet_colors.obj");
  WriteMesh(path, mesh);
  const TriangleMesh read = ReadMesh(path);
  EXPECT_TRUE(read.V == mesh.V);
  EXPECT_TRUE(read.F == mesh.F);
  ASSERT_EQ(read.C.rows(), 4);
  EXPECT_TRUE(read.C == mesh.C);
}

TEST(MeshIo, PlyRoundTripThroughDispatch) {
  const TriangleMesh mesh = Tetrahedron();
  const std::string path = TempPath("tet.PLY");  // extension is case-insensitive
  WriteMesh(path, mesh);
  EXPECT_EQ(ReadFileToString(path).rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  const TriangleMesh read = ReadMesh(path);
  EXPECT_TRUE(read.V == mesh.V.cast<float>().cast<double>());
  EXPECT_TRUE(read.F == mesh.F);
}

TEST(MeshIo, ObjFaceForms) {
  const std::string path = TempPath("forms.obj");
  WriteRaw(path,
           "# comment line\n"
           "mtllib x.mtl\no thing\ng group\ns off\n"
           "v 0 0 0\nv 1 0 0\nv 1 1 0   # trailing comment\n"
           "v 0 1 0 1.0\n"  // with w
           "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
           "usemtl m\n"
           "f 1 2 3\n"
           "f 1/1 2/2 3/3\n"
           "f 1/1/1 2/2/1 3/3/1\r\n"
           "f 1//1 2//1 3//1\n"
           "f -4 -3 -2\n"         // negative = relative to the last vertex
           "f 1 2 3 4\n"          // quad -> 2 triangles
           "v 2 2 0\n"
           "f -5/1/1 -4/2/1 -3/3/1 -2 -1\n"  // pentagon -> 3 triangles
           "l 1 2\n");
  const TriangleMesh mesh = ReadMesh(path);
  ASSERT_EQ(mesh.NumVertices(), 5);
  EXPECT_EQ(mesh.V.row(4), Eigen::RowVector3d(2, 2, 0));
  EXPECT_EQ(mesh.C.size(), 0);
  Eigen::MatrixXi expected(10, 3);
  expected << 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2,  //
      0, 1, 2, 0, 2, 3,                                     //
      0, 1, 2, 0, 2, 3, 0, 3, 4;
  EXPECT_TRUE(mesh.F == expected) << mesh.F;
}

TEST(MeshIo, ObjVertexColors) {
  const std::string path = TempPath("colors.obj");
  WriteRaw(path, "v 0 0 0 1 0 0.5\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
  const TriangleMesh mesh = ReadMesh(path);
  ASSERT_EQ(mesh.C.rows(), 3);
  EXPECT_EQ(int(mesh.C(0, 0)), 255);
  EXPECT_EQ(int(mesh.C(0, 2)), 128);
  EXPECT_EQ(int(mesh.C(2, 2)), 255);
}

// Reading `path` must fail with a message naming the file and `fragment`.
void ExpectReadError(const std::string& path, const std::string& fragment) {
  ExpectInputError([&] { ReadMesh(path); }, {path, fragment});
}

TEST(MeshIoBadInput, ObjIndexOutOfRange) {
  const std::string path = TempPath("bad_index.obj");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  ExpectReadError(path, ":4: face vertex index 4 out of range (3 vertices");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  ExpectReadError(path, "face vertex index 0 out of range");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  ExpectReadError(path, "face vertex index -4 out of range");
  // A face may only use vertices defined before it.
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n");
  ExpectReadError(path, ":3: face vertex index 3");
}

TEST(MeshIoBadInput, ObjMalformedLines) {
  const std::string path = TempPath("malformed.obj");
  WriteRaw(path, "v 0 0\n");
  ExpectReadError(path, ":1: vertex with 2 coordinates");
  WriteRaw(path, "v 0 0 zero\n");
  ExpectReadError(path, "invalid number 'zero'");
  WriteRaw(path, "v 0 0 nan\n");
  ExpectReadError(path, "non-finite vertex coordinate");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nf 1 2\n");
  ExpectReadError(path, ":3: face with 2 corners");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n");
  ExpectReadError(path, "invalid face corner 'x'");
  WriteRaw(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 /2 3\n");
  ExpectReadError(path, "invalid face corner '/2'");
}

TEST(MeshIoBadInput, UnknownExtensionAndMissingFile) {
  const std::string path = TempPath("mesh.stl");
  WriteRaw(path, "solid\n");
  ExpectReadError(path, "unsupported mesh extension '.stl'");
  EXPECT_THROW(WriteMesh(path, Tetrahedron()), InputError);
  ExpectReadError(TempPath("missing.obj"), "cannot open");
}

// The shared models: counts from their own headers / `grep -c`.
struct SharedModel {
  const char* file;
  int vertices;
  int faces;
};

TEST(MeshIo, SharedModelsLoad) {
  const SharedModel models[] = {{"stanford-bunny.obj", 35947, 69451},
                                {"fandisk.obj", 6475, 12946},
                                {"rocker-arm.obj", 10044, 20088}};
  for (const SharedModel& model : models) {
    const std::string path = JoinPaths(JoinPaths(MR_SHARED_DIR, "data/models"), model.file);
    if (!ExistsFile(path)) GTEST_SKIP() << path << " not available";
    const TriangleMesh mesh = ReadMesh(path);
    EXPECT_EQ(mesh.NumVertices(), model.vertices) << path;
    EXPECT_EQ(mesh.NumFaces(), model.faces) << path;
    // Closed genus-0/1 surfaces: F ~ 2V.
    EXPECT_NEAR(static_cast<double>(mesh.NumFaces()) / mesh.NumVertices(), 2.0, 0.1) << path;
    EXPECT_GE(mesh.F.minCoeff(), 0);
    EXPECT_LT(mesh.F.maxCoeff(), mesh.NumVertices());
    EXPECT_TRUE(mesh.V.allFinite());
    // Round trip through binary PLY keeps the topology.
    const std::string ply = TempPath(std::string(model.file) + ".ply");
    WriteMesh(ply, mesh);
    const TriangleMesh back = ReadMesh(ply);
    EXPECT_TRUE(back.F == mesh.F);
    EXPECT_LT((back.V - mesh.V).cwiseAbs().maxCoeff(), 1e-6 * mesh.V.cwiseAbs().maxCoeff());
  }
}

}  // namespace
}  // namespace mr
