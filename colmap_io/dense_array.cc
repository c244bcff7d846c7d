#include "colmap_io/dense_array.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "util/error.h"
#include "util/file.h"

namespace mr {
namespace {

constexpr int kMaxSide = 1 << 20;     // pixels; sanity bound on width/height
constexpr int kMaxChannels = 1 << 10;  // sanity bound on channels

// Parses one "<digits>&" field of the header starting at *pos.
int ParseHeaderField(const std::string& path, const std::string& data, size_t* pos,
                     const char* what, int max_value) {
  size_t p = *pos;
  long long value = 0;
  const size_t start = p;
  while (p < data.size() && p - start < 12 && data[p] >= '0' && data[p] <= '9') {
    value = value * 10 + (data[p] - '0');
    ++p;
  }
  if (p == start || p >= data.size() || data[p] != '&') {
    MR_THROW_INPUT << path << ": malformed dense array header (expected \"W&H&C&\" with decimal "
                   << "numbers; could not read " << what << " at byte " << start << ")";
  }
  if (value < 1 || value > max_value) {
    MR_THROW_INPUT << path << ": dense array " << what << " = " << value << " (expected 1.."
                   << max_value << ")";
  }
  *pos = p + 1;
  return static_cast<int>(value);
}

}  // namespace

DenseArray ReadDenseArray(const std::string& path) {
  return ReadDenseArrayData(path, ReadFileToString(path));
}

DenseArray ReadDenseArrayData(const std::string& path, const std::string& data) {
  DenseArray array;
  size_t pos = 0;
  array.width = ParseHeaderField(path, data, &pos, "width", kMaxSide);
  array.height = ParseHeaderField(path, data, &pos, "height", kMaxSide);
  array.channels = ParseHeaderField(path, data, &pos, "channels", kMaxChannels);
  const uint64_t count = uint64_t(array.width) * array.height * array.channels;
  const uint64_t body = data.size() - pos;
  if (body != count * sizeof(float)) {
    MR_THROW_INPUT << path << ": dense array " << array.width << "x" << array.height << "x"
                   << array.channels << " needs " << count * sizeof(float)
                   << " bytes of data but the file has " << body
                   << (body < count * sizeof(float) ? " (truncated file)" : " (trailing bytes)");
  }
  array.data.resize(count);
  std::memcpy(array.data.data(), data.data() + pos, count * sizeof(float));
  for (uint64_t i = 0; i < count; ++i) {
    if (!std::isfinite(array.data[i])) {
      const uint64_t plane = uint64_t(array.width) * array.height;
      MR_THROW_INPUT << path << ": non-finite value " << array.data[i] << " at row "
                     << (i % plane) / array.width << ", col " << (i % plane) % array.width
                     << ", channel " << i / plane;
    }
  }
  return array;
}

void WriteDenseArray(const std::string& path, const DenseArray& array) {
  MR_CHECK(array.width > 0 && array.height > 0 && array.channels > 0)
      << path << ": " << array.width << "x" << array.height << "x" << array.channels;
  MR_CHECK_EQ(array.data.size(), size_t(array.width) * array.height * array.channels) << path;
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << array.width << "&" << array.height << "&" << array.channels << "&";
    out.write(reinterpret_cast<const char*>(array.data.data()),
              static_cast<std::streamsize>(array.data.size() * sizeof(float)));
  });
}

std::vector<std::vector<uint32_t>> ReadFusedVisibility(const std::string& path) {
  return ReadFusedVisibilityData(path, ReadFileToString(path));
}

std::vector<std::vector<uint32_t>> ReadFusedVisibilityData(const std::string& path,
                                                           const std::string& data) {
  size_t pos = 0;
  auto read = [&](auto* value, const char* what) {
    if (data.size() - pos < sizeof(*value)) {
      MR_THROW_INPUT << path << ": truncated file: cannot read " << what << " at byte " << pos
                     << " (file has " << data.size() << " bytes)";
    }
    std::memcpy(value, data.data() + pos, sizeof(*value));
    pos += sizeof(*value);
  };
  uint64_t num_points = 0;
  read(&num_points, "number of points");
  if (num_points > (data.size() - pos) / sizeof(uint32_t)) {
    MR_THROW_INPUT << path << ": number of points = " << num_points << " cannot fit in the "
                   << data.size() - pos << " bytes left (truncated or corrupt file)";
  }
  std::vector<std::vector<uint32_t>> visibility(num_points);
  for (uint64_t i = 0; i < num_points; ++i) {
    uint32_t n = 0;
    read(&n, "visibility count");
    if (n > (data.size() - pos) / sizeof(uint32_t)) {
      MR_THROW_INPUT << path << ": truncated file: point " << i << " lists " << n
                     << " images but only " << data.size() - pos << " bytes are left";
    }
    if (n == 0) continue;  // seen by no image: the empty list's data() may be null
    visibility[i].resize(n);
    std::memcpy(visibility[i].data(), data.data() + pos, n * sizeof(uint32_t));
    pos += n * sizeof(uint32_t);
  }
  if (pos != data.size()) {
    MR_THROW_INPUT << path << ": " << data.size() - pos
                   << " unexpected trailing bytes after the last point (corrupt file?)";
  }
  return visibility;
}

void WriteFusedVisibility(const std::string& path,
                          const std::vector<std::vector<uint32_t>>& visibility) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    const uint64_t n = visibility.size();
    out.write(reinterpret_cast<const char*>(&n), sizeof(n));
    for (const auto& images : visibility) {
      MR_CHECK_LE(images.size(), size_t(std::numeric_limits<uint32_t>::max())) << path;
      const uint32_t m = static_cast<uint32_t>(images.size());
      out.write(reinterpret_cast<const char*>(&m), sizeof(m));
      out.write(reinterpret_cast<const char*>(images.data()),
                static_cast<std::streamsize>(m * sizeof(uint32_t)));
    }
  });
}

}  // namespace mr
