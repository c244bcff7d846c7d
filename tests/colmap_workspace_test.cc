// mesh_refiner on a workspace whose fused.ply and meshed-poisson.ply were
// written by COLMAP's own stereo_fusion and poisson_mesher (through
// workspace_synthesizer), with the sparse model as .bin and, converted by
// `colmap model_converter`, as .txt. Then a short refinement on it that must
// improve accuracy on the observed surface.

#include <gtest/gtest.h>

#include <filesystem>

#include "colmap_io/ply.h"
#include "colmap_io/workspace.h"
#include "eval/evaluator.h"
#include "tests/command.h"
#include "tests/observed_evaluation.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

// Synthesizes the workspace once per process (ctest runs each test in its
// own process, possibly in parallel: the folder is per process). A failure
// fails the test that needed it.
class ColmapWorkspace : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::string(MR_COLMAP_EXECUTABLE).empty()) GTEST_SKIP() << "colmap not found";
    static std::string dir, log;
    if (dir.empty() && log.empty()) {
      const std::string candidate = FreshTestPath("colmap_ws");
      const CommandResult r = RunCommand(
          std::string(MR_BIN_DIR) + "/workspace_synthesizer --output_path " + candidate +
          " --num_views 10 --width 640 --height 480 --colmap_path " + MR_COLMAP_EXECUTABLE +
          " --num_threads 1 --colmap_timeout_s 300");
      log = r.output.empty() ? "(no output)" : r.output;
      if (r.exit_code == 0) dir = candidate;
    }
    ASSERT_FALSE(dir.empty()) << "workspace_synthesizer failed:\n" << log;
    dir_ = dir;
  }
  std::string dir_;
};

TEST_F(ColmapWorkspace, DryRunWithBinaryAndTextModels) {
  const std::string dense = dir_ + "/dense";
  ASSERT_TRUE(ExistsFile(dense + "/fused.ply"));
  ASSERT_TRUE(ExistsFile(dense + "/meshed-poisson.ply"));
  CommandResult r =
      RunCommand(std::string(MR_BIN_DIR) + "/mesh_refiner --workspace_path " + dense + " --dry_run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Images:      10 registered"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("meshed-poisson.ply"), std::string::npos) << r.output;

  // The same workspace with the model converted to TXT by colmap itself.
  const std::string txt = dir_ + "/dense_txt";
  fs::remove_all(txt);
  fs::create_directories(txt + "/sparse");
  fs::create_directory_symlink(fs::absolute(dense + "/images"), txt + "/images");
  fs::copy_file(dense + "/meshed-poisson.ply", txt + "/meshed-poisson.ply");
  r = RunCommand("QT_QPA_PLATFORM=offscreen " + std::string(MR_COLMAP_EXECUTABLE) +
                 " model_converter --input_path " + dense + "/sparse --output_path " + txt +
                 "/sparse --output_type TXT");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(ExistsFile(txt + "/sparse/cameras.txt"));
  ASSERT_FALSE(ExistsFile(txt + "/sparse/cameras.bin"));
  r = RunCommand(std::string(MR_BIN_DIR) + "/mesh_refiner --workspace_path " + txt + " --dry_run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Images:      10 registered"), std::string::npos) << r.output;
}

TEST_F(ColmapWorkspace, RefinementImprovesObservedAccuracy) {
  const std::string dense = dir_ + "/dense";
  const CommandResult r =
      RunCommand(std::string(MR_BIN_DIR) + "/mesh_refiner --workspace_path " + dense);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EvaluationOptions options;
  options.num_samples = 50000;
  const ObservedEvaluation e = EvaluateObservedSurface(dense, dir_ + "/ground_truth.ply", options);
  const EvaluationResult& b = e.input;
  const EvaluationResult& a = e.refined;
  EXPECT_LT(a.accuracy90, 0.8 * b.accuracy90) << b.ToJson() << "\n" << a.ToJson() << "\n" << r.output;
  EXPECT_LT(a.chamfer, b.chamfer) << b.ToJson() << "\n" << a.ToJson();
  EXPECT_GE(a.completeness, b.completeness - 1.0) << b.ToJson() << "\n" << a.ToJson();
}

}  // namespace
}  // namespace mr
