#include "util/file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "util/error.h"
#include "util/interrupt.h"

namespace mr {
namespace fs = std::filesystem;

bool ExistsFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool ExistsDir(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

std::string JoinPaths(const std::string& a, const std::string& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return (fs::path(a) / fs::path(b)).string();
}

std::string GetParentDir(const std::string& path) {
  return fs::path(path).parent_path().string();
}

std::string GetFileName(const std::string& path) { return fs::path(path).filename().string(); }

std::string GetExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void CreateDirIfNotExists(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return;
  fs::create_directories(path, ec);
  if (ec) MR_THROW_INPUT << path << ": cannot create directory: " << ec.message();
}

std::vector<std::string> ListFiles(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file()) names.push_back(entry.path().filename().string());
  }
  if (ec) MR_THROW_INPUT << dir << ": cannot list directory: " << ec.message();
  std::sort(names.begin(), names.end());
  return names;
}

std::string ReadFileToString(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) MR_THROW_INPUT << path << ": cannot open file for reading";
  std::ostringstream buffer;
  buffer << file.rdbuf();
  return buffer.str();
}

std::vector<std::string> ReadNameList(const std::string& path) {
  std::vector<std::string> names;
  std::istringstream in(ReadFileToString(path));
  std::string line;
  while (std::getline(in, line)) {
    const auto begin = line.find_first_not_of(" \t\r");
    if (begin == std::string::npos || line[begin] == '#') continue;
    names.push_back(line.substr(begin, line.find_last_not_of(" \t\r") - begin + 1));
  }
  return names;
}

namespace {

// Absolute, normalized, with the symbolic links of its existing part
// resolved and no trailing separator.
fs::path Resolve(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) p = fs::absolute(path).lexically_normal();
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

bool IsInside(const fs::path& path, const fs::path& dir) {
  auto p = path.begin();
  for (auto d = dir.begin(); d != dir.end(); ++d, ++p) {
    if (p == path.end() || *p != *d) return false;
  }
  return p != path.end();
}

}  // namespace

void RefuseOutputOverInput(const std::string& what, const std::string& output,
                           const std::vector<std::string>& inputs) {
  if (output.empty()) return;
  const fs::path out = Resolve(output);
  for (const std::string& input : inputs) {
    if (input.empty()) continue;
    const fs::path in = Resolve(input);
    std::error_code ec;
    if (out == in || fs::equivalent(output, input, ec)) {
      MR_THROW_INPUT << what << " " << output << ": is the input " << input
                     << "; refusing to overwrite an input";
    }
    if (fs::is_directory(in, ec) && IsInside(out, in)) {
      MR_THROW_INPUT << what << " " << output << ": is inside the input folder " << input
                     << "; refusing to overwrite inputs";
    }
  }
}

void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write) {
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(dir)) {
    MR_THROW_INPUT << path << ": output folder " << dir.string() << " does not exist";
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const TemporaryFileRegistration removed_on_interrupt(tmp);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) MR_THROW_INPUT << tmp << ": cannot open for writing";
      write(out);
      out.flush();
      if (!out) MR_THROW_INPUT << tmp << ": write failed (disk full?)";
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) MR_THROW_INPUT << path << ": cannot rename temporary file into place: " << ec.message();
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

namespace {

// Creates and removes an empty file "<name>.tmp.<pid>.probe" in `dir`;
// returns "" or why it could not (the system's words).
std::string ProbeCreateFile(const fs::path& dir, const std::string& name) {
  const std::string probe =
      (dir / (name + ".tmp." + std::to_string(::getpid()) + ".probe")).string();
  const TemporaryFileRegistration removed_on_interrupt(probe);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return std::strerror(errno);
  ::close(fd);
  if (::unlink(probe.c_str()) != 0) return std::strerror(errno);
  return "";
}

}  // namespace

void CheckOutputFile(const std::string& what, const std::string& path) {
  if (path.empty()) MR_THROW_INPUT << what << ": empty path";
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    MR_THROW_INPUT << what << " " << path << ": is a folder; expected a file name";
  }
  const fs::path target(path);
  if (target.filename().empty() || target.filename() == "." || target.filename() == "..") {
    MR_THROW_INPUT << what << " " << path << ": expected a file name, not a folder";
  }
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::exists(dir, ec)) {
    MR_THROW_INPUT << what << " " << path << ": folder " << dir.string() << " does not exist";
  }
  if (!fs::is_directory(dir, ec)) {
    MR_THROW_INPUT << what << " " << path << ": " << dir.string() << " is not a folder";
  }
  const std::string why = ProbeCreateFile(dir, target.filename().string());
  if (!why.empty()) {
    MR_THROW_INPUT << what << " " << path << ": cannot create a file in folder " << dir.string()
                   << " (" << why << "); choose a writable folder";
  }
}

void CheckOutputFolder(const std::string& what, const std::string& path) {
  if (path.empty()) MR_THROW_INPUT << what << ": empty path";
  std::error_code ec;
  fs::path dir = fs::absolute(path, ec).lexically_normal();
  if (dir.filename().empty() && dir.has_parent_path()) dir = dir.parent_path();
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    MR_THROW_INPUT << what << " " << path << ": is a file; expected a folder";
  }
  // The folder itself, or the nearest existing folder it will be created in.
  fs::path existing = dir;
  while (!fs::exists(existing, ec) && existing.has_parent_path() &&
         existing.parent_path() != existing) {
    existing = existing.parent_path();
  }
  if (!fs::is_directory(existing, ec)) {
    MR_THROW_INPUT << what << " " << path << ": " << existing.string()
                   << " is not a folder; cannot create " << path;
  }
  const std::string why = ProbeCreateFile(existing, ".mesh_refiner");
  if (!why.empty()) {
    MR_THROW_INPUT << what << " " << path << ": cannot create files in folder "
                   << existing.string() << " (" << why << "); choose a writable folder";
  }
}

}  // namespace mr
