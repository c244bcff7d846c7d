// scripts/colmap_pipeline.sh end to end, as a user runs it on photographs:
// COLMAP's own CPU structure-from-motion on the real templeSparseRing images,
// the visual hull of their masks, and mesh_refiner (at 320 px, to keep the
// test short: the route is tested here, the refinement's quality elsewhere).

#include <unistd.h>

#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "colmap_io/mesh_io.h"
#include "colmap_io/sparse_model.h"
#include "tests/command.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

const std::string kScript = std::string(MR_SOURCE_DIR) + "/scripts/colmap_pipeline.sh";
const std::string kColmap = MR_COLMAP_EXECUTABLE;
const std::string kTemple = std::string(MR_SHARED_DIR) + "/data/middlebury/templeSparseRing";

std::string FreshDir(const std::string& name) { return MakeTestDir("pipeline_" + name); }

bool ColmapHasCuda() {
  return RunCommand(kColmap + " -h").output.find("with CUDA") != std::string::npos;
}

std::set<std::string> Listing(const std::string& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    names.insert(entry.path().string() + " " +
                 std::to_string(entry.is_regular_file() ? fs::file_size(entry.path()) : 0));
  }
  return names;
}

std::string Pipeline(const std::string& args) {
  return "bash " + kScript + " --colmap " + kColmap + " --bin " + MR_BIN_DIR + " " + args;
}

TEST(ColmapPipeline, TempleFromPhotosOnTheCpuRoute) {
  if (!fs::exists(kTemple)) GTEST_SKIP() << "no " << kTemple;
  if (ColmapHasCuda()) GTEST_SKIP() << "COLMAP has CUDA: the CPU route is not taken";
  const std::string dir = FreshDir("temple");
  // Masks as a user would bring them (COLMAP's convention, <image>.png),
  // here thresholded from the black background by middlebury_to_colmap.
  const CommandResult masks = RunCommand(std::string(MR_BIN_DIR) + "/middlebury_to_colmap " +
                                         "--input_path " + kTemple + " --output_path " + dir +
                                         "/masks_ws --holdout_every 0");
  ASSERT_EQ(masks.exit_code, 0) << masks.output;
  const std::set<std::string> inputs_before = Listing(kTemple);
  const std::string project = dir + "/project";
  const std::string command =
      Pipeline("--image_path " + kTemple + " --mask_path " + dir + "/masks_ws/masks" +
               " --output_path " + project + " --single_camera 1" +
               " -- --Refine.max_image_size 320");
  const CommandResult run = RunCommand(command);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("COLMAP: "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("route: COLMAP has no CUDA"), std::string::npos) << run.output;
  // No shell error on the way (bash prefixes them with "<script>: line N:").
  EXPECT_EQ(run.output.find("colmap_pipeline.sh: line "), std::string::npos) << run.output;

  // COLMAP's model: the images registered (the default mapper leaves some
  // of this wide-baseline ring out; the script then retries leniently).
  const Reconstruction model = ReadSparseModel(project + "/sparse/0");
  EXPECT_GE(model.images.size(), 14u) << run.output;
  std::printf("registered %zu of 16 images\n", model.images.size());

  // The visual hull and the refined mesh, and what the refiner logged.
  const TriangleMesh hull = ReadMesh(project + "/meshed-visualhull.ply");
  const TriangleMesh refined = ReadMesh(project + "/meshed-refined.ply");
  EXPECT_GT(hull.NumFaces(), 1000);
  EXPECT_GT(refined.NumFaces(), 1000);
  const std::string log = ReadFileToString(project + "/logs/mesh_refiner.log");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(log, m, std::regex("mean similarity ([-0-9.]+) -> ([-0-9.]+)")))
      << log;
  const double before = std::stod(m[1]), after = std::stod(m[2]);
  std::printf("mean similarity %.3f -> %.3f\n", before, after);
  EXPECT_GT(after, before + 0.1);
  EXPECT_EQ(Listing(kTemple), inputs_before) << "the image folder was changed";

  // Run again: every stage is skipped and nothing is rewritten.
  const std::string refined_bytes = ReadFileToString(project + "/meshed-refined.ply");
  const auto refined_time = fs::last_write_time(project + "/meshed-refined.ply");
  const CommandResult again = RunCommand(command);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  for (const char* stage : {"1. features: ", "2. sfm: ", "3. surface: ", "4. refine: "}) {
    const size_t at = again.output.find(stage);
    ASSERT_NE(at, std::string::npos) << stage << "\n" << again.output;
    EXPECT_NE(again.output.substr(at, again.output.find('\n', at) - at).find("skipped"),
              std::string::npos)
        << again.output;
  }
  EXPECT_EQ(fs::last_write_time(project + "/meshed-refined.ply"), refined_time);
  EXPECT_TRUE(ReadFileToString(project + "/meshed-refined.ply") == refined_bytes);
  fs::remove_all(dir);
}

TEST(ColmapPipeline, RefusesWhatItCannotDo) {
  const std::string dir = FreshDir("refuse");
  fs::create_directories(dir + "/photos");
  struct Case {
    std::string args, message;
  };
  std::vector<Case> cases = {
      {"--output_path " + dir + "/p", "--image_path"},
      {"--image_path " + dir + "/none --output_path " + dir + "/p", "not a folder"},
      {"--image_path " + dir + "/photos --output_path " + dir + "/p --mask_path " + dir + "/none",
       "--mask_path"},
      {"--image_path " + dir + "/photos --output_path " + dir + "/photos/p", "inside --image_path"},
      {"--image_path " + dir + "/photos --output_path " + dir + "/p --single_camera 2",
       "expected 0 or 1"},
      {"--image_path " + dir + "/photos --output_path " + dir + "/p --bogus 1", "unknown argument"},
  };
  if (!ColmapHasCuda()) {
    cases.push_back({"--image_path " + dir + "/photos --output_path " + dir + "/p",
                     "give --mask_path"});
  }
  for (const Case& c : cases) {
    const CommandResult run = RunCommand(Pipeline(c.args));
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.output;
    EXPECT_NE(run.output.find(c.message), std::string::npos) << c.args << "\n" << run.output;
  }
  const CommandResult no_colmap =
      RunCommand("bash " + kScript + " --colmap /nonexistent/colmap --image_path " + dir +
                 "/photos --output_path " + dir + "/p");
  EXPECT_EQ(no_colmap.exit_code, 2);
  EXPECT_NE(no_colmap.output.find("COLMAP not found"), std::string::npos) << no_colmap.output;
  EXPECT_TRUE(fs::is_empty(dir + "/photos"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mr
