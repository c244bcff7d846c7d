#include "synth/colmap_runner.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {
namespace {

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}

std::string LogTail(const std::string& path, int lines) {
  std::ifstream in(path);
  std::deque<std::string> tail;
  std::string line;
  while (std::getline(in, line)) {
    tail.push_back(line);
    if (static_cast<int>(tail.size()) > lines) tail.pop_front();
  }
  std::string out;
  for (const auto& l : tail) out += "    " + l + "\n";
  return out;
}

// How one run of a colmap tool ended.
struct RunStatus {
  bool timed_out = false;
  int exit_code = -1;  // the exit status; -1 if a signal ended it
};

// Runs `executable args...` with QT_QPA_PLATFORM=offscreen in a process group
// of its own, stdout and stderr appended to `log_path` (which starts with the
// command line). After `timeout_s` seconds (0: never) the whole group is
// killed and the run reported as timed out.
RunStatus RunLogged(const std::string& executable, const std::vector<std::string>& args,
                    const std::string& log_path, double timeout_s) {
  {
    std::ofstream log(log_path);
    log << "$ QT_QPA_PLATFORM=offscreen " << ShellQuote(executable);
    for (const auto& a : args) log << " " << ShellQuote(a);
    log << "\n";
  }
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(executable.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  MR_LOG(VERBOSE) << "Running " << executable << " " << args.front() << " (log: " << log_path
                  << ")";
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed while starting colmap");
  if (pid == 0) {
    ::setpgid(0, 0);
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_APPEND);
    if (fd < 0) ::_exit(126);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    ::setenv("QT_QPA_PLATFORM", "offscreen", 1);
    ::execv(executable.c_str(), argv.data());
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also here, so the group exists before any kill
  RunStatus result;
  const double start = ElapsedSeconds();
  int status = 0;
  for (;;) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) return result;
    if (timeout_s > 0 && ElapsedSeconds() - start > timeout_s) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      result.timed_out = true;
      return result;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  return result;
}

// Runs a colmap tool; throws with the log's tail if it fails or does not end
// within options.timeout_s.
void RunOrThrow(const std::string& executable, const std::string& tool,
                const std::vector<std::string>& args, const std::string& log_path,
                const ColmapRunOptions& options) {
  const RunStatus status = RunLogged(executable, args, log_path, options.timeout_s);
  if (status.timed_out) {
    std::ostringstream message;
    message << "colmap " << tool << " did not end within " << options.timeout_s
            << " s (--colmap_timeout_s) and was killed; see " << log_path
            << ". Several OpenMP programs sharing the cores can slow it down tenfold; "
            << "try --num_threads 1. Last lines:\n"
            << LogTail(log_path, 15);
    throw std::runtime_error(message.str());
  }
  if (status.exit_code != 0) {
    throw std::runtime_error("colmap " + tool + " failed (exit status " +
                             std::to_string(status.exit_code) + "); see " + log_path +
                             ". Last lines:\n" + LogTail(log_path, 15));
  }
}

}  // namespace

bool ColmapRunOptions::Check() const {
  if (colmap_path.empty()) {
    MR_THROW_INPUT << "ColmapRunOptions::colmap_path is empty. Violated constraint: non-empty";
  }
  if (fusion_min_num_pixels < 1 || fusion_min_num_pixels > 100) {
    MR_THROW_INPUT << "ColmapRunOptions::fusion_min_num_pixels = " << fusion_min_num_pixels
                   << ". Violated constraint: 1 <= fusion_min_num_pixels <= 100";
  }
  if (fusion_max_image_size != -1 && fusion_max_image_size < 100) {
    MR_THROW_INPUT << "ColmapRunOptions::fusion_max_image_size = " << fusion_max_image_size
                   << ". Violated constraint: fusion_max_image_size == -1 or >= 100";
  }
  if (!(poisson_trim >= 0 && poisson_trim <= 20)) {
    MR_THROW_INPUT << "ColmapRunOptions::poisson_trim = " << poisson_trim
                   << ". Violated constraint: 0 <= poisson_trim <= 20";
  }
  if (poisson_depth < 4 || poisson_depth > 16) {
    MR_THROW_INPUT << "ColmapRunOptions::poisson_depth = " << poisson_depth
                   << ". Violated constraint: 4 <= poisson_depth <= 16";
  }
  if (!(timeout_s >= 0 && timeout_s <= 1e6)) {
    MR_THROW_INPUT << "ColmapRunOptions::timeout_s = " << timeout_s
                   << ". Violated constraint: 0 <= timeout_s <= 1e6";
  }
  if (num_threads == 0 || num_threads < -1) {
    MR_THROW_INPUT << "ColmapRunOptions::num_threads = " << num_threads
                   << ". Violated constraint: num_threads == -1 or num_threads >= 1";
  }
  return true;
}

std::string FindExecutable(const std::string& name_or_path) {
  auto is_exec = [](const std::string& p) {
    struct stat st;
    return stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(p.c_str(), X_OK) == 0;
  };
  if (name_or_path.empty()) return "";
  if (name_or_path.find('/') != std::string::npos) return is_exec(name_or_path) ? name_or_path : "";
  const char* path = std::getenv("PATH");
  if (path == nullptr) return "";
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) continue;
    const std::string candidate = JoinPaths(dir, name_or_path);
    if (is_exec(candidate)) return candidate;
  }
  return "";
}

void ReadPlyElementCounts(const std::string& path, long* num_vertices, long* num_faces) {
  std::ifstream in(path, std::ios::binary);
  if (!in) MR_THROW_INPUT << path << ": cannot open";
  std::string line;
  std::getline(in, line);
  if (line.rfind("ply", 0) != 0) MR_THROW_INPUT << path << ": not a PLY file (no 'ply' magic)";
  *num_vertices = -1;
  *num_faces = -1;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string word, name;
    long count = 0;
    ls >> word;
    if (word == "end_header") return;
    if (word == "element" && (ls >> name >> count)) {
      if (name == "vertex") *num_vertices = count;
      if (name == "face") *num_faces = count;
    }
  }
  MR_THROW_INPUT << path << ": PLY header has no end_header";
}

ColmapRunSummary RunColmapFusionAndPoisson(const std::string& dense_path,
                                           const std::string& log_dir,
                                           const ColmapRunOptions& options) {
  options.Check();
  const std::string colmap = FindExecutable(options.colmap_path);
  if (colmap.empty()) {
    MR_THROW_INPUT << "colmap executable '" << options.colmap_path
                   << "' not found (install colmap, pass --colmap_path, or --run_colmap 0)";
  }
  CreateDirIfNotExists(log_dir);
  ColmapRunSummary summary;
  const std::string threads = std::to_string(options.num_threads);

  // Fusion.
  const std::string fused = JoinPaths(dense_path, "fused.ply");
  const std::string fusion_log = JoinPaths(log_dir, "stereo_fusion.log");
  double t0 = ElapsedSeconds();
  MR_LOG(INFO) << "Running colmap stereo_fusion (log: " << fusion_log << ")";
  RunOrThrow(colmap, "stereo_fusion",
             {"stereo_fusion", "--workspace_path", dense_path, "--workspace_format", "COLMAP",
              "--input_type", "geometric", "--output_path", fused,
              "--StereoFusion.min_num_pixels", std::to_string(options.fusion_min_num_pixels),
              "--StereoFusion.max_image_size", std::to_string(options.fusion_max_image_size),
              "--StereoFusion.num_threads", threads, "--log_to_stderr", "1"},
             fusion_log, options);
  summary.fusion_seconds = ElapsedSeconds() - t0;
  if (!ExistsFile(fused)) {
    throw std::runtime_error("colmap stereo_fusion wrote no " + fused + "; see " + fusion_log +
                             ". Last lines:\n" + LogTail(fusion_log, 15));
  }
  long faces = 0;
  ReadPlyElementCounts(fused, &summary.fused_points, &faces);
  if (summary.fused_points <= 0) {
    throw std::runtime_error("colmap stereo_fusion fused 0 points into " + fused + "; see " +
                             fusion_log + ". Last lines:\n" + LogTail(fusion_log, 15));
  }
  MR_LOG(INFO) << "stereo_fusion: " << summary.fused_points << " points in "
               << summary.fusion_seconds << " s";

  // Poisson, retried with lower trims if the trim deletes everything.
  const std::string mesh = JoinPaths(dense_path, "meshed-poisson.ply");
  const std::string poisson_log = JoinPaths(log_dir, "poisson_mesher.log");
  t0 = ElapsedSeconds();
  std::vector<double> trims = {options.poisson_trim};
  for (double t : {options.poisson_trim / 2, 0.0}) {
    if (t < trims.back()) trims.push_back(t);
  }
  for (size_t k = 0; k < trims.size(); ++k) {
    std::ostringstream trim;
    trim << trims[k];
    MR_LOG(INFO) << "Running colmap poisson_mesher with trim " << trims[k]
                 << " (log: " << poisson_log << ")";
    RunOrThrow(colmap, "poisson_mesher",
               {"poisson_mesher", "--input_path", fused, "--output_path", mesh,
                "--PoissonMeshing.trim", trim.str(), "--PoissonMeshing.depth",
                std::to_string(options.poisson_depth), "--PoissonMeshing.num_threads", threads,
                "--log_to_stderr", "1"},
               poisson_log, options);
    if (!ExistsFile(mesh)) {
      throw std::runtime_error("colmap poisson_mesher wrote no " + mesh + "; see " +
                               poisson_log + ". Last lines:\n" + LogTail(poisson_log, 15));
    }
    ReadPlyElementCounts(mesh, &summary.poisson_vertices, &summary.poisson_faces);
    summary.trim_used = trims[k];
    if (summary.poisson_vertices > 0 && summary.poisson_faces > 0) break;
    if (k + 1 < trims.size()) {
      MR_LOG(WARNING) << "poisson_mesher with trim " << trims[k] << " left "
                      << summary.poisson_vertices << " vertices and " << summary.poisson_faces
                      << " faces; retrying with trim " << trims[k + 1];
    }
  }
  summary.poisson_seconds = ElapsedSeconds() - t0;
  if (summary.poisson_vertices <= 0 || summary.poisson_faces <= 0) {
    throw std::runtime_error("colmap poisson_mesher produced an empty mesh " + mesh +
                             " even with trim 0; see " + poisson_log);
  }
  MR_LOG(INFO) << "poisson_mesher: " << summary.poisson_vertices << " vertices, "
               << summary.poisson_faces << " faces (trim " << summary.trim_used << ") in "
               << summary.poisson_seconds << " s";
  return summary;
}

}  // namespace mr
