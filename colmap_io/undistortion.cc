#include "colmap_io/undistortion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap_io/image_file.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {

const char kUndistortionMarker[] = "mesh_refiner_undistortion.txt";
const char kUndistortionPartialMarker[] = "mesh_refiner_undistortion.partial";

bool UndistortionOptions::Check() const {
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    MR_THROW_INPUT << "UndistortionOptions::jpeg_quality = " << jpeg_quality
                   << ". Violated constraint: 1 <= jpeg_quality <= 100";
  }
  return true;
}

Camera UndistortedCamera(const Camera& camera) {
  Camera out;
  out.camera_id = camera.camera_id;
  out.model = CameraModel::kPinhole;
  out.width = camera.width;
  out.height = camera.height;
  out.params = {CameraFocalX(camera.model, camera.params), CameraFocalY(camera.model, camera.params),
                CameraPrincipalX(camera.model, camera.params),
                CameraPrincipalY(camera.model, camera.params)};
  return out;
}

namespace {

// Share of the undistorted image's pixels (every `stride`-th row and column)
// whose sample lies outside the distorted image, or is not finite: the part
// that would come out black.
double OutsideFraction(const Camera& camera, int stride) {
  const Camera pinhole = UndistortedCamera(camera);
  const double fx = pinhole.params[0], fy = pinhole.params[1], cx = pinhole.params[2],
               cy = pinhole.params[3];
  long outside = 0, total = 0;
  for (int row = 0; row < static_cast<int>(camera.height); row += stride) {
    for (int col = 0; col < static_cast<int>(camera.width); col += stride) {
      const Eigen::Vector2d n((col + 0.5 - cx) / fx, (row + 0.5 - cy) / fy);
      const Eigen::Vector2d d = CameraImageFromWorld(camera.model, camera.params, n);
      const bool inside = d.allFinite() && d.x() >= 0 && d.x() <= camera.width && d.y() >= 0 &&
                          d.y() <= camera.height;
      outside += inside ? 0 : 1;
      ++total;
    }
  }
  return total > 0 ? static_cast<double>(outside) / total : 0.0;
}

// "k1 = 5, k2 = 0" for the distortion parameters of `camera`.
std::string DistortionText(const Camera& camera) {
  const std::vector<std::string> names = CameraModelParamNames(camera.model);
  const int first =
      CameraModelNumParams(camera.model) - CameraModelNumDistortionParams(camera.model);
  std::ostringstream text;
  for (int i = first; i < CameraModelNumParams(camera.model); ++i) {
    text << (i > first ? ", " : "") << names[i] << " = " << camera.params[i];
  }
  return text.str();
}

// Refuses a camera whose distortion sends more than kMaxOutsideFraction of
// the undistorted image outside the distorted one (OPENCV k1 = 5, RADIAL
// k1 = 240: the refinement then compares black images and "finishes" at
// similarity 0). Names the parameter(s) that alone bring it back within
// bounds when set to 0. Real lenses stay far below: barrel distortion
// (k1 < 0) samples inside the image, and strong pincushion (OPENCV
// k1 = +0.3 at a 65-degree field of view) loses 18 %; k1 = 5 at 40 degrees
// loses 45 %.
constexpr double kMaxOutsideFraction = 0.25;

void CheckDistortionRange(const Camera& camera) {
  const long pixels = static_cast<long>(camera.width) * camera.height;
  const int stride = std::max(1, static_cast<int>(std::sqrt(pixels / 40000.0)));
  const double outside = OutsideFraction(camera, stride);
  if (outside <= kMaxOutsideFraction) return;
  std::ostringstream culprits;
  const std::vector<std::string> names = CameraModelParamNames(camera.model);
  const int first =
      CameraModelNumParams(camera.model) - CameraModelNumDistortionParams(camera.model);
  for (int i = first; i < CameraModelNumParams(camera.model); ++i) {
    if (camera.params[i] == 0) continue;
    Camera without = camera;
    without.params[i] = 0;
    const double fraction = OutsideFraction(without, stride);
    if (fraction <= kMaxOutsideFraction) {
      culprits << (culprits.tellp() > 0 ? "; " : "") << names[i] << " = " << camera.params[i]
               << " (with " << names[i] << " = 0: " << std::lround(100 * fraction) << " %)";
    }
  }
  MR_THROW_INPUT << "camera " << camera.camera_id << " (" << CameraModelName(camera.model) << ", "
                 << DistortionText(camera) << "): " << std::lround(100 * outside)
                 << " % of the undistorted " << camera.width << "x" << camera.height
                 << " image would sample outside the distorted image (at most "
                 << std::lround(100 * kMaxOutsideFraction) << " % allowed): "
                 << (culprits.tellp() > 0 ? "implausible distortion parameter " + culprits.str()
                                          : std::string("implausible distortion parameters"))
                 << "; check the sparse model's cameras";
}

}  // namespace

void ComputeUndistortionMaps(const Camera& camera, cv::Mat* map_x, cv::Mat* map_y) {
  CheckDistortionRange(camera);
  const Camera pinhole = UndistortedCamera(camera);
  const int w = static_cast<int>(camera.width), h = static_cast<int>(camera.height);
  const double fx = pinhole.params[0], fy = pinhole.params[1], cx = pinhole.params[2],
               cy = pinhole.params[3];
  // Distorted positions at the pixel corners grid (w+1)x(h+1) would be more
  // work; sample at pixel centres and check the Jacobian between neighbours.
  cv::Mat mx(h, w, CV_64F), my(h, w, CV_64F);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector2d n((col + 0.5 - cx) / fx, (row + 0.5 - cy) / fy);
      const Eigen::Vector2d d = CameraImageFromWorld(camera.model, camera.params, n);
      if (!d.allFinite()) {
        MR_THROW_INPUT << "camera " << camera.camera_id << " (" << CameraModelName(camera.model)
                       << "): the distortion is not finite at pixel (" << col << ", " << row
                       << "); cannot undistort it with the built-in equations";
      }
      mx.at<double>(row, col) = d.x() - 0.5;
      my.at<double>(row, col) = d.y() - 0.5;
    }
  }
  // A fold (non-positive Jacobian determinant) means several output pixels
  // see the same distorted pixel: the model is used beyond its valid range.
  for (int row = 0; row + 1 < h; ++row) {
    for (int col = 0; col + 1 < w; ++col) {
      const double a = mx.at<double>(row, col + 1) - mx.at<double>(row, col);
      const double b = mx.at<double>(row + 1, col) - mx.at<double>(row, col);
      const double c = my.at<double>(row, col + 1) - my.at<double>(row, col);
      const double d = my.at<double>(row + 1, col) - my.at<double>(row, col);
      const bool inside = mx.at<double>(row, col) > -0.5 && mx.at<double>(row, col) < w - 0.5 &&
                          my.at<double>(row, col) > -0.5 && my.at<double>(row, col) < h - 0.5;
      if (inside && a * d - b * c <= 0) {
        MR_THROW_INPUT << "camera " << camera.camera_id << " (" << CameraModelName(camera.model)
                       << ", " << DistortionText(camera)
                       << "): the distortion folds over at pixel (" << col << ", " << row
                       << ") of the image (parameters outside the model's valid range); "
                       << "cannot undistort it; run `colmap image_undistorter` instead";
      }
    }
  }
  mx.convertTo(*map_x, CV_32F);
  my.convertTo(*map_y, CV_32F);
}

cv::Mat UndistortImage(const cv::Mat& image, const Camera& camera, int interpolation) {
  MR_CHECK(image.cols == static_cast<int>(camera.width) &&
           image.rows == static_cast<int>(camera.height))
      << "image " << image.cols << "x" << image.rows << " vs camera " << camera.width << "x"
      << camera.height;
  cv::Mat map_x, map_y, out;
  ComputeUndistortionMaps(camera, &map_x, &map_y);
  cv::remap(image, out, map_x, map_y, interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

std::string UndistortionFingerprint(const std::string& image_dir, const std::string& mask_dir,
                                    const Reconstruction& model) {
  std::ostringstream s;
  s << std::setprecision(std::numeric_limits<double>::max_digits10);
  s << "mesh_refiner undistortion v1\n";
  s << "image_dir " << image_dir << "\nmask_dir " << mask_dir << "\n";
  for (const auto& [id, camera] : model.cameras) {
    s << "camera " << id << " " << CameraModelName(camera.model) << " " << camera.width << " "
      << camera.height;
    for (double p : camera.params) s << " " << p;
    s << "\n";
  }
  // Sizes and modification times of the source files, so replaced images or
  // masks are undistorted again.
  auto stamp = [&](const std::string& path) {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) return std::string("-");
    const auto time = std::filesystem::last_write_time(path, ec);
    if (ec) return std::string("-");
    return std::to_string(size) + "@" + std::to_string(time.time_since_epoch().count());
  };
  for (const auto& [id, image] : model.images) {
    s << "image " << id << " " << image.camera_id << " " << image.name << " "
      << stamp(JoinPaths(image_dir, image.name));
    if (!mask_dir.empty()) s << " mask " << stamp(JoinPaths(mask_dir, image.name + ".png"));
    s << "\n";
  }
  return s.str();
}

UndistortionSummary UndistortSparseModel(const std::string& image_dir,
                                         const std::string& mask_dir,
                                         const Reconstruction& model,
                                         const std::string& output_dir,
                                         const UndistortionOptions& options) {
  options.Check();
  // Image names become paths below output_dir: refuse any that would escape it.
  for (const auto& [id, image] : model.images) {
    const std::filesystem::path name(image.name);
    bool escapes = name.is_absolute() || name.empty();
    for (const auto& part : name) escapes = escapes || part == "..";
    if (escapes) {
      MR_THROW_INPUT << "image " << id << " has the name '" << image.name
                     << "', which is not a relative path inside the image folder";
    }
  }
  // Validate every camera before writing anything.
  std::map<uint32_t, std::pair<cv::Mat, cv::Mat>> maps;
  Reconstruction out_model;
  for (const auto& [id, camera] : model.cameras) {
    cv::Mat mx, my;
    ComputeUndistortionMaps(camera, &mx, &my);
    maps[id] = {mx, my};
    out_model.cameras[id] = UndistortedCamera(camera);
  }
  out_model.points3D = model.points3D;
  for (const auto& [id, image] : model.images) {
    const Camera& camera = model.cameras.at(image.camera_id);
    const Camera& pinhole = out_model.cameras.at(image.camera_id);
    Image out = image;
    for (Point2D& p : out.points2D) {
      const Eigen::Vector2d n = CameraWorldFromImage(camera.model, camera.params, p.xy);
      p.xy = CameraImageFromWorld(pinhole.model, pinhole.params, n);
    }
    out_model.images[id] = std::move(out);
  }

  const std::string out_images = JoinPaths(output_dir, "images");
  const std::string out_masks = JoinPaths(output_dir, "masks");
  const std::string out_sparse = JoinPaths(output_dir, "sparse");
  CreateDirIfNotExists(output_dir);
  // Mark the folder as ours (and incomplete) before writing into it.
  std::remove(JoinPaths(output_dir, kUndistortionMarker).c_str());
  WriteFileAtomically(JoinPaths(output_dir, kUndistortionPartialMarker),
                      [&](std::ostream& out) { out << "incomplete mesh_refiner undistortion\n"; });
  CreateDirIfNotExists(out_images);
  CreateDirIfNotExists(out_sparse);

  UndistortionSummary summary;
  summary.output_path = output_dir;
  Progress progress("Undistorting images", static_cast<long>(model.images.size()));
  for (const auto& [id, image] : model.images) {
    const Camera& camera = model.cameras.at(image.camera_id);
    const auto& [mx, my] = maps.at(image.camera_id);
    const std::string src = JoinPaths(image_dir, image.name);
    const cv::Mat in = ReadImageFile(src, cv::IMREAD_UNCHANGED, "image " + std::to_string(id));
    if (in.cols != static_cast<int>(camera.width) || in.rows != static_cast<int>(camera.height)) {
      MR_THROW_INPUT << src << ": image is " << in.cols << "x" << in.rows << " but camera "
                     << camera.camera_id << " is " << camera.width << "x" << camera.height;
    }
    cv::Mat undistorted;
    cv::remap(in, undistorted, mx, my, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    WriteImageFile(JoinPaths(out_images, image.name), undistorted, options.jpeg_quality);
    ++summary.num_images;

    if (!mask_dir.empty()) {
      const std::string mask_path = JoinPaths(mask_dir, image.name + ".png");
      if (ExistsFile(mask_path)) {
        const cv::Mat mask = ReadImageFile(mask_path, cv::IMREAD_GRAYSCALE, "mask");
        if (mask.size() != in.size()) {
          MR_THROW_INPUT << mask_path << ": mask is " << mask.cols << "x" << mask.rows
                         << " but its image is " << in.cols << "x" << in.rows;
        }
        cv::Mat out_mask;
        cv::remap(mask, out_mask, mx, my, cv::INTER_NEAREST, cv::BORDER_CONSTANT,
                  cv::Scalar::all(0));
        WriteImageFile(JoinPaths(out_masks, image.name + ".png"), out_mask,
                             options.jpeg_quality);
        ++summary.num_masks;
      }
    }
    progress.Update(summary.num_images);
  }
  progress.Done();
  WriteSparseModelBinary(out_sparse, out_model);
  const std::string fingerprint = UndistortionFingerprint(image_dir, mask_dir, model);
  WriteFileAtomically(JoinPaths(output_dir, kUndistortionMarker),
                      [&](std::ostream& out) { out << fingerprint; });
  std::remove(JoinPaths(output_dir, kUndistortionPartialMarker).c_str());
  return summary;
}

}  // namespace mr
