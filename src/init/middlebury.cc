#include "init/middlebury.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/SVD>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap_io/image_file.h"
#include "util/components.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"

namespace mr {
namespace {

// Splits on whitespace.
std::vector<std::string> Tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string tok;
  while (in >> tok) out.push_back(tok);
  return out;
}

bool ParseDouble(const std::string& text, double* value) {
  try {
    size_t pos = 0;
    *value = std::stod(text, &pos);
    return pos == text.size() && std::isfinite(*value);
  } catch (const std::exception&) {
    return false;
  }
}

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  WriteFileAtomically(path, [&](std::ostream& out) { out.write(bytes.data(), bytes.size()); });
}

}  // namespace

Eigen::Matrix<double, 3, 4> MiddleburyCamera::Projection() const {
  Eigen::Matrix<double, 3, 4> Rt;
  Rt.leftCols<3>() = R;
  Rt.col(3) = t;
  return K * Rt;
}

std::vector<MiddleburyCamera> ReadMiddleburyPar(const std::string& path) {
  const std::string text = ReadFileToString(path);
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  // First non-empty line: the count.
  long count = -1;
  while (std::getline(in, line)) {
    ++line_no;
    if (Trim(line).empty()) continue;
    const auto tok = Tokens(line);
    double c = 0;
    if (tok.size() != 1 || !ParseDouble(tok[0], &c) || c != std::floor(c) || c < 1) {
      MR_THROW_INPUT << path << ":" << line_no << ": expected the number of images (an integer "
                     << ">= 1) on the first line, got \"" << Trim(line) << "\"";
    }
    count = static_cast<long>(c);
    break;
  }
  if (count < 0) MR_THROW_INPUT << path << ": empty file, expected a camera count";

  std::vector<MiddleburyCamera> cameras;
  std::set<std::string> names;
  while (std::getline(in, line)) {
    ++line_no;
    if (Trim(line).empty()) continue;
    const auto tok = Tokens(line);
    if (tok.size() != 22) {
      MR_THROW_INPUT << path << ":" << line_no << ": expected 22 fields (name k11..k33 r11..r33 "
                     << "t1 t2 t3), got " << tok.size();
    }
    double v[21];
    for (int i = 0; i < 21; ++i) {
      if (!ParseDouble(tok[i + 1], &v[i])) {
        MR_THROW_INPUT << path << ":" << line_no << ": field " << i + 2 << " (\"" << tok[i + 1]
                       << "\") is not a finite number";
      }
    }
    MiddleburyCamera cam;
    cam.name = tok[0];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        cam.K(r, c) = v[3 * r + c];
        cam.R(r, c) = v[9 + 3 * r + c];
      }
    }
    cam.t = Eigen::Vector3d(v[18], v[19], v[20]);
    const double ortho = (cam.R * cam.R.transpose() - Eigen::Matrix3d::Identity()).norm();
    if (ortho > 1e-5 || cam.R.determinant() < 0) {
      MR_THROW_INPUT << path << ":" << line_no << ": rotation of " << cam.name
                     << " is not a rotation (|R R^T - I| = " << ortho
                     << ", det = " << cam.R.determinant() << ")";
    }
    if (!names.insert(cam.name).second) {
      MR_THROW_INPUT << path << ":" << line_no << ": duplicate image name " << cam.name;
    }
    cameras.push_back(cam);
  }
  if (static_cast<long>(cameras.size()) != count) {
    MR_THROW_INPUT << path << ": the first line announces " << count << " images but "
                   << cameras.size() << " camera lines follow";
  }
  return cameras;
}

bool ReadMiddleburyBoundingBox(const std::string& readme_path, Eigen::AlignedBox3d* bbox) {
  const std::string text = ReadFileToString(readme_path);
  std::istringstream in(text);
  std::string line;
  bool after_header = false;
  std::vector<Eigen::Vector3d> corners;
  while (std::getline(in, line)) {
    std::string lower = line;
    std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
    if (!after_header) {
      if (lower.find("bounding box") != std::string::npos) after_header = true;
      continue;
    }
    const std::string s = Trim(line);
    if (s.empty()) {
      if (corners.empty()) continue;
      break;
    }
    if (s.front() != '(' || s.back() != ')') break;
    const auto tok = Tokens(s.substr(1, s.size() - 2));
    Eigen::Vector3d p;
    if (tok.size() != 3 || !ParseDouble(tok[0], &p.x()) || !ParseDouble(tok[1], &p.y()) ||
        !ParseDouble(tok[2], &p.z())) {
      MR_THROW_INPUT << readme_path << ": malformed bounding-box corner \"" << s
                     << "\", expected (x y z)";
    }
    corners.push_back(p);
    if (corners.size() == 2) break;
  }
  if (corners.size() != 2) return false;
  if ((corners[0].array() > corners[1].array()).any()) {
    MR_THROW_INPUT << readme_path << ": bounding box min (" << corners[0].transpose()
                   << ") exceeds max (" << corners[1].transpose() << ")";
  }
  *bbox = Eigen::AlignedBox3d(corners[0], corners[1]);
  return true;
}

bool SilhouetteOptions::Check() const {
  if (!(threshold >= 0 && threshold <= 1)) {
    MR_THROW_INPUT << "SilhouetteOptions::threshold = " << threshold
                   << ". Violated constraint: 0 <= threshold <= 1";
  }
  if (dilate_px < 0) {
    MR_THROW_INPUT << "SilhouetteOptions::dilate_px = " << dilate_px
                   << ". Violated constraint: dilate_px >= 0";
  }
  if (fill_holes_px < 0) {
    MR_THROW_INPUT << "SilhouetteOptions::fill_holes_px = " << fill_holes_px
                   << ". Violated constraint: fill_holes_px >= 0";
  }
  if (erode_px < 0) {
    MR_THROW_INPUT << "SilhouetteOptions::erode_px = " << erode_px
                   << ". Violated constraint: erode_px >= 0";
  }
  return true;
}

cv::Mat ComputeSilhouette(const cv::Mat& image, const SilhouetteOptions& options,
                          SilhouetteStats* stats) {
  options.Check();
  MR_CHECK(image.depth() == CV_8U) << "8-bit image expected";
  cv::Mat gray;
  if (image.channels() == 1) {
    image.convertTo(gray, CV_32F);
  } else {
    MR_CHECK(image.channels() == 3) << "grey or BGR image expected";
    gray.create(image.size(), CV_32F);
    for (int r = 0; r < image.rows; ++r) {
      const cv::Vec3b* src = image.ptr<cv::Vec3b>(r);
      float* dst = gray.ptr<float>(r);
      for (int c = 0; c < image.cols; ++c) {
        dst[c] = 0.2989f * src[c][2] + 0.5870f * src[c][1] + 0.1140f * src[c][0];
      }
    }
  }
  cv::Mat mask;
  // Matlab's im2bw: foreground where intensity > level.
  cv::threshold(gray, mask, options.threshold * 255.0, 255, cv::THRESH_BINARY);
  mask.convertTo(mask, CV_8U);
  auto disc = [](int radius) {
    return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  };
  // Matlab's imdilate/imerode semantics at the image border: outside pixels
  // neither dilate nor erode (OpenCV's default border values, -inf for
  // dilation and +inf for erosion). An object cut by the image border thus
  // stays foreground up to the border.
  if (options.dilate_px > 0) cv::dilate(mask, mask, disc(options.dilate_px));
  if (options.erode_px > 0) cv::erode(mask, mask, disc(options.erode_px));
  SilhouetteStats local;
  if (options.fill_holes_px > 0) {
    // Background is 4-connected where the foreground is 8-connected; a
    // background component off the border is a hole.
    cv::Mat labels;
    const std::vector<uchar> fill = SelectComponents(
        mask == 0, 4,
        [&](bool touches, int area) {
          if (touches) return false;
          if (area <= options.fill_holes_px) {
            ++local.filled_holes;
            local.largest_filled = std::max(local.largest_filled, area);
            return true;
          }
          ++local.kept_holes;
          local.smallest_kept = local.smallest_kept == 0 ? area : std::min(local.smallest_kept, area);
          return false;
        },
        &labels);
    if (local.filled_holes > 0) {
      for (int r = 0; r < mask.rows; ++r) {
        const int* l = labels.ptr<int>(r);
        uchar* m = mask.ptr<uchar>(r);
        for (int c = 0; c < mask.cols; ++c) {
          if (fill[l[c]]) m[c] = 255;
        }
      }
    }
  }
  if (stats != nullptr) *stats = local;
  return mask;
}

void MiddleburyToColmap(const MiddleburyCamera& mb, int width, int height, double scale,
                        uint32_t id, Camera* camera, Image* image) {
  const Eigen::Matrix3d& K = mb.K;
  const double fx = K(0, 0), fy = K(1, 1);
  if (!(fx > 0 && fy > 0) || std::abs(K(0, 1)) > 1e-6 * fx || K(1, 0) != 0 || K(2, 0) != 0 ||
      K(2, 1) != 0 || std::abs(K(2, 2) - 1) > 1e-12) {
    MR_THROW_INPUT << mb.name << ": intrinsic matrix K = [" << K.row(0) << "; " << K.row(1)
                   << "; " << K.row(2)
                   << "] is not a pinhole matrix (expected fx, fy > 0, zero skew, last row 0 0 1)";
  }
  if (!(scale > 0)) MR_THROW_INPUT << "scale = " << scale << ", expected > 0";
  camera->camera_id = id;
  camera->model = CameraModel::kPinhole;
  camera->width = static_cast<uint64_t>(width);
  camera->height = static_cast<uint64_t>(height);
  // Middlebury: top-left pixel centre (0, 0); COLMAP: (0.5, 0.5).
  camera->params = {fx, fy, K(0, 2) + 0.5, K(1, 2) + 0.5};
  image->image_id = id;
  image->camera_id = id;
  image->name = mb.name;
  // The data sets' rotations are orthonormal to about 1e-7; project onto the
  // nearest rotation before converting to a quaternion.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(mb.R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  image->qvec = RotationToQuaternion(svd.matrixU() * svd.matrixV().transpose());
  image->tvec = scale * mb.t;
  image->points2D.clear();
}

bool MiddleburyConversionOptions::Check() const {
  if (!(scale > 0) || !std::isfinite(scale)) {
    MR_THROW_INPUT << "MiddleburyConversionOptions::scale = " << scale
                   << ". Violated constraint: scale > 0";
  }
  if (holdout_every < 0) {
    MR_THROW_INPUT << "MiddleburyConversionOptions::holdout_every = " << holdout_every
                   << ". Violated constraint: holdout_every >= 0";
  }
  silhouette.Check();
  return true;
}

std::string MiddleburyConversionSummary::BriefReport() const {
  std::ostringstream s;
  s << num_images << " images (" << holdout.size() << " held out), " << filled_holes
    << " silhouette holes filled, " << kept_holes << " kept, bbox "
    << (has_bbox ? "from README" : "none") << ", " << seconds << " s";
  return s.str();
}

std::vector<std::string> ReadImageNameList(const std::string& path) {
  if (!ExistsFile(path)) return {};
  return ReadNameList(path);
}

Eigen::AlignedBox3d ParseBoundingBox(const std::string& text, const std::string& what) {
  const auto tok = Tokens(text);
  double v[6];
  bool ok = tok.size() == 6;
  for (int i = 0; ok && i < 6; ++i) ok = ParseDouble(tok[i], &v[i]);
  if (!ok) {
    MR_THROW_INPUT << what << ": bounding box \"" << Trim(text)
                   << "\" is malformed, expected six numbers \"x0 y0 z0 x1 y1 z1\"";
  }
  const Eigen::Vector3d lo(v[0], v[1], v[2]), hi(v[3], v[4], v[5]);
  if (!((hi - lo).array() > 0).all()) {
    MR_THROW_INPUT << what << ": bounding box \"" << Trim(text)
                   << "\" is empty, expected x0 < x1, y0 < y1, z0 < z1";
  }
  return Eigen::AlignedBox3d(lo, hi);
}

Eigen::AlignedBox3d ReadBoundingBoxFile(const std::string& path) {
  return ParseBoundingBox(ReadFileToString(path), path);
}

MiddleburyConversionSummary ConvertMiddlebury(const std::string& input_path,
                                              const std::string& output_path,
                                              const MiddleburyConversionOptions& options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  if (!ExistsDir(input_path)) MR_THROW_INPUT << input_path << ": not a folder";
  std::string par_path;
  std::string good_path;
  for (const std::string& f : ListFiles(input_path)) {
    if (f.size() > 8 && f.substr(f.size() - 8) == "_par.txt") {
      if (!par_path.empty()) {
        MR_THROW_INPUT << input_path << ": more than one *_par.txt (" << GetFileName(par_path)
                       << ", " << f << ")";
      }
      par_path = JoinPaths(input_path, f);
    }
    if (f.find("good_silhouette_images") != std::string::npos) good_path = JoinPaths(input_path, f);
  }
  if (par_path.empty()) MR_THROW_INPUT << input_path << ": no *_par.txt camera file";
  const std::vector<MiddleburyCamera> cams = ReadMiddleburyPar(par_path);

  // Held-out images.
  std::set<int> holdout_idx;
  if (!options.holdout.empty()) {
    std::string list = options.holdout;
    std::replace(list.begin(), list.end(), ',', ' ');
    for (const std::string& tok : Tokens(list)) {
      double v = 0;
      if (!ParseDouble(tok, &v) || v != std::floor(v) || v < 1 ||
          v > static_cast<double>(cams.size())) {
        MR_THROW_INPUT << "holdout: \"" << tok << "\" is not an image index in [1, "
                       << cams.size() << "]";
      }
      holdout_idx.insert(static_cast<int>(v));
    }
  } else if (options.holdout_every > 0) {
    for (int i = options.holdout_every; i <= static_cast<int>(cams.size());
         i += options.holdout_every) {
      holdout_idx.insert(i);
    }
  }
  if (holdout_idx.size() >= cams.size()) {
    MR_THROW_INPUT << "holdout: all " << cams.size() << " images would be held out";
  }

  CreateDirIfNotExists(output_path);
  const std::string image_dir = JoinPaths(output_path, "images");
  const std::string mask_dir = JoinPaths(output_path, "masks");
  const std::string sparse_dir = JoinPaths(output_path, "sparse");
  CreateDirIfNotExists(image_dir);
  CreateDirIfNotExists(mask_dir);
  CreateDirIfNotExists(sparse_dir);

  MiddleburyConversionSummary summary;
  Reconstruction model;
  for (size_t i = 0; i < cams.size(); ++i) {
    const MiddleburyCamera& mb = cams[i];
    const std::string src = JoinPaths(input_path, mb.name);
    if (!ExistsFile(src)) MR_THROW_INPUT << par_path << ": image " << mb.name << " is missing";
    const std::string bytes = ReadFileToString(src);
    // The bytes are copied as they are: the camera must match the raw pixels
    // (EXIF orientation ignored, as COLMAP and our workspace reader do).
    const cv::Mat image = DecodeImageFile(src, bytes, cv::IMREAD_COLOR);
    const uint32_t id = static_cast<uint32_t>(i + 1);
    Camera camera;
    Image img;
    MiddleburyToColmap(mb, image.cols, image.rows, options.scale, id, &camera, &img);
    model.cameras[id] = camera;
    model.images[id] = img;
    WriteBytes(JoinPaths(image_dir, mb.name), bytes);
    std::vector<uchar> png;
    SilhouetteStats stats;
    cv::imencode(".png", ComputeSilhouette(image, options.silhouette, &stats), png);
    MR_LOG(VERBOSE) << mb.name << ": filled " << stats.filled_holes << " silhouette hole(s) (largest "
                    << stats.largest_filled << " px), kept " << stats.kept_holes
                    << " (smallest " << stats.smallest_kept << " px)";
    summary.filled_holes += stats.filled_holes;
    summary.kept_holes += stats.kept_holes;
    WriteBytes(JoinPaths(mask_dir, mb.name + ".png"), std::string(png.begin(), png.end()));
    if (holdout_idx.count(static_cast<int>(i + 1))) summary.holdout.push_back(mb.name);
  }
  WriteSparseModelBinary(sparse_dir, model);

  WriteFileAtomically(JoinPaths(output_path, "holdout.txt"), [&](std::ostream& out) {
    out << "# Images held out from reconstruction (for photo-consistency checks only).\n";
    for (const std::string& n : summary.holdout) out << n << "\n";
  });
  if (!good_path.empty()) {
    WriteBytes(JoinPaths(output_path, "silhouette_images.txt"), ReadFileToString(good_path));
  }
  const std::string readme = JoinPaths(input_path, "README.txt");
  Eigen::AlignedBox3d bbox;
  if (ExistsFile(readme) && ReadMiddleburyBoundingBox(readme, &bbox)) {
    summary.has_bbox = true;
    summary.bbox = Eigen::AlignedBox3d(options.scale * bbox.min(), options.scale * bbox.max());
    WriteFileAtomically(JoinPaths(output_path, "bbox.txt"), [&](std::ostream& out) {
      out.precision(9);
      out << summary.bbox.min().transpose() << " " << summary.bbox.max().transpose() << "\n";
    });
  }
  summary.num_images = static_cast<int>(cams.size());
  summary.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace mr
