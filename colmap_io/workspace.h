#pragma once

// Discovery of a COLMAP workspace.
//
// A dense workspace (the output of `colmap image_undistorter`) has images/,
// sparse/ (PINHOLE or SIMPLE_PINHOLE cameras, .bin or .txt), optionally
// stereo/{depth_maps,normal_maps}/, fused.ply (+ .vis), meshed-poisson.ply,
// meshed-delaunay.ply. A sparse workspace (a project folder with images/ and
// sparse/0 in a distorted model) is undistorted first, into
// <workspace>/mesh_refiner_undistorted/, which is then opened as a dense
// workspace; the log and Workspace::undistortion say how. A complete earlier
// undistortion of the same model and folders is reused; a folder of that name
// not written by mesh_refiner is never overwritten (InputError).
// The sparse model is looked for in <workspace>/sparse, then in the
// lowest-numbered <workspace>/sparse/<n>.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "colmap_io/sparse_model.h"

namespace mr {

struct WorkspaceOptions {
  // Folder of masks named "<image name>.png" (COLMAP's convention:
  // images/a.jpg -> masks/a.jpg.png); must exist if set. Empty: use
  // <workspace>/masks, else <workspace>/stereo/masks, if it exists, else no
  // masks. Masks of a distorted sparse project are undistorted with it.
  std::string mask_path;
  // Folder of the images; empty: <workspace>/images.
  std::string image_path;
  // false: no masks are looked for or checked (mask_dir stays ""), for
  // programs that use only the cameras.
  bool use_masks = true;

  bool Check() const;
};

struct Workspace {
  std::string root;        // the workspace folder (dense; after undistortion the new folder)
  std::string image_dir;   // folder of the images
  std::string sparse_dir;  // folder holding cameras/images/points3D
  std::string mask_dir;    // folder of masks, or "" if none
  std::string undistortion;  // "" if already undistorted, else how it was done
  Reconstruction model;    // all cameras are PINHOLE or SIMPLE_PINHOLE
  std::vector<uint32_t> image_ids;  // registered images, sorted by name

  std::string ImagePath(uint32_t image_id) const;
  // Path of the mask of an image, or "" if there is none.
  std::string MaskPath(uint32_t image_id) const;
  // meshed-poisson.ply if present, else meshed-delaunay.ply, else "";
  // looked for in `root`, then (after undistortion) in the project folder.
  std::string DefaultMeshPath() const;
  // Reads an image (8-bit; grayscale or BGR). Throws InputError if missing or
  // if its size differs from its camera's.
  cv::Mat ReadImage(uint32_t image_id, bool grayscale) const;
  // Reads a mask (8-bit, nonzero = foreground), or an empty Mat if none.
  cv::Mat ReadMask(uint32_t image_id) const;
};

// Opens a dense or sparse workspace. Throws InputError with the path and
// what is missing (no images/, no sparse model, images listed in the model
// but missing from images/, a mask folder none of whose masks matches an
// image, ...). Masks missing for some images and masks that are all
// background are logged as warnings (see CheckMasks).
Workspace OpenWorkspace(const std::string& path, const WorkspaceOptions& options = {});

// Throws InputError "<list_path>: N image names are not in the sparse model
// ...: a.png, ..." if any of `names` (read from the file `list_path`, such
// as a --holdout_path list) is not the name of an image of the model.
void CheckImageNamesInModel(const Workspace& workspace, const std::vector<std::string>& names,
                            const std::string& list_path);

// The files and folders of the workspace at `path` that the programs read,
// for RefuseOutputOverInput, without opening it: the image folder, sparse/
// (every model in it), the mask folders, mesh_refiner_undistorted/, and the
// default meshes meshed-poisson.ply and meshed-delaunay.ply. Not all exist.
std::vector<std::string> WorkspaceInputPaths(const std::string& path,
                                             const WorkspaceOptions& options = {});

// What CheckMasks found in a mask folder.
struct MaskCheck {
  int num_images = 0;                // images in the model
  std::vector<std::string> missing;  // names of images without a mask, sorted
  std::vector<std::string> empty;    // paths of masks with no nonzero pixel, sorted by image
};

// Looks for "<image name>.png" in `mask_dir` for every image of `model` and
// reads each one found. Throws InputError if none is found (saying which
// name was expected, e.g. "view_0000.png.png"), or if a mask cannot be read.
MaskCheck CheckMasks(const std::string& mask_dir, const Reconstruction& model);

}  // namespace mr
