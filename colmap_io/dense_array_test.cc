#include "colmap_io/dense_array.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "colmap_io/test_models.h"
#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

using test::TempDir;

void WriteString(const std::string& path, const std::string& s) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << s;
}

DenseArray MakeArray(int w, int h, int c) {
  DenseArray a;
  a.width = w;
  a.height = h;
  a.channels = c;
  a.data.resize(size_t(w) * h * c);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> uni(-10, 10);
  for (float& v : a.data) v = uni(rng);
  return a;
}

template <typename Fn>
void ExpectInputErrorWith(Fn fn, const std::string& part) {
  ExpectInputError(fn, {part});
}

TEST(DenseArray, RoundTrip) {
  TempDir dir("dense_rt");
  for (int c : {1, 3}) {
    const DenseArray a = MakeArray(7, 5, c);
    const std::string path = dir.path() + "/a.bin";
    WriteDenseArray(path, a);
    const DenseArray b = ReadDenseArray(path);
    EXPECT_EQ(b.width, 7);
    EXPECT_EQ(b.height, 5);
    EXPECT_EQ(b.channels, c);
    EXPECT_EQ(a.data, b.data);
  }
}

// The exact byte layout COLMAP uses: "W&H&C&" then channel-major float32.
TEST(DenseArray, ColmapLayout) {
  TempDir dir("dense_layout");
  std::string s = "3&2&2&";
  std::vector<float> values(12);
  for (int i = 0; i < 12; ++i) values[i] = static_cast<float>(i);
  s.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  WriteString(dir.path() + "/x.bin", s);
  const DenseArray a = ReadDenseArray(dir.path() + "/x.bin");
  EXPECT_EQ(a.At(0, 0, 0), 0);
  EXPECT_EQ(a.At(0, 2, 0), 2);
  EXPECT_EQ(a.At(1, 0, 0), 3);
  EXPECT_EQ(a.At(0, 0, 1), 6);
  EXPECT_EQ(a.At(1, 2, 1), 11);
  WriteDenseArray(dir.path() + "/y.bin", a);
  EXPECT_EQ(ReadFileToString(dir.path() + "/y.bin"), s);
}

TEST(DenseArray, BadHeader) {
  TempDir dir("dense_header");
  const std::string path = dir.path() + "/a.bin";
  for (const std::string header : {"", "3&2", "3&2&", "a&2&1&", "3&&1&", "0&2&1&", "-3&2&1&",
                                   "99999999999&2&1&", "3&2&1"}) {
    WriteString(path, header + std::string(24, '\0'));
    ExpectInputErrorWith([&] { ReadDenseArray(path); }, path);
  }
}

TEST(DenseArray, TruncatedFile) {
  TempDir dir("dense_trunc");
  const std::string path = dir.path() + "/a.bin";
  WriteDenseArray(path, MakeArray(4, 4, 1));
  const std::string full = ReadFileToString(path);
  WriteString(path, full.substr(0, full.size() - 1));
  ExpectInputErrorWith([&] { ReadDenseArray(path); }, "truncated");
  WriteString(path, full + "x");
  ExpectInputErrorWith([&] { ReadDenseArray(path); }, "trailing");
  // A huge header must not allocate.
  WriteString(path, "1000000&1000000&1000&" + std::string(8, '\0'));
  ExpectInputErrorWith([&] { ReadDenseArray(path); }, path);
}

TEST(DenseArray, NonFinite) {
  TempDir dir("dense_nan");
  DenseArray a = MakeArray(4, 3, 2);
  a.At(2, 1, 1) = std::numeric_limits<float>::quiet_NaN();
  const std::string path = dir.path() + "/a.bin";
  WriteDenseArray(path, a);
  ExpectInputErrorWith([&] { ReadDenseArray(path); }, "row 2, col 1, channel 1");
}

TEST(DenseArray, MissingFile) {
  ExpectInputErrorWith([&] { ReadDenseArray("/nonexistent/depth.bin"); }, "/nonexistent/depth.bin");
}

TEST(FusedVisibility, RoundTrip) {
  TempDir dir("vis_rt");
  const std::vector<std::vector<uint32_t>> vis = {{0, 3, 7}, {}, {2}, {1, 2, 3, 4, 5}};
  const std::string path = dir.path() + "/fused.ply.vis";
  WriteFusedVisibility(path, vis);
  EXPECT_EQ(ReadFusedVisibility(path), vis);
  EXPECT_EQ(ReadFileToString(path).size(), 8u + 4 * 4 + 9 * 4);
  WriteFusedVisibility(path, {});
  EXPECT_TRUE(ReadFusedVisibility(path).empty());
}

// Points seen by no image (COLMAP writes a count of 0 and nothing after it):
// reading them must not copy from the empty list's null data pointer
// (UBSan: "null pointer passed as argument 1 ... declared to never be null").
TEST(FusedVisibility, ZeroVisibleImages) {
  TempDir dir("vis_zero");
  const std::string path = dir.path() + "/fused.ply.vis";
  for (const std::vector<std::vector<uint32_t>>& vis :
       std::vector<std::vector<std::vector<uint32_t>>>{{{}}, {{}, {}, {}}, {{}, {4}, {}}}) {
    WriteFusedVisibility(path, vis);
    size_t ids = 0;
    for (const auto& images : vis) ids += images.size();
    EXPECT_EQ(ReadFileToString(path).size(), 8u + 4 * vis.size() + 4 * ids);
    EXPECT_EQ(ReadFusedVisibility(path), vis);
  }
}

TEST(FusedVisibility, TruncatedAndCorrupt) {
  TempDir dir("vis_bad");
  const std::string path = dir.path() + "/fused.ply.vis";
  WriteFusedVisibility(path, {{0, 3, 7}, {1}});
  const std::string full = ReadFileToString(path);
  for (size_t cut : {size_t(0), size_t(5), size_t(10), full.size() - 2}) {
    WriteString(path, full.substr(0, cut));
    ExpectInputErrorWith([&] { ReadFusedVisibility(path); }, path);
  }
  WriteString(path, full + "zz");
  ExpectInputErrorWith([&] { ReadFusedVisibility(path); }, "trailing");
  std::string huge(8, '\xff');
  WriteString(path, huge + "abcd");
  ExpectInputErrorWith([&] { ReadFusedVisibility(path); }, "number of points");
}

}  // namespace
}  // namespace mr
