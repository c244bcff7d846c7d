// The documentation's relative links resolve: every [text](target) in the
// project's markdown files (README.md, docs/, benchmark/, fuzz/,
// workspace_examples/) names a file that exists, and a #fragment names a
// heading of that file, spelt as GitHub makes its anchors: lower case, spaces
// to hyphens, every character but letters, digits, '-' and '_' dropped, and
// -1, -2, ... after a repeated heading. Links to the web are not followed.

#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace mr {
namespace {

namespace fs = std::filesystem;

const fs::path kSource = MR_SOURCE_DIR;

std::vector<fs::path> MarkdownFiles() {
  std::vector<fs::path> files = {kSource / "README.md"};
  for (const char* dir : {"docs", "benchmark", "fuzz", "workspace_examples"}) {
    if (!fs::is_directory(kSource / dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(kSource / dir)) {
      if (entry.is_regular_file() && entry.path().extension() == ".md") {
        files.push_back(entry.path());
      }
    }
  }
  return files;
}

// GitHub's anchor for a heading's text. Non-ASCII bytes are dropped: the
// project's headings use non-ASCII characters only for punctuation (a dash).
std::string Anchor(const std::string& heading) {
  std::string anchor;
  for (const unsigned char c : heading) {
    if (c >= 0x80) continue;
    if (std::isalnum(c) || c == '-' || c == '_') {
      anchor += static_cast<char>(std::tolower(c));
    } else if (c == ' ') {
      anchor += '-';
    }
  }
  return anchor;
}

bool IsFence(const std::string& line) { return line.rfind("```", 0) == 0; }

std::vector<std::string> Lines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::set<std::string> Anchors(const fs::path& path) {
  std::set<std::string> anchors;
  std::map<std::string, int> seen;
  bool in_code = false;
  const std::regex heading(R"(^#{1,6}\s+(.*?)\s*$)");
  for (const std::string& line : Lines(path)) {
    if (IsFence(line)) in_code = !in_code;
    std::smatch m;
    if (in_code || !std::regex_match(line, m, heading)) continue;
    const std::string anchor = Anchor(m[1]);
    const int n = seen[anchor]++;
    anchors.insert(n == 0 ? anchor : anchor + "-" + std::to_string(n));
  }
  return anchors;
}

TEST(DocsLinks, Anchor) {
  EXPECT_EQ(Anchor("Speed and memory"), "speed-and-memory");
  EXPECT_EQ(Anchor("Working resolution (`--Refine.max_image_size`)"),
            "working-resolution---refinemax_image_size");
  EXPECT_EQ(Anchor("Scaling: time per iteration against pixels x views and faces"),
            "scaling-time-per-iteration-against-pixels-x-views-and-faces");
  EXPECT_EQ(Anchor("The derivative (eq. De5\xE2\x80\x93" "De7a with the mask)"),
            "the-derivative-eq-de5de7a-with-the-mask");
}

TEST(DocsLinks, EveryRelativeLinkResolves) {
  const std::vector<fs::path> files = MarkdownFiles();
  ASSERT_GT(files.size(), 5u);
  std::map<fs::path, std::set<std::string>> anchors;
  // [text](target): a target with a '.', '/' or '#' (a formula's "](p)" is
  // not a link).
  const std::regex link(R"(\]\(([^)\s]*[./#][^)\s]*)\))");
  int checked = 0;
  for (const fs::path& file : files) {
    bool in_code = false;
    const std::vector<std::string> lines = Lines(file);
    for (size_t n = 0; n < lines.size(); ++n) {
      if (IsFence(lines[n])) in_code = !in_code;
      if (in_code) continue;
      for (std::sregex_iterator it(lines[n].begin(), lines[n].end(), link), end; it != end;
           ++it) {
        const std::string target = (*it)[1];
        if (target.rfind("http://", 0) == 0 || target.rfind("https://", 0) == 0 ||
            target.rfind("mailto:", 0) == 0) {
          continue;
        }
        const size_t hash = target.find('#');
        const std::string path = target.substr(0, hash);
        const fs::path resolved =
            path.empty() ? file : fs::weakly_canonical(file.parent_path() / path);
        const std::string where = fs::relative(file, kSource).string() + ":" +
                                  std::to_string(n + 1) + ": " + target;
        ++checked;
        if (!fs::exists(resolved)) {
          ADD_FAILURE() << where << " (no such file)";
          continue;
        }
        if (hash == std::string::npos || resolved.extension() != ".md") continue;
        if (!anchors.count(resolved)) anchors[resolved] = Anchors(resolved);
        EXPECT_TRUE(anchors[resolved].count(target.substr(hash + 1)))
            << where << " (no such heading)";
      }
    }
  }
  RecordProperty("links_checked", checked);
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace mr
