#include "colmap_io/image_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

uint8_t Byte(const std::string& data, size_t i) { return static_cast<uint8_t>(data[i]); }

uint32_t Be16(const std::string& data, size_t i) { return (uint32_t(Byte(data, i)) << 8) | Byte(data, i + 1); }
uint32_t Be32(const std::string& data, size_t i) { return (Be16(data, i) << 16) | Be16(data, i + 2); }
uint32_t Le16(const std::string& data, size_t i) { return (uint32_t(Byte(data, i + 1)) << 8) | Byte(data, i); }
uint32_t Le32(const std::string& data, size_t i) { return (Le16(data, i + 2) << 16) | Le16(data, i); }

[[noreturn]] void Truncated(const std::string& path, const std::string& why) {
  MR_THROW_INPUT << path << ": truncated or corrupt image (" << why << ")";
}

// Walks the marker segments up to the first scan (SOS), then looks for the
// end-of-image marker FF D9 after it. Entropy-coded data never holds FF D9
// (a data byte FF is followed by 00, a restart marker by D0-D7), so the first
// FF D9 after the scan ends the image; segments before the scan (the EXIF
// thumbnail has its own FF D9) are skipped by their lengths. The size comes
// from the first start-of-frame segment (SOF0-SOF15 but DHT C4, JPG C8, DAC CC).
ImageHeader ReadJpegHeader(const std::string& path, const std::string& data) {
  ImageHeader header{"JPEG", 0, 0, 0, 1};
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
    const size_t length = Be16(data, pos);
    if (length < 2 || pos + length > data.size()) {
      Truncated(path, "JPEG segment at byte " + std::to_string(pos - 2) +
                          " runs past the end of the file");
    }
    const bool frame = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 &&
                       marker != 0xcc;
    if (frame && header.channels == 0) {
      if (length < 8) Truncated(path, "JPEG frame header shorter than 8 bytes");
      header.height = Be16(data, pos + 3);
      header.width = Be16(data, pos + 5);
      // OpenCV decodes grey as one channel and everything else (YCbCr, CMYK) as three.
      header.channels = Byte(data, pos + 7) == 1 ? 1 : 3;
    }
    pos += length;
    if (marker == 0xda) break;  // start of scan: entropy-coded data follows
  }
  if (header.channels == 0) Truncated(path, "JPEG has no frame header before its image data");
  for (size_t i = pos; i + 1 < data.size(); ++i) {
    if (Byte(data, i) == 0xff && Byte(data, i + 1) == 0xd9) return header;
  }
  Truncated(path, "no JPEG end-of-image marker FF D9 after the image data");
}

// The size from the IHDR chunk, which must come first; then walks the chunks
// (length, type, data, CRC) up to IEND.
ImageHeader ReadPngHeader(const std::string& path, const std::string& data) {
  if (data.size() < 33 || data.compare(12, 4, "IHDR") != 0 || Be32(data, 8) != 13) {
    Truncated(path, "PNG does not start with its 13-byte IHDR chunk");
  }
  // Colour types: 0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA; OpenCV
  // gives a palette or grey + alpha image up to four channels.
  const int color_type = Byte(data, 25);
  ImageHeader header{"PNG", Be32(data, 16), Be32(data, 20), color_type == 0 ? 1 : color_type == 2 ? 3 : 4,
                     Byte(data, 24) == 16 ? 2 : 1};
  size_t pos = 8;  // after the signature
  while (true) {
    if (pos + 8 > data.size()) Truncated(path, "PNG ends before its IEND chunk");
    const uint64_t length = Be32(data, pos);
    const std::string type = data.substr(pos + 4, 4);
    if (pos + 12 + length > data.size()) {
      Truncated(path, "PNG chunk '" + type + "' at byte " + std::to_string(pos) +
                          " runs past the end of the file; no IEND chunk");
    }
    if (type == "IEND") return header;
    pos += 12 + length;
  }
}

// The first image file directory: ImageWidth (256), ImageLength (257),
// BitsPerSample (258, the first sample's), SamplesPerPixel (277),
// RowsPerStrip (278), TileWidth (322) and TileLength (323).
ImageHeader ReadTiffHeader(const std::string& path, const std::string& data) {
  const bool le = data[0] == 'I';
  const auto u16 = [&](size_t i) { return le ? Le16(data, i) : Be16(data, i); };
  const auto u32 = [&](size_t i) { return le ? Le32(data, i) : Be32(data, i); };
  if (data.size() < 8) Truncated(path, "TIFF ends inside its header");
  const uint64_t ifd = u32(4);
  if (ifd + 2 > data.size()) Truncated(path, "TIFF directory offset past the end of the file");
  const uint64_t count = u16(ifd);
  if (ifd + 2 + 12 * count > data.size()) Truncated(path, "TIFF directory runs past the end of the file");
  ImageHeader header{"TIFF", 0, 0, 1, 1};
  int64_t rows_per_strip = 0, tile_width = 0, tile_length = 0;
  for (uint64_t e = 0; e < count; ++e) {
    const size_t entry = ifd + 2 + 12 * e;
    const uint32_t tag = u16(entry), type = u16(entry + 2), n = u32(entry + 4);
    // SHORT (3) values sit in the first two bytes of the value field, LONG (4) in all four.
    const uint32_t value = type == 3 ? u16(entry + 8) : u32(entry + 8);
    // A tag given twice counts at its largest, whichever copy libtiff keeps.
    const auto keep_max = [&](auto& field) { field = std::max<decltype(+field)>(field, value); };
    if (tag == 256) keep_max(header.width);
    if (tag == 257) keep_max(header.height);
    if (tag == 277) {
      header.channels = std::max(header.channels, static_cast<int>(std::clamp<uint32_t>(value, 1, 65535)));
    }
    if (tag == 278) keep_max(rows_per_strip);
    if (tag == 322) keep_max(tile_width);
    if (tag == 323) keep_max(tile_length);
    if (tag == 258) {
      uint64_t bits = value;
      if (type == 3 && n > 2) {  // more than fit in the field: it holds their offset
        const uint64_t at = u32(entry + 8);
        if (at + 2 > data.size()) Truncated(path, "TIFF BitsPerSample past the end of the file");
        bits = u16(at);
      }
      header.bytes_per_sample = std::max<int>(header.bytes_per_sample, static_cast<int>((bits + 7) / 8));
    }
  }
  // A missing tile dimension or RowsPerStrip means the image's; libtiff
  // clamps a strip to the image, but not a tile.
  if (tile_width > 0 || tile_length > 0) {
    header.block_width = tile_width > 0 ? tile_width : header.width;
    header.block_height = tile_length > 0 ? tile_length : header.height;
  } else {
    header.block_width = header.width;
    header.block_height = rows_per_strip > 0 ? std::min(rows_per_strip, header.height) : header.height;
  }
  return header;
}

// BITMAPCOREHEADER (12 bytes: 16-bit sizes) or a later info header (signed
// 32-bit sizes; a negative height means rows stored top-down).
ImageHeader ReadBmpHeader(const std::string& path, const std::string& data) {
  if (data.size() < 26) Truncated(path, "BMP ends inside its header");
  ImageHeader header{"BMP", 0, 0, 3, 1};
  if (Le32(data, 14) == 12) {
    header.width = Le16(data, 18);
    header.height = Le16(data, 20);
  } else {
    if (data.size() < 30) Truncated(path, "BMP ends inside its header");
    header.width = std::abs(static_cast<int64_t>(static_cast<int32_t>(Le32(data, 18))));
    header.height = std::abs(static_cast<int64_t>(static_cast<int32_t>(Le32(data, 22))));
    if (Le16(data, 28) == 32) header.channels = 4;
  }
  return header;
}

// P1-P6: magic, width, height and (but for P1 and P4) the maximum value, as
// decimal numbers separated by white space and '#' comments.
ImageHeader ReadPnmHeader(const std::string& path, const std::string& data) {
  const char kind = data[1];
  size_t pos = 2;
  const auto number = [&]() -> int64_t {
    while (pos < data.size()) {
      if (data[pos] == '#') {
        while (pos < data.size() && data[pos] != '\n' && data[pos] != '\r') ++pos;
      } else if (std::isspace(static_cast<unsigned char>(data[pos]))) {
        ++pos;
      } else {
        break;
      }
    }
    if (pos >= data.size() || !std::isdigit(static_cast<unsigned char>(data[pos]))) {
      Truncated(path, "PNM header: number expected at byte " + std::to_string(pos));
    }
    int64_t v = 0;
    while (pos < data.size() && std::isdigit(static_cast<unsigned char>(data[pos]))) {
      v = std::min<int64_t>(v * 10 + (data[pos++] - '0'), int64_t(1) << 32);  // no overflow
    }
    // Netpbm separates the numbers by white space. OpenCV's reader takes the
    // byte after a number as its separator whatever it is, so a comment that
    // touches a number ("1555#5\r9") hides its '#' from OpenCV, which then
    // reads the comment's digits as the next number: a header that says
    // 1555 x 9 here made OpenCV allocate 1555 x 555555 pixels (fuzzing).
    if (pos < data.size() && !std::isspace(static_cast<unsigned char>(data[pos]))) {
      MR_THROW_INPUT << path << ": PNM header: white space expected after the number ending at byte "
                     << pos << " (corrupt header)";
    }
    return v;
  };
  ImageHeader header{"PNM", 0, 0, kind == '3' || kind == '6' ? 3 : 1, 1};
  header.width = number();
  header.height = number();
  if (kind != '1' && kind != '4' && number() > 255) header.bytes_per_sample = 2;
  return header;
}

}  // namespace

ImageHeader ReadImageHeader(const std::string& path, const std::string& data) {
  const auto starts = [&](const char* magic, size_t n) {
    return data.size() >= n && data.compare(0, n, magic, n) == 0;
  };
  ImageHeader header;
  if (starts("\xff\xd8\xff", 3)) {
    header = ReadJpegHeader(path, data);
  } else if (starts("\x89PNG\r\n\x1a\n", 8)) {
    header = ReadPngHeader(path, data);
  } else if (starts("II*\0", 4) || starts("MM\0*", 4)) {
    header = ReadTiffHeader(path, data);
  } else if (starts("BM", 2)) {
    header = ReadBmpHeader(path, data);
  } else if (data.size() >= 2 && data[0] == 'P' && data[1] >= '1' && data[1] <= '6') {
    header = ReadPnmHeader(path, data);
  } else {
    MR_THROW_INPUT << path << ": not a JPEG, PNG, TIFF, BMP or PNM image (the formats read; "
                   << "convert others to PNG first)";
  }
  if (header.width < 1 || header.height < 1) {
    MR_THROW_INPUT << path << ": " << header.format << " header gives a size of " << header.width
                   << " x " << header.height << " pixels (corrupt)";
  }
  const double megapixels = 1e-6 * static_cast<double>(header.width) * static_cast<double>(header.height);
  // Each size is checked alone first: a header's two 32-bit sizes can overflow a product.
  if (header.width > kMaxImagePixels || header.height > kMaxImagePixels ||
      header.width * header.height > kMaxImagePixels) {
    MR_THROW_INPUT << path << ": " << header.format << " header gives " << header.width << " x "
                   << header.height << " pixels (" << megapixels << " megapixels), more than the "
                   << kMaxImagePixels / 1000000 << " megapixels read (corrupt header, or split the image)";
  }
  return header;
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
  const ImageHeader header = ReadImageHeader(path, data);
  // The decoded size: IMREAD_COLOR gives 8-bit BGR, IMREAD_GRAYSCALE 8-bit grey,
  // IMREAD_UNCHANGED the file's channels and depth.
  const int64_t bytes_per_pixel = flags == cv::IMREAD_UNCHANGED
                                      ? int64_t(header.channels) * header.bytes_per_sample
                                      : (flags & cv::IMREAD_COLOR) ? 3 : 1;
  // In floating point: a TIFF may claim 65535 samples of 8192 bytes.
  const double decoded = static_cast<double>(header.width * header.height) * bytes_per_pixel;
  if (decoded > static_cast<double>(kMaxDecodedImageBytes)) {
    MR_THROW_INPUT << path << ": " << header.format << " of " << header.width << " x "
                   << header.height << " pixels would take " << std::llround(decoded / (1 << 20))
                   << " MiB decoded, more than the " << kMaxDecodedImageBytes / (1 << 20)
                   << " MiB read per " << what << " (corrupt header, or split the image)";
  }
  // OpenCV's TIFF decoder holds one tile or strip besides the image: as
  // 32-bit RGBA for 8-bit output, else in the file's channels and depth.
  const double block_bytes_per_pixel =
      flags != cv::IMREAD_UNCHANGED || header.bytes_per_sample == 1
          ? 4.0
          : static_cast<double>(header.channels) * header.bytes_per_sample;
  const double block = static_cast<double>(header.block_width) *
                       static_cast<double>(header.block_height) * block_bytes_per_pixel;
  if (block > static_cast<double>(kMaxDecodedImageBytes)) {
    MR_THROW_INPUT << path << ": " << header.format << " tile or strip of " << header.block_width << " x "
                   << header.block_height << " pixels would take " << std::llround(block / (1 << 20))
                   << " MiB to decode, more than the " << kMaxDecodedImageBytes / (1 << 20)
                   << " MiB read per " << what << " (corrupt header, or rewrite the file with "
                   << "smaller tiles)";
  }
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

void WriteImageFile(const std::string& path, const cv::Mat& image, int jpeg_quality) {
  CreateDirIfNotExists(GetParentDir(path));
  std::vector<uchar> buffer;
  std::string ext = GetExtension(path);
  if (ext.empty()) ext = ".png";
  std::vector<int> params;
  if (ext == ".jpg" || ext == ".jpeg") params = {cv::IMWRITE_JPEG_QUALITY, jpeg_quality};
  bool ok = false;
  try {
    ok = cv::imencode(ext, image, buffer, params);
  } catch (const cv::Exception& e) {
    ok = false;
  }
  if (!ok) MR_THROW_INPUT << path << ": cannot encode the image as '" << ext << "'";
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(buffer.data()),
              static_cast<std::streamsize>(buffer.size()));
  });
}

}  // namespace mr
