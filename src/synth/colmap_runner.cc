#include "synth/colmap_runner.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <deque>
#include <fstream>
#include <sstream>
#include <stdexcept>
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

// Runs `args` (already quoted) with QT_QPA_PLATFORM=offscreen, stdout and
// stderr to `log_path`. Returns the exit status (or -1 if it did not exit).
int RunLogged(const std::string& executable, const std::vector<std::string>& args,
              const std::string& log_path) {
  std::string cmd = "QT_QPA_PLATFORM=offscreen " + ShellQuote(executable);
  for (const auto& a : args) cmd += " " + ShellQuote(a);
  {
    std::ofstream log(log_path);
    log << "$ " << cmd << "\n";
  }
  cmd += " >> " + ShellQuote(log_path) + " 2>&1";
  MR_LOG(VERBOSE) << "Running: " << cmd;
  const int status = std::system(cmd.c_str());
  if (status == -1 || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

void RunOrThrow(const std::string& executable, const std::string& tool,
                const std::vector<std::string>& args, const std::string& log_path) {
  const int code = RunLogged(executable, args, log_path);
  if (code != 0) {
    throw std::runtime_error("colmap " + tool + " failed (exit status " + std::to_string(code) +
                             "); see " + log_path + ". Last lines:\n" + LogTail(log_path, 15));
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
  if (!(poisson_trim >= 0 && poisson_trim <= 20)) {
    MR_THROW_INPUT << "ColmapRunOptions::poisson_trim = " << poisson_trim
                   << ". Violated constraint: 0 <= poisson_trim <= 20";
  }
  if (poisson_depth < 4 || poisson_depth > 16) {
    MR_THROW_INPUT << "ColmapRunOptions::poisson_depth = " << poisson_depth
                   << ". Violated constraint: 4 <= poisson_depth <= 16";
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
              "--StereoFusion.num_threads", threads, "--log_to_stderr", "1"},
             fusion_log);
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
               poisson_log);
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
