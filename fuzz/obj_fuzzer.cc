// Wavefront OBJ meshes (colmap_io/mesh_io.h).

#include "colmap_io/mesh_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mr::fuzz::Run([&] { mr::ReadObjData("fuzz.obj", mr::fuzz::Bytes(data, size)); });
}
