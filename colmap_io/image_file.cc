#include "colmap_io/image_file.h"

#include <cstdint>
#include <filesystem>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

uint8_t Byte(const std::string& data, size_t i) { return static_cast<uint8_t>(data[i]); }

[[noreturn]] void Truncated(const std::string& path, const std::string& why) {
  MR_THROW_INPUT << path << ": truncated or corrupt image (" << why << ")";
}

// Walks the marker segments up to the first scan (SOS), then looks for the
// end-of-image marker FF D9 after it. Entropy-coded data never holds FF D9
// (a data byte FF is followed by 00, a restart marker by D0-D7), so the first
// FF D9 after the scan ends the image; segments before the scan (the EXIF
// thumbnail has its own FF D9) are skipped by their lengths.
void CheckJpeg(const std::string& path, const std::string& data) {
  size_t pos = 2;  // after SOI
  while (true) {
    if (pos >= data.size()) Truncated(path, "JPEG ends before its image data");
    if (Byte(data, pos) != 0xff) {
      Truncated(path, "JPEG marker expected at byte " + std::to_string(pos));
    }
    while (pos < data.size() && Byte(data, pos) == 0xff) ++pos;  // fill bytes
    if (pos >= data.size()) Truncated(path, "JPEG ends before its image data");
    const uint8_t marker = Byte(data, pos++);
    if (marker == 0xd9) Truncated(path, "JPEG ends before its image data");
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) continue;  // no length
    if (pos + 2 > data.size()) Truncated(path, "JPEG ends inside a segment header");
    const size_t length = (size_t(Byte(data, pos)) << 8) | Byte(data, pos + 1);
    if (length < 2 || pos + length > data.size()) {
      Truncated(path, "JPEG segment at byte " + std::to_string(pos - 2) +
                          " runs past the end of the file");
    }
    pos += length;
    if (marker == 0xda) break;  // start of scan: entropy-coded data follows
  }
  for (size_t i = pos; i + 1 < data.size(); ++i) {
    if (Byte(data, i) == 0xff && Byte(data, i + 1) == 0xd9) return;
  }
  Truncated(path, "no JPEG end-of-image marker FF D9 after the image data");
}

// Walks the chunks (length, type, data, CRC) up to IEND.
void CheckPng(const std::string& path, const std::string& data) {
  size_t pos = 8;  // after the signature
  while (true) {
    if (pos + 8 > data.size()) Truncated(path, "PNG ends before its IEND chunk");
    const uint64_t length = (uint64_t(Byte(data, pos)) << 24) |
                            (uint64_t(Byte(data, pos + 1)) << 16) |
                            (uint64_t(Byte(data, pos + 2)) << 8) | Byte(data, pos + 3);
    const std::string type = data.substr(pos + 4, 4);
    if (pos + 12 + length > data.size()) {
      Truncated(path, "PNG chunk '" + type + "' at byte " + std::to_string(pos) +
                          " runs past the end of the file; no IEND chunk");
    }
    if (type == "IEND") return;
    pos += 12 + length;
  }
}

}  // namespace

void CheckImageComplete(const std::string& path, const std::string& data) {
  if (data.size() >= 3 && Byte(data, 0) == 0xff && Byte(data, 1) == 0xd8 && Byte(data, 2) == 0xff) {
    CheckJpeg(path, data);
  } else if (data.size() >= 8 && data.compare(0, 8, "\x89PNG\r\n\x1a\n", 8) == 0) {
    CheckPng(path, data);
  }
}

cv::Mat ReadImageFile(const std::string& path, int flags, const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) MR_THROW_INPUT << path << ": " << what << " is missing";
  if (!ExistsFile(path)) {
    MR_THROW_INPUT << path << ": " << what << " is not a file (expected an image file"
                   << (ExistsDir(path) ? ", found a folder)" : ")");
  }
  return DecodeImageFile(path, ReadFileToString(path), flags, what);
}

cv::Mat DecodeImageFile(const std::string& path, const std::string& data, int flags,
                        const std::string& what) {
  if (data.empty()) MR_THROW_INPUT << path << ": " << what << " file is empty";
  if (data.size() > static_cast<size_t>(std::numeric_limits<int>::max())) {
    MR_THROW_INPUT << path << ": " << what << " file of " << data.size()
                   << " bytes is too large (expected under 2 GiB)";
  }
  CheckImageComplete(path, data);
  // cv::IMREAD_UNCHANGED (-1) already ignores the orientation.
  if (flags != cv::IMREAD_UNCHANGED) flags |= cv::IMREAD_IGNORE_ORIENTATION;
  cv::Mat image;
  try {
    const cv::Mat bytes(1, static_cast<int>(data.size()), CV_8U, const_cast<char*>(data.data()));
    image = cv::imdecode(bytes, flags);
  } catch (const cv::Exception& e) {
    image.release();
  }
  if (image.empty()) {
    MR_THROW_INPUT << path << ": cannot decode the " << what
                   << " (not an image format OpenCV reads, or corrupt)";
  }
  return image;
}

}  // namespace mr
