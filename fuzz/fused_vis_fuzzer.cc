// fused.ply.vis, the visibility of the fused points (colmap_io/dense_array.h).

#include "colmap_io/dense_array.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mr::fuzz::Run(
      [&] { mr::ReadFusedVisibilityData("fused.ply.vis", mr::fuzz::Bytes(data, size)); });
}
