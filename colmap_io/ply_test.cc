#include "colmap_io/ply.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
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
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
}

std::string ReadRaw(const std::string& path) { return ReadFileToString(path); }

// A small closed mesh (tetrahedron plus a spare vertex) with random
// attributes; values are exactly representable as float.
TriangleMesh MakeMesh(bool normals, bool colors, bool values) {
  TriangleMesh mesh;
  mesh.V.resize(5, 3);
  mesh.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -2.5, 1e3, 0.125;
  mesh.F.resize(4, 3);
  mesh.F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  if (normals) {
    mesh.N.resize(5, 3);
    for (int i = 0; i < 15; ++i) mesh.N(i / 3, i % 3) = u(rng);
  }
  if (colors) {
    mesh.C.resize(5, 3);
    for (int i = 0; i < 15; ++i) mesh.C(i / 3, i % 3) = static_cast<uint8_t>(rng() % 256);
  }
  if (values) {
    mesh.values.resize(5);
    for (int i = 0; i < 5; ++i) mesh.values(i) = u(rng) * 100;
  }
  return mesh;
}

// float-rounded copy: what a float PLY stores.
Eigen::MatrixXd AsFloat(const Eigen::MatrixXd& m) { return m.cast<float>().cast<double>(); }

void ExpectSameMesh(const TriangleMesh& expected, const TriangleMesh& actual) {
  ASSERT_EQ(expected.V.rows(), actual.V.rows());
  EXPECT_TRUE(AsFloat(expected.V) == actual.V);
  ASSERT_EQ(expected.F.rows(), actual.F.rows());
  EXPECT_TRUE(expected.F == actual.F);
  ASSERT_EQ(expected.N.size(), actual.N.size());
  if (expected.N.size() > 0) {
    EXPECT_TRUE(AsFloat(expected.N) == actual.N);
  }
  ASSERT_EQ(expected.C.size(), actual.C.size());
  if (expected.C.size() > 0) {
    EXPECT_TRUE(expected.C == actual.C);
  }
  ASSERT_EQ(expected.values.size(), actual.values.size());
  if (expected.values.size() > 0) {
    EXPECT_TRUE(AsFloat(expected.values) == actual.values);
  }
}

class PlyRoundTrip : public ::testing::TestWithParam<std::tuple<PlyFormat, int>> {};

TEST_P(PlyRoundTrip, AllAttributeCombinations) {
  const PlyFormat format = std::get<0>(GetParam());
  const int mask = std::get<1>(GetParam());
  const TriangleMesh mesh = MakeMesh(mask & 1, mask & 2, mask & 4);
  const std::string path = TempPath("round_trip_" + std::to_string(static_cast<int>(format)) +
                                    "_" + std::to_string(mask) + ".ply");
  WritePly(path, mesh, format);
  ExpectSameMesh(mesh, ReadPly(path));
}

INSTANTIATE_TEST_SUITE_P(Formats, PlyRoundTrip,
                         ::testing::Combine(::testing::Values(PlyFormat::kBinaryLittleEndian,
                                                              PlyFormat::kBinaryBigEndian,
                                                              PlyFormat::kAscii),
                                            ::testing::Range(0, 8)));

TEST(Ply, HeaderMatchesFormat) {
  const TriangleMesh mesh = MakeMesh(true, true, true);
  const std::string path = TempPath("header.ply");
  WritePly(path, mesh, PlyFormat::kBinaryBigEndian);
  const std::string data = ReadRaw(path);
  EXPECT_NE(data.find("format binary_big_endian 1.0\n"), std::string::npos);
  EXPECT_NE(data.find("property list uchar int vertex_indices\n"), std::string::npos);
  // Big-endian float 0.0 then 0.0 then 0.0; vertex 1 starts with 1.0f = 3f 80 00 00.
  const size_t body = data.find("end_header\n") + 11;
  const size_t vertex_size = 12 + 12 + 3 + 4;
  EXPECT_EQ(static_cast<unsigned char>(data[body + vertex_size]), 0x3f);
  EXPECT_EQ(static_cast<unsigned char>(data[body + vertex_size + 1]), 0x80);
}

TEST(Ply, PointCloudWithoutFaces) {
  TriangleMesh cloud = MakeMesh(true, true, false);
  cloud.F.resize(0, 3);
  const std::string path = TempPath("cloud.ply");
  WritePly(path, cloud);
  EXPECT_EQ(ReadRaw(path).find("element face"), std::string::npos);
  const TriangleMesh read = ReadPly(path);
  ExpectSameMesh(cloud, read);
  EXPECT_EQ(read.NumFaces(), 0);
}

TEST(Ply, EmptyMesh) {
  const std::string path = TempPath("empty.ply");
  WritePly(path, TriangleMesh());
  const TriangleMesh read = ReadPly(path);
  EXPECT_EQ(read.NumVertices(), 0);
  EXPECT_EQ(read.NumFaces(), 0);
}

// Hand-written ASCII file: other types and names, extra properties (also
// lists) and extra elements before and after, a quad and a pentagon.
TEST(Ply, ExtraPropertiesAndElements) {
  const std::string path = TempPath("extra.ply");
  WriteRaw(path,
           "ply\r\n"
           "format ascii 1.0\r\n"
           "comment made by hand\r\n"
           "obj_info nothing\r\n"
           "element camera 1\r\n"
           "property float32 fx\r\n"
           "property list uint8 int32 stuff\r\n"
           "element vertex 6\r\n"
           "property int16 confidence\r\n"
           "property float64 x\r\n"
           "property list uchar float junk\r\n"
           "property float32 y\r\n"
           "property double z\r\n"
           "property uint8 red\r\n"
           "property uint8 green\r\n"
           "property uint8 blue\r\n"
           "property uint8 alpha\r\n"
           "element face 2\r\n"
           "property uint8 flags\r\n"
           "property list uint32 uint32 vertex_index\r\n"
           "property list uchar float texcoord\r\n"
           "element edge 1\r\n"
           "property int vertex1\r\n"
           "property int vertex2\r\n"
           "end_header\r\n"
           "500 3 1 2 3\r\n"
           "7 0 2 1.5 2.5 0 0 1 2 3 255\r\n"
           "7 1 0 0 0 4 5 6 255\r\n"
           "7 1 1 9 1 0 7 8 9 255\r\n"
           "7 0 1 1 1 0 10 11 12 255\r\n"
           "7 2 0 0.5 0 13 14 15 255\r\n"
           "7 2 0 1.5 0 16 17 18 255\r\n"
           "1 4 0 1 2 3 2 0.5 0.5\r\n"
           "0 5 1 4 5 2 2 0 0 0 0 0 0 0 0 0 0\r\n"
           "0 1\r\n");
  const TriangleMesh mesh = ReadPly(path);
  ASSERT_EQ(mesh.NumVertices(), 6);
  EXPECT_EQ(mesh.V.row(1), Eigen::RowVector3d(1, 0, 0));
  EXPECT_EQ(mesh.V.row(5), Eigen::RowVector3d(2, 1.5, 0));
  EXPECT_EQ(mesh.N.size(), 0);
  EXPECT_EQ(mesh.values.size(), 0);
  ASSERT_EQ(mesh.C.rows(), 6);
  EXPECT_EQ(mesh.C(5, 2), 18);
  ASSERT_EQ(mesh.NumFaces(), 2 + 3);  // quad -> 2, pentagon -> 3 (fan)
  Eigen::MatrixXi expected(5, 3);
  expected << 0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2, 1, 2, 2;
  EXPECT_TRUE(mesh.F == expected) << mesh.F;
}

// Binary big-endian written byte by byte (not with WritePly), with a double
// x, an int count type and a list property before the face indices.
TEST(Ply, BigEndianHandWritten) {
  std::string data =
      "ply\nformat binary_big_endian 1.0\n"
      "element vertex 3\nproperty double x\nproperty float y\nproperty float z\n"
      "property uchar flag\nproperty float value\n"
      "element face 1\nproperty list int short extra\nproperty list int uint vertex_indices\n"
      "end_header\n";
  auto put = [&](const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    for (size_t i = 0; i < n; ++i) data += c[n - 1 - i];  // host is little-endian
  };
  const double xs[3] = {0.1, 1.0, -7.25};
  for (int i = 0; i < 3; ++i) {
    put(&xs[i], 8);
    const float y = static_cast<float>(i), z = 2.0f * i, value = 10.0f + i;
    put(&y, 4);
    put(&z, 4);
    data += static_cast<char>(i);
    put(&value, 4);
  }
  const int32_t one = 1, three = 3;
  const int16_t extra = -5;
  put(&one, 4);
  put(&extra, 2);
  put(&three, 4);
  const uint32_t idx[3] = {2, 0, 1};
  for (uint32_t v : idx) put(&v, 4);
  const std::string path = TempPath("big.ply");
  WriteRaw(path, data);
  const TriangleMesh mesh = ReadPly(path);
  ASSERT_EQ(mesh.NumVertices(), 3);
  EXPECT_EQ(mesh.V(0, 0), 0.1);
  EXPECT_EQ(mesh.V(2, 0), -7.25);
  EXPECT_EQ(mesh.V(2, 2), 4.0);
  ASSERT_EQ(mesh.values.size(), 3);
  EXPECT_EQ(mesh.values(1), 11.0);
  ASSERT_EQ(mesh.NumFaces(), 1);
  EXPECT_EQ(mesh.F.row(0), Eigen::RowVector3i(2, 0, 1));
}

// Data after the last element is ignored (with a warning), in both modes.
TEST(Ply, TrailingDataIsIgnored) {
  const TriangleMesh mesh = MakeMesh(false, true, false);
  for (PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
    const std::string path = TempPath("trailing.ply");
    WritePly(path, mesh, format);
    WriteRaw(path, ReadRaw(path) + "garbage\n");
    ExpectSameMesh(mesh, ReadPly(path));
  }
}

TEST(Ply, FloatColorsAreScaled) {
  const std::string path = TempPath("float_colors.ply");
  WriteRaw(path,
           "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
           "property float z\nproperty float red\nproperty float green\nproperty float blue\n"
           "end_header\n0 0 0 1 0.5 0\n");
  const TriangleMesh mesh = ReadPly(path);
  ASSERT_EQ(mesh.C.rows(), 1);
  EXPECT_EQ(int(mesh.C(0, 0)), 255);
  EXPECT_EQ(int(mesh.C(0, 1)), 128);
  EXPECT_EQ(int(mesh.C(0, 2)), 0);
}

// ---- Bad input -------------------------------------------------------------

// Reading `path` must fail with a message naming the file and `fragment`.
void ExpectReadError(const std::string& path, const std::string& fragment) {
  ExpectInputError([&] { ReadPly(path); }, {path, fragment});
}

const char kAsciiHeader[] =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

TEST(PlyBadInput, MissingFile) { ExpectReadError(TempPath("does_not_exist.ply"), "cannot open"); }

TEST(PlyBadInput, WrongMagic) {
  const std::string path = TempPath("wrong_magic.ply");
  WriteRaw(path, "PLY\nformat ascii 1.0\nend_header\n");
  ExpectReadError(path, "not a PLY file");
  WriteRaw(path, "plyx\n");
  ExpectReadError(path, "not a PLY file");
  WriteRaw(path, "");
  ExpectReadError(path, "not a PLY file");
}

TEST(PlyBadInput, UnknownFormat) {
  const std::string path = TempPath("unknown_format.ply");
  WriteRaw(path, "ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n");
  ExpectReadError(path, "unknown PLY format 'binary_middle_endian'");
}

TEST(PlyBadInput, UnknownType) {
  const std::string path = TempPath("unknown_type.ply");
  WriteRaw(path, "ply\nformat ascii 1.0\nelement vertex 0\nproperty float128 x\nend_header\n");
  ExpectReadError(path, "unknown property type 'float128'");
}

TEST(PlyBadInput, TruncatedHeader) {
  const std::string path = TempPath("truncated_header.ply");
  WriteRaw(path, std::string(kAsciiHeader).substr(0, 60));
  ExpectReadError(path, "no 'end_header'");
}

TEST(PlyBadInput, TruncatedFile) {
  const TriangleMesh mesh = MakeMesh(true, true, true);
  for (PlyFormat format :
       {PlyFormat::kBinaryLittleEndian, PlyFormat::kBinaryBigEndian, PlyFormat::kAscii}) {
    const std::string path = TempPath("truncated.ply");
    WritePly(path, mesh, format);
    const std::string data = ReadRaw(path);
    // Cut in the face list (last face) and in the vertex block.
    for (size_t cut : {data.size() - 3, data.find("end_header\n") + 11 + 20}) {
      WriteRaw(path, data.substr(0, cut));
      ExpectReadError(path, "truncated PLY body");
    }
  }
}

// A header whose vertex count is larger than the file holds: the faces are
// then read from the wrong place ("face 0 has 0 corners" in binary). The
// message must say what is wrong.
TEST(PlyBadInput, HeaderClaimsMoreVertices) {
  const TriangleMesh mesh = MakeMesh(false, false, false);  // 5 vertices, 4 faces
  for (PlyFormat format :
       {PlyFormat::kBinaryLittleEndian, PlyFormat::kBinaryBigEndian, PlyFormat::kAscii}) {
    const std::string path = TempPath("more_vertices.ply");
    WritePly(path, mesh, format);
    std::string data = ReadRaw(path);
    const size_t at = data.find("element vertex 5\n");
    ASSERT_NE(at, std::string::npos);
    WriteRaw(path, data.substr(0, at) + "element vertex 6\n" + data.substr(at + 17));
    ExpectInputError([&] { ReadPly(path); },
                     {path, "claims more vertices than the file holds", "end after vertex 5 of 6"});
    // Far more than the file can hold.
    WriteRaw(path, data.substr(0, at) + "element vertex 500\n" + data.substr(at + 17));
    ExpectInputError([&] { ReadPly(path); }, {path, "truncated PLY body", "vertex", "of 500"});
  }
}

TEST(PlyBadInput, MissingCoordinate) {
  const std::string path = TempPath("missing_z.ply");
  WriteRaw(path,
           "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
           "end_header\n0 0\n");
  ExpectReadError(path, "lacks a scalar x, y or z");
}

TEST(PlyBadInput, NanCoordinate) {
  const std::string path = TempPath("nan.ply");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  ExpectReadError(path, "vertex 1 has a non-finite y");
  // Binary infinity.
  TriangleMesh mesh = MakeMesh(false, false, false);
  mesh.V(2, 2) = std::numeric_limits<double>::infinity();
  WritePly(path, mesh);
  ExpectReadError(path, "vertex 2 has a non-finite z");
}

TEST(PlyBadInput, IndexOutOfRange) {
  const std::string path = TempPath("index_range.ply");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  ExpectReadError(path, "face 0 has vertex index 3 out of range [0, 3)");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
  ExpectReadError(path, "vertex index -1 out of range");
  // Binary: write a good file, then corrupt the last index.
  TriangleMesh mesh = MakeMesh(false, false, false);
  WritePly(path, mesh);
  std::string data = ReadRaw(path);
  const int32_t bad = 99;
  std::memcpy(&data[data.size() - 4], &bad, 4);
  WriteRaw(path, data);
  ExpectReadError(path, "face 3 has vertex index 99 out of range [0, 5)");
}

TEST(PlyBadInput, FaceWithTwoCorners) {
  const std::string path = TempPath("two_corners.ply");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  ExpectReadError(path, "face 0 has 2 corners");
}

TEST(PlyBadInput, InvalidAsciiNumber) {
  const std::string path = TempPath("bad_number.ply");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 0x 0\n0 1 0\n3 0 1 2\n");
  ExpectReadError(path, "invalid number '0x'");
  WriteRaw(path, std::string(kAsciiHeader) + "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n");
  ExpectReadError(path, "non-integer value '1.5'");
}

TEST(PlyBadInput, HugeCountInHeader) {
  const std::string path = TempPath("huge_count.ply");
  WriteRaw(path,
           "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n"
           "property float x\nproperty float y\nproperty float z\nend_header\n");
  ExpectReadError(path, "truncated PLY body");
  WriteRaw(path,
           "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\n"
           "property float x\nproperty float y\nproperty float z\nend_header\n");
  ExpectReadError(path, "too many vertices");
}

// Found by fuzz/ply_fuzzer (the input is fuzz/corpus/ply/regression_huge_count):
// an element count beyond long long was read as LLONG_MAX, and the bytes the
// header then needs were converted to int64 for the message (undefined
// behaviour). Lengths of ASCII lists (3e30 reads as an integer) were
// converted the same way.
TEST(PlyBadInput, CountsBeyondIntegerRange) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
      "property float z\n";
  ExpectInputError(
      [&] {
        ReadPlyData("a.ply", header + "element face 99999999999999999999\n"
                                      "property list uchar int vertex_indices\nend_header\n");
      },
      {"a.ply", "malformed element line"});
  ExpectInputError(
      [&] {
        ReadPlyData("b.ply", header + "element face 9223372036854775807\n"
                                      "property list uchar int vertex_indices\nend_header\n");
      },
      {"b.ply", "truncated PLY body", "needs at least 18446744073709551616 characters"});
  ExpectInputError(
      [&] { ReadPlyData("c.ply", std::string(kAsciiHeader) + "0 0 0\n1 0 0\n0 1 0\n3e30 0 1 2\n"); },
      {"c.ply", "truncated PLY body", "element 'face' record 0 has a list of 3e+30 values"});
  // Binary: a list length the rest of the file cannot hold.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uint int vertex_indices\nend_header\n";
  binary += std::string("\xff\xff\xff\xff", 4) + std::string(12, '\0');
  ExpectInputError([&] { ReadPlyData("d.ply", binary); },
                   {"d.ply", "record 0 has a list of 4294967295 values but only 12 bytes"});
  // An ASCII element without properties is skipped, whatever its count.
  const TriangleMesh mesh = ReadPlyData(
      "e.ply", header + "element nothing 9223372036854775807\nend_header\n");
  EXPECT_EQ(mesh.NumVertices(), 0);
}

TEST(Ply, ReadPlyDataMatchesReadPly) {
  const std::string path = TempPath("data.ply");
  WritePly(path, MakeMesh(true, true, true), PlyFormat::kBinaryBigEndian);
  const TriangleMesh a = ReadPly(path);
  const TriangleMesh b = ReadPlyData(path, ReadRaw(path));
  EXPECT_EQ(a.V, b.V);
  EXPECT_EQ(a.F, b.F);
  EXPECT_EQ(a.N, b.N);
  EXPECT_EQ(a.C, b.C);
  EXPECT_EQ(a.values, b.values);
}

TEST(Ply, WriteIsAtomicOnBadFolder) {
  EXPECT_THROW(WritePly(TempPath("no_such_dir/mesh.ply"), MakeMesh(false, false, false)),
               InputError);
}

// ---- Real COLMAP ------------------------------------------------------------

// Writes COLMAP's fused.ply layout (x y z nx ny nz red green blue, binary
// little-endian) of points on a sphere, meshes it with `colmap
// poisson_mesher` and reads the result back.
TEST(Ply, ColmapPoissonMesher) {
  const std::string colmap = MR_COLMAP_EXECUTABLE;
  if (colmap.empty()) GTEST_SKIP() << "colmap executable not found at configure time";
  const double radius = 1.5;
  const Eigen::Vector3d center(0.2, -0.3, 4.0);
  const int num_points = 20000;
  TriangleMesh cloud;
  cloud.V.resize(num_points, 3);
  cloud.N.resize(num_points, 3);
  cloud.C.resize(num_points, 3);
  // Fibonacci sphere.
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < num_points; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / num_points;
    const double r = std::sqrt(1.0 - z * z);
    const Eigen::Vector3d n(r * std::cos(golden * i), r * std::sin(golden * i), z);
    cloud.V.row(i) = (center + radius * n).transpose();
    cloud.N.row(i) = n.transpose();
    cloud.C.row(i) << 200, static_cast<uint8_t>(i % 256), 30;
  }
  const std::string in = TempPath("fused.ply");
  const std::string out = TempPath("meshed-poisson.ply");
  std::remove(out.c_str());
  WritePly(in, cloud);
  // The header must be exactly COLMAP's fused.ply vertex layout.
  EXPECT_NE(ReadRaw(in).find("element vertex 20000\nproperty float x\nproperty float y\n"
                             "property float z\nproperty float nx\nproperty float ny\n"
                             "property float nz\nproperty uchar red\nproperty uchar green\n"
                             "property uchar blue\nend_header\n"),
            std::string::npos);
  const std::string command = "QT_QPA_PLATFORM=offscreen '" + colmap +
                              "' poisson_mesher --input_path '" + in + "' --output_path '" + out +
                              "' --PoissonMeshing.trim 5 --PoissonMeshing.depth 8 > '" + TempPath("colmap.log") + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << ReadRaw(TempPath("colmap.log"));
  const TriangleMesh mesh = ReadPly(out);
  ASSERT_GT(mesh.NumFaces(), 100);
  ASSERT_GT(mesh.NumVertices(), 50);
  EXPECT_EQ(mesh.values.size(), mesh.NumVertices());
  EXPECT_EQ(mesh.C.rows(), mesh.NumVertices());
  EXPECT_EQ(mesh.N.size(), 0);
  double max_error = 0;
  for (int i = 0; i < mesh.NumVertices(); ++i) {
    max_error = std::max(max_error, std::abs((mesh.V.row(i).transpose() - center).norm() - radius));
  }
  EXPECT_LT(max_error, 0.05 * radius);
  // Colours are interpolated from the input (red 200, blue 30).
  EXPECT_NEAR(mesh.C.col(0).cast<double>().mean(), 200, 5);
  EXPECT_NEAR(mesh.C.col(2).cast<double>().mean(), 30, 5);
  EXPECT_GE(mesh.F.minCoeff(), 0);
  EXPECT_LT(mesh.F.maxCoeff(), mesh.NumVertices());
}

}  // namespace
}  // namespace mr
