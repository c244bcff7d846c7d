// The development corpus's CI guard: four cases of
// benchmark/refine/corpus.txt (the same workspace_synthesizer command lines)
// refined with mesh_refiner's defaults, checked on the observed surface
// against bounds set from the full corpus run in docs/results.md. They catch
// a change that makes the defaults worse on image styles other than the
// high-contrast texture: headlight with image noise, smooth colour texture,
// thin parts seen by few views; and a scene in depth (an object on a ground).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

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

// Field `field` (1: the synthesizer's flags, 2: the evaluator's) of a corpus
// case's line, model paths made absolute; empty if absent.
std::string CorpusField(const std::string& name, int field) {
  const fs::path corpus = fs::path(__FILE__).parent_path() / "../benchmark/refine/corpus.txt";
  std::ifstream in(corpus);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t bar = line.find('|');
    std::istringstream head(line.substr(0, bar));
    std::string case_name;
    head >> case_name;
    if (case_name != name) continue;
    std::string flags = line.substr(bar + 1);
    const size_t second = flags.find('|');
    if (field == 2) return second == std::string::npos ? "" : flags.substr(second + 1);
    flags = flags.substr(0, second);
    const std::string key = "--model_path ";
    const size_t at = flags.find(key);
    if (at != std::string::npos) {
      flags.insert(at + key.size(), std::string(MR_SHARED_DIR) + "/data/models/");
    }
    return flags;
  }
  return "";
}

struct GuardCase {
  const char* name;
  double max_accuracy_ratio;  // accuracy90 after / Poisson input
  double max_normal_ratio;    // normal_deg after / Poisson input
};

class CorpusGuard : public ::testing::TestWithParam<GuardCase> {};

TEST_P(CorpusGuard, DefaultsImproveTheObservedSurface) {
  if (std::string(MR_COLMAP_EXECUTABLE).empty()) GTEST_SKIP() << "colmap not found";
  const GuardCase& c = GetParam();
  const std::string flags = CorpusField(c.name, 1);
  ASSERT_FALSE(flags.empty()) << c.name << " is not in benchmark/refine/corpus.txt";
  if (flags.find("--model_path") != std::string::npos &&
      !fs::exists(std::string(MR_SHARED_DIR) + "/data/models")) {
    GTEST_SKIP() << "no " << MR_SHARED_DIR << "/data/models";
  }
  const std::string dir = FreshTestPath("corpus_" + std::string(c.name));
  const CommandResult synth =
      RunCommand(std::string(MR_BIN_DIR) + "/workspace_synthesizer --output_path " + dir + " " +
                 flags + " --colmap_path " + MR_COLMAP_EXECUTABLE +
                 " --num_threads 1 --colmap_timeout_s 300");
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string dense = dir + "/dense";
  const CommandResult r =
      RunCommand(std::string(MR_BIN_DIR) + "/mesh_refiner --workspace_path " + dense);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The evaluator's flags of the case: at most a --region_box.
  std::istringstream eval_flags(CorpusField(c.name, 2));
  std::string key, value;
  std::unique_ptr<RegionBox> region;
  while (eval_flags >> key >> value) {
    ASSERT_EQ(key, "--region_box") << c.name << ": evaluator flag not understood here";
    region = std::make_unique<RegionBox>(RegionBox::Parse(value));
  }
  const ObservedEvaluation e = EvaluateObservedSurface(dense, dir + "/ground_truth.ply",
                                                       EvaluationOptions(), region.get());
  const EvaluationResult& b = e.input;
  const EvaluationResult& a = e.refined;
  RecordProperty("accuracy90_ratio", std::to_string(a.accuracy90 / b.accuracy90));
  RecordProperty("normal_ratio", std::to_string(a.normal_deg / b.normal_deg));
  EXPECT_LT(a.accuracy90, c.max_accuracy_ratio * b.accuracy90)
      << b.ToJson() << "\n" << a.ToJson() << "\n" << r.output;
  EXPECT_LT(a.normal_deg, c.max_normal_ratio * b.normal_deg) << b.ToJson() << "\n" << a.ToJson();
  EXPECT_GE(a.completeness, b.completeness - 1.0) << b.ToJson() << "\n" << a.ToJson();
  fs::remove_all(dir);
}

// Bounds: the ratios measured with the defaults on the full corpus run of 7
// December 2026 (docs/results.md, the corpus table: rocker-head-noise 0.270 /
// 0.567, bunny-color-hemi 0.382 / 0.661, cheburashka-head 0.195 / 0.458,
// builtin-ground, a scene in depth, 0.248 / 0.408), plus 0.05 for
// run-to-run and machine differences (COLMAP's fusion and Poisson meshing
// differ from one synthesis to the next: this test's own single-threaded
// syntheses gave 0.263 / 0.559, 0.385 / 0.679, 0.199 / 0.463 and 0.236 /
// 0.413 the same day, recorded as test properties). Until then the bounds
// were those of 4 December (0.41 / 0.74, 0.47 / 0.81, 0.37 / 0.70, 0.31 /
// 0.53), which the split and the fairing had left far behind.
INSTANTIATE_TEST_SUITE_P(Corpus, CorpusGuard,
                         ::testing::Values(GuardCase{"rocker-head-noise", 0.32, 0.62},
                                           GuardCase{"bunny-color-hemi", 0.43, 0.71},
                                           GuardCase{"cheburashka-head", 0.25, 0.51},
                                           GuardCase{"builtin-ground", 0.30, 0.46}),
                         [](const ::testing::TestParamInfo<GuardCase>& info) {
                           std::string name = info.param.name;
                           for (char& ch : name) {
                             if (ch == '-') ch = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace mr
