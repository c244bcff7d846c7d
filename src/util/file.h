#pragma once

// File-system helpers with clear errors (COLMAP util/file.h style).

#include <functional>
#include <string>
#include <vector>

namespace mr {

bool ExistsFile(const std::string& path);
bool ExistsDir(const std::string& path);
// Joins path parts with '/'.
std::string JoinPaths(const std::string& a, const std::string& b);
std::string GetParentDir(const std::string& path);
std::string GetFileName(const std::string& path);
// Lower-cased extension including the dot (".ply"), or "" if none.
std::string GetExtension(const std::string& path);
// Creates the directory (and parents) if missing; throws InputError on failure.
void CreateDirIfNotExists(const std::string& path);
// Sorted names (not paths) of regular files directly inside `dir`.
std::vector<std::string> ListFiles(const std::string& dir);
// Reads a whole file; throws InputError naming the path if it cannot.
std::string ReadFileToString(const std::string& path);

// The non-empty lines of a text file, trimmed, skipping '#' comments (image
// name lists such as holdout.txt). Throws InputError if it cannot be read.
std::vector<std::string> ReadNameList(const std::string& path);

// Refuses, before any work, an output that would replace or write into an
// input: throws InputError "<what> <output>: is the input <input>; refusing
// to overwrite an input" if `output` resolves to one of `inputs` (relative
// paths, "." and "..", symbolic links; a hard link to the same file), or
// "...: is inside the input folder <input>; ..." if it lies inside one of
// them that is an existing folder. Empty entries of `inputs` are ignored;
// inputs need not exist. `what` names the output ("--output_path").
void RefuseOutputOverInput(const std::string& what, const std::string& output,
                           const std::vector<std::string>& inputs);

// Refuses, before any work, an output file that could not be written:
// throws InputError "<what> <path>: <why>" if `path` is a folder, its folder
// does not exist or is not a folder, or no file can be created in that
// folder (no permission, a read-only or virtual file system such as /proc or
// /sys): checked by creating and removing "<path>.tmp.<pid>.probe". An
// existing `path` is not touched.
void CheckOutputFile(const std::string& what, const std::string& path);
// The same for an output folder that the program creates or fills: an
// existing `path` must be a folder that accepts new files; a missing one is
// probed in its nearest existing ancestor, which must be a folder.
void CheckOutputFolder(const std::string& what, const std::string& path);

// Writes a file atomically: `write` fills a temporary file in the same folder
// (opened in binary mode as `path + ".tmp.<pid>"`), which is renamed onto
// `path` only if `write` returns without throwing and the stream is good. On
// any failure the temporary is removed and an existing `path` is untouched;
// an interrupt (SIGINT, SIGTERM) removes it too (util/interrupt.h).
void WriteFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write);

}  // namespace mr
