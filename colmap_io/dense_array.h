#pragma once

// COLMAP's dense arrays (depth maps, normal maps): an ASCII header "W&H&C&"
// followed by little-endian float32, channel-major:
// data[c*W*H + row*W + col]. Note the dense code places depth pixel
// (col, row) at image point (col, row), half a pixel off the sparse model's
// convention.

#include <string>
#include <vector>

namespace mr {

struct DenseArray {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> data;  // channel-major, size width*height*channels

  float& At(int row, int col, int c) { return data[(size_t(c) * height + row) * width + col]; }
  float At(int row, int col, int c) const {
    return data[(size_t(c) * height + row) * width + col];
  }
};

// Throws InputError on a malformed header, a truncated body or non-finite data.
DenseArray ReadDenseArray(const std::string& path);
// The same from the file's bytes `data`; `path` only names them in errors
// (in-memory data, the fuzz harnesses). Likewise ReadFusedVisibilityData.
DenseArray ReadDenseArrayData(const std::string& path, const std::string& data);
// Writes atomically.
void WriteDenseArray(const std::string& path, const DenseArray& array);

// fused.ply.vis: u64 count, then per point u32 n and n u32 image indices.
std::vector<std::vector<uint32_t>> ReadFusedVisibility(const std::string& path);
std::vector<std::vector<uint32_t>> ReadFusedVisibilityData(const std::string& path,
                                                           const std::string& data);
void WriteFusedVisibility(const std::string& path,
                          const std::vector<std::vector<uint32_t>>& visibility);

}  // namespace mr
