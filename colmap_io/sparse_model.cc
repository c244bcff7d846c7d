#include "colmap_io/sparse_model.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

#include "util/error.h"
#include "util/file.h"

namespace mr {

Eigen::Matrix3d QuaternionToRotation(const Eigen::Vector4d& qvec) {
  const Eigen::Quaterniond q(qvec(0), qvec(1), qvec(2), qvec(3));
  return q.normalized().toRotationMatrix();
}

Eigen::Vector4d RotationToQuaternion(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

Eigen::Matrix3d Image::Rotation() const { return QuaternionToRotation(qvec); }

Eigen::Vector3d Image::ProjectionCenter() const { return -Rotation().transpose() * tvec; }

namespace {

constexpr uint64_t kMaxImageSide = uint64_t(1) << 20;  // pixels; sanity bound on width/height

// ---------------------------------------------------------------------------
// Checks shared by the binary and the text readers.

void CheckFinite(const std::string& path, double value, const std::string& what) {
  if (!std::isfinite(value)) MR_THROW_INPUT << path << ": " << what << " is not finite (" << value << ")";
}

void CheckCamera(const std::string& path, int model_id, const Camera& camera) {
  const std::string where = "camera " + std::to_string(camera.camera_id);
  if (camera.width == 0 || camera.height == 0 || camera.width > kMaxImageSide ||
      camera.height > kMaxImageSide) {
    MR_THROW_INPUT << path << ": " << where << " has size " << camera.width << "x" << camera.height
                   << " (expected 1.." << kMaxImageSide << " pixels per side)";
  }
  const int expected = CameraModelNumParams(camera.model);
  if (static_cast<int>(camera.params.size()) != expected) {
    MR_THROW_INPUT << path << ": " << where << " (model " << CameraModelName(camera.model)
                   << ", id " << model_id << ") has " << camera.params.size()
                   << " parameters (expected " << expected << ")";
  }
  for (size_t i = 0; i < camera.params.size(); ++i) {
    CheckFinite(path, camera.params[i], where + " parameter " + std::to_string(i));
  }
  const bool separate = HasSeparateFocalLengths(camera.model);
  const double fx = CameraFocalX(camera.model, camera.params);
  const double fy = CameraFocalY(camera.model, camera.params);
  if (fx <= 0 || fy <= 0) {
    const char* name = !separate ? "f" : fx <= 0 ? "fx" : "fy";
    MR_THROW_INPUT << path << ": " << where << " (" << CameraModelName(camera.model)
                   << ") has a non-positive focal length " << name << " = "
                   << (fx <= 0 ? fx : fy) << " (expected > 0)";
  }
}

void CheckImage(const std::string& path, const Image& image,
                const std::map<uint32_t, Camera>& cameras) {
  const std::string where = "image " + std::to_string(image.image_id);
  for (int i = 0; i < 4; ++i) CheckFinite(path, image.qvec[i], where + " quaternion");
  for (int i = 0; i < 3; ++i) CheckFinite(path, image.tvec[i], where + " translation");
  const double qnorm = image.qvec.norm();
  if (qnorm < 1e-6) {
    MR_THROW_INPUT << path << ": " << where << " has a degenerate quaternion of norm " << qnorm
                   << " (expected a unit quaternion)";
  }
  if (image.name.empty()) MR_THROW_INPUT << path << ": " << where << " has an empty name";
  if (cameras.count(image.camera_id) == 0) {
    MR_THROW_INPUT << path << ": " << where << " ('" << image.name << "') refers to camera "
                   << image.camera_id << ", which is not in cameras";
  }
  for (size_t i = 0; i < image.points2D.size(); ++i) {
    const Point2D& p = image.points2D[i];
    if (!p.xy.allFinite()) {
      MR_THROW_INPUT << path << ": " << where << " point2D " << i << " is not finite";
    }
    if (p.point3D_id < -1) {
      MR_THROW_INPUT << path << ": " << where << " point2D " << i << " has point3D id "
                     << p.point3D_id << " (expected -1 or a valid id)";
    }
  }
}

void CheckPoint3D(const std::string& path, const Point3D& point,
                  const std::map<uint32_t, Image>& images) {
  const std::string where = "point3D " + std::to_string(point.point3D_id);
  for (int i = 0; i < 3; ++i) CheckFinite(path, point.xyz[i], where + " coordinate");
  CheckFinite(path, point.error, where + " error");
  for (const TrackElement& el : point.track) {
    const auto it = images.find(el.image_id);
    if (it == images.end()) {
      MR_THROW_INPUT << path << ": " << where << " track refers to image " << el.image_id
                     << ", which is not in images";
    }
    if (el.point2D_idx >= it->second.points2D.size()) {
      MR_THROW_INPUT << path << ": " << where << " track refers to point2D " << el.point2D_idx
                     << " of image " << el.image_id << ", which has "
                     << it->second.points2D.size() << " points2D";
    }
  }
}

CameraModel ModelFromId(const std::string& path, uint32_t camera_id, int64_t model_id) {
  if (model_id < 0 || model_id > 10 || !IsKnownCameraModelId(static_cast<int>(model_id))) {
    MR_THROW_INPUT << path << ": camera " << camera_id << " has unknown camera model id "
                   << model_id << " (this build knows COLMAP 3.8's ids 0-10; newer COLMAP "
                   << "models are not supported)";
  }
  return static_cast<CameraModel>(model_id);
}

// ---------------------------------------------------------------------------
// Binary reading: a bounds-checked little-endian cursor over the whole file.

class BinaryCursor {
 public:
  BinaryCursor(const std::string& path, const std::string& data) : path_(path), data_(data) {}

  size_t Remaining() const { return data_.size() - pos_; }

  template <typename T>
  T Read(const char* what) {
    if (Remaining() < sizeof(T)) {
      MR_THROW_INPUT << path_ << ": truncated file: cannot read " << what << " at byte " << pos_
                     << " (file has " << data_.size() << " bytes)";
    }
    T value;
    std::memcpy(&value, data_.data() + pos_, sizeof(T));  // little-endian hosts only
    pos_ += sizeof(T);
    return value;
  }

  // A count of records of at least `min_record_bytes` each that must fit in
  // the rest of the file (no huge allocations from a corrupt count).
  uint64_t ReadCount(const char* what, size_t min_record_bytes) {
    const uint64_t n = Read<uint64_t>(what);
    if (min_record_bytes > 0 && n > Remaining() / min_record_bytes) {
      MR_THROW_INPUT << path_ << ": " << what << " = " << n << " needs at least "
                     << min_record_bytes << " bytes each but only " << Remaining()
                     << " bytes are left (truncated or corrupt file)";
    }
    return n;
  }

  std::string ReadName(const char* what) {
    const size_t end = data_.find('\0', pos_);
    if (end == std::string::npos) {
      MR_THROW_INPUT << path_ << ": truncated file: " << what << " at byte " << pos_
                     << " has no terminating NUL";
    }
    std::string s = data_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }

  void ExpectEnd() const {
    if (Remaining() != 0) {
      MR_THROW_INPUT << path_ << ": " << Remaining()
                     << " unexpected trailing bytes after the last record (corrupt file?)";
    }
  }

  const std::string& path() const { return path_; }

 private:
  const std::string& path_;
  const std::string& data_;
  size_t pos_ = 0;
};

static_assert(sizeof(double) == 8 && sizeof(float) == 4, "IEEE types expected");

void ReadCamerasBinary(const std::string& path, const std::string& data, Reconstruction* model) {
  BinaryCursor in(path, data);
  const uint64_t n = in.ReadCount("number of cameras", 24 + 3 * 8);
  for (uint64_t i = 0; i < n; ++i) {
    Camera camera;
    camera.camera_id = in.Read<uint32_t>("camera_id");
    const int32_t model_id = in.Read<int32_t>("camera model id");
    camera.model = ModelFromId(path, camera.camera_id, model_id);
    camera.width = in.Read<uint64_t>("camera width");
    camera.height = in.Read<uint64_t>("camera height");
    camera.params.resize(CameraModelNumParams(camera.model));
    for (double& p : camera.params) p = in.Read<double>("camera parameter");
    CheckCamera(path, model_id, camera);
    if (!model->cameras.emplace(camera.camera_id, camera).second) {
      MR_THROW_INPUT << path << ": duplicate camera id " << camera.camera_id;
    }
  }
  in.ExpectEnd();
}

void ReadImagesBinary(const std::string& path, const std::string& data, Reconstruction* model) {
  BinaryCursor in(path, data);
  const uint64_t n = in.ReadCount("number of images", 4 + 7 * 8 + 4 + 1 + 8);
  for (uint64_t i = 0; i < n; ++i) {
    Image image;
    image.image_id = in.Read<uint32_t>("image_id");
    for (int k = 0; k < 4; ++k) image.qvec[k] = in.Read<double>("image quaternion");
    for (int k = 0; k < 3; ++k) image.tvec[k] = in.Read<double>("image translation");
    image.camera_id = in.Read<uint32_t>("image camera_id");
    image.name = in.ReadName("image name");
    const uint64_t n2d = in.ReadCount("number of points2D", 24);
    image.points2D.resize(n2d);
    for (Point2D& p : image.points2D) {
      p.xy.x() = in.Read<double>("point2D x");
      p.xy.y() = in.Read<double>("point2D y");
      p.point3D_id = in.Read<int64_t>("point2D point3D_id");
    }
    CheckImage(path, image, model->cameras);
    const uint32_t id = image.image_id;
    if (!model->images.emplace(id, std::move(image)).second) {
      MR_THROW_INPUT << path << ": duplicate image id " << id;
    }
  }
  in.ExpectEnd();
}

void ReadPoints3DBinary(const std::string& path, const std::string& data, Reconstruction* model) {
  BinaryCursor in(path, data);
  const uint64_t n = in.ReadCount("number of points3D", 8 + 24 + 3 + 8 + 8);
  for (uint64_t i = 0; i < n; ++i) {
    Point3D point;
    point.point3D_id = in.Read<uint64_t>("point3D_id");
    for (int k = 0; k < 3; ++k) point.xyz[k] = in.Read<double>("point3D coordinate");
    for (int k = 0; k < 3; ++k) point.rgb[k] = in.Read<uint8_t>("point3D color");
    point.error = in.Read<double>("point3D error");
    const uint64_t len = in.ReadCount("point3D track length", 8);
    point.track.resize(len);
    for (TrackElement& el : point.track) {
      el.image_id = in.Read<uint32_t>("track image_id");
      el.point2D_idx = in.Read<uint32_t>("track point2D_idx");
    }
    CheckPoint3D(path, point, model->images);
    const uint64_t id = point.point3D_id;
    if (!model->points3D.emplace(id, std::move(point)).second) {
      MR_THROW_INPUT << path << ": duplicate point3D id " << id;
    }
  }
  in.ExpectEnd();
}

// ---------------------------------------------------------------------------
// Text reading: strict token parsing with file:line in every error.

class TextLine {
 public:
  TextLine(const std::string& path, int line_no, const std::string& line)
      : path_(path), line_no_(line_no), stream_(line) {}

  std::string Token(const char* what) {
    std::string token;
    if (!(stream_ >> token)) {
      MR_THROW_INPUT << path_ << ":" << line_no_ << ": missing " << what;
    }
    return token;
  }
  bool HasMore() {
    stream_ >> std::ws;
    return !stream_.eof();
  }
  std::string Rest() {
    std::string rest;
    std::getline(stream_ >> std::ws, rest);
    while (!rest.empty() && (rest.back() == ' ' || rest.back() == '\t' || rest.back() == '\r')) {
      rest.pop_back();
    }
    return rest;
  }
  double Double(const char* what) {
    const std::string t = Token(what);
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end != '\0') Bad(what, t, "a number");
    if (!std::isfinite(v)) Bad(what, t, "a finite number");
    return v;
  }
  int64_t Int(const char* what, int64_t lo, int64_t hi) {
    const std::string t = Token(what);
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(t.c_str(), &end, 10);
    if (end == t.c_str() || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
      Bad(what, t, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return v;
  }
  uint64_t U64(const char* what) {
    const std::string t = Token(what);
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(t.c_str(), &end, 10);
    if (t[0] == '-' || end == t.c_str() || *end != '\0' || errno == ERANGE) {
      Bad(what, t, "a non-negative integer");
    }
    return v;
  }
  [[noreturn]] void Bad(const char* what, const std::string& token, const std::string& expected) {
    MR_THROW_INPUT << path_ << ":" << line_no_ << ": " << what << " '" << token << "' (expected "
                   << expected << ")";
  }
  void ExpectEnd() {
    if (HasMore()) {
      MR_THROW_INPUT << path_ << ":" << line_no_ << ": unexpected extra values '" << Rest() << "'";
    }
  }
  std::string Where() const { return path_ + ":" + std::to_string(line_no_); }

 private:
  const std::string& path_;
  int line_no_;
  std::istringstream stream_;
};

constexpr int64_t kU32Max = std::numeric_limits<uint32_t>::max();

class LineReader {
 public:
  explicit LineReader(const std::string& data) {
    std::istringstream in(data);
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines_.push_back(line);
    }
  }
  // Next non-empty, non-comment line; false at the end.
  bool NextData(std::string* line, int* line_no) {
    while (pos_ < lines_.size()) {
      const std::string& l = lines_[pos_++];
      const size_t first = l.find_first_not_of(" \t");
      if (first == std::string::npos || l[first] == '#') continue;
      *line = l;
      *line_no = static_cast<int>(pos_);
      return true;
    }
    return false;
  }
  // The very next line, whatever it holds; false at the end.
  bool NextRaw(std::string* line, int* line_no) {
    if (pos_ >= lines_.size()) return false;
    *line = lines_[pos_++];
    *line_no = static_cast<int>(pos_);
    return true;
  }

 private:
  std::vector<std::string> lines_;
  size_t pos_ = 0;
};

void ReadCamerasText(const std::string& path, const std::string& data, Reconstruction* model) {
  LineReader reader(data);
  std::string line;
  int line_no = 0;
  while (reader.NextData(&line, &line_no)) {
    TextLine in(path, line_no, line);
    Camera camera;
    camera.camera_id = static_cast<uint32_t>(in.Int("CAMERA_ID", 0, kU32Max));
    const std::string name = in.Token("MODEL");
    try {
      camera.model = CameraModelFromName(name);
    } catch (const InputError& e) {
      MR_THROW_INPUT << in.Where() << ": camera " << camera.camera_id << ": " << e.what();
    }
    camera.width = in.U64("WIDTH");
    camera.height = in.U64("HEIGHT");
    while (in.HasMore()) camera.params.push_back(in.Double("PARAMS[]"));
    CheckCamera(in.Where(), static_cast<int>(camera.model), camera);
    if (!model->cameras.emplace(camera.camera_id, camera).second) {
      MR_THROW_INPUT << in.Where() << ": duplicate camera id " << camera.camera_id;
    }
  }
}

void ReadImagesText(const std::string& path, const std::string& data, Reconstruction* model) {
  LineReader reader(data);
  std::string line;
  int line_no = 0;
  while (reader.NextData(&line, &line_no)) {
    Image image;
    {
      TextLine in(path, line_no, line);
      image.image_id = static_cast<uint32_t>(in.Int("IMAGE_ID", 0, kU32Max));
      for (int k = 0; k < 4; ++k) image.qvec[k] = in.Double("quaternion QW QX QY QZ");
      for (int k = 0; k < 3; ++k) image.tvec[k] = in.Double("translation TX TY TZ");
      image.camera_id = static_cast<uint32_t>(in.Int("CAMERA_ID", 0, kU32Max));
      image.name = in.Rest();
      if (image.name.empty()) MR_THROW_INPUT << in.Where() << ": missing NAME";
    }
    // The points line follows directly (it may be empty). A missing last
    // line means no points.
    std::string points_line;
    int points_line_no = line_no + 1;
    if (reader.NextRaw(&points_line, &points_line_no)) {
      TextLine in(path, points_line_no, points_line);
      while (in.HasMore()) {
        Point2D p;
        p.xy.x() = in.Double("POINTS2D X");
        p.xy.y() = in.Double("POINTS2D Y");
        p.point3D_id = in.Int("POINTS2D POINT3D_ID", -1, std::numeric_limits<int64_t>::max());
        image.points2D.push_back(p);
      }
    }
    CheckImage(path + ":" + std::to_string(line_no), image, model->cameras);
    const uint32_t id = image.image_id;
    if (!model->images.emplace(id, std::move(image)).second) {
      MR_THROW_INPUT << path << ":" << line_no << ": duplicate image id " << id;
    }
  }
}

void ReadPoints3DText(const std::string& path, const std::string& data, Reconstruction* model) {
  LineReader reader(data);
  std::string line;
  int line_no = 0;
  while (reader.NextData(&line, &line_no)) {
    TextLine in(path, line_no, line);
    Point3D point;
    point.point3D_id = in.U64("POINT3D_ID");
    for (int k = 0; k < 3; ++k) point.xyz[k] = in.Double("X Y Z");
    for (int k = 0; k < 3; ++k) point.rgb[k] = static_cast<uint8_t>(in.Int("R G B", 0, 255));
    point.error = in.Double("ERROR");
    while (in.HasMore()) {
      TrackElement el;
      el.image_id = static_cast<uint32_t>(in.Int("TRACK IMAGE_ID", 0, kU32Max));
      el.point2D_idx = static_cast<uint32_t>(in.Int("TRACK POINT2D_IDX", 0, kU32Max));
      point.track.push_back(el);
    }
    CheckPoint3D(in.Where(), point, model->images);
    const uint64_t id = point.point3D_id;
    if (!model->points3D.emplace(id, std::move(point)).second) {
      MR_THROW_INPUT << in.Where() << ": duplicate point3D id " << id;
    }
  }
}

// ---------------------------------------------------------------------------
// Writing.

template <typename T>
void Put(std::ostream& out, T value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

void CheckWritable(const std::string& dir, const Reconstruction& model) {
  if (!ExistsDir(dir)) MR_THROW_INPUT << dir << ": output folder does not exist";
  for (const auto& [id, camera] : model.cameras) {
    MR_CHECK_EQ(id, camera.camera_id) << "camera map key";
    MR_CHECK_EQ(static_cast<int>(camera.params.size()), CameraModelNumParams(camera.model))
        << "camera " << id;
  }
  for (const auto& [id, image] : model.images) {
    MR_CHECK_EQ(id, image.image_id) << "image map key";
    MR_CHECK(image.name.find('\0') == std::string::npos && image.name.find('\n') == std::string::npos)
        << "image name";
  }
  for (const auto& [id, point] : model.points3D) MR_CHECK_EQ(id, point.point3D_id) << "point3D map key";
}

}  // namespace

void ReadSparseModelFile(const std::string& path, const std::string& data,
                         Reconstruction* model) {
  const std::string name = GetFileName(path);
  if (name == "cameras.bin") return ReadCamerasBinary(path, data, model);
  if (name == "images.bin") return ReadImagesBinary(path, data, model);
  if (name == "points3D.bin") return ReadPoints3DBinary(path, data, model);
  if (name == "cameras.txt") return ReadCamerasText(path, data, model);
  if (name == "images.txt") return ReadImagesText(path, data, model);
  if (name == "points3D.txt") return ReadPoints3DText(path, data, model);
  MR_THROW_INPUT << path << ": not a sparse model file (expected cameras, images or points3D "
                 << "with .bin or .txt)";
}

namespace {

Reconstruction ReadSparseModelFiles(const std::string& dir, const char* ext) {
  Reconstruction model;
  for (const char* name : {"cameras", "images", "points3D"}) {
    const std::string path = JoinPaths(dir, std::string(name) + ext);
    ReadSparseModelFile(path, ReadFileToString(path), &model);
  }
  return model;
}

}  // namespace

Reconstruction ReadSparseModelBinary(const std::string& dir) {
  return ReadSparseModelFiles(dir, ".bin");
}

Reconstruction ReadSparseModelText(const std::string& dir) {
  return ReadSparseModelFiles(dir, ".txt");
}

Reconstruction ReadSparseModel(const std::string& dir) {
  if (!ExistsDir(dir)) MR_THROW_INPUT << dir << ": sparse model folder does not exist";
  if (ExistsFile(JoinPaths(dir, "cameras.bin"))) return ReadSparseModelBinary(dir);
  if (ExistsFile(JoinPaths(dir, "cameras.txt"))) return ReadSparseModelText(dir);
  MR_THROW_INPUT << dir << ": no sparse model (expected cameras.bin, images.bin, points3D.bin "
                 << "or cameras.txt, images.txt, points3D.txt)";
}

void WriteSparseModelBinary(const std::string& dir, const Reconstruction& model) {
  CheckWritable(dir, model);
  WriteFileAtomically(JoinPaths(dir, "cameras.bin"), [&](std::ostream& out) {
    Put<uint64_t>(out, model.cameras.size());
    for (const auto& [id, camera] : model.cameras) {
      Put<uint32_t>(out, id);
      Put<int32_t>(out, static_cast<int32_t>(camera.model));
      Put<uint64_t>(out, camera.width);
      Put<uint64_t>(out, camera.height);
      for (double p : camera.params) Put<double>(out, p);
    }
  });
  WriteFileAtomically(JoinPaths(dir, "images.bin"), [&](std::ostream& out) {
    Put<uint64_t>(out, model.images.size());
    for (const auto& [id, image] : model.images) {
      Put<uint32_t>(out, id);
      for (int k = 0; k < 4; ++k) Put<double>(out, image.qvec[k]);
      for (int k = 0; k < 3; ++k) Put<double>(out, image.tvec[k]);
      Put<uint32_t>(out, image.camera_id);
      out.write(image.name.c_str(), image.name.size() + 1);
      Put<uint64_t>(out, image.points2D.size());
      for (const Point2D& p : image.points2D) {
        Put<double>(out, p.xy.x());
        Put<double>(out, p.xy.y());
        Put<int64_t>(out, p.point3D_id);
      }
    }
  });
  WriteFileAtomically(JoinPaths(dir, "points3D.bin"), [&](std::ostream& out) {
    Put<uint64_t>(out, model.points3D.size());
    for (const auto& [id, point] : model.points3D) {
      Put<uint64_t>(out, id);
      for (int k = 0; k < 3; ++k) Put<double>(out, point.xyz[k]);
      for (int k = 0; k < 3; ++k) Put<uint8_t>(out, point.rgb[k]);
      Put<double>(out, point.error);
      Put<uint64_t>(out, point.track.size());
      for (const TrackElement& el : point.track) {
        Put<uint32_t>(out, el.image_id);
        Put<uint32_t>(out, el.point2D_idx);
      }
    }
  });
}

void WriteSparseModelText(const std::string& dir, const Reconstruction& model) {
  CheckWritable(dir, model);
  const int digits = std::numeric_limits<double>::max_digits10;
  WriteFileAtomically(JoinPaths(dir, "cameras.txt"), [&](std::ostream& out) {
    out << std::setprecision(digits);
    out << "# Camera list with one line of data per camera:\n"
        << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
        << "# Number of cameras: " << model.cameras.size() << "\n";
    for (const auto& [id, camera] : model.cameras) {
      out << id << " " << CameraModelName(camera.model) << " " << camera.width << " "
          << camera.height;
      for (double p : camera.params) out << " " << p;
      out << "\n";
    }
  });
  WriteFileAtomically(JoinPaths(dir, "images.txt"), [&](std::ostream& out) {
    out << std::setprecision(digits);
    size_t num_points2D = 0;
    for (const auto& [id, image] : model.images) num_points2D += image.points2D.size();
    out << "# Image list with two lines of data per image:\n"
        << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
        << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
        << "# Number of images: " << model.images.size()
        << ", mean observations per image: "
        << (model.images.empty() ? 0.0 : double(num_points2D) / model.images.size()) << "\n";
    for (const auto& [id, image] : model.images) {
      out << id;
      for (int k = 0; k < 4; ++k) out << " " << image.qvec[k];
      for (int k = 0; k < 3; ++k) out << " " << image.tvec[k];
      out << " " << image.camera_id << " " << image.name << "\n";
      for (size_t i = 0; i < image.points2D.size(); ++i) {
        const Point2D& p = image.points2D[i];
        if (i > 0) out << " ";
        out << p.xy.x() << " " << p.xy.y() << " " << p.point3D_id;
      }
      out << "\n";
    }
  });
  WriteFileAtomically(JoinPaths(dir, "points3D.txt"), [&](std::ostream& out) {
    out << std::setprecision(digits);
    out << "# 3D point list with one line of data per point:\n"
        << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
        << "# Number of points: " << model.points3D.size() << "\n";
    for (const auto& [id, point] : model.points3D) {
      out << id << " " << point.xyz.x() << " " << point.xyz.y() << " " << point.xyz.z() << " "
          << int(point.rgb[0]) << " " << int(point.rgb[1]) << " " << int(point.rgb[2]) << " "
          << point.error;
      for (const TrackElement& el : point.track) out << " " << el.image_id << " " << el.point2D_idx;
      out << "\n";
    }
  });
}

}  // namespace mr
