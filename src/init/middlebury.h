#pragma once

// Middlebury multi-view stereo data sets (Seitz et al. 2006) as COLMAP dense
// workspaces.
//
// A data set folder holds the images, `<name>_par.txt` (first line the image
// count, then one line per image "name k11..k33 r11..r33 t1 t2 t3" with the
// projection P = K [R | t], in metres) and a README.txt that may give the
// object's tight bounding box.
//
// Conventions of the conversion (see docs/middlebury.md):
// - Pixels: Middlebury's K puts the centre of the top-left pixel at (0, 0);
//   COLMAP puts it at (0.5, 0.5). The PINHOLE camera gets cx + 0.5, cy + 0.5.
// - Units: the workspace is written in `scale` units per metre (default 1000,
//   i.e. millimetres), so that the evaluator's 1.25-unit threshold is
//   Middlebury's 1.25 mm. Translations and the bounding box are scaled;
//   rotations and intrinsics are unchanged.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "colmap_io/sparse_model.h"

namespace mr {

// One line of a *_par.txt file.
struct MiddleburyCamera {
  std::string name;  // image file name, e.g. "dinoSR0001.png"
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // cam_from_world
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // cam_from_world, metres

  // P = K [R | t] (Middlebury pixel convention: top-left pixel centre at (0, 0)).
  Eigen::Matrix<double, 3, 4> Projection() const;
};

// Parses a *_par.txt file. Throws InputError naming the file, the line and
// the problem (bad count, missing or non-numeric field, non-finite value,
// rotation that is not orthonormal with det +1, duplicate image name).
std::vector<MiddleburyCamera> ReadMiddleburyPar(const std::string& path);

// The tight bounding box given in a data set's README.txt as two lines
// "(x0 y0 z0)" and "(x1 y1 z1)" after a line mentioning "bounding box".
// Returns false (and leaves *bbox untouched) if the README gives none; throws
// InputError if it is malformed (min > max).
bool ReadMiddleburyBoundingBox(const std::string& readme_path, Eigen::AlignedBox3d* bbox);

// The silhouette recipe of the data sets' README: threshold the intensity at
// `threshold` (values in [0, 1]), dilate by `dilate_px`, erode by `erode_px`.
struct SilhouetteOptions {
  // Intensity threshold in [0, 1]; pixels brighter than it are foreground.
  // Intensity is Matlab's rgb2gray (0.2989 R + 0.5870 G + 0.1140 B).
  double threshold = 0.19;
  // Radius in pixels of the disc dilation (>= 0), then of the erosion (>= 0).
  int dilate_px = 10;
  int erode_px = 7;
  // Not in the README: afterwards, fill holes (background regions not
  // touching the image border) of at most this many pixels (>= 0; 0 fills
  // none). Dark shadows on the object leave such holes, and each would carve
  // a tunnel through the visual hull; filling them only makes the hull more
  // conservative. 1500 fills all shadow holes of dinoSparseRing (<= 1135 px)
  // and keeps the real gaps between templeSparseRing's columns (>= 1664 px).
  int fill_holes_px = 1500;
  bool Check() const;
};

struct SilhouetteStats {
  int filled_holes = 0;   // holes filled (area <= fill_holes_px)
  int kept_holes = 0;     // larger holes left open
  int largest_filled = 0;  // area in pixels of the largest filled hole
  int smallest_kept = 0;   // area of the smallest kept hole (0 if none)
};

// Returns an 8-bit mask (255 foreground, 0 background) of an 8-bit grey or
// BGR image.
cv::Mat ComputeSilhouette(const cv::Mat& image, const SilhouetteOptions& options,
                          SilhouetteStats* stats = nullptr);

// The COLMAP camera and image of a Middlebury camera. Checks that K is a
// pinhole matrix (|skew| <= 1e-6 fx, K(1,0) = K(2,0) = K(2,1) = 0, K(2,2) = 1,
// fx, fy > 0) and throws InputError naming the image otherwise. The
// translation is multiplied by `scale`.
void MiddleburyToColmap(const MiddleburyCamera& mb, int width, int height, double scale,
                        uint32_t id, Camera* camera, Image* image);

struct MiddleburyConversionOptions {
  // Workspace units per metre (> 0): 1000 writes millimetres.
  double scale = 1000;
  // Held-out images, by 1-based index in the *_par.txt order, as a comma- or
  // space-separated list ("2,9"). Empty: every `holdout_every`-th image.
  std::string holdout;
  // With `holdout` empty, hold out images k, 2k, ... (1-based); 0 holds out
  // none (>= 0).
  int holdout_every = 4;
  SilhouetteOptions silhouette;
  bool Check() const;
};

struct MiddleburyConversionSummary {
  int num_images = 0;
  std::vector<std::string> holdout;  // held-out image names
  int filled_holes = 0;  // silhouette holes filled, over all masks
  int kept_holes = 0;    // larger silhouette holes kept
  bool has_bbox = false;
  Eigen::AlignedBox3d bbox;  // in workspace units, if has_bbox
  double seconds = 0;
  std::string BriefReport() const;
};

// Writes a dense workspace into `output_path`:
//   images/<name>         copies of the images
//   sparse/{cameras,images,points3D}.bin   one PINHOLE camera per image, no points
//   masks/<name>.png      silhouettes (ComputeSilhouette)
//   holdout.txt           held-out image names, one per line
//   bbox.txt              "x0 y0 z0 x1 y1 z1" in workspace units (if the README has one)
//   silhouette_images.txt the data set's *_good_silhouette_images.txt, if any
// Throws InputError if the input is incomplete or inconsistent.
MiddleburyConversionSummary ConvertMiddlebury(const std::string& input_path,
                                              const std::string& output_path,
                                              const MiddleburyConversionOptions& options);

// Reads a list of image names, one per line (blank lines and '#' comments
// skipped). Returns an empty list if the file does not exist.
std::vector<std::string> ReadImageNameList(const std::string& path);

// Reads bbox.txt ("x0 y0 z0 x1 y1 z1"). Throws InputError if malformed.
Eigen::AlignedBox3d ReadBoundingBoxFile(const std::string& path);
// Parses "x0 y0 z0 x1 y1 z1"; throws InputError naming `what` if malformed.
Eigen::AlignedBox3d ParseBoundingBox(const std::string& text, const std::string& what);

}  // namespace mr
