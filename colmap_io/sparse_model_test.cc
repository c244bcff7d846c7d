#include "colmap_io/sparse_model.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "colmap_io/test_models.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

using test::MakeModelWithAllCameraModels;
using test::TempDir;

// Everything must be bit-identical, except quaternions, which COLMAP
// re-normalizes when it reads a model (last-bit changes): `qvec_tol`.
void ExpectEqualModels(const Reconstruction& a, const Reconstruction& b, double qvec_tol = 0) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, ca] : a.cameras) {
    ASSERT_EQ(b.cameras.count(id), 1u) << "camera " << id;
    const Camera& cb = b.cameras.at(id);
    EXPECT_EQ(ca.camera_id, cb.camera_id);
    EXPECT_EQ(ca.model, cb.model);
    EXPECT_EQ(ca.width, cb.width);
    EXPECT_EQ(ca.height, cb.height);
    EXPECT_EQ(ca.params, cb.params) << "camera " << id;
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (const auto& [id, ia] : a.images) {
    ASSERT_EQ(b.images.count(id), 1u) << "image " << id;
    const Image& ib = b.images.at(id);
    if (qvec_tol == 0) {
      EXPECT_EQ(ia.qvec, ib.qvec) << "image " << id;
    } else {
      EXPECT_LE((ia.qvec - ib.qvec).lpNorm<Eigen::Infinity>(), qvec_tol) << "image " << id;
    }
    EXPECT_EQ(ia.tvec, ib.tvec) << "image " << id;
    EXPECT_EQ(ia.camera_id, ib.camera_id);
    EXPECT_EQ(ia.name, ib.name);
    ASSERT_EQ(ia.points2D.size(), ib.points2D.size());
    for (size_t i = 0; i < ia.points2D.size(); ++i) {
      EXPECT_EQ(ia.points2D[i].xy, ib.points2D[i].xy);
      EXPECT_EQ(ia.points2D[i].point3D_id, ib.points2D[i].point3D_id);
    }
  }
  ASSERT_EQ(a.points3D.size(), b.points3D.size());
  for (const auto& [id, pa] : a.points3D) {
    ASSERT_EQ(b.points3D.count(id), 1u) << "point3D " << id;
    const Point3D& pb = b.points3D.at(id);
    EXPECT_EQ(pa.xyz, pb.xyz);
    EXPECT_EQ(pa.rgb, pb.rgb);
    EXPECT_EQ(pa.error, pb.error);
    ASSERT_EQ(pa.track.size(), pb.track.size());
    for (size_t i = 0; i < pa.track.size(); ++i) {
      EXPECT_EQ(pa.track[i].image_id, pb.track[i].image_id);
      EXPECT_EQ(pa.track[i].point2D_idx, pb.track[i].point2D_idx);
    }
  }
}

void WriteString(const std::string& path, const std::string& s) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << s;
}

template <typename T>
void Append(std::string* s, T v) {
  s->append(reinterpret_cast<const char*>(&v), sizeof(T));
}

int RunColmap(const std::string& args) {
  const std::string cmd = std::string("QT_QPA_PLATFORM=offscreen ") + MR_COLMAP_EXECUTABLE + " " +
                          args + " > /dev/null 2>&1";
  return std::system(cmd.c_str());
}

TEST(SparseModel, QuaternionRoundTrip) {
  const Eigen::Vector4d q = Eigen::Vector4d(0.9, 0.1, -0.3, 0.2).normalized();
  const Eigen::Vector4d q2 = RotationToQuaternion(QuaternionToRotation(q));
  EXPECT_LT((q - q2).norm(), 1e-12);
  const Eigen::Matrix3d R = QuaternionToRotation(q);
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  Image image;
  image.qvec = q;
  image.tvec = Eigen::Vector3d(1, 2, 3);
  // The projection centre maps to the camera origin.
  EXPECT_LT((image.Rotation() * image.ProjectionCenter() + image.tvec).norm(), 1e-12);
}

TEST(SparseModel, BinaryRoundTripAllCameraModels) {
  TempDir dir("sparse_bin");
  const Reconstruction model = MakeModelWithAllCameraModels();
  WriteSparseModelBinary(dir.path(), model);
  ExpectEqualModels(model, ReadSparseModelBinary(dir.path()));
  ExpectEqualModels(model, ReadSparseModel(dir.path()));
}

TEST(SparseModel, TextRoundTripAllCameraModels) {
  TempDir dir("sparse_txt");
  const Reconstruction model = MakeModelWithAllCameraModels();
  WriteSparseModelText(dir.path(), model);
  ExpectEqualModels(model, ReadSparseModelText(dir.path()));
  ExpectEqualModels(model, ReadSparseModel(dir.path()));
}

TEST(SparseModel, EmptyModelRoundTrip) {
  TempDir dir("sparse_empty");
  const Reconstruction model;
  WriteSparseModelBinary(dir.path(), model);
  WriteSparseModelText(dir.path(), model);
  ExpectEqualModels(model, ReadSparseModelBinary(dir.path()));
  ExpectEqualModels(model, ReadSparseModelText(dir.path()));
}

TEST(SparseModel, PrefersBinary) {
  TempDir dir("sparse_prefer");
  Reconstruction bin_model = MakeModelWithAllCameraModels(1);
  Reconstruction txt_model = MakeModelWithAllCameraModels(2);
  WriteSparseModelBinary(dir.path(), bin_model);
  WriteSparseModelText(dir.path(), txt_model);
  ExpectEqualModels(bin_model, ReadSparseModel(dir.path()));
}

TEST(SparseModel, ColmapConvertsOurBinaryToText) {
  if (std::string(MR_COLMAP_EXECUTABLE).empty()) GTEST_SKIP() << "colmap not found";
  TempDir dir("sparse_colmap_b2t");
  const Reconstruction model = MakeModelWithAllCameraModels();
  const std::string a = dir.Sub("a"), b = dir.Sub("b");
  WriteSparseModelBinary(a, model);
  ASSERT_EQ(RunColmap("model_converter --input_path " + a + " --output_path " + b +
                      " --output_type TXT"),
            0);
  ASSERT_TRUE(ExistsFile(b + "/images.txt"));
  ExpectEqualModels(model, ReadSparseModelText(b), 4e-16);
}

TEST(SparseModel, ColmapConvertsOurTextToBinary) {
  if (std::string(MR_COLMAP_EXECUTABLE).empty()) GTEST_SKIP() << "colmap not found";
  TempDir dir("sparse_colmap_t2b");
  const Reconstruction model = MakeModelWithAllCameraModels(3);
  const std::string a = dir.Sub("a"), b = dir.Sub("b");
  WriteSparseModelText(a, model);
  ASSERT_EQ(RunColmap("model_converter --input_path " + a + " --output_path " + b +
                      " --output_type BIN"),
            0);
  ASSERT_TRUE(ExistsFile(b + "/images.bin"));
  ExpectEqualModels(model, ReadSparseModelBinary(b), 4e-16);
}

TEST(SparseModel, TruncatedFile) {
  TempDir dir("sparse_trunc");
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  for (const std::string name : {"cameras.bin", "images.bin", "points3D.bin"}) {
    const std::string path = dir.path() + "/" + name;
    const std::string full = ReadFileToString(path);
    for (size_t cut : {size_t(3), size_t(9), full.size() / 2, full.size() - 1}) {
      WriteString(path, full.substr(0, cut));
      ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {name});
    }
    WriteString(path, full);
  }
  EXPECT_NO_THROW(ReadSparseModelBinary(dir.path()));
}

TEST(SparseModel, TrailingBytes) {
  TempDir dir("sparse_trailing");
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  const std::string path = dir.path() + "/points3D.bin";
  WriteString(path, ReadFileToString(path) + "xyz");
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"points3D.bin", "trailing"});
}

TEST(SparseModel, UnknownCameraModelId) {
  TempDir dir("sparse_model11");
  std::string s;
  Append<uint64_t>(&s, 1);
  Append<uint32_t>(&s, 5);   // camera id
  Append<int32_t>(&s, 11);   // a newer COLMAP model
  Append<uint64_t>(&s, 640);
  Append<uint64_t>(&s, 480);
  for (int i = 0; i < 8; ++i) Append<double>(&s, 100);
  WriteString(dir.path() + "/cameras.bin", s);
  ExpectInputError([&] { ReadSparseModel(dir.path()); }, {"cameras.bin", "model id 11"});
}

TEST(SparseModel, UnknownCameraModelName) {
  TempDir dir("sparse_model_name");
  WriteString(dir.path() + "/cameras.txt", "# comment\n1 RAD_TAN_THIN_PRISM_FISHEYE 640 480 1 2 3\n");
  ExpectInputError([&] { ReadSparseModel(dir.path()); },
                   {"cameras.txt:2", "RAD_TAN_THIN_PRISM_FISHEYE"});
}

TEST(SparseModel, WrongParamCount) {
  TempDir dir("sparse_params");
  WriteString(dir.path() + "/cameras.txt", "1 PINHOLE 640 480 500 500 320\n");
  ExpectInputError([&] { ReadSparseModel(dir.path()); }, {"cameras.txt:1", "3 parameters", "4"});
}

TEST(SparseModel, NaNValues) {
  TempDir dir("sparse_nan");
  WriteString(dir.path() + "/cameras.txt", "1 PINHOLE 640 480 500 nan 320 240\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "nan"});

  Reconstruction model = MakeModelWithAllCameraModels();
  model.points3D.begin()->second.xyz.y() = std::nan("");
  WriteSparseModelBinary(dir.path(), model);
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"points3D.bin", "not finite"});
}

TEST(SparseModel, GarbageText) {
  TempDir dir("sparse_garbage_txt");
  WriteString(dir.path() + "/cameras.txt", "1 PINHOLE 640 480x 500 500 320 240\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "HEIGHT"});
}

TEST(SparseModel, GarbageBinary) {
  TempDir dir("sparse_garbage_bin");
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  std::string junk;
  std::mt19937 rng(3);
  for (int i = 0; i < 4000; ++i) junk.push_back(static_cast<char>(rng()));
  for (const std::string name : {"cameras.bin", "images.bin", "points3D.bin"}) {
    TempDir d2("sparse_garbage_bin2");
    WriteSparseModelBinary(d2.path(), MakeModelWithAllCameraModels());
    WriteString(d2.path() + "/" + name, junk);
    ExpectInputError([&] { ReadSparseModelBinary(d2.path()); }, {name});
  }
}

TEST(SparseModel, AbsurdCount) {
  TempDir dir("sparse_absurd");
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  // A count of 2^60 cameras must be rejected without allocating.
  std::string s;
  Append<uint64_t>(&s, uint64_t(1) << 60);
  WriteString(dir.path() + "/cameras.bin", s);
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"cameras.bin", "number of cameras"});
  // Same for a points2D count inside images.bin.
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  std::string img;
  Append<uint64_t>(&img, 1);
  Append<uint32_t>(&img, 1);
  for (int i = 0; i < 7; ++i) Append<double>(&img, i == 0 ? 1.0 : 0.0);
  Append<uint32_t>(&img, 1);
  img += std::string("a.jpg") + '\0';
  Append<uint64_t>(&img, ~uint64_t(0));
  WriteString(dir.path() + "/images.bin", img);
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"images.bin", "points2D"});
}

TEST(SparseModel, MissingCamera) {
  TempDir dir("sparse_missing_cam");
  Reconstruction model = MakeModelWithAllCameraModels();
  model.images.begin()->second.camera_id = 99;
  WriteSparseModelBinary(dir.path(), model);
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"images.bin", "camera 99"});
  WriteSparseModelText(dir.path(), model);
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"images.txt", "camera 99"});
}

TEST(SparseModel, TrackRefersToMissingImage) {
  TempDir dir("sparse_missing_img");
  Reconstruction model = MakeModelWithAllCameraModels();
  model.points3D.begin()->second.track.push_back({777, 0});
  WriteSparseModelText(dir.path(), model);
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"points3D.txt", "image 777"});
}

TEST(SparseModel, TrackPoint2DIndexOutOfRange) {
  TempDir dir("sparse_bad_idx");
  Reconstruction model = MakeModelWithAllCameraModels();
  model.points3D.begin()->second.track.push_back({model.images.begin()->first, 1000});
  WriteSparseModelBinary(dir.path(), model);
  ExpectInputError([&] { ReadSparseModelBinary(dir.path()); }, {"points3D.bin", "point2D 1000"});
}

TEST(SparseModel, MissingFiles) {
  TempDir dir("sparse_missing_files");
  ExpectInputError([&] { ReadSparseModel(dir.path()); }, {dir.path(), "no sparse model"});
  ExpectInputError([&] { ReadSparseModel(dir.path() + "/nope"); }, {"does not exist"});
  WriteSparseModelBinary(dir.path(), MakeModelWithAllCameraModels());
  std::filesystem::remove(dir.path() + "/points3D.bin");
  ExpectInputError([&] { ReadSparseModel(dir.path()); }, {"points3D.bin"});
}

TEST(SparseModel, TextImagesWithoutPointsLines) {
  TempDir dir("sparse_txt_nopoints");
  WriteString(dir.path() + "/cameras.txt", "1 SIMPLE_PINHOLE 64 48 50 32 24\n");
  // Image 1 has an empty points line; image 2 is last and has none at all.
  WriteString(dir.path() + "/images.txt",
              "# header\n1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0 0 1 1 b c.png\n");
  WriteString(dir.path() + "/points3D.txt", "");
  const Reconstruction model = ReadSparseModelText(dir.path());
  ASSERT_EQ(model.images.size(), 2u);
  EXPECT_EQ(model.images.at(1).name, "a.png");
  EXPECT_EQ(model.images.at(2).name, "b c.png");
  EXPECT_TRUE(model.images.at(2).points2D.empty());
  EXPECT_EQ(model.images.at(2).tvec.z(), 1.0);
}

// Random byte corruption either still parses or throws InputError; never
// anything else (no crash, no internal error, no huge allocation).
TEST(SparseModel, RandomCorruptionOnlyThrowsInputError) {
  TempDir dir("sparse_fuzz");
  const Reconstruction model = MakeModelWithAllCameraModels();
  std::mt19937 rng(17);
  int input_errors = 0;
  for (const bool text : {false, true}) {
    if (text) {
      WriteSparseModelText(dir.path(), model);
    } else {
      WriteSparseModelBinary(dir.path(), model);
    }
    for (const std::string base : {"cameras", "images", "points3D"}) {
      const std::string path = dir.path() + "/" + base + (text ? ".txt" : ".bin");
      const std::string original = ReadFileToString(path);
      for (int trial = 0; trial < 60; ++trial) {
        std::string corrupt = original;
        const int flips = 1 + static_cast<int>(rng() % 4);
        for (int f = 0; f < flips; ++f) {
          corrupt[rng() % corrupt.size()] = text ? "0123456789.-e #\nxn"[rng() % 17]
                                                 : static_cast<char>(rng());
        }
        WriteString(path, corrupt);
        try {
          text ? ReadSparseModelText(dir.path()) : ReadSparseModelBinary(dir.path());
        } catch (const InputError&) {
          ++input_errors;
        } catch (const std::exception& e) {
          ADD_FAILURE() << path << " trial " << trial << ": unexpected " << e.what();
        }
      }
      WriteString(path, original);
    }
  }
  EXPECT_GT(input_errors, 120) << input_errors << " of 360";
}

TEST(SparseModel, DuplicateIds) {
  TempDir dir("sparse_dup");
  WriteString(dir.path() + "/cameras.txt",
              "1 SIMPLE_PINHOLE 64 48 50 32 24\n1 SIMPLE_PINHOLE 64 48 50 32 24\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:2", "duplicate"});
}

TEST(SparseModel, BadSizeAndFocal) {
  TempDir dir("sparse_bad_size");
  WriteString(dir.path() + "/cameras.txt", "1 SIMPLE_PINHOLE 0 48 50 32 24\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "size"});
  WriteString(dir.path() + "/cameras.txt", "1 SIMPLE_PINHOLE 64 48 -50 32 24\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "focal"});
}

// The message names the focal length that is wrong, with its value.
TEST(SparseModel, NonPositiveFocalIsNamed) {
  TempDir dir("sparse_bad_focal");
  WriteString(dir.path() + "/cameras.txt", "1 PINHOLE 640 480 576 -576 320 240\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "fy = -576"});
  WriteString(dir.path() + "/cameras.txt", "1 PINHOLE 640 480 0 576 320 240\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "fx = 0"});
  WriteString(dir.path() + "/cameras.txt", "1 SIMPLE_RADIAL 640 480 -576 320 240 0\n");
  ExpectInputError([&] { ReadSparseModelText(dir.path()); }, {"cameras.txt:1", "f = -576"});
}

}  // namespace
}  // namespace mr
