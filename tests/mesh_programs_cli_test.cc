// End-to-end tests of mesh_denoiser and mesh_evaluator as a user runs them:
// no output may replace an input, however its path is spelled.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "tests/command.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

const std::string kDenoiser = std::string(MR_BIN_DIR) + "/mesh_denoiser";
const std::string kEvaluator = std::string(MR_BIN_DIR) + "/mesh_evaluator";
const std::string kInitializer = std::string(MR_BIN_DIR) + "/mesh_initializer";
const std::string kMiddlebury = std::string(MR_BIN_DIR) + "/middlebury_to_colmap";
const std::string kRender = std::string(MR_BIN_DIR) + "/mesh_render";
const std::string kSynthesizer = std::string(MR_BIN_DIR) + "/workspace_synthesizer";

// An octahedron: small, closed, and quick for both programs.
TriangleMesh Octahedron(double scale) {
  TriangleMesh mesh;
  mesh.V.resize(6, 3);
  mesh.V << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1;
  mesh.V *= scale;
  mesh.F.resize(8, 3);
  mesh.F << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
  return mesh;
}

class MeshProgramsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = FreshTestPath(
        "cli_programs_" +
        std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_ + "/sub");
    WritePly(dir_ + "/m.ply", Octahedron(1.0));
    WritePly(dir_ + "/gt.ply", Octahedron(1.01));
    mesh_bytes_ = ReadFileToString(dir_ + "/m.ply");
    gt_bytes_ = ReadFileToString(dir_ + "/gt.ply");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Refused: exit code 1, an ERROR line with `message`, the inputs
  // byte-identical and no temporary file left.
  void ExpectRefused(const std::string& command, const std::string& message) {
    const CommandResult r = RunCommand(command);
    EXPECT_EQ(r.exit_code, 1) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("ERROR: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << command << "\n" << r.output;
    EXPECT_TRUE(ReadFileToString(dir_ + "/m.ply") == mesh_bytes_) << "m.ply was changed";
    EXPECT_TRUE(ReadFileToString(dir_ + "/gt.ply") == gt_bytes_) << "gt.ply was changed";
    for (const auto& name : ListFiles(dir_)) {
      EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
    }
  }

  std::string dir_, mesh_bytes_, gt_bytes_;
};

TEST_F(MeshProgramsCli, DenoiserOutputOverInputIsRefused) {
  const std::string m = dir_ + "/m.ply";
  ExpectRefused(kDenoiser + " --input_path " + m + " --output_path " + m, "refusing to overwrite");
  ExpectRefused(kDenoiser + " --input_path " + m + " --output_path " + dir_ + "/sub/../m.ply",
                "refusing to overwrite");
  ExpectRefused("cd " + dir_ + "/sub && " + kDenoiser + " --input_path ../m.ply --output_path " +
                    m,
                "refusing to overwrite");
  fs::create_symlink(m, dir_ + "/link.ply");
  ExpectRefused(kDenoiser + " --input_path " + dir_ + "/link.ply --output_path " + m,
                "refusing to overwrite");
  fs::create_hard_link(m, dir_ + "/hard.ply");
  ExpectRefused(kDenoiser + " --input_path " + dir_ + "/hard.ply --output_path " + m,
                "refusing to overwrite");
  // A different file is written.
  const CommandResult r =
      RunCommand(kDenoiser + " --input_path " + m + " --output_path " + dir_ + "/out.ply");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadMesh(dir_ + "/out.ply").NumFaces(), 8);
}

TEST_F(MeshProgramsCli, DenoiserWriteConfigOverInputIsRefused) {
  const std::string m = dir_ + "/m.ply";
  ExpectRefused(kDenoiser + " --input_path " + m + " --output_path " + dir_ + "/out.ply" +
                    " --write_config " + m,
                "refusing to overwrite");
  const CommandResult r = RunCommand(kDenoiser + " --input_path " + m + " --output_path " + dir_ +
                                     "/out.ply --write_config " + dir_ + "/d.ini");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(ExistsFile(dir_ + "/d.ini"));
}

TEST_F(MeshProgramsCli, DenoiserOutputExtension) {
  std::ofstream(dir_ + "/out.stl") << "sentinel";
  ExpectRefused(kDenoiser + " --input_path " + dir_ + "/m.ply --output_path " + dir_ + "/out.stl",
                "expected .ply or .obj");
  EXPECT_EQ(ReadFileToString(dir_ + "/out.stl"), "sentinel");
}

TEST_F(MeshProgramsCli, EvaluatorWriteConfigOverInputIsRefused) {
  const std::string args = " --input_path " + dir_ + "/m.ply --gt_path " + dir_ + "/gt.ply";
  ExpectRefused(kEvaluator + args + " --write_config " + dir_ + "/gt.ply", "refusing to overwrite");
  ExpectRefused(kEvaluator + args + " --write_config " + dir_ + "/sub/../m.ply",
                "refusing to overwrite");
  const CommandResult r = RunCommand(kEvaluator + args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("accuracy90"), std::string::npos) << r.output;
}

// --region_box keeps the ground truth whose faces' centroids lie in the box:
// a second octahedron 10 units away, missing from the mesh, leaves the
// completeness at about half without it and whole with a box around the
// first one.
TEST_F(MeshProgramsCli, EvaluatorRegionBox) {
  TriangleMesh gt = Octahedron(1.01);
  const TriangleMesh far = Octahedron(1.01);
  gt.V.conservativeResize(12, 3);
  gt.V.bottomRows(6) = far.V.rowwise() + Eigen::RowVector3d(10, 0, 0);
  gt.F.conservativeResize(16, 3);
  gt.F.bottomRows(8) = far.F.array() + 6;
  WritePly(dir_ + "/two.ply", gt);
  const std::string evaluate = kEvaluator + " --input_path " + dir_ + "/m.ply --gt_path " + dir_ +
                               "/two.ply --num_samples 4000 --threshold 0.05";
  const auto number = [](const std::string& json, const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key << " in " << json;
    return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size() + 4));
  };
  const CommandResult all = RunCommand(evaluate);
  ASSERT_EQ(all.exit_code, 0) << all.output;
  EXPECT_NEAR(number(all.output, "completeness"), 50, 3) << all.output;
  const CommandResult box = RunCommand(evaluate + " --region_box \"-2 -2 -2 2 2 2\"");
  ASSERT_EQ(box.exit_code, 0) << box.output;
  EXPECT_GT(number(box.output, "completeness"), 99) << box.output;
  EXPECT_NEAR(number(box.output, "observed_percent"), 50, 1e-6) << box.output;
  EXPECT_LT(number(box.output, "accuracy90"), 0.02) << box.output;
  const CommandResult commas = RunCommand(evaluate + " --region_box -2,-2,-2,2,2,2");
  ASSERT_EQ(commas.exit_code, 0) << commas.output;
  EXPECT_EQ(commas.output, box.output);
  for (const std::string bad : {"1 2 3", "0 0 0 -1 1 1", "a b c d e f", "0 0 0 1 1 1 7"}) {
    ExpectRefused(evaluate + " --region_box \"" + bad + "\"", "expected six numbers");
  }
  ExpectRefused(evaluate + " --region_box \"50 50 50 60 60 60\"",
                "no (observed) ground-truth face");
}

// The other programs name their inputs too: --write_config is refused over
// a workspace's model or lists, into a Middlebury data set folder, and over
// a second mesh. (Refused before the inputs are read, so stand-ins do.)
// --sparse_path / --true_sparse_path: two PINHOLE cameras (fx 500) 5 units
// from the ground truth's centre, one of them moved 0.01 units sideways in
// its own frame. The moved view's ground-truth vertices lie at depths 3.99,
// 6.01 and 5 (four of them), so they move by 500 * 0.01 / depth pixels: RMS
// 1.0216 px; over both images sqrt(1.0216^2 / 2) = 0.7224 px.
TEST_F(MeshProgramsCli, EvaluatorComparesCamerasWithTheTrueOnes) {
  Reconstruction truth;
  for (uint32_t id : {1u, 2u}) {
    Camera camera;
    camera.camera_id = id;
    camera.model = CameraModel::kPinhole;
    camera.width = 640;
    camera.height = 480;
    camera.params = {500, 500, 320, 240};
    truth.cameras[id] = camera;
    Image image;
    image.image_id = id;
    image.camera_id = id;
    image.name = id == 1 ? "a.png" : "b.png";
    // a: at (0, 0, -5) looking along +z; b: at (-5, 0, 0) looking along +x.
    image.qvec = id == 1 ? Eigen::Vector4d(1, 0, 0, 0)
                         : Eigen::Vector4d(std::sqrt(0.5), 0, -std::sqrt(0.5), 0);
    image.tvec = Eigen::Vector3d(0, 0, 5);
    truth.images[id] = image;
  }
  Reconstruction moved = truth;
  moved.images.at(2).tvec.x() += 0.01;
  for (const auto& [name, model] : {std::make_pair("true", truth), std::make_pair("moved", moved)}) {
    fs::create_directories(dir_ + "/" + name);
    WriteSparseModelBinary(dir_ + "/" + name, model);
  }
  const std::string evaluate = kEvaluator + " --input_path " + dir_ + "/m.ply --gt_path " + dir_ +
                               "/gt.ply --num_samples 1000 --true_sparse_path " + dir_ + "/true";
  const auto number = [](const std::string& json, const std::string& key) {
    const size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key << " in " << json;
    return at == std::string::npos ? -1.0 : std::stod(json.substr(at + key.size() + 4));
  };
  const CommandResult same = RunCommand(evaluate + " --sparse_path " + dir_ + "/true");
  ASSERT_EQ(same.exit_code, 0) << same.output;
  EXPECT_EQ(number(same.output, "camera_images"), 2);
  EXPECT_LT(number(same.output, "camera_rms_px"), 1e-9);
  const CommandResult off = RunCommand(evaluate + " --sparse_path " + dir_ + "/moved");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_NEAR(number(off.output, "camera_rms_px"), 0.7224, 1e-3) << off.output;
  EXPECT_NEAR(number(off.output, "camera_max_rms_px"), 1.0216, 1e-3) << off.output;
  EXPECT_NE(off.output.find("\"camera_max_rms_image\": \"b.png\""), std::string::npos)
      << off.output;
  EXPECT_EQ(number(off.output, "camera_max_focal_percent"), 0);
  EXPECT_NE(off.output.find("\"accuracy90\": "), std::string::npos) << off.output;

  // --align_cameras: both cameras moved 0.02 units along world x (the world
  // moved, a gauge change) compare as equal once aligned, and the alignment
  // says how far it carried them; without it they are 2 px off.
  Reconstruction shifted = truth;
  for (auto& [id, image] : shifted.images) {
    image.tvec -= QuaternionToRotation(image.qvec) * Eigen::Vector3d(0.02, 0, 0);
  }
  fs::create_directories(dir_ + "/shifted");
  WriteSparseModelBinary(dir_ + "/shifted", shifted);
  const CommandResult raw = RunCommand(evaluate + " --sparse_path " + dir_ + "/shifted");
  ASSERT_EQ(raw.exit_code, 0) << raw.output;
  EXPECT_GT(number(raw.output, "camera_rms_px"), 1) << raw.output;
  const CommandResult aligned =
      RunCommand(evaluate + " --sparse_path " + dir_ + "/shifted --align_cameras 1");
  ASSERT_EQ(aligned.exit_code, 0) << aligned.output;
  EXPECT_LT(number(aligned.output, "camera_rms_px"), 1e-4) << aligned.output;
  EXPECT_NEAR(number(aligned.output, "alignment_shift"), 0.02, 1e-5) << aligned.output;
  EXPECT_NEAR(number(aligned.output, "alignment_scale"), 1, 1e-5) << aligned.output;
  EXPECT_LT(number(aligned.output, "alignment_rotation_deg"), 1e-3) << aligned.output;
}

TEST_F(MeshProgramsCli, OtherProgramsWriteConfigOverInputIsRefused) {
  const std::string ws = dir_ + "/ws", cameras = ws + "/sparse/cameras.bin";
  fs::create_directories(ws + "/sparse");
  std::ofstream(cameras) << "model";
  std::ofstream(ws + "/holdout.txt") << "a.png\n";
  ExpectRefused(kInitializer + " --workspace_path " + ws + " --write_config " + cameras,
                "refusing to overwrite");
  ExpectRefused(kInitializer + " --workspace_path " + ws + " --write_config " + ws + "/holdout.txt",
                "refusing to overwrite");
  EXPECT_EQ(ReadFileToString(cameras), "model");
  EXPECT_EQ(ReadFileToString(ws + "/holdout.txt"), "a.png\n");

  const std::string mb = dir_ + "/temple";
  fs::create_directories(mb);
  std::ofstream(mb + "/temple_par.txt") << "0\n";
  ExpectRefused(kMiddlebury + " --input_path " + mb + " --output_path " + dir_ + "/out" +
                    " --write_config " + mb + "/temple_par.txt",
                "refusing to overwrite");
  EXPECT_EQ(ReadFileToString(mb + "/temple_par.txt"), "0\n");

  ExpectRefused(kRender + " --input_path " + dir_ + "/m.ply --output_path " + dir_ +
                    "/r.png --side_by_side " + dir_ + "/gt.ply --write_config " + dir_ + "/gt.ply",
                "refusing to overwrite");
}

// Every program refuses, before reading its inputs, an output it could not
// write: in a virtual file system (/proc, /sys; root cannot create files
// there either), an existing folder where a file is expected, a file where a
// folder is expected. An existing output is left as it was.
TEST_F(MeshProgramsCli, UnwritableOutputsAreRefusedBeforeAnyWork) {
  const std::string m = dir_ + "/m.ply";
  fs::create_directories(dir_ + "/folder.ply");
  std::ofstream(dir_ + "/out.ply") << "sentinel";
  const std::string denoise = kDenoiser + " --input_path " + m + " --output_path ";
  ExpectRefused(denoise + "/proc/out.ply", "--output_path /proc/out.ply: cannot create a file");
  ExpectRefused(denoise + "/sys/out.ply", "cannot create a file in folder /sys");
  ExpectRefused(denoise + dir_ + "/folder.ply", "is a folder");
  ExpectRefused(denoise + dir_ + "/out.ply --write_config /proc/d.ini",
                "--write_config /proc/d.ini: cannot create a file in folder /proc");
  EXPECT_EQ(ReadFileToString(dir_ + "/out.ply"), "sentinel");
  ExpectRefused(kEvaluator + " --input_path " + m + " --gt_path " + dir_ +
                    "/gt.ply --write_config /sys/e.ini",
                "--write_config /sys/e.ini: cannot create a file in folder /sys");
  // The workspace is never opened (it does not exist): refused first.
  ExpectRefused(kInitializer + " --workspace_path " + dir_ + "/ws --output_path /proc/hull.ply",
                "--output_path /proc/hull.ply: cannot create a file");
  ExpectRefused(kRender + " --input_path " + m + " --view \"0 0\" --output_path /proc/r.png",
                "--output_path /proc/r.png: cannot create a file");
  ExpectRefused(kRender + " --input_path " + m + " --view \"0 0\" --output_path " + dir_ +
                    "/folder.ply",
                "is a folder");
  ExpectRefused(kMiddlebury + " --input_path " + dir_ + "/temple --output_path /proc/mb",
                "--output_path /proc/mb: cannot create files in folder /proc");
  ExpectRefused(kMiddlebury + " --input_path " + dir_ + "/temple --output_path " + m + "/ws",
                "is not a folder");
  ExpectRefused(kSynthesizer + " --output_path /proc/synth/deeper",
                "--output_path /proc/synth/deeper: cannot create files in folder /proc");
  ExpectRefused(kSynthesizer + " --output_path " + m, "is a file; expected a folder");
}

}  // namespace
}  // namespace mr
