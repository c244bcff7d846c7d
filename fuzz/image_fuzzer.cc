// Workspace images and masks (colmap_io/image_file.h): the header reader
// (format, size limits, JPEG and PNG completeness), then OpenCV's decoders. The read flag follows the input's
// size modulo 3 (colour as for images, greyscale as for masks, unchanged as
// for undistortion), so every input picks one and trailing bytes, which a
// complete JPEG or PNG may carry, switch between them.
//
// OpenCV and its codec libraries are not instrumented: the fuzzer sees the
// coverage of our checks only, and a memory error inside a codec shows only
// if it crashes.

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/image_file.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const int kFlags[3] = {cv::IMREAD_COLOR, cv::IMREAD_GRAYSCALE, cv::IMREAD_UNCHANGED};
  return mr::fuzz::Run(
      [&] { mr::DecodeImageFile("fuzz_image", mr::fuzz::Bytes(data, size), kFlags[size % 3]); });
}
