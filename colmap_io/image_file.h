#pragma once

// Reading the images and masks of a workspace exactly as COLMAP reads them.
//
// Raw pixels: EXIF orientation is ignored (COLMAP's image_undistorter copies
// the pixels and keeps the tag, so the poses belong to the stored pixels).
// Completeness: libjpeg only warns about a cut file ("Premature end of JPEG
// file") and OpenCV then returns an image whose missing rows are grey; so a
// JPEG must contain the end-of-image marker after its first scan and a PNG
// must contain its IEND chunk. Data after a complete image (zero padding,
// trailers some cameras append) is allowed.

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace mr {

// The formats read are JPEG, PNG, TIFF, BMP and PNM (P1-P6); their headers
// are read here, before OpenCV decodes, so that a corrupt header cannot make
// the decoder allocate gigabytes. At most kMaxImagePixels pixels and
// kMaxDecodedImageBytes decoded bytes per image (the largest camera sensors
// give about 150 megapixels, 900 MiB as 16-bit RGB).
constexpr int64_t kMaxImagePixels = int64_t(1) << 28;        // 268 megapixels
constexpr int64_t kMaxDecodedImageBytes = int64_t(1) << 30;  // 1 GiB

struct ImageHeader {
  const char* format = "";  // "JPEG", "PNG", "TIFF", "BMP", "PNM"
  int64_t width = 0;
  int64_t height = 0;
  int channels = 0;          // as OpenCV decodes with IMREAD_UNCHANGED (at most)
  int bytes_per_sample = 0;  // likewise
  // TIFF only (0 elsewhere): the tile, or the strip clamped to the image,
  // that OpenCV's decoder buffers whole as 32-bit RGBA for 8-bit output. A
  // tile's size is the header's TileWidth x TileLength, which may exceed the
  // image (the fuzz finding: a 16 x 16 TIFF with 2-gigabyte tiles).
  int64_t block_width = 0;
  int64_t block_height = 0;
};

// The header of the image file at `path` whose bytes are `data`. Throws
// InputError naming `path` for another format, a size of zero or over
// kMaxImagePixels, and "truncated or corrupt image (...)" for a JPEG or PNG
// that ends before its image does.
ImageHeader ReadImageHeader(const std::string& path, const std::string& data);

// Reads an image file with cv::imread flags (cv::IMREAD_COLOR, _GRAYSCALE,
// _UNCHANGED; cv::IMREAD_IGNORE_ORIENTATION is added). `what` names the file
// in errors ("image", "mask"). Throws InputError naming the path if it is
// missing, is not a regular file, is truncated or cannot be decoded.
cv::Mat ReadImageFile(const std::string& path, int flags, const std::string& what = "image");

// ReadImageFile after the file was read: checks and decodes its bytes `data`
// (empty, another format, too large, truncated, undecodable: InputError
// naming `path`).
cv::Mat DecodeImageFile(const std::string& path, const std::string& data, int flags,
                        const std::string& what = "image");

// Writes `image` to `path` atomically (a temporary beside it, then renamed),
// creating the folder, in the format of the path's extension (PNG when it has
// none); `jpeg_quality` (1-100) is used for .jpg and .jpeg. Throws InputError
// naming `path` if OpenCV cannot encode the image in that format.
void WriteImageFile(const std::string& path, const cv::Mat& image, int jpeg_quality = 95);

}  // namespace mr
