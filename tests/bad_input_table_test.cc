// Every bad input we know of, as a table: mesh_refiner, mesh_denoiser and
// mesh_evaluator are run as a user would on a small workspace with one thing
// wrong, and each row says what exit status and which words of the message
// to expect. For every row, the run must leave the case folder exactly as it
// was: the existing outputs byte-identical, no temporary file
// (*.tmp.<pid>, *.tmp.<pid>.probe), nothing added or removed.
// docs/bad_inputs.md lists the same rows.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "refine/test_scene.h"
#include "render/renderer.h"
#include "tests/command.h"
#include "tests/test_workspace.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

// The existing outputs, whose bytes every run must leave as they are.
const char kExistingOutput[] = "existing output, must stay byte-identical\n";
// Small and quick: the point here is the refusal, not the refinement.
const char kFast[] =
    " --Refine.num_levels 1 --Refine.iterations_per_level 1 --Refine.target_edge_px 4";

struct BadInput {
  std::string name;         // test name (letters, digits, _)
  std::string program;      // mesh_refiner, mesh_denoiser or mesh_evaluator
  std::string description;  // the input, for docs/bad_inputs.md
  // Makes the case's bad input in `dir`, a fresh copy of the base folder
  // (dir/ws: workspace; dir/m.ply, dir/gt.ply: meshes; outputs:
  // dir/ws/meshed-refined.ply and dir/out.ply).
  std::function<void(const std::string& dir)> prepare;
  std::string args;  // "{dir}" is replaced by the case folder
  int exit_code;
  std::string message;  // expected in the output
};

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// Keeps the first `keep` of a file's bytes (keep < 1: that fraction).
void Truncate(const std::string& path, double keep) {
  const std::string bytes = ReadFileToString(path);
  const size_t n = keep < 1 ? static_cast<size_t>(keep * bytes.size()) : static_cast<size_t>(keep);
  WriteText(path, bytes.substr(0, n));
}

TriangleMesh Sphere(int level, double radius) {
  TriangleMesh mesh;
  MakeIcosphere(level, radius, &mesh.V, &mesh.F);
  return mesh;
}

void EditModel(const std::string& dir, const std::function<void(Reconstruction*)>& edit) {
  Reconstruction model = ReadSparseModel(dir + "/ws/sparse");
  edit(&model);
  WriteSparseModelBinary(dir + "/ws/sparse", model);
}

std::string AsciiPly(const std::string& vertices, int num_vertices, const std::string& faces,
                     int num_faces) {
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(num_vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(num_faces) + "\nproperty list uchar int vertex_indices\nend_header\n" +
         vertices + faces;
}

// A sphere of 80 faces with one vertex set to `value` (NaN, inf) in ASCII.
std::string SphereWithBadVertex(const std::string& value) {
  const TriangleMesh mesh = Sphere(1, 0.8);
  std::string vertices, faces;
  for (int v = 0; v < mesh.V.rows(); ++v) {
    vertices += (v == 3 ? value : std::to_string(mesh.V(v, 0))) + " " +
                std::to_string(mesh.V(v, 1)) + " " + std::to_string(mesh.V(v, 2)) + "\n";
  }
  for (int f = 0; f < mesh.F.rows(); ++f) {
    faces += "3 " + std::to_string(mesh.F(f, 0)) + " " + std::to_string(mesh.F(f, 1)) + " " +
             std::to_string(mesh.F(f, 2)) + "\n";
  }
  return AsciiPly(vertices, static_cast<int>(mesh.V.rows()), faces,
                  static_cast<int>(mesh.F.rows()));
}

const std::string kWs = " --workspace_path {dir}/ws";
const std::string kDenoise = " --input_path {dir}/m.ply --output_path {dir}/out.ply";
const std::string kEvaluate = " --input_path {dir}/m.ply --gt_path {dir}/gt.ply --num_samples 2000";
const auto kNothing = [](const std::string&) {};

std::vector<BadInput> Table() {
  const std::string R = "mesh_refiner", D = "mesh_denoiser", E = "mesh_evaluator";
  return {
      // ---- mesh_refiner: the workspace ----
      {"RefinerWorkspaceMissing", R, "`--workspace_path` that does not exist", kNothing,
       " --workspace_path {dir}/nope" + std::string(kFast), 1, "workspace folder does not exist"},
      {"RefinerWorkspaceIsAFile", R, "`--workspace_path` is a file",
       kNothing, " --workspace_path {dir}/m.ply" + std::string(kFast), 1,
       "m.ply: is a file; expected a workspace folder"},
      {"RefinerNoImagesFolder", R, "workspace without `images/`",
       [](const std::string& d) { fs::remove_all(d + "/ws/images"); }, kWs + kFast, 1,
       "no images folder"},
      {"RefinerNoSparseModel", R, "workspace without a sparse model",
       [](const std::string& d) { fs::remove_all(d + "/ws/sparse"); }, kWs + kFast, 1,
       "no sparse model"},
      {"RefinerTruncatedCamerasBin", R, "`sparse/cameras.bin` cut in the middle",
       [](const std::string& d) { Truncate(d + "/ws/sparse/cameras.bin", 0.5); }, kWs + kFast, 1,
       "sparse/cameras.bin: number of cameras = 8 needs at least"},
      {"RefinerMissingImagesBin", R, "`sparse/images.bin` missing (cameras.bin present)",
       [](const std::string& d) { fs::remove(d + "/ws/sparse/images.bin"); }, kWs + kFast, 1,
       "sparse/images.bin: cannot open file for reading"},
      {"RefinerGarbagePoints3D", R, "`sparse/points3D.bin` of random bytes",
       [](const std::string& d) { WriteText(d + "/ws/sparse/points3D.bin", "\x07garbage"); },
       kWs + kFast, 1, "sparse/points3D.bin: number of points3D"},
      {"RefinerNoRegisteredImages", R, "sparse model with zero images",
       [](const std::string& d) { EditModel(d, [](Reconstruction* m) { m->images.clear(); }); },
       kWs + kFast, 1, "zero registered images"},
      {"RefinerWrongCameraSize", R, "camera 200x120 for 160x120 images",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) { m->cameras.at(1).width = 200; });
       },
       kWs + kFast, 1, "but camera 1 is 200x120"},
      {"RefinerNegativeFocalLength", R, "PINHOLE camera with fy = -100",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) { m->cameras.at(1).params[1] = -100; });
       },
       kWs + kFast, 1, "camera 1 (PINHOLE) has a non-positive focal length fy = -100"},
      {"RefinerImplausibleDistortion", R,
       "OPENCV camera with k1 = 5 (most of the undistorted image outside the photo)",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) {
           for (auto& [id, camera] : m->cameras) {
             camera.model = CameraModel::kOpenCV;
             camera.params.insert(camera.params.end(), {5, 0, 0, 0});
           }
         });
       },
       kWs + kFast, 1, "implausible distortion parameter k1 = 5"},
      {"RefinerImplausibleRadialDistortion", R, "RADIAL camera with k1 = 240",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) {
           for (auto& [id, camera] : m->cameras) {
             camera.model = CameraModel::kRadial;
             camera.params = {camera.params[0], camera.params[2], camera.params[3], 240, 0};
           }
         });
       },
       kWs + kFast, 1, "implausible distortion parameter k1 = 240"},
      {"RefinerFoldingDistortion", R, "OPENCV camera with k1 = -3 (the distortion folds over)",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) {
           for (auto& [id, camera] : m->cameras) {
             camera.model = CameraModel::kOpenCV;
             camera.params.insert(camera.params.end(), {-3, 0, 0, 0});
           }
         });
       },
       kWs + kFast, 1, "folds over"},
      // ---- mesh_refiner: images and masks ----
      {"RefinerMissingImage", R, "an image of the model missing from `images/`",
       [](const std::string& d) { fs::remove(d + "/ws/images/view_3.png"); }, kWs + kFast, 1,
       "are missing: view_3.png"},
      {"RefinerImageIsAFolder", R, "an image path that is a folder",
       [](const std::string& d) {
         fs::remove(d + "/ws/images/view_3.png");
         fs::create_directories(d + "/ws/images/view_3.png");
       },
       kWs + kFast, 1, "view_3.png: image 4 of the sparse model"},
      {"RefinerTruncatedPng", R, "a PNG image cut in the middle",
       [](const std::string& d) { Truncate(d + "/ws/images/view_2.png", 0.5); }, kWs + kFast, 1,
       "view_2.png: truncated or corrupt image"},
      {"RefinerTruncatedJpeg", R, "a JPEG image cut in the middle",
       [](const std::string& d) {
         const cv::Mat image = cv::imread(d + "/ws/images/view_2.png", cv::IMREAD_UNCHANGED);
         fs::remove(d + "/ws/images/view_2.png");
         cv::imwrite(d + "/ws/images/view_2.jpg", image);
         Truncate(d + "/ws/images/view_2.jpg", 0.6);
         EditModel(d, [](Reconstruction* m) {
           for (auto& [id, image] : m->images) {
             if (image.name == "view_2.png") image.name = "view_2.jpg";
           }
         });
       },
       kWs + kFast, 1, "view_2.jpg: truncated or corrupt image"},
      {"RefinerImageNotAnImage", R, "an image file that holds text",
       [](const std::string& d) { WriteText(d + "/ws/images/view_2.png", "not an image\n"); },
       kWs + kFast, 1, "view_2.png: not a JPEG, PNG, TIFF, BMP or PNM image"},
      {"RefinerImageInAnotherFormat", R, "a WebP image (a format OpenCV reads but we do not)",
       [](const std::string& d) {
         WriteText(d + "/ws/images/view_2.png", std::string("RIFF\x24\0\0\0WEBPVP8 ", 16));
       },
       kWs + kFast, 1, "view_2.png: not a JPEG, PNG, TIFF, BMP or PNM image"},
      {"RefinerImageHeaderOfAGigapixel", R,
       "a PNM image whose header claims 40000 x 40000 pixels (the decoder would allocate 4.8 GB)",
       [](const std::string& d) {
         WriteText(d + "/ws/images/view_2.png", "P6\n40000 40000\n255\n" + std::string(64, 'x'));
       },
       kWs + kFast, 1, "view_2.png: PNM header gives 40000 x 40000 pixels"},
      {"RefinerMasksMatchingNoImage", R,
       "`masks/` whose files match no image (`view_0.png`, not COLMAP's `view_0.png.png`)",
       [](const std::string& d) {
         fs::create_directories(d + "/ws/masks");
         cv::imwrite(d + "/ws/masks/view_0.png", cv::Mat(120, 160, CV_8U, cv::Scalar(255)));
       },
       kWs + kFast, 1, "no mask matches the images"},
      {"RefinerMaskWrongSize", R, "a mask of another size than its image",
       [](const std::string& d) {
         fs::create_directories(d + "/ws/masks");
         cv::imwrite(d + "/ws/masks/view_0.png.png", cv::Mat(60, 80, CV_8U, cv::Scalar(255)));
       },
       kWs + kFast, 1, "masks/view_0.png.png: is 80x60 but camera 1 is 160x120"},
      {"RefinerMaskFolderMissing", R, "`--mask_path` that does not exist", kNothing,
       kWs + " --mask_path {dir}/nomasks" + kFast, 1, "mask folder does not exist"},
      // ---- mesh_refiner: the mesh ----
      {"RefinerNoMesh", R, "workspace without `meshed-poisson.ply` or `meshed-delaunay.ply`",
       [](const std::string& d) { fs::remove(d + "/ws/meshed-poisson.ply"); }, kWs + kFast, 1,
       "no meshed-poisson.ply or meshed-delaunay.ply"},
      {"RefinerInputMissing", R, "`--input_path` that does not exist", kNothing,
       kWs + " --input_path {dir}/nope.ply" + kFast, 1, "nope.ply: cannot open file for reading"},
      {"RefinerInputIsAFolder", R, "`--input_path` is a folder",
       [](const std::string& d) { fs::create_directories(d + "/folder.ply"); },
       kWs + " --input_path {dir}/folder.ply" + kFast, 1,
       "folder.ply: is a folder; expected a PLY mesh"},
      {"RefinerTruncatedBinaryPly", R, "binary PLY mesh cut in the middle",
       [](const std::string& d) { Truncate(d + "/ws/meshed-poisson.ply", 0.6); }, kWs + kFast,
       1, "meshed-poisson.ply: truncated PLY body"},
      {"RefinerPlyVertexCountTooHigh", R, "PLY header announcing more vertices than there are",
       [](const std::string& d) {
         WriteText(d + "/ws/meshed-poisson.ply",
                   AsciiPly("0 0 0\n1 0 0\n0 1 0\n", 9, "3 0 1 2\n", 1));
       },
       kWs + kFast, 1, "meshed-poisson.ply: truncated PLY body"},
      {"RefinerPlyFaceIndexOutOfRange", R, "PLY face with a vertex index past the vertices",
       [](const std::string& d) {
         WriteText(d + "/ws/meshed-poisson.ply",
                   AsciiPly("0 0 0\n1 0 0\n0 1 0\n", 3, "3 0 1 7\n", 1));
       },
       kWs + kFast, 1, "face 0 has vertex index 7 out of range [0, 3)"},
      {"RefinerNotAPly", R, "mesh file that is not a PLY",
       [](const std::string& d) { WriteText(d + "/ws/meshed-poisson.ply", "solid stl\n"); },
       kWs + kFast, 1, "meshed-poisson.ply: not a PLY file"},
      {"RefinerNaNVertex", R, "PLY mesh with a NaN vertex coordinate",
       [](const std::string& d) {
         WriteText(d + "/ws/meshed-poisson.ply", SphereWithBadVertex("nan"));
       },
       kWs + kFast, 1, "meshed-poisson.ply: vertex 3 has a non-finite x (nan)"},
      {"RefinerPointCloud", R, "PLY with vertices and no faces (a point cloud)",
       [](const std::string& d) {
         WriteText(d + "/ws/meshed-poisson.ply", AsciiPly("0 0 0\n1 0 0\n0 1 0\n", 3, "", 0));
       },
       kWs + kFast, 1, "no faces"},
      {"RefinerOneTriangle", R, "a one-triangle mesh",
       [](const std::string& d) {
         WriteText(d + "/ws/meshed-poisson.ply",
                   AsciiPly("0 0 0\n0.5 0 0\n0 0.5 0\n", 3, "3 0 1 2\n", 1));
       },
       kWs + kFast, 1, "the mesh has 1 face; at least 20"},
      {"RefinerInvisibleMesh", R, "a mesh that no camera sees (far away)",
       [](const std::string& d) {
         TriangleMesh mesh = Sphere(2, 1.0);
         mesh.V.col(2).array() += 1000.0;
         WritePly(d + "/ws/meshed-poisson.ply", mesh);
       },
       kWs + kFast, 1, "meshed-poisson.ply: the mesh is not visible in any view"},
      {"RefinerViewsWithoutOverlap", R, "two opposite views only: no pair sees the same surface",
       [](const std::string& d) {
         EditModel(d, [](Reconstruction* m) {
           for (uint32_t id = 1; id <= 8; ++id) {
             if (id != 1 && id != 5) m->images.erase(id);
           }
         });
       },
       kWs + kFast, 1, "overlap"},
      // ---- mesh_refiner: options ----
      {"RefinerUnknownOption", R, "an unknown option", kNothing, kWs + " --Refine.bogus 1", 1,
       "unknown option 'Refine.bogus'"},
      {"RefinerOptionOutOfRange", R, "`--Refine.num_levels 9`", kNothing,
       kWs + " --Refine.num_levels 9", 1, "RefineOptions::num_levels = 9. Violated constraint"},
      {"RefinerMaxImageSizeZero", R, "`--Refine.max_image_size 0`", kNothing,
       kWs + " --Refine.max_image_size 0", 1,
       "RefineOptions::max_image_size = 0. Violated constraint: max_image_size >= 32 or -1"},
      {"RefinerAverageLastIteratesZero", R, "`--Refine.average_last_iterates 0`", kNothing,
       kWs + " --Refine.average_last_iterates 0", 1,
       "RefineOptions::average_last_iterates = 0. Violated constraint: average_last_iterates >= 1"},
      {"RefinerCameraRoundsZero", R, "`--Refine.camera_rounds 0`", kNothing,
       kWs + " --Refine.camera_rounds 0", 1,
       "RefineOptions::camera_rounds = 0. Violated constraint: camera_rounds >= 1"},
      {"RefinerOutputSubdivisionsThree", R, "`--Refine.output_subdivisions 3`", kNothing,
       kWs + " --Refine.output_subdivisions 3", 1,
       "RefineOptions::output_subdivisions = 3. Violated constraint: "
       "0 <= output_subdivisions <= 2"},
      {"RefinerFairingWeightUnstable", R, "`--Denoise.fairing_weight 0.5`", kNothing,
       kWs + " --Denoise.fairing_weight 0.5", 1,
       "DenoiseOptions::fairing_weight = 0.5. Violated constraint: "
       "0 <= fairing_weight < 0.5 (stability)"},
      {"RefinerMaskOutlineOffsetNegative", R, "`--MaskOutline.min_offset_px -1`", kNothing,
       kWs + " --MaskOutline.min_offset_px -1", 1,
       "MaskOutlineOptions::min_offset_px = -1. Violated constraint: min_offset_px >= 0"},
      {"RefinerRefineCamerasUnknown", R, "`--Refine.refine_cameras all`", kNothing,
       kWs + " --Refine.refine_cameras all", 1,
       "RefineOptions::refine_cameras = all. Violated constraint: one of none, poses, "
       "poses_intrinsics"},
      {"RefinerLightUnknown", R, "`--Refine.light sun`", kNothing, kWs + " --Refine.light sun", 1,
       "RefineOptions::light = sun. Violated constraint: one of world, headlight, auto"},
      {"RefinerOptionNotANumber", R, "`--Refine.step abc`", kNothing, kWs + " --Refine.step abc",
       1, "--Refine.step abc: expected a finite number"},
      {"RefinerOptionNaN", R, "`--Refine.step nan`", kNothing, kWs + " --Refine.step nan", 1,
       "--Refine.step nan: expected a finite number"},
      {"RefinerOptionBadString", R, "`--Refine.similarity ssd`", kNothing,
       kWs + " --Refine.similarity ssd", 1, "RefineOptions::similarity = ssd"},
      {"RefinerOptionMissingValue", R, "an option without its value", kNothing,
       kWs + " --Refine.step", 1, "--Refine.step: missing value"},
      {"RefinerPositionalArgument", R, "a bare argument", kNothing, kWs + " extra", 1,
       "unexpected argument 'extra'"},
      {"RefinerMissingRequired", R, "no `--workspace_path`", kNothing, kFast, 1,
       "missing required option --workspace_path"},
      {"RefinerConfigMissing", R, "`--config_path` that does not exist", kNothing,
       kWs + " --config_path {dir}/nope.ini", 1, "nope.ini: cannot open file"},
      {"RefinerConfigUnknownKey", R, "config file with an unknown key",
       [](const std::string& d) { WriteText(d + "/c.ini", "[Refine]\nbogus = 1\n"); },
       kWs + " --config_path {dir}/c.ini", 1, "c.ini:2: unknown option 'Refine.bogus'"},
      {"RefinerConfigMalformed", R, "config file with a line that is not key=value",
       [](const std::string& d) { WriteText(d + "/c.ini", "[Refine]\nnum_levels\n"); },
       kWs + " --config_path {dir}/c.ini", 1, "c.ini:2: expected 'key=value'"},
      {"RefinerHoldoutNameUnknown", R, "`--holdout_path` naming an image the model lacks",
       [](const std::string& d) { WriteText(d + "/holdout.txt", "view_1.png\nview_9.png\n"); },
       kWs + " --holdout_path {dir}/holdout.txt" + kFast, 1, "view_9.png"},
      {"RefinerHoldoutMissing", R, "`--holdout_path` that does not exist", kNothing,
       kWs + " --holdout_path {dir}/nope.txt" + kFast, 1, "nope.txt: cannot open file for reading"},
      // ---- mesh_refiner: outputs ----
      {"RefinerOutputOverInputMesh", R, "`--output_path` is the input mesh", kNothing,
       kWs + " --output_path {dir}/ws/meshed-poisson.ply" + kFast, 1, "refusing to overwrite"},
      {"RefinerOutputInsideSparse", R, "`--output_path` inside the sparse model folder",
       kNothing, kWs + " --output_path {dir}/ws/sparse/out.ply" + kFast, 1,
       "is inside the input folder"},
      {"RefinerOutputIsAFolder", R, "`--output_path` is an existing folder",
       [](const std::string& d) { fs::create_directories(d + "/folder.ply"); },
       kWs + " --output_path {dir}/folder.ply" + kFast, 1, "is a folder"},
      {"RefinerOutputFolderMissing", R, "`--output_path` in a folder that does not exist",
       kNothing, kWs + " --output_path {dir}/nope/out.ply" + kFast, 1, "does not exist"},
      {"RefinerOutputInProc", R, "`--output_path` in `/proc` (no file can be created)", kNothing,
       kWs + " --output_path /proc/out.ply" + kFast, 1,
       "cannot create a file in folder /proc"},
      {"RefinerOutputInSys", R, "`--output_path` in `/sys` (read-only to everyone)", kNothing,
       kWs + " --output_path /sys/out.ply" + kFast, 1, "cannot create a file in folder /sys"},
      {"RefinerOutputBadExtension", R, "`--output_path out.stl`", kNothing,
       kWs + " --output_path {dir}/out.stl" + kFast, 1, "expected .ply or .obj"},
      {"RefinerWriteConfigOverInput", R, "`--write_config` is the sparse model's cameras.bin",
       kNothing, kWs + " --write_config {dir}/ws/sparse/cameras.bin", 1,
       "refusing to overwrite"},
      {"RefinerWriteConfigInProc", R, "`--write_config` in `/proc`", kNothing,
       kWs + " --write_config /proc/refine.ini", 1, "cannot create a file in folder /proc"},
      {"RefinerWriteConfigIsAFolder", R, "`--write_config` is a folder",
       [](const std::string& d) { fs::create_directories(d + "/c.ini"); },
       kWs + " --write_config {dir}/c.ini", 1, "is a folder"},

      // ---- mesh_denoiser ----
      {"DenoiserInputMissing", D, "`--input_path` that does not exist", kNothing,
       " --input_path {dir}/nope.ply --output_path {dir}/out.ply", 1, "nope.ply: no such file"},
      {"DenoiserInputExtension", D, "`--input_path m.stl`",
       [](const std::string& d) { fs::copy_file(d + "/m.ply", d + "/m.stl"); },
       " --input_path {dir}/m.stl --output_path {dir}/out.ply", 1, "expected .ply or .obj"},
      {"DenoiserOutputExtension", D, "`--output_path out.stl`", kNothing,
       " --input_path {dir}/m.ply --output_path {dir}/out.stl", 1, "expected .ply or .obj"},
      {"DenoiserOutputOverInput", D, "`--output_path` is the input", kNothing,
       " --input_path {dir}/m.ply --output_path {dir}/sub/../m.ply", 1,
       "refusing to overwrite"},
      {"DenoiserOutputIsAFolder", D, "`--output_path` is a folder",
       [](const std::string& d) { fs::create_directories(d + "/folder.ply"); },
       " --input_path {dir}/m.ply --output_path {dir}/folder.ply", 1, "is a folder"},
      {"DenoiserOutputInProc", D, "`--output_path` in `/proc`", kNothing,
       " --input_path {dir}/m.ply --output_path /proc/out.ply", 1,
       "cannot create a file in folder /proc"},
      {"DenoiserOutputFolderMissing", D, "`--output_path` in a folder that does not exist",
       kNothing, " --input_path {dir}/m.ply --output_path {dir}/nope/out.ply", 1,
       "does not exist"},
      {"DenoiserTruncatedPly", D, "binary PLY cut in the middle",
       [](const std::string& d) { Truncate(d + "/m.ply", 0.6); }, kDenoise, 1,
       "m.ply: truncated PLY body"},
      {"DenoiserNaNVertex", D, "PLY with a NaN vertex coordinate",
       [](const std::string& d) { WriteText(d + "/m.ply", SphereWithBadVertex("nan")); },
       kDenoise, 1, "m.ply: vertex 3 has a non-finite x (nan)"},
      {"DenoiserInfVertex", D, "PLY with an infinite vertex coordinate",
       [](const std::string& d) { WriteText(d + "/m.ply", SphereWithBadVertex("inf")); },
       kDenoise, 1, "m.ply: vertex 3 has a non-finite x (inf)"},
      {"DenoiserBadObjFace", D, "OBJ with a face index past the vertices",
       [](const std::string& d) {
         WriteText(d + "/m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
       },
       " --input_path {dir}/m.obj --output_path {dir}/out.ply", 1,
       "m.obj:4: face vertex index 9 out of range"},
      {"DenoiserEmptyMesh", D, "PLY with no faces",
       [](const std::string& d) {
         WriteText(d + "/m.ply", AsciiPly("0 0 0\n1 0 0\n0 1 0\n", 3, "", 0));
       },
       kDenoise, 1, "no faces"},
      {"DenoiserBadMethod", D, "`--Denoise.method foo`", kNothing,
       kDenoise + " --Denoise.method foo", 1, "method = foo"},
      {"DenoiserUnknownOption", D, "an unknown option", kNothing, kDenoise + " --bogus 1", 1,
       "unknown option 'bogus'"},
      {"DenoiserMissingOutput", D, "no `--output_path`", kNothing, " --input_path {dir}/m.ply", 1,
       "missing required option --output_path"},
      {"DenoiserWriteConfigOverInput", D, "`--write_config` is the input mesh", kNothing,
       kDenoise + " --write_config {dir}/m.ply", 1, "refusing to overwrite"},

      // ---- mesh_evaluator ----
      {"EvaluatorGroundTruthMissing", E, "`--gt_path` that does not exist", kNothing,
       " --input_path {dir}/m.ply --gt_path {dir}/nope.ply", 1, "nope.ply: file does not exist"},
      {"EvaluatorInputIsAFolder", E, "`--input_path` is a folder",
       [](const std::string& d) { fs::create_directories(d + "/folder.ply"); },
       " --input_path {dir}/folder.ply --gt_path {dir}/gt.ply", 1,
       "folder.ply: is a folder; expected a mesh file"},
      {"EvaluatorGroundTruthPointCloud", E, "ground truth with no faces",
       [](const std::string& d) {
         WriteText(d + "/gt.ply", AsciiPly("0 0 0\n1 0 0\n0 1 0\n", 3, "", 0));
       },
       kEvaluate, 1, "gt.ply: mesh has no faces"},
      {"EvaluatorTruncatedInput", E, "evaluated PLY cut in the middle",
       [](const std::string& d) { Truncate(d + "/m.ply", 0.6); }, kEvaluate, 1,
       "m.ply: truncated PLY body"},
      {"EvaluatorGroundTruthNaN", E, "ground truth with a NaN vertex",
       [](const std::string& d) { WriteText(d + "/gt.ply", SphereWithBadVertex("nan")); },
       kEvaluate, 1, "gt.ply: vertex 3 has a non-finite x (nan)"},
      {"EvaluatorZeroThreshold", E, "`--threshold 0`", kNothing, kEvaluate + " --threshold 0", 1,
       "EvaluationOptions::threshold = 0. Violated constraint"},
      {"EvaluatorZeroSamples", E, "`--num_samples 0`", kNothing,
       " --input_path {dir}/m.ply --gt_path {dir}/gt.ply --num_samples 0", 1,
       "num_samples = 0. Violated constraint: num_samples >= 1"},
      {"EvaluatorNegativeSeed", E, "`--seed -1`", kNothing, kEvaluate + " --seed -1", 1,
       "seed = -1"},
      {"EvaluatorZeroMinViews", E, "`--min_views 0` with a workspace", kNothing,
       kEvaluate + " --workspace_path {dir}/ws --min_views 0", 1, "--min_views 0: expected >= 1"},
      {"EvaluatorWorkspaceMissing", E, "`--workspace_path` that does not exist", kNothing,
       kEvaluate + " --workspace_path {dir}/nope", 1, "workspace folder does not exist"},
      {"EvaluatorSparsePathAlone", E, "`--sparse_path` without `--true_sparse_path`", kNothing,
       kEvaluate + " --sparse_path {dir}/ws/sparse", 1,
       "--sparse_path and --true_sparse_path go together (got only --sparse_path)"},
      {"EvaluatorAlignWithoutModels", E, "`--align_cameras 1` without the two models", kNothing,
       kEvaluate + " --align_cameras 1", 1,
       "--align_cameras needs --sparse_path and --true_sparse_path"},
      {"EvaluatorTrueSparseMissing", E, "`--true_sparse_path` that does not exist", kNothing,
       kEvaluate + " --sparse_path {dir}/ws/sparse --true_sparse_path {dir}/nope", 1,
       "nope: folder does not exist"},
      {"EvaluatorTrueModelLacksImage", E, "the true model lacks an image of `--sparse_path`",
       [](const std::string& d) {
         Reconstruction model = ReadSparseModel(d + "/ws/sparse");
         model.images.begin()->second.name = "elsewhere.png";
         fs::create_directories(d + "/other");
         WriteSparseModelBinary(d + "/other", model);
       },
       kEvaluate + " --sparse_path {dir}/ws/sparse --true_sparse_path {dir}/other", 1,
       ") is not in the true model"},
      {"EvaluatorErrorMapOverGroundTruth", E, "`--output_error_path` is the ground truth",
       kNothing, kEvaluate + " --output_error_path {dir}/gt.ply", 1,
       "refusing to overwrite an input"},
      {"EvaluatorErrorMapNotPly", E, "`--output_error_path map.obj`", kNothing,
       kEvaluate + " --output_error_path {dir}/map.obj", 1, "expected a .ply file"},
      {"EvaluatorNegativeErrorMax", E, "`--error_max -1`", kNothing,
       kEvaluate + " --output_error_path {dir}/map.ply --error_max -1", 1,
       "--error_max -1: expected >= 0"},
      {"EvaluatorUnknownErrorMap", E, "`--error_map colour`", kNothing,
       kEvaluate + " --output_error_path {dir}/map.ply --error_map colour", 1,
       "--error_map colour: expected distance or normal"},
      {"EvaluatorUnknownOption", E, "an unknown option", kNothing, kEvaluate + " --bogus 1", 1,
       "unknown option 'bogus'"},
      {"EvaluatorWriteConfigOverGroundTruth", E, "`--write_config` is the ground truth", kNothing,
       kEvaluate + " --write_config {dir}/gt.ply", 1, "refusing to overwrite"},
      {"EvaluatorWriteConfigInSys", E, "`--write_config` in `/sys`", kNothing,
       kEvaluate + " --write_config /sys/e.ini", 1, "cannot create a file in folder /sys"},
  };
}

// Every file and folder under `dir` with its bytes (folders: a marker).
std::map<std::string, std::string> Snapshot(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string name = fs::relative(entry.path(), dir).string();
    if (entry.is_directory()) {
      files[name] = "<folder>";
    } else if (entry.is_regular_file()) {
      files[name] = ReadFileToString(entry.path().string());
    } else {
      files[name] = "<other>";
    }
  }
  return files;
}

std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t pos = text.find(from); pos != std::string::npos; pos = text.find(from, pos)) {
    text.replace(pos, from.size(), to);
    pos += to.size();
  }
  return text;
}

// gtest prints the row by its name (not as bytes) in failure reports.
void PrintTo(const BadInput& row, std::ostream* out) { *out << row.program << ": " << row.name; }

class BadInputTable : public ::testing::TestWithParam<BadInput> {
 protected:
  // The base folder: a workspace of 8 rendered views of a bumpy sphere with
  // a PINHOLE model and a smooth sphere as the mesh; two meshes beside it;
  // the existing outputs. CTest runs every row in its own process, so it is
  // made once per build of this test (named after the executable's time
  // stamp) and kept in the temporary folder; folders of earlier builds are
  // removed.
  static void SetUpTestSuite() {
    std::error_code ec;
    const auto stamp = fs::last_write_time("/proc/self/exe", ec).time_since_epoch().count();
    const fs::path tmp = fs::temp_directory_path();
    const std::string prefix = "mr_bad_input_base_";
    base_ = (tmp / (prefix + std::to_string(stamp))).string();
    if (ExistsFile(base_ + "/complete")) return;
    for (const auto& entry : fs::directory_iterator(tmp, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(prefix, 0) == 0 && entry.path().string() != base_) {
        fs::remove_all(entry.path(), ec);
      }
    }
    // Built beside, then renamed into place: parallel test processes either
    // find it complete or build their own.
    const std::string building = base_ + "_building_" + std::to_string(::getpid());
    fs::remove_all(building);
    BuildBase(building);
    WriteText(building + "/complete", "");
    fs::rename(building, base_, ec);
    if (ec) fs::remove_all(building);  // another process was first
    ASSERT_TRUE(ExistsFile(base_ + "/complete"));
  }

  static void BuildBase(const std::string& base) {
    fs::create_directories(base + "/sub");
    WriteRenderedTestWorkspace(base + "/ws");
    WritePly(base + "/ws/meshed-poisson.ply", Sphere(3, 1.0));
    WriteText(base + "/ws/meshed-refined.ply", kExistingOutput);
    WritePly(base + "/m.ply", Sphere(2, 1.0));
    WritePly(base + "/gt.ply", Sphere(3, 1.01));
    WriteText(base + "/out.ply", kExistingOutput);
  }

  static std::string base_;
};
std::string BadInputTable::base_;

TEST_P(BadInputTable, RefusedAndNothingChanged) {
  const BadInput& row = GetParam();
  const std::string dir = FreshTestPath("bad_input_" + row.name);
  fs::copy(base_, dir, fs::copy_options::recursive);
  fs::remove(dir + "/complete");
  row.prepare(dir);
  const std::map<std::string, std::string> before = Snapshot(dir);

  const std::string command =
      std::string(MR_BIN_DIR) + "/" + row.program + ReplaceAll(row.args, "{dir}", dir);
  const CommandResult r = RunCommand(command);
  EXPECT_EQ(r.exit_code, row.exit_code) << command << "\n" << r.output;
  EXPECT_NE(r.output.find(row.message), std::string::npos)
      << "expected '" << row.message << "' in the output of\n" << command << "\n" << r.output;
  if (row.exit_code == 1) {
    EXPECT_NE(r.output.find("ERROR: "), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("ERROR (internal)"), std::string::npos) << r.output;
  }

  // The case folder is exactly as it was: outputs byte-identical, nothing
  // temporary left, nothing added.
  const std::map<std::string, std::string> after = Snapshot(dir);
  for (const auto& [name, bytes] : after) {
    EXPECT_EQ(name.find(".tmp."), std::string::npos) << "left behind: " << name;
    const auto it = before.find(name);
    if (it == before.end()) {
      ADD_FAILURE() << "created: " << name;
    } else if (it->second != bytes) {
      ADD_FAILURE() << "changed: " << name;
    }
  }
  for (const auto& [name, bytes] : before) {
    if (!after.count(name)) ADD_FAILURE() << "removed: " << name;
  }
  EXPECT_EQ(ReadFileToString(dir + "/ws/meshed-refined.ply"), kExistingOutput);
  EXPECT_EQ(ReadFileToString(dir + "/out.ply"), kExistingOutput);

  // The row of docs/bad_inputs.md, with the message as printed.
  std::string line;
  for (size_t pos = r.output.find("ERROR"); pos != std::string::npos;) {
    line = r.output.substr(pos, r.output.find('\n', pos) - pos);
    break;
  }
  std::printf("| %s | %s | %d | `%s` |\n", row.program.c_str(), row.description.c_str(),
              r.exit_code, ReplaceAll(line, dir, "...").c_str());
  if (!HasFailure()) fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Programs, BadInputTable, ::testing::ValuesIn(Table()),
                         [](const ::testing::TestParamInfo<BadInput>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace mr
