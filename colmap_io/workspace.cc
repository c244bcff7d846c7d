#include "colmap_io/workspace.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/image_file.h"
#include "colmap_io/undistortion.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

const char kUndistortedFolder[] = "mesh_refiner_undistorted";

bool HasModelFiles(const std::string& dir) {
  return ExistsFile(JoinPaths(dir, "cameras.bin")) || ExistsFile(JoinPaths(dir, "cameras.txt"));
}

// sparse/ itself (dense workspace), else the numerically smallest
// sparse/<n>/ holding a model (sparse project; COLMAP's mapper writes
// sparse/0, sparse/1, ...). "" if none.
std::string FindSparseDir(const std::string& root) {
  const std::string sparse = JoinPaths(root, "sparse");
  if (HasModelFiles(sparse)) return sparse;
  if (!ExistsDir(sparse)) return "";
  long best = -1;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(sparse, ec)) {
    if (!entry.is_directory()) continue;
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.size() > 9 ||
        !std::all_of(name.begin(), name.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      continue;
    }
    if (!HasModelFiles(entry.path().string())) continue;
    const long n = std::stol(name);
    if (best < 0 || n < best) best = n;
  }
  return best < 0 ? "" : JoinPaths(sparse, std::to_string(best));
}

// Up to `max` items joined with ", ", then ", ..." if there are more.
std::string Examples(const std::vector<std::string>& items, size_t max = 3) {
  std::string list;
  for (size_t i = 0; i < items.size() && i < max; ++i) list += (i ? ", " : "") + items[i];
  if (items.size() > max) list += ", ...";
  return list;
}

// Checks the masks and logs what is wrong with them; throws if none matches.
void ReportMasks(const std::string& mask_dir, const Reconstruction& model) {
  const MaskCheck check = CheckMasks(mask_dir, model);
  if (!check.missing.empty()) {
    MR_LOG(WARNING) << mask_dir << ": " << check.missing.size() << " of " << check.num_images
                    << " images have no mask (expected <image name>.png, e.g. "
                    << check.missing.front() << ".png); those images are used without a mask";
  }
  if (!check.empty.empty()) {
    MR_LOG(WARNING) << check.empty.size() << " of " << check.num_images - check.missing.size()
                    << " masks are all background (no nonzero pixel; nonzero marks the object): "
                    << Examples(check.empty, 5);
  }
}

bool IsEmptyDir(const std::string& dir) {
  std::error_code ec;
  return fs::is_empty(dir, ec) && !ec;
}

Workspace OpenWorkspaceImpl(const std::string& path, const WorkspaceOptions& options,
                            bool check_masks);

Workspace OpenUndistorted(const std::string& root, const std::string& image_dir,
                          const std::string& mask_dir, const std::string& sparse_dir,
                          const Reconstruction& model) {
  const std::string out = JoinPaths(root, kUndistortedFolder);
  const std::string fingerprint = UndistortionFingerprint(image_dir, mask_dir, model);
  const std::string marker = JoinPaths(out, kUndistortionMarker);
  const std::string partial = JoinPaths(out, kUndistortionPartialMarker);
  std::vector<std::string> distorted;
  for (const auto& [id, camera] : model.cameras) {
    if (!IsPinholeModel(camera.model)) distorted.push_back(CameraModelName(camera.model));
  }
  std::sort(distorted.begin(), distorted.end());
  distorted.erase(std::unique(distorted.begin(), distorted.end()), distorted.end());
  std::string models;
  for (const std::string& m : distorted) models += (models.empty() ? "" : ", ") + m;

  std::string how;
  if (ExistsFile(marker) && ReadFileToString(marker) == fingerprint) {
    how = "reused images undistorted earlier with built-in camera model equations (" + models +
          ") in " + out;
    MR_LOG(INFO) << "Reusing undistorted workspace " << out;
  } else {
    if (ExistsDir(out) && !ExistsFile(marker) && !ExistsFile(partial) && !IsEmptyDir(out)) {
      MR_THROW_INPUT << out << ": exists but was not written by mesh_refiner (no "
                     << kUndistortionMarker << "); will not overwrite it. Remove or rename it, "
                     << "or undistort with `colmap image_undistorter` and open that folder";
    }
    if (ExistsFile(marker)) {
      MR_LOG(INFO) << out << " is out of date (the model or folders changed); undistorting again";
    }
    MR_LOG(INFO) << "The model in " << sparse_dir << " has distorted cameras (" << models
                 << "); undistorting into " << out;
    const UndistortionSummary summary = UndistortSparseModel(image_dir, mask_dir, model, out);
    how = "undistorted " + std::to_string(summary.num_images) +
          " images with built-in camera model equations (" + models + ") into " + out;
    MR_LOG(INFO) << how;
  }
  WorkspaceOptions dense_options;
  if (!mask_dir.empty() && ExistsDir(JoinPaths(out, "masks"))) {
    dense_options.mask_path = JoinPaths(out, "masks");
  }
  // The source masks were checked; the undistorted ones are the same set.
  Workspace ws = OpenWorkspaceImpl(out, dense_options, /*check_masks=*/false);
  if (mask_dir.empty()) ws.mask_dir.clear();
  ws.undistortion = how;
  return ws;
}

Workspace OpenWorkspaceImpl(const std::string& path, const WorkspaceOptions& options,
                            bool check_masks) {
  if (!ExistsDir(path)) MR_THROW_INPUT << path << ": workspace folder does not exist";
  const std::string image_dir =
      options.image_path.empty() ? JoinPaths(path, "images") : options.image_path;
  if (!ExistsDir(image_dir)) {
    MR_THROW_INPUT << path << ": no images folder " << image_dir
                   << " (expected a COLMAP workspace with images/ and sparse/)";
  }
  const std::string sparse_dir = FindSparseDir(path);
  if (sparse_dir.empty()) {
    MR_THROW_INPUT << path << ": no sparse model (looked for cameras.bin or cameras.txt in "
                   << JoinPaths(path, "sparse") << " and " << JoinPaths(path, "sparse/0")
                   << ")";
  }
  Reconstruction model = ReadSparseModel(sparse_dir);
  if (model.images.empty()) {
    MR_THROW_INPUT << sparse_dir << ": the sparse model has zero registered images";
  }

  std::string mask_dir;
  if (!options.use_masks) {
    // Cameras only (mesh_evaluator, mesh_render): no mask folder is looked for.
  } else if (!options.mask_path.empty()) {
    if (!ExistsDir(options.mask_path)) {
      MR_THROW_INPUT << options.mask_path << ": mask folder does not exist";
    }
    mask_dir = options.mask_path;
  } else if (ExistsDir(JoinPaths(path, "masks"))) {
    mask_dir = JoinPaths(path, "masks");
  } else if (ExistsDir(JoinPaths(path, "stereo/masks"))) {
    mask_dir = JoinPaths(path, "stereo/masks");
  }

  std::vector<std::string> missing;
  for (const auto& [id, image] : model.images) {
    const std::string image_path = JoinPaths(image_dir, image.name);
    if (ExistsFile(image_path)) continue;
    std::error_code ec;
    if (fs::exists(image_path, ec)) {
      MR_THROW_INPUT << image_path << ": image " << id << " of the sparse model " << sparse_dir
                     << " is not a file ("
                     << (ExistsDir(image_path) ? "a folder" : "not a regular file")
                     << "; expected an image file)";
    }
    missing.push_back(image.name);
  }
  if (!missing.empty()) {
    std::sort(missing.begin(), missing.end());
    std::string list;
    for (size_t i = 0; i < missing.size() && i < 5; ++i) list += (i ? ", " : "") + missing[i];
    if (missing.size() > 5) list += ", ...";
    MR_THROW_INPUT << image_dir << ": " << missing.size() << " of " << model.images.size()
                   << " images listed in the sparse model " << sparse_dir
                   << " are missing: " << list;
  }

  if (check_masks && !mask_dir.empty()) ReportMasks(mask_dir, model);

  const bool all_pinhole =
      std::all_of(model.cameras.begin(), model.cameras.end(),
                  [](const auto& c) { return IsPinholeModel(c.second.model); });
  if (!all_pinhole) return OpenUndistorted(path, image_dir, mask_dir, sparse_dir, model);

  Workspace ws;
  ws.root = path;
  ws.image_dir = image_dir;
  ws.sparse_dir = sparse_dir;
  ws.mask_dir = mask_dir;
  ws.model = std::move(model);
  for (const auto& [id, image] : ws.model.images) ws.image_ids.push_back(id);
  std::sort(ws.image_ids.begin(), ws.image_ids.end(), [&](uint32_t a, uint32_t b) {
    return ws.model.images.at(a).name < ws.model.images.at(b).name;
  });
  MR_LOG(INFO) << "Workspace " << path << ": " << ws.image_ids.size() << " images, "
               << ws.model.cameras.size() << " cameras, " << ws.model.points3D.size()
               << " points3D" << (mask_dir.empty() ? "" : ", masks in " + mask_dir);
  return ws;
}

}  // namespace

bool WorkspaceOptions::Check() const { return true; }

Workspace OpenWorkspace(const std::string& path, const WorkspaceOptions& options) {
  options.Check();
  return OpenWorkspaceImpl(path, options, /*check_masks=*/true);
}

void CheckImageNamesInModel(const Workspace& workspace, const std::vector<std::string>& names,
                            const std::string& list_path) {
  std::set<std::string> registered;
  for (const auto& [id, image] : workspace.model.images) registered.insert(image.name);
  std::vector<std::string> unknown;
  for (const std::string& name : names) {
    if (!registered.count(name)) unknown.push_back(name);
  }
  if (unknown.empty()) return;
  MR_THROW_INPUT << list_path << ": " << unknown.size() << " of " << names.size()
                 << " image names are not in the sparse model " << workspace.sparse_dir << ": "
                 << Examples(unknown, 5) << " (expected names as the model has them, e.g. "
                 << (registered.empty() ? std::string("none") : *registered.begin()) << ")";
}

std::vector<std::string> WorkspaceInputPaths(const std::string& path,
                                             const WorkspaceOptions& options) {
  if (path.empty()) return {};
  std::vector<std::string> inputs = {
      options.image_path.empty() ? JoinPaths(path, "images") : options.image_path,
      JoinPaths(path, "sparse"), JoinPaths(path, kUndistortedFolder),
      JoinPaths(path, "meshed-poisson.ply"), JoinPaths(path, "meshed-delaunay.ply")};
  if (options.use_masks) {
    for (const std::string& dir : {options.mask_path, JoinPaths(path, "masks"),
                                   JoinPaths(path, "stereo/masks")}) {
      if (!dir.empty()) inputs.push_back(dir);
    }
  }
  return inputs;
}

MaskCheck CheckMasks(const std::string& mask_dir, const Reconstruction& model) {
  std::vector<std::string> names;
  for (const auto& [id, image] : model.images) names.push_back(image.name);
  std::sort(names.begin(), names.end());
  MaskCheck check;
  check.num_images = static_cast<int>(names.size());
  for (const std::string& name : names) {
    // COLMAP's convention: "<image name>.png" (images/a.jpg -> masks/a.jpg.png).
    const std::string path = JoinPaths(mask_dir, name + ".png");
    if (!ExistsFile(path)) {
      check.missing.push_back(name);
      continue;
    }
    if (cv::countNonZero(ReadImageFile(path, cv::IMREAD_GRAYSCALE, "mask")) == 0) {
      check.empty.push_back(path);
    }
  }
  if (!names.empty() && check.missing.size() == names.size()) {
    const std::vector<std::string> files = ListFiles(mask_dir);
    MR_THROW_INPUT << mask_dir << ": no mask matches the images; expected <image name>.png such as "
                   << names.front() << ".png, found "
                   << (files.empty()
                           ? "no files"
                           : std::to_string(files.size()) + " files such as " + Examples(files))
                   << " (COLMAP's naming: images/a.jpg -> masks/a.jpg.png)";
  }
  return check;
}

std::string Workspace::ImagePath(uint32_t image_id) const {
  const auto it = model.images.find(image_id);
  MR_CHECK(it != model.images.end()) << "unknown image id " << image_id;
  return JoinPaths(image_dir, it->second.name);
}

std::string Workspace::MaskPath(uint32_t image_id) const {
  const auto it = model.images.find(image_id);
  MR_CHECK(it != model.images.end()) << "unknown image id " << image_id;
  if (mask_dir.empty()) return "";
  // COLMAP's convention: "<image name>.png" (images/a.jpg -> masks/a.jpg.png).
  const std::string path = JoinPaths(mask_dir, it->second.name + ".png");
  return ExistsFile(path) ? path : "";
}

std::string Workspace::DefaultMeshPath() const {
  // After undistortion `root` is <project>/mesh_refiner_undistorted; the
  // project's own meshes (same world frame) are looked for next.
  std::vector<std::string> dirs = {root};
  if (!undistortion.empty()) dirs.push_back(GetParentDir(root));
  for (const std::string& dir : dirs) {
    for (const char* name : {"meshed-poisson.ply", "meshed-delaunay.ply"}) {
      const std::string path = JoinPaths(dir, name);
      if (ExistsFile(path)) return path;
    }
  }
  return "";
}

namespace {

void CheckSize(const std::string& path, const cv::Mat& mat, const Camera& camera) {
  if (mat.cols != static_cast<int>(camera.width) || mat.rows != static_cast<int>(camera.height)) {
    MR_THROW_INPUT << path << ": is " << mat.cols << "x" << mat.rows << " but camera "
                   << camera.camera_id << " is " << camera.width << "x" << camera.height;
  }
}

}  // namespace

cv::Mat Workspace::ReadImage(uint32_t image_id, bool grayscale) const {
  const std::string path = ImagePath(image_id);
  const cv::Mat image =
      ReadImageFile(path, grayscale ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR, "image");
  CheckSize(path, image, model.cameras.at(model.images.at(image_id).camera_id));
  return image;
}

cv::Mat Workspace::ReadMask(uint32_t image_id) const {
  const std::string path = MaskPath(image_id);
  if (path.empty()) return cv::Mat();
  const cv::Mat mask = ReadImageFile(path, cv::IMREAD_GRAYSCALE, "mask");
  CheckSize(path, mask, model.cameras.at(model.images.at(image_id).camera_id));
  return mask;
}

}  // namespace mr
