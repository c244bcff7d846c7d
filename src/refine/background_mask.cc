#include "refine/background_mask.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/components.h"
#include "util/mask_distance.h"
#include "util/statistics.h"

namespace mr {

bool BackgroundMaskOptions::Check() const {
  auto fail = [](const std::string& name, double value, const std::string& constraint) {
    MR_THROW_INPUT << "BackgroundMaskOptions::" << name << " = " << value
                   << ". Violated constraint: " << constraint;
  };
  if (border_px < 1) fail("border_px", border_px, "border_px >= 1");
  if (!(min_border_share > 0 && min_border_share <= 1)) {
    fail("min_border_share", min_border_share, "0 < min_border_share <= 1");
  }
  if (!(min_tolerance >= 0)) fail("min_tolerance", min_tolerance, "min_tolerance >= 0");
  if (!(tolerance_sigmas >= 0)) fail("tolerance_sigmas", tolerance_sigmas, "tolerance_sigmas >= 0");
  if (!(max_spread >= 0)) fail("max_spread", max_spread, "max_spread >= 0");
  if (!(min_hole_share >= 0 && min_hole_share <= 1)) {
    fail("min_hole_share", min_hole_share, "0 <= min_hole_share <= 1");
  }
  if (!(min_agreement >= 0 && min_agreement <= 1)) {
    fail("min_agreement", min_agreement, "0 <= min_agreement <= 1");
  }
  if (!(min_clear_outline >= 0 && min_clear_outline <= 1)) {
    fail("min_clear_outline", min_clear_outline, "0 <= min_clear_outline <= 1");
  }
  if (min_object_px < 0) fail("min_object_px", min_object_px, "min_object_px >= 0");
  if (!(max_offset >= 0 && max_offset <= 1)) fail("max_offset", max_offset, "0 <= max_offset <= 1");
  if (!(min_support >= 0 && min_support <= 1)) fail("min_support", min_support, "0 <= min_support <= 1");
  if (!(witness_tolerances >= 1)) {
    fail("witness_tolerances", witness_tolerances, "witness_tolerances >= 1");
  }
  if (!(visibility_tolerance > 0)) {
    fail("visibility_tolerance", visibility_tolerance, "visibility_tolerance > 0");
  }
  return true;
}

namespace {

// The image as BGR, 3x3 median filtered.
cv::Mat Smoothed(const cv::Mat& image) {
  MR_CHECK(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3))
      << "8-bit grey or BGR image expected";
  cv::Mat bgr;
  if (image.channels() == 1) {
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  } else {
    bgr = image;
  }
  cv::Mat filtered;
  cv::medianBlur(bgr, filtered, 3);
  return filtered;
}

// Largest channel difference between a pixel and a colour.
inline double ColorDistance(const cv::Vec3b& p, const cv::Vec3d& c) {
  return std::max({std::abs(p[0] - c[0]), std::abs(p[1] - c[1]), std::abs(p[2] - c[2])});
}

// The pixels of the border band of width `band`.
template <typename Visit>
void ForEachBorderPixel(const cv::Mat& image, int band, Visit visit) {
  band = std::min({band, image.rows / 2, image.cols / 2});
  for (int r = 0; r < image.rows; ++r) {
    const cv::Vec3b* row = image.ptr<cv::Vec3b>(r);
    const bool full = r < band || r >= image.rows - band;
    for (int c = 0; c < image.cols; ++c) {
      if (full || c < band || c >= image.cols - band) visit(row[c]);
      if (!full && c == band - 1) c = image.cols - band - 1;  // skip the interior
    }
  }
}

// Whether pixel (r, c) of `mask` (CV_8U) has a 4-neighbour outside it (0);
// beyond the image counts as inside.
bool OnOutline(const cv::Mat& mask, int r, int c) {
  auto outside = [&](int rr, int cc) {
    return rr >= 0 && rr < mask.rows && cc >= 0 && cc < mask.cols && mask.at<uchar>(rr, cc) == 0;
  };
  return outside(r - 1, c) || outside(r + 1, c) || outside(r, c - 1) || outside(r, c + 1);
}

BackgroundModel EstimateFiltered(const cv::Mat& filtered, const BackgroundMaskOptions& options) {
  std::vector<double> channel[3];
  ForEachBorderPixel(filtered, options.border_px, [&](const cv::Vec3b& p) {
    for (int k = 0; k < 3; ++k) channel[k].push_back(p[k]);
  });
  BackgroundModel model;
  for (int k = 0; k < 3; ++k) {
    const MedianAndSpread robust = RobustMedianAndSpread(&channel[k]);
    model.color[k] = robust.median;
    model.spread = std::max(model.spread, robust.sigma);
  }
  model.tolerance = std::max(options.min_tolerance, options.tolerance_sigmas * model.spread);
  long within = 0, total = 0;
  ForEachBorderPixel(filtered, options.border_px, [&](const cv::Vec3b& p) {
    within += ColorDistance(p, model.color) <= model.tolerance ? 1 : 0;
    ++total;
  });
  model.border_share = static_cast<double>(within) / std::max(1L, total);
  model.uniform = model.border_share >= options.min_border_share && model.spread <= options.max_spread;
  return model;
}

cv::Mat MaskOfFiltered(const cv::Mat& filtered, const BackgroundModel& model,
                       const BackgroundMaskOptions& options) {
  const int rows = filtered.rows, cols = filtered.cols;
  cv::Mat distance(filtered.size(), CV_32F), like(filtered.size(), CV_8U);
  for (int r = 0; r < rows; ++r) {
    const cv::Vec3b* src = filtered.ptr<cv::Vec3b>(r);
    float* d = distance.ptr<float>(r);
    uchar* l = like.ptr<uchar>(r);
    for (int c = 0; c < cols; ++c) {
      d[c] = static_cast<float>(ColorDistance(src[c], model.color));
      l[c] = d[c] <= model.tolerance ? 1 : 0;
    }
  }
  // Background is 4-connected, the object 8-connected. A background-coloured
  // region is background where it touches the border or is a large hole;
  // an object region smaller than min_object_px is noise.
  cv::Mat labels;
  const double min_hole = options.min_hole_share * rows * cols;
  const std::vector<uchar> background = SelectComponents(
      like, 4, [&](bool touches, int area) { return touches || area >= min_hole; }, &labels);
  cv::Mat mask(filtered.size(), CV_8U);
  for (int r = 0; r < rows; ++r) {
    const int* l = labels.ptr<int>(r);
    const uchar* is_like = like.ptr<uchar>(r);
    uchar* m = mask.ptr<uchar>(r);
    for (int c = 0; c < cols; ++c) m[c] = is_like[c] && background[l[c]] ? 0 : 255;
  }
  const std::vector<uchar> object = SelectComponents(
      mask, 8, [&](bool, int area) { return area >= options.min_object_px; }, &labels);
  for (int r = 0; r < rows; ++r) {
    const int* l = labels.ptr<int>(r);
    uchar* m = mask.ptr<uchar>(r);
    for (int c = 0; c < cols; ++c) m[c] = m[c] && object[l[c]] ? 255 : 0;
  }
  // The outline at half coverage: a pixel of the object next to the
  // background that differs from it by less than half as much as the object
  // pixels beside it is mostly background (an anti-aliased edge pixel).
  const cv::Mat before = mask.clone();
  auto on_outline = [&](int r, int c) { return OnOutline(before, r, c); };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!before.at<uchar>(r, c) || !on_outline(r, c)) continue;
      float inside = 0;  // the mean of the object pixels within 2 px that are not on the outline
      int count = 0;
      for (int dr = -2; dr <= 2; ++dr) {
        for (int dc = -2; dc <= 2; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if (rr < 0 || rr >= rows || cc < 0 || cc >= cols || !before.at<uchar>(rr, cc) ||
              on_outline(rr, cc)) {
            continue;
          }
          inside += distance.at<float>(rr, cc);
          ++count;
        }
      }
      if (count > 0) inside /= count;
      if (inside > 0 && distance.at<float>(r, c) < 0.5f * inside) mask.at<uchar>(r, c) = 0;
    }
  }
  return mask;
}

// `mask` with its holes filled: everything but the background connected to
// the image border (4-connected, as MaskOfFiltered's background).
cv::Mat WithoutHoles(const cv::Mat& mask) {
  cv::Mat labels;
  const std::vector<uchar> outside =
      SelectComponents(mask == 0, 4, [](bool touches, int) { return touches; }, &labels);
  cv::Mat filled(mask.size(), CV_8U);
  for (int r = 0; r < mask.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    uchar* f = filled.ptr<uchar>(r);
    for (int c = 0; c < mask.cols; ++c) f[c] = outside[l[c]] ? 0 : 255;
  }
  return filled;
}

double ClearShareOfFiltered(const cv::Mat& filtered, const cv::Mat& mask,
                            const BackgroundModel& model, const BackgroundMaskOptions& options) {
  MR_CHECK(mask.size() == filtered.size() && mask.type() == CV_8U);
  const int rows = mask.rows, cols = mask.cols;
  auto inside = [&](int r, int c) { return mask.at<uchar>(r, c) != 0; };
  const double clear = options.witness_tolerances * model.tolerance;
  long outline = 0, clear_outline = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!inside(r, c)) continue;
      if (!OnOutline(mask, r, c)) continue;
      double sum = 0;  // over the object pixels of the 5x5 window
      int count = 0;
      for (int rr = std::max(0, r - 2); rr <= std::min(rows - 1, r + 2); ++rr) {
        for (int cc = std::max(0, c - 2); cc <= std::min(cols - 1, c + 2); ++cc) {
          if (!inside(rr, cc)) continue;
          sum += ColorDistance(filtered.at<cv::Vec3b>(rr, cc), model.color);
          ++count;
        }
      }
      ++outline;
      clear_outline += sum >= clear * count ? 1 : 0;
    }
  }
  return outline == 0 ? 1.0 : static_cast<double>(clear_outline) / outline;
}

}  // namespace

BackgroundModel EstimateBackground(const cv::Mat& image, const BackgroundMaskOptions& options) {
  options.Check();
  return EstimateFiltered(Smoothed(image), options);
}

cv::Mat BackgroundMask(const cv::Mat& image, const BackgroundModel& model,
                       const BackgroundMaskOptions& options) {
  return MaskOfFiltered(Smoothed(image), model, options);
}

double ClearOutlineShare(const cv::Mat& image, const cv::Mat& mask, const BackgroundModel& model,
                         const BackgroundMaskOptions& options) {
  return ClearShareOfFiltered(Smoothed(image), mask, model, options);
}

double MaskAgreement(const cv::Mat& a, const cv::Mat& b) {
  MR_CHECK(a.size() == b.size() && a.type() == CV_8U && b.type() == CV_8U);
  const int both = cv::countNonZero(a & b), either = cv::countNonZero(a | b);
  return either == 0 ? 1.0 : static_cast<double>(both) / either;
}

BackgroundMaskedViewSource::BackgroundMaskedViewSource(const ViewSource& base,
                                                       std::vector<std::vector<uchar>> masks)
    : DerivedViewSource(base), masks_(std::move(masks)) {
  MR_CHECK(static_cast<int>(masks_.size()) == base_.NumViews());
  for (const auto& m : masks_) num_masked_ += m.empty() ? 0 : 1;
}

cv::Mat BackgroundMaskedViewSource::LoadMask(int i) const {
  const std::vector<uchar>& png = masks_.at(i);
  if (png.empty()) return {};
  return cv::imdecode(png, cv::IMREAD_GRAYSCALE);
}

cv::Mat LimitToOutlineBand(const cv::Mat& mask, const cv::Mat& covered, double max_offset_px) {
  MR_CHECK(mask.size() == covered.size() && mask.type() == CV_8U && covered.type() == CV_8U);
  // |sdf| + 0.5: the distance of each pixel to the nearest pixel on the other
  // side of the outline of `covered`.
  const cv::Mat sdf = MaskSignedDistance(covered);
  cv::Mat out = covered > 0;
  for (int r = 0; r < out.rows; ++r) {
    const uchar* m = mask.ptr<uchar>(r);
    const float* d = sdf.ptr<float>(r);
    uchar* o = out.ptr<uchar>(r);
    for (int c = 0; c < out.cols; ++c) {
      const bool object = m[c] > 0;
      if (object != (o[c] > 0) && std::abs(d[c]) + 0.5f <= max_offset_px) {
        o[c] = object ? 255 : 0;
      }
    }
  }
  return out;
}

std::string BackgroundMaskReport::BriefReport() const {
  // The per-view figures of the views with a uniform background, sorted.
  auto of_uniform = [](const std::vector<double>& per_view) {
    std::vector<double> values;
    for (double v : per_view) {
      if (v >= 0) values.push_back(v);
    }
    std::sort(values.begin(), values.end());
    return values;
  };
  const std::vector<double> accepted = of_uniform(agreement), clear = of_uniform(clear_share);
  std::ostringstream out;
  out.precision(3);
  out << num_uniform << " of " << num_views << " views have a uniform background; " << num_clear
      << " of these a clear outline";
  if (!clear.empty()) {
    out << " (share of the outline clearly unlike the background: min " << clear.front()
        << ", median " << clear[clear.size() / 2] << ")";
  }
  out << "; " << num_accepted << " of those agree with the input mesh and get masks";
  if (num_removals > 0) {
    out << "; " << num_confirmed << " of " << num_removals
        << " pixels they take from the mesh are confirmed by other views";
  }
  if (!accepted.empty()) {
    out << " (mask vs rendered mesh, intersection over union: min " << accepted.front()
        << ", median " << accepted[accepted.size() / 2] << ")";
  }
  return out.str();
}

cv::Mat RenderedCoverage(const RenderBuffers& render) {
  cv::Mat covered(render.height, render.width, CV_8U);
  for (int r = 0; r < render.height; ++r) {
    uchar* row = covered.ptr<uchar>(r);
    for (int c = 0; c < render.width; ++c) row[c] = render.FaceAt(r, c) >= 0 ? 255 : 0;
  }
  return covered;
}

namespace {

// A pixel the mask takes from the input mesh's coverage, with the mesh's
// point it shows and how the other views see that point.
struct Removal {
  int row = 0, col = 0;
  Eigen::Vector3d X;
  int views = 0;          // other views in which X is visible (a uniform background)
  int object_views = 0;   // ... and whose pixel there differs from their background
};

}  // namespace

std::unique_ptr<BackgroundMaskedViewSource> MakeBackgroundMasks(
    const ViewSource& source, const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
    Renderer* renderer, const BackgroundMaskOptions& options, BackgroundMaskReport* report) {
  options.Check();
  const int n = source.NumViews();
  BackgroundMaskReport local;
  local.num_views = n;
  local.agreement.assign(n, -1.0);
  local.clear_share.assign(n, -1.0);
  std::vector<BackgroundModel> models(n);
  std::vector<std::vector<uchar>> encoded(n);
  std::vector<std::vector<Removal>> removals(n);
  renderer->SetMesh(V, F);
  // Each view's mask, limited to the band around the mesh's outline; the
  // pixels it takes from the mesh's coverage are kept as removals.
  for (int i = 0; i < n; ++i) {
    const cv::Mat filtered = Smoothed(source.LoadColor(i));
    models[i] = EstimateFiltered(filtered, options);
    const BackgroundModel& model = models[i];
    if (!model.uniform) {
      MR_LOG(VERBOSE) << source.Name(i) << ": no uniform background (spread " << model.spread
                      << ", " << 100 * model.border_share << " % of the border within "
                      << model.tolerance << ")";
      continue;
    }
    ++local.num_uniform;
    const PinholeView& view = source.View(i);
    const cv::Mat mask = MaskOfFiltered(filtered, model, options);
    const RenderBuffers render = renderer->Render(view);
    const cv::Mat covered = RenderedCoverage(render);
    // The outer outlines are compared: a hole of the mask is checked pixel by
    // pixel below (the band and the other views), and on a backdrop that
    // is not black every patch of the texture with its colour is one.
    local.agreement[i] = MaskAgreement(WithoutHoles(mask), WithoutHoles(covered));
    local.clear_share[i] = ClearShareOfFiltered(filtered, mask, model, options);
    const bool clear = local.clear_share[i] >= options.min_clear_outline;
    const bool accepted = clear && local.agreement[i] >= options.min_agreement;
    MR_LOG(VERBOSE) << source.Name(i) << ": background (B, G, R) = (" << model.color[0] << ", "
                    << model.color[1] << ", " << model.color[2] << "), spread " << model.spread
                    << ", " << 100 * model.border_share << " % of the border within "
                    << model.tolerance << "; outline clear " << local.clear_share[i]
                    << ", mask vs rendered mesh " << local.agreement[i]
                    << (accepted ? "" : ": no mask");
    local.num_clear += clear ? 1 : 0;
    if (!accepted) continue;
    ++local.num_accepted;
    const double max_offset_px = options.max_offset * std::max(view.width, view.height);
    const cv::Mat banded = LimitToOutlineBand(mask, covered, max_offset_px);
    for (int r = 0; r < view.height; ++r) {
      for (int c = 0; c < view.width; ++c) {
        if (covered.at<uchar>(r, c) && !banded.at<uchar>(r, c)) {
          Removal removal;
          removal.row = r;
          removal.col = c;
          removal.X = view.Center() + render.DepthAt(r, c) * view.RayDirection(c + 0.5, r + 0.5);
          removals[i].push_back(removal);
          ++local.num_removals;
        }
      }
    }
    cv::imencode(".png", banded, encoded[i]);
  }
  // A removal is confirmed by the other views: a surface point outside the
  // object lies in front of the object or the background, so the views
  // that see it face on see the object's colours through it; a dark part of
  // the object taken for background stays dark in every view (a light fixed
  // in the world leaves the same side unlit).
  if (options.min_support > 0 && local.num_removals > 0) {
    for (int j = 0; j < n; ++j) {
      if (!models[j].uniform) continue;
      const cv::Mat filtered = Smoothed(source.LoadColor(j));
      const PinholeView& view = source.View(j);
      const RenderBuffers render = renderer->Render(view);
      for (int i = 0; i < n; ++i) {
        if (i == j) continue;
        for (Removal& removal : removals[i]) {
          const Eigen::Vector3d Xc = view.WorldToCamera(removal.X);
          if (!(Xc.z() > 0)) continue;
          const Eigen::Vector2d q = view.CameraToImage(Xc);
          if (!view.InImage(q)) continue;
          const int r = static_cast<int>(q.y()), c = static_cast<int>(q.x());
          const double depth = render.DepthAt(r, c);
          if (!(depth > 0) || std::abs(depth - Xc.z()) > options.visibility_tolerance * Xc.z()) {
            continue;
          }
          ++removal.views;
          if (ColorDistance(filtered.at<cv::Vec3b>(r, c), models[j].color) >
              options.witness_tolerances * models[j].tolerance) {
            ++removal.object_views;
          }
        }
      }
    }
    for (int i = 0; i < n; ++i) {
      if (removals[i].empty()) continue;
      cv::Mat mask = cv::imdecode(encoded[i], cv::IMREAD_GRAYSCALE);
      for (const Removal& removal : removals[i]) {
        if (removal.views > 0 && removal.object_views >= options.min_support * removal.views) {
          ++local.num_confirmed;
        } else {
          mask.at<uchar>(removal.row, removal.col) = 255;
        }
      }
      cv::imencode(".png", mask, encoded[i]);
    }
  } else {
    local.num_confirmed = local.num_removals;
  }
  if (report) *report = local;
  return std::make_unique<BackgroundMaskedViewSource>(source, std::move(encoded));
}

}  // namespace mr
