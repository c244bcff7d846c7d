// COLMAP dense arrays (colmap_io/dense_array.h): depth_maps/*.bin, normal_maps/*.bin.

#include "colmap_io/dense_array.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mr::fuzz::Run(
      [&] { mr::ReadDenseArrayData("fuzz.geometric.bin", mr::fuzz::Bytes(data, size)); });
}
