#include "init/mesh_picture.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "geometry/mesh.h"
#include "util/error.h"
#include "util/file.h"

namespace mr {

bool MeshPictureOptions::Check() const {
  if (supersample < 1 || supersample > 4) {
    MR_THROW_INPUT << "MeshPictureOptions::supersample = " << supersample
                   << ". Violated constraint: 1 <= supersample <= 4";
  }
  if (lighting != "key" && lighting != "headlight") {
    MR_THROW_INPUT << "MeshPictureOptions::lighting = " << lighting
                   << ". Violated constraint: lighting in {key, headlight}";
  }
  if (!(ambient >= 0 && ambient < 1)) {
    MR_THROW_INPUT << "MeshPictureOptions::ambient = " << ambient
                   << ". Violated constraint: 0 <= ambient < 1";
  }
  if (background < 0 || background > 255) {
    MR_THROW_INPUT << "MeshPictureOptions::background = " << background
                   << ". Violated constraint: 0 <= background <= 255";
  }
  return true;
}

PinholeView OrbitView(const Eigen::AlignedBox3d& bounds, double azimuth_deg,
                      double elevation_deg, int width, int height, const Eigen::Vector3d& up_in,
                      const Eigen::Vector3d& front_in) {
  if (bounds.isEmpty()) MR_THROW_INPUT << "OrbitView: empty bounds (no vertices?)";
  if (width < 1 || height < 1) {
    MR_THROW_INPUT << "OrbitView: image size " << width << "x" << height << ", expected >= 1";
  }
  if (!(up_in.norm() > 0)) MR_THROW_INPUT << "OrbitView: zero up vector";
  const Eigen::Vector3d up = up_in.normalized();
  Eigen::Vector3d front = front_in - front_in.dot(up) * up;
  if (front.norm() < 1e-9) front = up.unitOrthogonal();
  front.normalize();
  const Eigen::Vector3d side = up.cross(front);
  const double az = azimuth_deg * M_PI / 180, el = elevation_deg * M_PI / 180;
  const Eigen::Vector3d dir =
      std::cos(el) * (std::cos(az) * front + std::sin(az) * side) + std::sin(el) * up;
  const double radius = std::max(0.5 * bounds.diagonal().norm(), 1e-12);
  const double dist = 3.0 * radius;
  const Eigen::Vector3d center = bounds.center() + dist * dir;

  const Eigen::Vector3d z = -dir;
  Eigen::Vector3d y = -(up - up.dot(z) * z);  // image down = world down
  if (y.norm() < 1e-9) y = -(front - front.dot(z) * z);
  y.normalize();
  const Eigen::Vector3d x = y.cross(z);
  PinholeView view;
  view.width = width;
  view.height = height;
  view.R.row(0) = x.transpose();
  view.R.row(1) = y.transpose();
  view.R.row(2) = z.transpose();
  view.t = -view.R * center;
  const double half_angle = std::asin(radius / dist);
  view.fx = view.fy = 0.5 * std::min(width, height) / std::tan(half_angle) * 0.98;
  view.cx = 0.5 * width;
  view.cy = 0.5 * height;
  return view;
}

cv::Mat ShadeBuffers(const RenderBuffers& buffers, const Eigen::MatrixXd& face_normals,
                     const PinholeView& view, const MeshPictureOptions& options,
                     const Eigen::MatrixXi* F, const VertexColors* colors) {
  MR_CHECK(buffers.width == view.width && buffers.height == view.height)
      << "buffers " << buffers.width << "x" << buffers.height << ", view " << view.width << "x"
      << view.height;
  MR_CHECK((F == nullptr) == (colors == nullptr)) << "colours need the faces that index them";
  MR_CHECK(F == nullptr || F->rows() == face_normals.rows())
      << F->rows() << " faces, " << face_normals.rows() << " normals";
  const Eigen::Vector3d key_cam = Eigen::Vector3d(-0.4, -0.6, -1.0).normalized();
  const Eigen::Vector3d key = view.R.transpose() * key_cam;
  const uchar bg = static_cast<uchar>(options.background);
  cv::Mat image(view.height, view.width, CV_8UC3, cv::Scalar(bg, bg, bg));
  for (int row = 0; row < view.height; ++row) {
    cv::Vec3b* out = image.ptr<cv::Vec3b>(row);
    for (int col = 0; col < view.width; ++col) {
      const int f = buffers.FaceAt(row, col);
      if (f < 0) continue;
      MR_CHECK(f < face_normals.rows()) << "face id " << f;
      const Eigen::Vector3d n = face_normals.row(f).transpose();
      const Eigen::Vector3d to_eye = -view.RayDirection(col + 0.5, row + 0.5).normalized();
      const bool back = n.dot(to_eye) < 0;
      const Eigen::Vector3d ns = back ? Eigen::Vector3d(-n) : n;
      const Eigen::Vector3d light = options.lighting == "headlight" ? to_eye : key;
      const double lambert = std::max(0.0, ns.dot(light));
      const double intensity = options.ambient + (1 - options.ambient) * lambert;
      // Grey (or the vertex colours) for front faces, red (BGR) for back faces.
      Eigen::Vector3d albedo =
          back ? Eigen::Vector3d(70, 70, 230) : Eigen::Vector3d(225, 225, 225);
      if (!back && colors != nullptr) {
        const size_t pixel = static_cast<size_t>(row) * view.width + col;
        const double u = buffers.bary[2 * pixel], v = buffers.bary[2 * pixel + 1];
        const Eigen::Vector3d rgb = (1 - u - v) * colors->row((*F)(f, 0)).cast<double>() +
                                    u * colors->row((*F)(f, 1)).cast<double>() +
                                    v * colors->row((*F)(f, 2)).cast<double>();
        albedo = rgb.reverse();  // BGR
      }
      for (int c = 0; c < 3; ++c) {
        out[col][c] = static_cast<uchar>(std::clamp(albedo(c) * intensity, 1.0, 255.0));
      }
    }
  }
  return image;
}

cv::Mat RenderMeshPicture(Renderer* renderer, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                          const PinholeView& view, const MeshPictureOptions& options,
                          const VertexColors* colors) {
  options.Check();
  if (colors != nullptr && colors->rows() != V.rows()) {
    MR_THROW_INPUT << "RenderMeshPicture: " << colors->rows() << " vertex colours for "
                   << V.rows() << " vertices";
  }
  const PinholeView big = options.supersample == 1 ? view : view.Scaled(options.supersample);
  RenderBuffers buffers;
  if (renderer != nullptr) {
    renderer->SetMesh(V, F);
    buffers = renderer->Render(big);
  } else {
    buffers = RenderCpu(V, F, big);
  }
  cv::Mat image = ShadeBuffers(buffers, FaceNormals(V, F), big, options,
                               colors != nullptr ? &F : nullptr, colors);
  if (options.supersample > 1) {
    cv::resize(image, image, cv::Size(view.width, view.height), 0, 0, cv::INTER_AREA);
  }
  return image;
}

void WritePng(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> png;
  if (image.empty() || !cv::imencode(".png", image, png)) {
    MR_THROW_INPUT << path << ": cannot encode the image as PNG";
  }
  WriteFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  });
}

}  // namespace mr
