#include "colmap_io/image_file.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "util/error.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

std::string Encode(const std::string& ext, const cv::Mat& image) {
  std::vector<uchar> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes)) << ext;
  return std::string(bytes.begin(), bytes.end());
}

// The InputError message of `f`, or "" if it did not throw.
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

cv::Mat Pattern(int rows, int cols, int type) {
  cv::Mat image(rows, cols, type);
  cv::randu(image, 0, CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255);
  return image;
}

// The header gives the size, channels and depth that OpenCV then decodes.
TEST(ImageFile, HeaderMatchesTheDecodedImage) {
  struct Case {
    std::string ext;
    int type;
  };
  const std::vector<Case> cases = {
      {".jpg", CV_8UC1},  {".jpg", CV_8UC3},  {".png", CV_8UC1},  {".png", CV_8UC3},
      {".png", CV_8UC4},  {".png", CV_16UC1}, {".png", CV_16UC3}, {".tif", CV_8UC1},
      {".tif", CV_8UC3},  {".tif", CV_16UC3}, {".bmp", CV_8UC3},  {".bmp", CV_8UC4},
      {".pgm", CV_8UC1},  {".ppm", CV_8UC3},  {".pgm", CV_16UC1}, {".ppm", CV_16UC3}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.ext + " type " + std::to_string(c.type));
    const std::string data = Encode(c.ext, Pattern(37, 53, c.type));
    const ImageHeader header = ReadImageHeader("x" + c.ext, data);
    const cv::Mat decoded = DecodeImageFile("x" + c.ext, data, cv::IMREAD_UNCHANGED);
    EXPECT_EQ(header.width, 53);
    EXPECT_EQ(header.height, 37);
    EXPECT_EQ(decoded.cols, 53);
    EXPECT_EQ(decoded.rows, 37);
    // The header may overstate (a BMP's channels), never understate.
    EXPECT_GE(header.channels, decoded.channels());
    EXPECT_EQ(header.bytes_per_sample, static_cast<int>(decoded.elemSize1()));
    EXPECT_EQ(DecodeImageFile("x" + c.ext, data, cv::IMREAD_COLOR).type(), CV_8UC3);
    EXPECT_EQ(DecodeImageFile("x" + c.ext, data, cv::IMREAD_GRAYSCALE).type(), CV_8UC1);
  }
}

// A few bytes of header that claim a huge image are refused before OpenCV
// allocates it (the fuzz finding: a 3 GB allocation from a 200-byte file).
TEST(ImageFile, HugeHeadersAreRefusedBeforeDecoding) {
  const std::string pnm = "P6\n# comment\n40000 40000\n255\n" + std::string(64, 'x');
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("a.ppm", pnm, cv::IMREAD_COLOR); })
                .find("a.ppm: PNM header gives 40000 x 40000 pixels (1600 megapixels), more "
                      "than the 268 megapixels read"),
            std::string::npos);

  std::string png = Encode(".png", Pattern(8, 8, CV_8UC3));
  // IHDR: big-endian width at byte 16, height at 20; 65535 x 65535.
  png.replace(16, 8, std::string("\0\0\xff\xff\0\0\xff\xff", 8));
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("b.png", png, cv::IMREAD_COLOR); })
                .find("b.png: PNG header gives 65535 x 65535 pixels"),
            std::string::npos);

  // A JPEG's start-of-frame segment: FF C0, length, precision, height, width.
  std::string jpg = Encode(".jpg", Pattern(8, 8, CV_8UC3));
  const size_t sof = jpg.find("\xff\xc0");
  ASSERT_NE(sof, std::string::npos);
  jpg[sof + 5] = jpg[sof + 6] = jpg[sof + 7] = jpg[sof + 8] = char(0xff);
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("c.jpg", jpg, cv::IMREAD_GRAYSCALE); })
                .find("c.jpg: JPEG header gives 65535 x 65535 pixels"),
            std::string::npos);

  std::string bmp = Encode(".bmp", Pattern(8, 8, CV_8UC3));
  bmp.replace(18, 4, std::string("\0\0\0\x10", 4));  // little-endian width 0x10000000
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("d.bmp", bmp, cv::IMREAD_COLOR); })
                .find("d.bmp: BMP header gives 268435456 x 8 pixels"),
            std::string::npos);

  // Sizes whose product overflows 64 bits (a fuzz finding: UBSan's signed
  // overflow in the pixel count).
  const std::string pnm_huge = "P6 99999999999999999999 99999999999999999999 255\n";
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("g.ppm", pnm_huge, cv::IMREAD_COLOR); })
                .find("g.ppm: PNM header gives 4294967296 x 4294967296 pixels"),
            std::string::npos);

  EXPECT_NE(ErrorOf([&] { DecodeImageFile("e.pgm", "P5 0 7 255\n", cv::IMREAD_COLOR); })
                .find("e.pgm: PNM header gives a size of 0 x 7 pixels (corrupt)"),
            std::string::npos);

  // A comment that touches a number (a fuzz finding): OpenCV takes the '#' as
  // the number's separator and reads the comment's digits as the height,
  // 1555 x 555555 pixels where this header reads 1555 x 5.
  EXPECT_NE(ErrorOf([&] {
              DecodeImageFile("h.pbm", "P1\r\r1555#555555\r\r5", cv::IMREAD_COLOR);
            }).find("h.pbm: PNM header: white space expected after the number ending at byte 8"),
            std::string::npos);
  // A comment on a line of its own is read as before.
  const cv::Mat commented =
      DecodeImageFile("k.pgm", "P2\n# made by hand\n2 1 # width, height\n255\n0 255\n",
                      cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(commented.cols, 2);
  ASSERT_EQ(commented.rows, 1);
  EXPECT_EQ(commented.at<uint8_t>(0, 1), 255);
}

// Within the pixel limit, the decoded bytes are limited too: 16384 x 16384
// pixels as 16-bit RGBA would take 2 GiB.
TEST(ImageFile, DecodedSizeIsLimitedForTheFlagsAsked) {
  std::string png = Encode(".png", Pattern(8, 8, CV_16UC4));
  png.replace(16, 8, std::string("\0\0\x40\0\0\0\x40\0", 8));  // 16384 x 16384
  const ImageHeader header = ReadImageHeader("f.png", png);
  EXPECT_EQ(header.width * header.height, kMaxImagePixels);
  EXPECT_EQ(header.channels * header.bytes_per_sample, 8);
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("f.png", png, cv::IMREAD_UNCHANGED, "mask"); })
                .find("f.png: PNG of 16384 x 16384 pixels would take 2048 MiB decoded, more "
                      "than the 1024 MiB read per mask"),
            std::string::npos);
}

// A TIFF whose SamplesPerPixel is 2^32 - 1 and BitsPerSample 2^32 - 1: the
// decoded size, computed without overflow, is refused.
TEST(ImageFile, TiffSampleCountsCannotOverflowTheSize) {
  std::string tif = Encode(".tif", Pattern(8, 8, CV_8UC3));
  ASSERT_EQ(tif.compare(0, 4, "II*\0", 4), 0);
  const auto le32 = [&](size_t i) {
    return uint32_t(uint8_t(tif[i])) | uint32_t(uint8_t(tif[i + 1])) << 8 |
           uint32_t(uint8_t(tif[i + 2])) << 16 | uint32_t(uint8_t(tif[i + 3])) << 24;
  };
  const uint32_t ifd = le32(4);
  const int n = uint8_t(tif[ifd]) | uint8_t(tif[ifd + 1]) << 8;
  int patched = 0;
  for (int e = 0; e < n; ++e) {
    const size_t entry = ifd + 2 + 12 * e;
    const int tag = uint8_t(tif[entry]) | uint8_t(tif[entry + 1]) << 8;
    if (tag == 258 || tag == 277) {  // BitsPerSample, SamplesPerPixel: LONG 0xffffffff
      tif.replace(entry + 2, 10, std::string("\x04\0\x01\0\0\0\xff\xff\xff\xff", 10));
      ++patched;
    }
  }
  ASSERT_EQ(patched, 2);
  const ImageHeader header = ReadImageHeader("s.tif", tif);
  EXPECT_EQ(header.channels, 65535);
  EXPECT_EQ(header.bytes_per_sample, 536870912);
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("s.tif", tif, cv::IMREAD_UNCHANGED); })
                .find("s.tif: TIFF of 8 x 8 pixels would take"),
            std::string::npos);
}

// A little-endian TIFF of 8-bit grey, uncompressed, one tile or strip at
// byte 8 + its directory: `entries` are (tag, LONG value) pairs besides the
// fixed ones, in ascending tag order as TIFF requires.
std::string GreyTiff(uint32_t width, uint32_t height,
                     const std::vector<std::pair<uint16_t, uint32_t>>& extra) {
  std::vector<std::pair<uint16_t, uint32_t>> entries = {
      {256, width}, {257, height}, {258, 8}, {259, 1}, {262, 1}, {277, 1}};
  entries.insert(entries.end(), extra.begin(), extra.end());
  const uint32_t data_at = 8 + 2 + 12 * static_cast<uint32_t>(entries.size()) + 4;
  const auto le = [](uint64_t v, int bytes) {
    std::string s;
    for (int i = 0; i < bytes; ++i) s += static_cast<char>((v >> (8 * i)) & 0xff);
    return s;
  };
  std::string tif = std::string("II*\0", 4) + le(8, 4) + le(entries.size(), 2);
  for (auto [tag, value] : entries) {
    if (tag == 273 || tag == 324) value = data_at;  // StripOffsets, TileOffsets
    tif += le(tag, 2) + le(4, 2) + le(1, 4) + le(value, 4);
  }
  return tif + le(0, 4) + std::string(width * height, '\x80');
}

// OpenCV's TIFF decoder allocates a whole tile, whose size the header gives
// and which may exceed the image: the fuzz finding was a 2.3 GB allocation for
// a file of a few hundred bytes. Strips are clamped to the image.
TEST(ImageFile, TiffTilesAreLimitedLikeImages) {
  const std::string big_tiles = GreyTiff(16, 16, {{322, 32768}, {323, 16384}, {324, 0}, {325, 256}});
  const ImageHeader header = ReadImageHeader("t.tif", big_tiles);
  EXPECT_EQ(header.block_width, 32768);
  EXPECT_EQ(header.block_height, 16384);
  EXPECT_NE(ErrorOf([&] { DecodeImageFile("t.tif", big_tiles, cv::IMREAD_GRAYSCALE); })
                .find("t.tif: TIFF tile or strip of 32768 x 16384 pixels would take 2048 MiB to "
                      "decode, more than the 1024 MiB read per image"),
            std::string::npos);

  // Tiles of the image's size pass the check (Debian's OpenCV 4.6 then fails
  // to read this hand-made tiled file, which is beside the point here); a
  // strip whose RowsPerStrip exceeds the image is clamped, and decodes.
  const std::string small_tiles = GreyTiff(16, 16, {{322, 16}, {323, 16}, {324, 0}, {325, 256}});
  EXPECT_EQ(ReadImageHeader("u.tif", small_tiles).block_width, 16);
  EXPECT_EQ(ErrorOf([&] { DecodeImageFile("u.tif", small_tiles, cv::IMREAD_GRAYSCALE); })
                .find("tile or strip"),
            std::string::npos);
  const std::string long_strip = GreyTiff(16, 16, {{273, 0}, {278, 1 << 28}, {279, 256}});
  EXPECT_EQ(ReadImageHeader("v.tif", long_strip).block_height, 16);
  EXPECT_EQ(DecodeImageFile("v.tif", long_strip, cv::IMREAD_COLOR).at<cv::Vec3b>(9, 2)[1], 0x80);
}

TEST(ImageFile, OtherFormatsAndNonImagesAreRefused) {
  const std::string kWhy = ": not a JPEG, PNG, TIFF, BMP or PNM image";
  EXPECT_NE(ErrorOf([] { DecodeImageFile("t.png", "not an image\n", cv::IMREAD_COLOR); })
                .find("t.png" + kWhy),
            std::string::npos);
  // Radiance HDR: OpenCV would decode it (through a temporary file).
  EXPECT_NE(ErrorOf([] {
              DecodeImageFile("h.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 9 +X 9\n",
                              cv::IMREAD_COLOR);
            }).find("h.hdr" + kWhy),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { DecodeImageFile("e.png", "", cv::IMREAD_COLOR); })
                .find("e.png: image file is empty"),
            std::string::npos);
}

// Cut files: the JPEG and PNG completeness checks name what is missing.
TEST(ImageFile, TruncatedHeadersAreCorrupt) {
  const std::string png = Encode(".png", Pattern(8, 8, CV_8UC3));
  for (size_t keep : {size_t(9), size_t(20), size_t(40)}) {
    EXPECT_NE(ErrorOf([&] { ReadImageHeader("p.png", png.substr(0, keep)); })
                  .find("p.png: truncated or corrupt image"),
              std::string::npos)
        << keep;
  }
  const std::string jpg = Encode(".jpg", Pattern(8, 8, CV_8UC3));
  for (size_t keep : {size_t(3), size_t(10), jpg.size() - 2}) {
    EXPECT_NE(ErrorOf([&] { ReadImageHeader("j.jpg", jpg.substr(0, keep)); })
                  .find("j.jpg: truncated or corrupt image"),
              std::string::npos)
        << keep;
  }
  const std::string tif = Encode(".tif", Pattern(8, 8, CV_8UC3));
  EXPECT_NE(ErrorOf([&] { ReadImageHeader("t.tif", tif.substr(0, 6)); })
                .find("t.tif: truncated or corrupt image (TIFF ends inside its header)"),
            std::string::npos);
}

// WriteImageFile writes in the format of the extension and round-trips: a PNG
// exactly, a JPEG within its compression error (and smaller at a lower
// quality); the folder is created; a format OpenCV cannot write is refused.
TEST(ImageFile, WrittenImagesReadBack) {
  const std::string dir = JoinPaths(MakeTestDir("write_image_file"), "sub");
  cv::Mat image(40, 56, CV_8UC3);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(4 * c, 6 * r, 2 * (r + c));  // smooth ramps
    }
  }
  WriteImageFile(JoinPaths(dir, "a.png"), image);
  const cv::Mat png = cv::imread(JoinPaths(dir, "a.png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.size(), image.size());
  EXPECT_EQ(cv::norm(png, image, cv::NORM_INF), 0);
  WriteImageFile(JoinPaths(dir, "b.jpg"), image, 95);
  WriteImageFile(JoinPaths(dir, "c.jpg"), image, 30);
  const std::string high = ReadFileToString(JoinPaths(dir, "b.jpg"));
  ASSERT_GE(high.size(), 2u);
  EXPECT_EQ(static_cast<unsigned char>(high[0]), 0xFF);
  EXPECT_EQ(static_cast<unsigned char>(high[1]), 0xD8);
  EXPECT_LT(ReadFileToString(JoinPaths(dir, "c.jpg")).size(), high.size());
  const cv::Mat jpg = cv::imread(JoinPaths(dir, "b.jpg"), cv::IMREAD_COLOR);
  ASSERT_EQ(jpg.size(), image.size());
  EXPECT_LT(cv::norm(jpg, image, cv::NORM_L1) / (3.0 * image.total()), 8.0);
  EXPECT_THROW(WriteImageFile(JoinPaths(dir, "d.unknownformat"), image), InputError);
}

}  // namespace
}  // namespace mr
