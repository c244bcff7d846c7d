// One file of a COLMAP sparse model (colmap_io/sparse_model.h), chosen at
// build time by MR_SPARSE_FILE: cameras.bin, images.bin, points3D.bin or the
// .txt ones. Images and points3D refer to cameras and images: they are read
// into a fixed model holding cameras 0-15 and images 0-15 (kPointsPerImage
// points2D each), so the references in the seeds (files colmap wrote) resolve
// and the fuzzer can reach the checks after them.

#include <string>

#include "colmap_io/sparse_model.h"
#include "fuzz/fuzz_util.h"

#ifndef MR_SPARSE_FILE
#error "define MR_SPARSE_FILE (cameras.bin, images.txt, ...)"
#endif

namespace {

constexpr uint32_t kNumIds = 16;
constexpr int kPointsPerImage = 1024;

mr::Reconstruction* MakeContext(const std::string& file) {
  auto* model = new mr::Reconstruction;
  const bool needs_cameras = file.rfind("cameras", 0) != 0;
  const bool needs_images = file.rfind("points3D", 0) == 0;
  for (uint32_t id = 0; needs_cameras && id < kNumIds; ++id) {
    mr::Camera& camera = model->cameras[id];
    camera.camera_id = id;
    camera.model = mr::CameraModel::kPinhole;
    camera.width = 160;
    camera.height = 120;
    camera.params = {150, 150, 80, 60};
  }
  for (uint32_t id = 0; needs_images && id < kNumIds; ++id) {
    mr::Image& image = model->images[id];
    image.image_id = id;
    image.camera_id = id;
    image.name = "image" + std::to_string(id) + ".png";
    image.points2D.resize(kPointsPerImage);
  }
  return model;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string file = MR_SPARSE_FILE;
  static mr::Reconstruction* const model = MakeContext(file);
  mr::fuzz::Run(
      [&] { mr::ReadSparseModelFile("sparse/" + file, mr::fuzz::Bytes(data, size), model); });
  // Only the file's own records were added (also when it was refused).
  if (file.rfind("cameras", 0) == 0) model->cameras.clear();
  if (file.rfind("images", 0) == 0) model->images.clear();
  if (file.rfind("points3D", 0) == 0) model->points3D.clear();
  return 0;
}
