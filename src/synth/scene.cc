#include "synth/scene.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "util/error.h"

namespace mr {
namespace {

constexpr double kPi = 3.14159265358979323846;

PinholeView LookAtOrigin(const Eigen::Vector3d& centre, int width, int height, double focal) {
  PinholeView v;
  v.width = width;
  v.height = height;
  v.fx = v.fy = focal;
  v.cx = 0.5 * width;
  v.cy = 0.5 * height;
  const Eigen::Vector3d z = (-centre).normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (std::abs(z.dot(up)) > 0.999) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = z.cross(up).normalized();
  const Eigen::Vector3d y = z.cross(x);  // points "down" in the image
  v.R.row(0) = x.transpose();
  v.R.row(1) = y.transpose();
  v.R.row(2) = z.transpose();
  v.t = -v.R * centre;
  return v;
}

}  // namespace

bool CameraRigOptions::Check() const {
  if (num_views < 2 || num_views > 1000) {
    MR_THROW_INPUT << "CameraRigOptions::num_views = " << num_views
                   << ". Violated constraint: 2 <= num_views <= 1000";
  }
  if (width < 16 || width > 8192 || height < 16 || height > 8192) {
    MR_THROW_INPUT << "CameraRigOptions::width/height = " << width << "/" << height
                   << ". Violated constraint: 16 <= width, height <= 8192";
  }
  if (layout != "ring" && layout != "hemisphere") {
    MR_THROW_INPUT << "CameraRigOptions::layout = " << layout
                   << ". Violated constraint: layout is ring or hemisphere";
  }
  if (!(elevation_deg >= -89 && elevation_deg <= 89)) {
    MR_THROW_INPUT << "CameraRigOptions::elevation_deg = " << elevation_deg
                   << ". Violated constraint: -89 <= elevation_deg <= 89";
  }
  if (!(min_elevation_deg >= -89 && min_elevation_deg < max_elevation_deg &&
        max_elevation_deg <= 89)) {
    MR_THROW_INPUT << "CameraRigOptions::min_elevation_deg/max_elevation_deg = "
                   << min_elevation_deg << "/" << max_elevation_deg
                   << ". Violated constraint: -89 <= min_elevation_deg < max_elevation_deg <= 89";
  }
  if (!(fill_fraction > 0 && fill_fraction <= 1)) {
    MR_THROW_INPUT << "CameraRigOptions::fill_fraction = " << fill_fraction
                   << ". Violated constraint: 0 < fill_fraction <= 1";
  }
  if (!(alternate_fill_fraction >= 0 && alternate_fill_fraction <= 3)) {
    MR_THROW_INPUT << "CameraRigOptions::alternate_fill_fraction = " << alternate_fill_fraction
                   << ". Violated constraint: 0 <= alternate_fill_fraction <= 3";
  }
  if (!(focal_factor > 0.1 && focal_factor <= 10)) {
    MR_THROW_INPUT << "CameraRigOptions::focal_factor = " << focal_factor
                   << ". Violated constraint: 0.1 < focal_factor <= 10";
  }
  return true;
}

std::vector<PinholeView> MakeCameras(const CameraRigOptions& options, double bounding_radius) {
  options.Check();
  MR_CHECK_GT(bounding_radius, 0);
  const double focal = options.focal_factor * options.width;
  // Angular radius alpha of the bounding sphere: focal * tan(alpha) = fill * height / 2.
  auto distance_filling = [&](double fill) {
    const double alpha = std::atan(fill * 0.5 * options.height / focal);
    return bounding_radius / std::sin(alpha);
  };
  const double even_distance = distance_filling(options.fill_fraction);
  const double odd_distance = options.alternate_fill_fraction > 0
                                  ? distance_filling(options.alternate_fill_fraction)
                                  : even_distance;
  std::vector<PinholeView> views;
  const int n = options.num_views;
  for (int i = 0; i < n; ++i) {
    const double distance = i % 2 == 0 ? even_distance : odd_distance;
    double elevation, azimuth;
    if (options.layout == "ring") {
      elevation = options.elevation_deg * kPi / 180;
      azimuth = 2 * kPi * i / n;
    } else {
      // Fibonacci spiral, uniform in sin(elevation) over the band.
      const double s0 = std::sin(options.min_elevation_deg * kPi / 180);
      const double s1 = std::sin(options.max_elevation_deg * kPi / 180);
      elevation = std::asin(s0 + (s1 - s0) * (i + 0.5) / n);
      azimuth = i * kPi * (3 - std::sqrt(5.0));
    }
    const Eigen::Vector3d centre =
        distance * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                   std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    views.push_back(LookAtOrigin(centre, options.width, options.height, focal));
  }
  return views;
}

PinholeView DenseConventionView(const PinholeView& view) {
  // A point at image point x of `view` is at x + 0.5 in the returned view,
  // whose pixel col is sampled at col + 0.5, i.e. at image point col of `view`.
  PinholeView v = view;
  v.cx += 0.5;
  v.cy += 0.5;
  return v;
}

Eigen::Vector3d BufferPoint(const SynthScene& scene, const RenderBuffers& buffers, size_t index) {
  const int f = buffers.face_id[index];
  const double u = buffers.bary[2 * index], v = buffers.bary[2 * index + 1];
  return (1 - u - v) * scene.V.row(scene.F(f, 0)).transpose() +
         u * scene.V.row(scene.F(f, 1)).transpose() + v * scene.V.row(scene.F(f, 2)).transpose();
}

std::optional<Eigen::Vector3d> ShadeBufferPixel(const SynthScene& scene,
                                                const RenderBuffers& buffers, size_t index,
                                                const Eigen::Vector3d& eye) {
  const int f = buffers.face_id[index];
  if (f < 0) return std::nullopt;
  return ShadePoint(scene.appearance, BufferPoint(scene, buffers, index),
                    scene.face_normals.row(f).transpose(), eye);
}

SynthImage RenderImage(Renderer& renderer, const SynthScene& scene, const PinholeView& view,
                       int supersample) {
  MR_CHECK_GE(supersample, 1);
  const PinholeView hi = supersample == 1 ? view : view.Scaled(supersample);
  MR_CHECK_EQ(hi.width, view.width * supersample);
  MR_CHECK_EQ(hi.height, view.height * supersample);
  const RenderBuffers buffers = renderer.Render(hi);
  SynthImage image;
  image.width = view.width;
  image.height = view.height;
  const size_t n = static_cast<size_t>(view.width) * view.height;
  image.radiance.assign(3 * n, 0.f);
  image.coverage.assign(n, 0.f);
  const double inv = 1.0 / (supersample * supersample);
  const Eigen::Vector3d eye = view.Center();
#pragma omp parallel for schedule(dynamic, 4)
  for (int row = 0; row < view.height; ++row) {
    for (int col = 0; col < view.width; ++col) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double covered = 0;
      for (int a = 0; a < supersample; ++a) {
        for (int b = 0; b < supersample; ++b) {
          const size_t idx =
              static_cast<size_t>(row * supersample + a) * hi.width + col * supersample + b;
          const std::optional<Eigen::Vector3d> value =
              ShadeBufferPixel(scene, buffers, idx, eye);
          if (value) {
            sum += *value;
            covered += 1;
          }
        }
      }
      const size_t out = static_cast<size_t>(row) * view.width + col;
      for (int c = 0; c < 3; ++c) image.radiance[3 * out + c] = static_cast<float>(sum(c) * inv);
      image.coverage[out] = static_cast<float>(covered * inv);
    }
  }
  return image;
}

void AddImageNoise(double sigma, uint32_t seed, uint32_t view_index, SynthImage* image) {
  MR_CHECK(image != nullptr);
  MR_CHECK(sigma >= 0 && sigma <= 0.5) << "image noise sigma " << sigma;
  MR_CHECK_EQ(image->radiance.size(), 3 * image->coverage.size());
  if (sigma == 0) return;
  // A seed sequence of its own, so that the image noise is independent of
  // the depth-map noise of the same view.
  std::seed_seq sequence{seed, view_index, 0x696d6731u};
  std::mt19937 rng(sequence);
  std::normal_distribution<double> gauss(0.0, sigma);
  for (float& value : image->radiance) {
    value = static_cast<float>(std::clamp(value + gauss(rng), 0.0, 1.0));
  }
}

double ApplyExposureJitter(double sigma, uint32_t seed, uint32_t view_index, SynthImage* image) {
  MR_CHECK(image != nullptr);
  MR_CHECK(sigma >= 0 && sigma <= 1) << "exposure jitter sigma " << sigma;
  if (sigma == 0) return 1.0;
  // A seed sequence of its own, independent of the image and depth noise.
  std::seed_seq sequence{seed, view_index, 0x65787031u};
  std::mt19937 rng(sequence);
  const double gain = std::exp(std::normal_distribution<double>(0.0, sigma)(rng));
  for (float& value : image->radiance) {
    value = static_cast<float>(std::min(1.0, value * gain));
  }
  return gain;
}

void ApplyBackground(double grey, SynthImage* image) {
  MR_CHECK(image != nullptr);
  MR_CHECK(grey >= 0 && grey <= 1) << "background " << grey;
  MR_CHECK_EQ(image->radiance.size(), 3 * image->coverage.size());
  if (grey == 0) return;
  for (size_t pixel = 0; pixel < image->coverage.size(); ++pixel) {
    const float add = static_cast<float>((1.0 - image->coverage[pixel]) * grey);
    for (int c = 0; c < 3; ++c) image->radiance[3 * pixel + c] += add;
  }
}

void ApplyVignetting(double strength, SynthImage* image) {
  MR_CHECK(image != nullptr);
  MR_CHECK(strength >= 0 && strength <= 0.9) << "vignetting strength " << strength;
  MR_CHECK_EQ(image->radiance.size(), 3 * static_cast<size_t>(image->width) * image->height);
  if (strength == 0) return;
  const double cx = 0.5 * (image->width - 1), cy = 0.5 * (image->height - 1);
  const double corner_squared = cx * cx + cy * cy;
  if (!(corner_squared > 0)) return;  // a one-pixel image has no corners
  for (int row = 0; row < image->height; ++row) {
    for (int col = 0; col < image->width; ++col) {
      const double r_squared = (col - cx) * (col - cx) + (row - cy) * (row - cy);
      const double gain = 1.0 - strength * r_squared / corner_squared;
      float* pixel = &image->radiance[3 * (static_cast<size_t>(row) * image->width + col)];
      for (int c = 0; c < 3; ++c) pixel[c] = static_cast<float>(pixel[c] * gain);
    }
  }
}

bool DepthNoiseOptions::Check() const {
  if (!(depth_noise >= 0 && depth_noise <= 0.1)) {
    MR_THROW_INPUT << "DepthNoiseOptions::depth_noise = " << depth_noise
                   << ". Violated constraint: 0 <= depth_noise <= 0.1";
  }
  if (!(correlated_noise >= 0 && correlated_noise <= 0.1)) {
    MR_THROW_INPUT << "DepthNoiseOptions::correlated_noise = " << correlated_noise
                   << ". Violated constraint: 0 <= correlated_noise <= 0.1";
  }
  if (!(correlation_px >= 0.5 && correlation_px <= 100)) {
    MR_THROW_INPUT << "DepthNoiseOptions::correlation_px = " << correlation_px
                   << ". Violated constraint: 0.5 <= correlation_px <= 100";
  }
  if (!(depth_blur_px >= 0 && depth_blur_px <= 20)) {
    MR_THROW_INPUT << "DepthNoiseOptions::depth_blur_px = " << depth_blur_px
                   << ". Violated constraint: 0 <= depth_blur_px <= 20";
  }
  if (!(outlier_fraction >= 0 && outlier_fraction <= 0.5)) {
    MR_THROW_INPUT << "DepthNoiseOptions::outlier_fraction = " << outlier_fraction
                   << ". Violated constraint: 0 <= outlier_fraction <= 0.5";
  }
  if (!(normal_noise >= 0 && normal_noise <= 1)) {
    MR_THROW_INPUT << "DepthNoiseOptions::normal_noise = " << normal_noise
                   << ". Violated constraint: 0 <= normal_noise <= 1";
  }
  if (!(min_cos_incidence >= 0 && min_cos_incidence < 1)) {
    MR_THROW_INPUT << "DepthNoiseOptions::min_cos_incidence = " << min_cos_incidence
                   << ". Violated constraint: 0 <= min_cos_incidence < 1";
  }
  return true;
}

DenseMaps RenderDenseMaps(Renderer& renderer, const SynthScene& scene, const PinholeView& view,
                          const DepthNoiseOptions& options, uint32_t seed) {
  options.Check();
  const PinholeView dense = DenseConventionView(view);
  DenseMaps maps;
  maps.exact = renderer.Render(dense);
  const int W = view.width, H = view.height;
  maps.depth.width = maps.normal.width = W;
  maps.depth.height = maps.normal.height = H;
  maps.depth.channels = 1;
  maps.normal.channels = 3;
  maps.depth.data.assign(static_cast<size_t>(W) * H, 0.f);
  maps.normal.data.assign(static_cast<size_t>(W) * H * 3, 0.f);
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  // Smoothed true depth (normalised convolution over the object's pixels).
  cv::Mat valid(H, W, CV_32F, cv::Scalar(0)), depth(H, W, CV_32F, cv::Scalar(0));
  for (int row = 0; row < H; ++row) {
    for (int col = 0; col < W; ++col) {
      const size_t idx = static_cast<size_t>(row) * W + col;
      if (maps.exact.face_id[idx] < 0) continue;
      valid.at<float>(row, col) = 1;
      depth.at<float>(row, col) = maps.exact.depth[idx];
    }
  }
  cv::Mat smooth = depth;
  if (options.depth_blur_px > 0) {
    cv::Mat num, den;
    cv::GaussianBlur(depth, num, cv::Size(0, 0), options.depth_blur_px);
    cv::GaussianBlur(valid, den, cv::Size(0, 0), options.depth_blur_px);
    smooth = num / cv::max(den, 1e-6);
  }
  // A smooth random field with unit standard deviation.
  cv::Mat field(H, W, CV_32F, cv::Scalar(0));
  if (options.correlated_noise > 0) {
    for (int row = 0; row < H; ++row) {
      for (int col = 0; col < W; ++col) field.at<float>(row, col) = static_cast<float>(gauss(rng));
    }
    cv::GaussianBlur(field, field, cv::Size(0, 0), options.correlation_px);
    cv::Scalar mean, stddev;
    cv::meanStdDev(field, mean, stddev);
    if (stddev[0] > 0) field = (field - mean[0]) / stddev[0];
  }

  for (int row = 0; row < H; ++row) {
    for (int col = 0; col < W; ++col) {
      const size_t idx = static_cast<size_t>(row) * W + col;
      const int f = maps.exact.face_id[idx];
      if (f < 0) continue;
      const double d = maps.exact.depth[idx];
      // Camera-frame normal, facing the camera.
      Eigen::Vector3d n = dense.R * scene.face_normals.row(f).transpose();
      const Eigen::Vector3d ray = Eigen::Vector3d((col + 0.5 - dense.cx) / dense.fx,
                                                  (row + 0.5 - dense.cy) / dense.fy, 1.0)
                                      .normalized();
      if (n.dot(ray) > 0) n = -n;
      const double cos_incidence = -n.dot(ray);
      // Draw all random numbers unconditionally so the noise of a pixel does
      // not depend on its neighbours' options.
      const double g = gauss(rng);
      const double u_out = uniform(rng), u_scale = uniform(rng);
      const Eigen::Vector3d gn(gauss(rng), gauss(rng), gauss(rng));
      if (cos_incidence < options.min_cos_incidence) continue;
      const double base = smooth.at<float>(row, col);
      double noisy = base * (1 + options.depth_noise * g +
                             options.correlated_noise * field.at<float>(row, col));
      if (u_out < options.outlier_fraction) noisy = d * (0.85 + 0.3 * u_scale);
      if (!(noisy > 0)) continue;
      Eigen::Vector3d nn = (n + options.normal_noise * gn).normalized();
      if (nn.dot(ray) > 0) nn = n;  // keep it facing the camera
      maps.depth.At(row, col, 0) = static_cast<float>(noisy);
      for (int c = 0; c < 3; ++c) maps.normal.At(row, col, c) = static_cast<float>(nn(c));
    }
  }
  return maps;
}

Reconstruction MakeSparseModel(const SynthScene& scene, const std::vector<PinholeView>& views,
                               const std::vector<std::string>& names,
                               const std::vector<RenderBuffers>& exact,
                               const std::vector<SynthImage>& images, int num_points,
                               uint32_t seed) {
  MR_CHECK(!views.empty());
  MR_CHECK_EQ(views.size(), names.size());
  MR_CHECK_EQ(views.size(), exact.size());
  MR_CHECK_EQ(views.size(), images.size());
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model = CameraModel::kPinhole;
  camera.width = views[0].width;
  camera.height = views[0].height;
  camera.params = {views[0].fx, views[0].fy, views[0].cx, views[0].cy};
  model.cameras[1] = camera;
  for (size_t i = 0; i < views.size(); ++i) {
    const PinholeView& v = views[i];
    MR_CHECK(v.width == views[0].width && v.height == views[0].height && v.fx == views[0].fx &&
             v.fy == views[0].fy && v.cx == views[0].cx && v.cy == views[0].cy)
        << "all views must share one camera";
    Image image;
    image.image_id = static_cast<uint32_t>(i + 1);
    image.camera_id = 1;
    image.name = names[i];
    image.qvec = RotationToQuaternion(v.R);
    image.tvec = v.t;
    model.images[image.image_id] = image;
  }
  if (num_points <= 0 || scene.F.rows() == 0) return model;

  // Area-uniform surface samples.
  std::vector<double> cumulative(scene.F.rows());
  double total = 0;
  for (int f = 0; f < scene.F.rows(); ++f) {
    const Eigen::Vector3d a = scene.V.row(scene.F(f, 0)), b = scene.V.row(scene.F(f, 1)),
                          c = scene.V.row(scene.F(f, 2));
    total += 0.5 * (b - a).cross(c - a).norm();
    cumulative[f] = total;
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int max_candidates = 20 * num_points;
  uint64_t next_id = 1;
  for (int k = 0; k < max_candidates && static_cast<int>(model.points3D.size()) < num_points;
       ++k) {
    const double r = uniform(rng) * total;
    const int f = static_cast<int>(
        std::min<size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), r) -
                             cumulative.begin(),
                         cumulative.size() - 1));
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const Eigen::Vector3d X = (1 - u - v) * scene.V.row(scene.F(f, 0)).transpose() +
                              u * scene.V.row(scene.F(f, 1)).transpose() +
                              v * scene.V.row(scene.F(f, 2)).transpose();
    const Eigen::Vector3d n = scene.face_normals.row(f).transpose();
    std::vector<std::pair<size_t, Eigen::Vector2d>> seen;
    for (size_t i = 0; i < views.size(); ++i) {
      const PinholeView& view = views[i];
      if (n.dot(view.Center() - X) <= 0) continue;
      const Eigen::Vector3d Xc = view.WorldToCamera(X);
      if (Xc.z() <= 0) continue;
      const Eigen::Vector2d p = view.CameraToImage(Xc);
      // Dense-convention pixel (col, row) sits at image point (col, row).
      const int col = static_cast<int>(std::lround(p.x()));
      const int row = static_cast<int>(std::lround(p.y()));
      if (col < 0 || row < 0 || col >= view.width || row >= view.height) continue;
      if (p.x() < 0.5 || p.y() < 0.5 || p.x() > view.width - 0.5 || p.y() > view.height - 0.5) {
        continue;
      }
      const size_t idx = static_cast<size_t>(row) * view.width + col;
      if (exact[i].face_id[idx] < 0) continue;
      if (std::abs(exact[i].depth[idx] - Xc.z()) > 2e-3 * Xc.z()) continue;
      seen.emplace_back(i, p);
    }
    if (seen.size() < 2) continue;
    Point3D point;
    point.point3D_id = next_id++;
    point.xyz = X;
    point.error = 0.0;
    Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
    for (const auto& [i, p] : seen) {
      Image& image = model.images.at(static_cast<uint32_t>(i + 1));
      Point2D p2;
      p2.xy = p;
      p2.point3D_id = static_cast<int64_t>(point.point3D_id);
      point.track.push_back({image.image_id, static_cast<uint32_t>(image.points2D.size())});
      image.points2D.push_back(p2);
      const int col = std::clamp(static_cast<int>(p.x()), 0, images[i].width - 1);
      const int row = std::clamp(static_cast<int>(p.y()), 0, images[i].height - 1);
      const size_t pixel = static_cast<size_t>(row) * images[i].width + col;
      for (int c = 0; c < 3; ++c) rgb(c) += images[i].radiance[3 * pixel + c];
    }
    for (int c = 0; c < 3; ++c) {
      point.rgb(c) =
          static_cast<uint8_t>(std::clamp(255.0 * rgb(c) / seen.size(), 0.0, 255.0));
    }
    model.points3D[point.point3D_id] = point;
  }
  return model;
}

}  // namespace mr
