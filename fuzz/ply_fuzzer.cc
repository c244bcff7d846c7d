// PLY meshes and point clouds (colmap_io/ply.h): fused.ply, meshed-*.ply.

#include "colmap_io/ply.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mr::fuzz::Run([&] { mr::ReadPlyData("fuzz.ply", mr::fuzz::Bytes(data, size)); });
}
