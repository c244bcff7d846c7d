#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "util/error.h"
#include "util/file.h"
#include "util/interrupt.h"
#include "util/isolated.h"
#include "util/statistics.h"
#include "util/testing.h"
#include "util/options.h"
#include "util/program.h"

namespace mr {
namespace {

TEST(WriteFileAtomically, Nominal) {
  const std::string path = JoinPaths(MakeTestDir("atomic"), "a.txt");
  WriteFileAtomically(path, [](std::ostream& out) { out << "hello"; });
  EXPECT_EQ(ReadFileToString(path), "hello");
}

TEST(WriteFileAtomically, FailureLeavesExistingFileUntouched) {
  const std::string dir = MakeTestDir("atomic_fail");
  const std::string path = JoinPaths(dir, "a.txt");
  WriteFileAtomically(path, [](std::ostream& out) { out << "old"; });
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](std::ostream& out) {
                                     out << "partial";
                                     MR_THROW_INPUT << "simulated failure";
                                   }),
               InputError);
  EXPECT_EQ(ReadFileToString(path), "old");
  EXPECT_EQ(ListFiles(dir).size(), 1u);  // no temporary left behind
}

TEST(WriteFileAtomically, MissingFolder) {
  EXPECT_THROW(WriteFileAtomically("/nonexistent_dir_xyz/a.txt", [](std::ostream&) {}),
               InputError);
}

TEST(RefuseOutputOverInput, SameFileHoweverSpelled) {
  namespace fs = std::filesystem;
  const std::string dir = MakeTestDir("refuse");
  const std::string m = JoinPaths(dir, "m.ply");
  WriteFileAtomically(m, [](std::ostream& out) { out << "mesh"; });
  fs::create_directories(JoinPaths(dir, "sub"));
  fs::create_symlink(m, JoinPaths(dir, "link.ply"));
  fs::create_hard_link(m, JoinPaths(dir, "hard.ply"));
  fs::create_directory_symlink(dir, JoinPaths(dir, "sub/up"));
  for (const std::string& output :
       {m, dir + "/./m.ply", dir + "/sub/../m.ply", dir + "/link.ply", dir + "/hard.ply",
        dir + "/sub/up/m.ply", dir + "//m.ply"}) {
    ExpectInputError([&] { RefuseOutputOverInput("--output_path", output, {"", m}); },
                     {"--output_path " + output, "is the input " + m, "refusing to overwrite"});
  }
  // A relative output against an absolute input.
  const fs::path cwd = fs::current_path();
  fs::current_path(JoinPaths(dir, "sub"));
  ExpectInputError([&] { RefuseOutputOverInput("--write_config", "../m.ply", {m}); },
                   {"--write_config ../m.ply", "is the input"});
  fs::current_path(cwd);
  // Inside an input folder, at any depth; inputs that do not exist yet.
  ExpectInputError([&] { RefuseOutputOverInput("--write_config", dir + "/sub/a.ini", {dir}); },
                   {"inside the input folder " + dir});
  ExpectInputError(
      [&] { RefuseOutputOverInput("--output_path", dir + "/new.ply", {dir + "/new.ply"}); },
      {"is the input"});
  // Other paths pass: a sibling, a name that only starts like the folder.
  RefuseOutputOverInput("--output_path", dir + "/out.ply", {m, dir + "/sub"});
  RefuseOutputOverInput("--output_path", dir + "/sub2/x.ply", {dir + "/sub"});
  RefuseOutputOverInput("--output_path", dir + "/m.ply.bak", {m});
  RefuseOutputOverInput("--output_path", "", {m});
}

// No file in `dir` whose name has ".tmp." (a temporary or a probe).
void ExpectNoTemporary(const std::string& dir) {
  for (const auto& name : ListFiles(dir)) EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
}

TEST(CheckOutputFile, WritableFolderPasses) {
  const std::string dir = MakeTestDir("check_output");
  CheckOutputFile("--output_path", JoinPaths(dir, "new.ply"));
  const std::string existing = JoinPaths(dir, "old.ply");
  WriteFileAtomically(existing, [](std::ostream& out) { out << "old"; });
  CheckOutputFile("--output_path", existing);
  EXPECT_EQ(ReadFileToString(existing), "old");
  EXPECT_FALSE(ExistsFile(JoinPaths(dir, "new.ply")));
  ExpectNoTemporary(dir);
  const std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  CheckOutputFile("--output_path", "relative.ply");  // the current folder
  std::filesystem::current_path(cwd);
  ExpectNoTemporary(dir);
}

TEST(CheckOutputFile, UnwritableOutputsAreRefused) {
  const std::string dir = MakeTestDir("check_output_bad");
  CreateDirIfNotExists(JoinPaths(dir, "folder.ply"));
  WriteFileAtomically(JoinPaths(dir, "file"), [](std::ostream& out) { out << "x"; });
  ExpectInputError([&] { CheckOutputFile("--output_path", JoinPaths(dir, "folder.ply")); },
                   {"--output_path " + dir + "/folder.ply", "is a folder"});
  ExpectInputError([&] { CheckOutputFile("--output_path", dir + "/"); }, {"folder"});
  ExpectInputError([&] { CheckOutputFile("--output_path", JoinPaths(dir, "nope/a.ply")); },
                   {"folder " + dir + "/nope does not exist"});
  ExpectInputError([&] { CheckOutputFile("--output_path", JoinPaths(dir, "file/a.ply")); },
                   {dir + "/file is not a folder"});
  // Virtual file systems: the folder exists, no file can be made in it (root
  // included, so this holds whoever runs the test).
  ExpectInputError([&] { CheckOutputFile("--write_config", "/proc/a.ini"); },
                   {"--write_config /proc/a.ini", "cannot create a file in folder /proc"});
  ExpectInputError([&] { CheckOutputFile("--output_path", "/sys/a.ply"); },
                   {"cannot create a file in folder /sys"});
  ExpectInputError([&] { CheckOutputFile("--output_path", ""); }, {"empty path"});
  ExpectNoTemporary(dir);
}

TEST(CheckOutputFolder, ExistingMissingAndUnwritable) {
  const std::string dir = MakeTestDir("check_output_folder");
  CheckOutputFolder("--output_path", dir);
  CheckOutputFolder("--output_path", JoinPaths(dir, "new/deeper"));  // made later
  EXPECT_FALSE(ExistsDir(JoinPaths(dir, "new")));
  WriteFileAtomically(JoinPaths(dir, "file"), [](std::ostream& out) { out << "x"; });
  ExpectInputError([&] { CheckOutputFolder("--output_path", JoinPaths(dir, "file")); },
                   {"is a file; expected a folder"});
  ExpectInputError([&] { CheckOutputFolder("--output_path", JoinPaths(dir, "file/sub")); },
                   {"is not a folder"});
  ExpectInputError([&] { CheckOutputFolder("--output_path", "/proc/new_folder"); },
                   {"cannot create files in folder /proc"});
  ExpectNoTemporary(dir);
}

// In a child process (the handler ends the process): a registered temporary
// is removed by SIGINT / SIGTERM, whose exit status is 128 + signal; one
// whose registration has ended is left alone.
TEST(InterruptHandlers, RemoveRegisteredTemporariesAndExit) {
  const std::string dir = MakeTestDir("interrupt");
  for (const int signal_number : {SIGINT, SIGTERM}) {
    const std::string tmp = JoinPaths(dir, "out.ply.tmp.1"), kept = JoinPaths(dir, "kept.tmp.2");
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::signal(SIGINT, SIG_DFL);
      ::signal(SIGTERM, SIG_DFL);
      InstallInterruptHandlers();
      { TemporaryFileRegistration done(kept); }
      std::ofstream(kept) << "no longer registered";
      const TemporaryFileRegistration registration(tmp);
      std::ofstream(tmp) << "half-written";
      ::raise(signal_number);
      ::_exit(99);  // not reached
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal_number);
    EXPECT_FALSE(ExistsFile(tmp));
    EXPECT_TRUE(ExistsFile(kept));
    std::filesystem::remove(kept);
  }
}

// What is allocated and kept shows in the heap in use, and leaves it when
// freed (glibc's count; AddressSanitizer's allocator is not in it).
TEST(HeapBytesInUse, FollowsAnAllocation) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's heap is not glibc's";
#else
  const size_t before = HeapBytesInUse();
  ASSERT_GT(before, 0u);
  constexpr size_t kBytes = 32 << 20;
  auto buffer = std::make_unique<char[]>(kBytes);
  std::fill(buffer.get(), buffer.get() + kBytes, 1);
  const size_t held = HeapBytesInUse();
  EXPECT_GE(held, before + kBytes);
  EXPECT_LT(held, before + kBytes + (1 << 20));
  buffer.reset();
  EXPECT_LT(HeapBytesInUse(), before + (1 << 20));
#endif
}

TEST(ReadNameList, SkipsBlankLinesAndComments) {
  const std::string path = JoinPaths(MakeTestDir("names"), "list.txt");
  WriteFileAtomically(path, [](std::ostream& out) { out << "# held out\n a.png \n\nb c.png\r\n"; });
  EXPECT_EQ(ReadNameList(path), (std::vector<std::string>{"a.png", "b c.png"}));
  EXPECT_THROW(ReadNameList(path + ".missing"), InputError);
}

TEST(OptionManager, FlagsConfigAndOverride) {
  const std::string dir = MakeTestDir("options");
  int iterations = 3;
  double step = 0.5;
  bool dry_run = false;
  std::string path;
  OptionManager options("prog", "test");
  options.AddRequired("workspace_path", &path, "ws");
  options.Add("Refine.num_iterations", &iterations, "it");
  options.Add("Refine.step", &step, "step");
  options.Add("dry_run", &dry_run, "dry");
  const std::string ini = JoinPaths(dir, "a.ini");
  {
    std::ofstream f(ini);
    f << "workspace_path=/ws\n[Refine]\nnum_iterations = 7\nstep=0.25\n";
  }
  const char* argv[] = {"prog", "--config_path", ini.c_str(), "--Refine.step", "0.125",
                        "--dry_run"};
  ASSERT_TRUE(options.Parse(6, const_cast<char**>(argv)));
  EXPECT_EQ(path, "/ws");
  EXPECT_EQ(iterations, 7);
  EXPECT_DOUBLE_EQ(step, 0.125);
  EXPECT_TRUE(dry_run);

  // Round trip through --write_config.
  const std::string out = JoinPaths(dir, "b.ini");
  const char* argv2[] = {"prog", "--write_config", out.c_str()};
  EXPECT_FALSE(options.Parse(3, const_cast<char**>(argv2)));
  int iterations2 = 0;
  double step2 = 0;
  bool dry2 = false;
  std::string path2;
  OptionManager options2("prog", "test");
  options2.AddRequired("workspace_path", &path2, "ws");
  options2.Add("Refine.num_iterations", &iterations2, "it");
  options2.Add("Refine.step", &step2, "step");
  options2.Add("dry_run", &dry2, "dry");
  options2.ReadConfig(out);
  EXPECT_EQ(iterations2, 7);
  EXPECT_DOUBLE_EQ(step2, 0.125);
  EXPECT_EQ(path2, "/ws");
}

// --write_config never replaces an input: the config it read, a *_path
// option's file, or what the program names with SetInputPaths.
TEST(OptionManager, WriteConfigOverAnInputIsRefused) {
  const std::string dir = MakeTestDir("options_inputs");
  const std::string ini = JoinPaths(dir, "a.ini"), mesh = JoinPaths(dir, "m.ply");
  const std::string model = JoinPaths(dir, "sparse");
  WriteFileAtomically(ini, [](std::ostream& out) { out << "n = 2\n"; });
  WriteFileAtomically(mesh, [](std::ostream& out) { out << "mesh"; });
  CreateDirIfNotExists(model);
  auto parse = [&](std::vector<std::string> args) {
    int n = 0;
    std::string input_path, output_path, workspace_path;
    OptionManager options("prog", "test");
    options.Add("n", &n, "n");
    options.Add("input_path", &input_path, "in");
    options.Add("output_path", &output_path, "out");
    options.Add("workspace_path", &workspace_path, "ws");
    options.SetInputPaths(
        [&] { return std::vector<std::string>{JoinPaths(workspace_path, "sparse")}; });
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(&a[0]);
    return options.Parse(static_cast<int>(argv.size()), argv.data());
  };
  ExpectInputError([&] { parse({"--config_path", ini, "--write_config", ini}); },
                   {"--write_config " + ini, "is the input", "refusing to overwrite"});
  ExpectInputError([&] { parse({"--input_path", mesh, "--write_config", mesh}); },
                   {"--write_config " + mesh, "is the input " + mesh});
  ExpectInputError(
      [&] { parse({"--workspace_path", dir, "--write_config", model + "/cameras.bin"}); },
      {"inside the input folder " + model});
  EXPECT_EQ(ReadFileToString(ini), "n = 2\n");
  EXPECT_EQ(ReadFileToString(mesh), "mesh");
  // Beside the inputs, in the workspace folder, or at the output path: written.
  EXPECT_FALSE(parse({"--input_path", mesh, "--workspace_path", dir, "--output_path",
                      JoinPaths(dir, "b.ini"), "--write_config", JoinPaths(dir, "b.ini")}));
  EXPECT_NE(ReadFileToString(JoinPaths(dir, "b.ini")).find("input_path="), std::string::npos);
}

TEST(OptionManager, BadInput) {
  int n = 0;
  std::string s;
  OptionManager options("prog", "test");
  options.Add("n", &n, "n");
  options.AddRequired("s", &s, "s");
  const char* unknown[] = {"prog", "--s", "x", "--bogus", "1"};
  EXPECT_THROW(options.Parse(5, const_cast<char**>(unknown)), InputError);
  const char* not_int[] = {"prog", "--s", "x", "--n", "1.5"};
  EXPECT_THROW(options.Parse(5, const_cast<char**>(not_int)), InputError);
  OptionManager options2("prog", "test");
  options2.AddRequired("s", &s, "s");
  const char* missing[] = {"prog"};
  EXPECT_THROW(options2.Parse(1, const_cast<char**>(missing)), InputError);
}

TEST(Statistics, MedianIsTheUpperMedian) {
  std::vector<double> odd = {5, 1, 4, 2, 3};
  EXPECT_EQ(Median(&odd), 3);
  std::vector<double> even = {4, 1, 3, 2};
  EXPECT_EQ(Median(&even), 3);  // rank n / 2: the larger middle element, not 2.5
  std::vector<float> single = {7};
  EXPECT_EQ(Median(&single), 7);
  std::vector<int> two = {9, 8};
  EXPECT_EQ(Median(&two), 9);
  std::vector<double> empty;
  EXPECT_THROW(Median(&empty), InternalError);
}

TEST(Statistics, QuantileRanksAndClamping) {
  // Rank floor(q n), clamped to n - 1.
  EXPECT_EQ(QuantileRank(5, 0.0), 0u);
  EXPECT_EQ(QuantileRank(5, 0.5), 2u);
  EXPECT_EQ(QuantileRank(5, 0.9), 4u);
  EXPECT_EQ(QuantileRank(5, 1.0), 4u);  // clamped from 5
  EXPECT_EQ(QuantileRank(4, 0.5), 2u);
  EXPECT_EQ(QuantileRank(4, 0.9), 3u);
  EXPECT_EQ(QuantileRank(4, 1.0), 3u);   // clamped from 4
  EXPECT_EQ(QuantileRank(10, 0.9), 9u);  // not the nearest rank ceil(0.9 n) - 1 = 8
  EXPECT_EQ(QuantileRank(1, 0.0), 0u);
  EXPECT_EQ(QuantileRank(1, 1.0), 0u);
  EXPECT_THROW(QuantileRank(0, 0.5), InternalError);
  EXPECT_THROW(QuantileRank(5, -0.1), InternalError);
  EXPECT_THROW(QuantileRank(5, 1.1), InternalError);
  EXPECT_THROW(QuantileRank(5, std::numeric_limits<double>::quiet_NaN()), InternalError);

  const std::vector<double> odd = {30, 10, 50, 20, 40};
  const std::vector<double> even = {3, 1, 4, 2};
  const auto quantile = [](std::vector<double> values, double q) { return Quantile(&values, q); };
  EXPECT_EQ(quantile(odd, 0.0), 10);
  EXPECT_EQ(quantile(odd, 0.5), 30);
  EXPECT_EQ(quantile(odd, 0.9), 50);
  EXPECT_EQ(quantile(odd, 1.0), 50);
  EXPECT_EQ(quantile(even, 0.0), 1);
  EXPECT_EQ(quantile(even, 0.5), 3);
  EXPECT_EQ(quantile(even, 0.9), 4);
  EXPECT_EQ(quantile(even, 1.0), 4);
  EXPECT_THROW(quantile({}, 0.5), InternalError);
}

TEST(Statistics, AgreesWithSorting) {
  std::mt19937 rng(7);
  for (int n = 1; n <= 40; ++n) {
    std::vector<int> values(n);
    for (int& v : values) v = static_cast<int>(rng() % 10);  // with ties
    std::vector<int> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    for (int k = 0; k < n; ++k) {
      std::vector<int> copy = values;
      EXPECT_EQ(NthSmallest(&copy, k), sorted[k]) << "n " << n << " k " << k;
    }
    std::vector<int> copy = values;
    EXPECT_EQ(Median(&copy), sorted[n / 2]);
    for (double q : {0.0, 0.25, 0.5, 0.9, 1.0}) {
      copy = values;
      EXPECT_EQ(Quantile(&copy, q), sorted[QuantileRank(n, q)]);
    }
    copy = values;
    EXPECT_THROW(NthSmallest(&copy, n), InternalError);
  }
}

// The median and 1.4826 x the median absolute deviation; a minority of wild
// values moves neither.
TEST(Statistics, RobustMedianAndSpread) {
  std::vector<double> values = {1, 2, 3, 4, 5};
  MedianAndSpread robust = RobustMedianAndSpread(&values);
  EXPECT_EQ(robust.median, 3);
  EXPECT_DOUBLE_EQ(robust.sigma, 1.4826);  // deviations 0 1 1 2 2
  values = {1, 2, 3, 4, 5, 1000, -1000};
  robust = RobustMedianAndSpread(&values);
  EXPECT_EQ(robust.median, 3);
  EXPECT_DOUBLE_EQ(robust.sigma, 2 * 1.4826);  // deviations 0 1 1 2 2 997 1003
  values = {4};
  robust = RobustMedianAndSpread(&values);
  EXPECT_EQ(robust.median, 4);
  EXPECT_EQ(robust.sigma, 0);
}

// RunIsolated: what the child returns arrives (large answers too: more than
// the pipe holds); a child that dies is reported with its signal; the
// errors it throws are thrown again in the caller.
TEST(RunIsolated, ReturnsReportsCrashesAndRethrows) {
  const IsolatedResult small = RunIsolated([] { return std::string("remeshed"); });
  EXPECT_EQ(small.status, IsolatedResult::Status::kDone);
  EXPECT_EQ(small.payload, "remeshed");
  std::string large(3 << 20, 'x');
  large[12345] = 'y';
  const IsolatedResult big = RunIsolated([&] { return large; });
  EXPECT_EQ(big.status, IsolatedResult::Status::kDone);
  EXPECT_EQ(big.payload, large);
  // (SIGKILL: a sanitizer turns a segmentation fault into an exit status.)
  const IsolatedResult crashed = RunIsolated([]() -> std::string {
    raise(SIGKILL);
    return "never";
  });
  EXPECT_EQ(crashed.status, IsolatedResult::Status::kCrashed);
  EXPECT_EQ(crashed.signal, SIGKILL);
  EXPECT_TRUE(crashed.payload.empty());
  try {
    RunIsolated([]() -> std::string { throw InputError("bad mesh"); });
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "bad mesh");
  }
  EXPECT_THROW(RunIsolated([]() -> std::string { throw std::runtime_error("oops"); }),
               InternalError);
  // The child's changes to memory stay in the child.
  int touched = 0;
  RunIsolated([&] {
    touched = 1;
    return std::string();
  });
  EXPECT_EQ(touched, 0);
}

}  // namespace
}  // namespace mr
