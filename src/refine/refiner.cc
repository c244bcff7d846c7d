#include "refine/refiner.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <future>
#include <iomanip>
#include <limits>
#include <list>
#include <memory>
#include <set>
#include <sstream>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "eval/evaluator.h"
#include "geometry/mesh.h"
#include "geometry/remesh.h"
#include "refine/pyramid.h"
#include "refine/silhouette.h"
#include "render/renderer.h"
#include "util/error.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/statistics.h"

namespace mr {
namespace {

// Renders of the current mesh in the views of one level, made on demand and
// kept in a least-recently-used cache bounded in bytes. Invalidate() after
// the mesh moves.
class RenderCache {
 public:
  RenderCache(Renderer* renderer, const std::vector<PinholeView>& views, size_t max_bytes)
      : renderer_(renderer), views_(views), max_bytes_(max_bytes) {}

  std::shared_ptr<const RenderBuffers> Get(int i) {
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->first == i) {
        entries_.splice(entries_.begin(), entries_, it);
        return entries_.front().second;
      }
    }
    auto render = std::make_shared<const RenderBuffers>(renderer_->Render(views_[i]));
    const size_t bytes = RenderBuffers::Bytes(render->width, render->height);
    entries_.emplace_front(i, render);
    bytes_ += bytes;
    while (bytes_ > max_bytes_ && entries_.size() > 1) {
      const auto& last = entries_.back().second;
      bytes_ -= RenderBuffers::Bytes(last->width, last->height);
      entries_.pop_back();
    }
    ++num_renders_;
    return render;
  }
  void Invalidate() {
    entries_.clear();
    bytes_ = 0;
  }
  long num_renders() const { return num_renders_; }
  // All view indices: the cached ones from the most recently used, then the
  // others in index order.
  std::vector<int> CachedFirst() const {
    std::vector<int> order;
    std::vector<char> listed(views_.size(), 0);
    for (const auto& entry : entries_) {
      order.push_back(entry.first);
      listed[entry.first] = 1;
    }
    for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
      if (!listed[i]) order.push_back(i);
    }
    return order;
  }

 private:
  Renderer* renderer_;
  const std::vector<PinholeView>& views_;
  size_t max_bytes_;
  size_t bytes_ = 0;
  long num_renders_ = 0;
  std::list<std::pair<int, std::shared_ptr<const RenderBuffers>>> entries_;
};

std::vector<PinholeView> LevelViews(const std::vector<PinholeView>& cameras, int level) {
  std::vector<PinholeView> views;
  for (const PinholeView& camera : cameras) views.push_back(PyramidLevelView(camera, level));
  return views;
}

// `value` with `digits` significant digits, for a log line.
std::string FormatShort(double value, int digits = 3) {
  std::ostringstream out;
  out << std::setprecision(digits) << value;
  return out.str();
}

// The bytes of the grey images (CV_32F) of `views`.
size_t GrayBytes(const std::vector<PinholeView>& views) {
  size_t bytes = 0;
  for (const PinholeView& view : views) bytes += size_t(view.width) * view.height * sizeof(float);
  return bytes;
}

// refine_cameras: refines the cameras against the current mesh, with priors
// that hold them near `input_cameras` (the SfM cameras at the working
// resolution, so that repeated refinements do not wander), at `level` or,
// where its images exceed `max_bytes`, at a coarser pyramid level
// (CameraRefinementLevel), and carries the result to the working-resolution
// `cameras` and the level's `views` (a level's intrinsics are the full ones
// times 2^-level exactly, PyramidLevelView).
void RefineCamerasAtLevel(const RefineOptions& options,
                          const std::vector<std::pair<int, int>>& pairs, const Eigen::MatrixXd& V,
                          const Eigen::MatrixXi& F, int level,
                          const std::vector<int>& camera_of_view, Renderer* renderer,
                          size_t max_bytes, const std::vector<PinholeView>& input_cameras,
                          ImageCache* images, std::vector<PinholeView>* views,
                          std::vector<PinholeView>* cameras, RefineSummary* summary) {
  const int camera_level = CameraRefinementLevel(*views, level, max_bytes);
  const auto mib = [](size_t bytes) { return FormatShort(bytes / 1048576.0) + " MiB"; };
  const std::string budget = mib(max_bytes) + " (half of --Refine.cache_mb)";
  if (camera_level < 0) {
    MR_LOG(INFO) << "Cameras not refined at level " << level << ": the images take "
                 << mib(GrayBytes(LevelViews(*cameras, level + kMaxCameraLevelsCoarser)))
                 << " even at level " << level + kMaxCameraLevelsCoarser << ", more than "
                 << budget;
    return;
  }
  std::vector<PinholeView> camera_views = LevelViews(*cameras, camera_level);
  std::string where;
  if (camera_level != level) {
    where = " (at pyramid level " + std::to_string(camera_level) + ": level " +
            std::to_string(level) + "'s images take " + mib(GrayBytes(*views)) + ", more than " +
            budget + ")";
  }
  std::vector<cv::Mat> gray;
  for (int i = 0; i < static_cast<int>(camera_views.size()); ++i) {
    gray.push_back(images->Gray(i, camera_level));
  }
  CameraRefinementOptions camera_options = options.camera_refinement;
  camera_options.mode = options.refine_cameras;
  camera_options.interpolation = options.pair.interpolation;
  camera_options.max_render_mb = std::max<int>(1, static_cast<int>(max_bytes >> 20));
  // The options in pixel footprints keep their size in the surface level's
  // pixels (the user's), which are 2^-(camera_level - level) of a coarser
  // level's.
  const double coarser = std::ldexp(1.0, camera_level - level);
  camera_options.prior_center_px /= coarser;
  camera_options.surface_sigma_px /= coarser;
  camera_options.datum_sigma_px /= coarser;
  const std::vector<PinholeView> prior = LevelViews(input_cameras, camera_level);
  const CameraRefinementSummary refined = RefineCameras(
      gray, pairs, V, F, renderer, camera_of_view, camera_options, &camera_views, &prior);
  MR_LOG(INFO) << "Level " << level << " cameras" << where << ": " << refined.BriefReport();
  MR_LOG(VERBOSE) << refined.FullReport();
  summary->camera_reports.push_back("level " + std::to_string(level) + where + ": " +
                                    refined.BriefReport());
  const double scale = std::ldexp(1.0, camera_level);
  for (size_t i = 0; i < camera_views.size(); ++i) {
    PinholeView full = camera_views[i].Scaled(scale);
    full.width = (*cameras)[i].width;  // the level's sizes were rounded up
    full.height = (*cameras)[i].height;
    (*cameras)[i] = full;
    // At camera_level == level this is camera_views[i] again: the intrinsics
    // scale by powers of 2, exactly.
    (*views)[i] = PyramidLevelView(full, level);
  }
}

// Faces per spatial piece of the remeshing's decimations, the first one and
// the trim to the face budget (the example's 303k-face Poisson mesh: 8
// pieces; docs/results.md, "Speed and memory").
constexpr int kDecimateFacesPerPiece = 50000;

// The open border's membrane step (RefineOptions::open_border_rings): half-way
// to the neighbours' mean. The umbrella operator's eigenvalues lie in
// [-2, 0], so this is the largest explicit step that flips the sign of no
// frequency (no zig-zag is made worse).
constexpr double kOpenBorderStep = 0.5;

// Per band vertex, 1 where the membrane step may move it (the images see it
// and disagree), 0 elsewhere; `contradicted_below` is the similarity bound
// (ContradictedSimilarity).
Eigen::VectorXd UnheldBandVertices(const VertexBand& band, const DataTerm& term,
                                   double contradicted_below) {
  Eigen::VectorXd unheld(band.vertices.size());
  for (size_t i = 0; i < band.vertices.size(); ++i) {
    const int v = band.vertices[i];
    const bool contradicted = term.weight(v) > 0 &&
                              term.similarity(v) < contradicted_below * term.weight(v);
    unheld(i) = contradicted ? 1.0 : 0.0;
  }
  return unheld;
}

// Remeshes to the level's target edge length, within the face budget.
// Returns false, leaving (V, F) half-done, when *cancel (if given) was set
// before the end; it is checked during the decimation and between stages.
bool RemeshForLevel(const std::vector<PinholeView>& views, const RefineOptions& options,
                    int max_faces, Eigen::MatrixXd* V, Eigen::MatrixXi* F,
                    const std::atomic<bool>* cancel = nullptr) {
  auto cancelled = [cancel] { return cancel != nullptr && cancel->load(); };
  const EdgeSizing sizing(views, *V, *F, options.target_edge_px, max_faces);
  if (!sizing.visible()) MR_THROW_INPUT << "the mesh is not visible in any view";
  const int target_faces = sizing.expected_faces();
  const double t0 = ElapsedSeconds();
  const int faces_before = static_cast<int>(F->rows());
  if (faces_before > 2 * target_faces) {
    // Large reductions by quadric decimation first (Garland-Heckbert), which
    // keeps the shape better than collapsing to length alone. On spatial
    // pieces in parallel (their cuts, left at the input's resolution, are
    // remeshed below); the pieces follow from the face count alone, so the
    // result does not depend on the number of threads.
    DecimateOptions decimate;
    decimate.cancel = cancel;
    decimate.faces_per_piece = kDecimateFacesPerPiece;
    const DecimateSummary decimated = Decimate(V, F, std::max(4, target_faces), decimate);
    MR_LOG(VERBOSE) << decimated.BriefReport();
  }
  if (cancelled()) return false;
  if (sizing.uniform()) {
    IsotropicRemesh(V, F, sizing.band_edges()[0]);
  } else {
    IsotropicRemeshBands(V, F, sizing.band_edges(),
                         [&sizing](const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
                           return sizing.BandOf(x, n);
                         });
  }
  // The count above is that of equilateral triangles; the remesher's edges
  // come out shorter than its target (mean 0.93x on a 352k-face Poisson mesh
  // remeshed for 1600x1200 images: 820k faces for a budget of 704k), so the
  // budget is enforced by a last, small quadric decimation.
  if (cancelled()) return false;
  if (F->rows() > max_faces) {
    // On pieces too: the triangles kept along the cuts are the remeshed
    // ones, already at the working length.
    DecimateOptions trim;
    trim.faces_per_piece = kDecimateFacesPerPiece;
    const DecimateSummary trimmed = Decimate(V, F, max_faces, trim);
    MR_LOG(INFO) << "Remeshed mesh over the face budget (max_faces " << max_faces
                 << "): " << trimmed.BriefReport();
  }
  // Faces and vertices in spatial order, so that the renders and every
  // per-vertex pass run from the cache (CGAL's remeshing leaves them
  // scattered; the example: renders 37 -> 21 ms, iterations 35 % faster,
  // docs/results.md). Not before the first remeshing: CGAL's result depends
  // on the order of its input, and ordering the input moved the corpus's
  // results by up to 4 % either way for 1.3 s of the example's time.
  OrderSpatially(V, F);
  std::ostringstream edges;
  if (!sizing.uniform()) {
    edges << " of each point's median footprint: " << sizing.band_edges().size()
          << " depth bands a factor sqrt(2) apart, " << sizing.band_edges().front() << " to "
          << sizing.band_edges().back() << " scene units";
  }
  MR_LOG(INFO) << "Remeshed " << faces_before << " -> " << F->rows() << " faces (edge "
               << sizing.edge_px() << " px at this level" << edges.str() << ", "
               << ElapsedSeconds() - t0 << " s)";
  return true;
}

// The input remeshed for the full-resolution level on a second thread while
// the main thread measures the schedule (ChooseNumLevels renders through the
// GL context, which stays on the main thread). A close start (one level, as
// for every Poisson mesh of the corpus) begins from it; a coarse-to-fine
// schedule cancels it. The same RemeshForLevel on the same input as the
// sequential path, so the result is the same. Cancelled and joined on
// destruction, also when the main thread unwinds.
class BackgroundRemesh {
 public:
  BackgroundRemesh(std::vector<PinholeView> views, const RefineOptions& options, int max_faces,
                   Eigen::MatrixXd V, Eigen::MatrixXi F)
      : V_(std::move(V)), F_(std::move(F)) {
    result_ = std::async(std::launch::async,
                         [this, views = std::move(views), &options, max_faces] {
                           return RemeshForLevel(views, options, max_faces, &V_, &F_, &cancel_);
                         });
  }
  ~BackgroundRemesh() {
    cancel_ = true;
    if (result_.valid()) result_.wait();
  }
  BackgroundRemesh(const BackgroundRemesh&) = delete;
  BackgroundRemesh& operator=(const BackgroundRemesh&) = delete;

  // Waits for the remeshed mesh (rethrows what the remeshing threw).
  void Take(Eigen::MatrixXd* V, Eigen::MatrixXi* F) {
    MR_CHECK(result_.get()) << "the background remeshing was cancelled";
    *V = std::move(V_);
    *F = std::move(F_);
  }

 private:
  Eigen::MatrixXd V_;
  Eigen::MatrixXi F_;
  std::atomic<bool> cancel_{false};
  std::future<bool> result_;
};

// Median of the positive entries, or 0.
double MedianPositive(const Eigen::VectorXd& x) {
  std::vector<double> values;
  for (int i = 0; i < x.size(); ++i) {
    if (x(i) > 0) values.push_back(x(i));
  }
  return values.empty() ? 0.0 : Median(&values);
}

}  // namespace

std::vector<int> CameraRoundIterations(int iterations, int rounds) {
  std::vector<int> at;
  for (int k = 1; k <= rounds && k * (k + 1) / 2 < iterations; ++k) {
    at.push_back(k * (k + 1) / 2);
  }
  return at;
}

int CameraRefinementLevel(const std::vector<PinholeView>& level_views, int level,
                          size_t max_bytes) {
  MR_CHECK_GE(level, 0);
  for (int k = 0; k <= kMaxCameraLevelsCoarser; ++k) {
    if (GrayBytes(LevelViews(level_views, k)) <= max_bytes) return level + k;
  }
  return -1;
}

int FirstAveragedIteration(int iterations, int average_last,
                           const std::vector<int>& camera_rounds) {
  int first = std::max(0, iterations - average_last);
  if (!camera_rounds.empty()) {
    first = std::max(first, camera_rounds.back() + kCameraSettlingIterations);
  }
  return iterations - first >= 2 ? first : iterations;
}

double ContradictedSimilarity(const Eigen::VectorXd& similarity, const Eigen::VectorXd& weight) {
  MR_CHECK_EQ(similarity.size(), weight.size());
  std::vector<double> mean;
  mean.reserve(weight.size());
  for (Eigen::Index v = 0; v < weight.size(); ++v) {
    if (weight(v) > 0) mean.push_back(similarity(v) / weight(v));
  }
  if (mean.empty()) return -std::numeric_limits<double>::infinity();
  const MedianAndSpread robust = RobustMedianAndSpread(&mean);
  return std::min(kOpenBorderMaxSimilarity,
                  robust.median - kOpenBorderOutlierSigmas * robust.sigma);
}

int BestIterateToKeep(const std::vector<double>& similarities, double giveback) {
  if (similarities.size() < 2) return -1;
  const auto best = std::max_element(similarities.begin(), similarities.end());
  const double gain = *best - similarities.front();
  const double fall = *best - similarities.back();
  if (!(fall > 0) || !(fall > giveback * gain)) return -1;
  return static_cast<int>(best - similarities.begin());
}

namespace {

// Sums the data term over all ordered pairs of the level (only its scalars
// without `with_gradient`). `visit`, if given, is called with a view's render
// each time the pass fetches it (twice per pair).
DataTerm ComputeDataTerm(const MeshGeometry& mesh, const std::vector<PinholeView>& views,
                         const std::vector<std::pair<int, int>>& pairs, int level,
                         const SimilarityOptions& similarity, const PairTermOptions& pair_options,
                         RenderCache* renders, ImageCache* images, bool with_gradient,
                         const std::function<void(int, const RenderBuffers&)>& visit = {}) {
  DataTermAccumulator accumulator(static_cast<int>(mesh.V->rows()));
  auto get = [&](int i) {
    auto render = renders->Get(i);
    if (visit) visit(i, *render);
    return render;
  };
  for (const auto& [a, b] : pairs) {
    for (int dir = 0; dir < 2; ++dir) {
      const int i = dir == 0 ? a : b, j = dir == 0 ? b : a;
      const auto render_i = get(i);
      const auto render_j = get(j);
      accumulator.AddPair(mesh, views[i], *render_i, images->Gray(i, level), views[j], *render_j,
                          images->Gray(j, level), similarity, pair_options, with_gradient);
    }
  }
  return accumulator.Sum();
}

// Mean plain-ZNCC similarity of all pairs at pyramid `level` through (V, F),
// once per entry of `pair_options` and through the same renders (the light
// changes the comparison, not what each pixel sees); `views` are the
// full-resolution ones. `visit` (optional) sees each render of a view in a
// pair, as in ComputeDataTerm.
std::vector<double> MeanSimilaritiesAtLevel(
    const std::vector<PinholeView>& views, const std::vector<std::pair<int, int>>& pairs,
    const SimilarityOptions& similarity, const std::vector<PairTermOptions>& pair_options,
    const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Renderer* renderer, size_t cache_bytes,
    ImageCache* images, int level,
    const std::function<void(int, const RenderBuffers&)>& visit = {}) {
  const std::vector<PinholeView> level_views = LevelViews(views, level);
  RenderCache renders(renderer, level_views, cache_bytes);
  renderer->SetMesh(V, F);
  MeshGeometry geometry{&V, &F, FaceNormals(V, F)};
  SimilarityOptions plain = similarity;
  plain.method = "zncc";
  plain.kappa = 0;
  std::vector<double> means;
  for (const PairTermOptions& options : pair_options) {
    means.push_back(ComputeDataTerm(geometry, level_views, pairs, level, plain, options, &renders,
                                    images, /*with_gradient=*/false, means.empty() ? visit : nullptr)
                        .MeanSimilarity());
  }
  return means;
}

double MeanSimilarityAtLevel(const std::vector<PinholeView>& views,
                             const std::vector<std::pair<int, int>>& pairs,
                             const SimilarityOptions& similarity,
                             const PairTermOptions& pair_options, const Eigen::MatrixXd& V,
                             const Eigen::MatrixXi& F, Renderer* renderer, size_t cache_bytes,
                             ImageCache* images, int level,
                             const std::function<void(int, const RenderBuffers&)>& visit = {}) {
  return MeanSimilaritiesAtLevel(views, pairs, similarity, {pair_options}, V, F, renderer,
                                 cache_bytes, images, level, visit)[0];
}

// The same at full resolution.
double FullResolutionSimilarity(const std::vector<PinholeView>& views,
                                const std::vector<std::pair<int, int>>& pairs,
                                const SimilarityOptions& similarity,
                                const PairTermOptions& pair_options, const Eigen::MatrixXd& V,
                                const Eigen::MatrixXi& F, Renderer* renderer, size_t cache_bytes,
                                ImageCache* images,
                                const std::function<void(int, const RenderBuffers&)>& visit = {}) {
  return MeanSimilarityAtLevel(views, pairs, similarity, pair_options, V, F, renderer,
                               cache_bytes, images, 0, visit);
}

// Per-vertex colours: the mean colour of each vertex over the views where
// it is visible, weighted by the cosine of the viewing angle. Each view is
// added once with its render of (V, F) (the final similarity pass lends its
// renders, so that the views are not rendered twice); Colors() renders the
// views that were not added.
class VertexColorSampler {
 public:
  VertexColorSampler(const ViewSource& source, const std::vector<PinholeView>& views,
                     const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
      : source_(source),
        views_(views),
        V_(V),
        F_(F),
        N_(VertexNormals(V, F)),
        sum_(Eigen::MatrixXd::Zero(V.rows(), 3)),
        weight_(Eigen::VectorXd::Zero(V.rows())),
        added_(views.size(), 0) {}

  void Add(int i, const RenderBuffers& render) {
    if (added_[i]) return;
    added_[i] = 1;
    const PinholeView& view = views_[i];
    const cv::Mat color = source_.LoadColor(i);
#pragma omp parallel for schedule(static)
    for (int v = 0; v < V_.rows(); ++v) {
      const Eigen::Vector3d x = V_.row(v);
      const Eigen::Vector3d xc = view.WorldToCamera(x);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d p = view.CameraToImage(xc);
      if (!view.InImage(p)) continue;
      const int col = static_cast<int>(p.x()), row = static_cast<int>(p.y());
      const float d = render.DepthAt(row, col);
      if (render.FaceAt(row, col) < 0 || std::abs(d - xc.z()) > 0.01 * xc.z()) continue;
      const double w = N_.row(v).dot((view.Center() - x).normalized());
      if (w <= 0) continue;
      const cv::Vec3b bgr = color.at<cv::Vec3b>(row, col);
      sum_.row(v) += w * Eigen::Vector3d(bgr[2], bgr[1], bgr[0]).transpose();
      weight_(v) += w;
    }
  }

  void Colors(Renderer* renderer, Eigen::Matrix<uint8_t, Eigen::Dynamic, 3>* colors) {
    bool mesh_set = false;
    for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
      if (added_[i]) continue;
      if (!mesh_set) {
        renderer->SetMesh(V_, F_);
        mesh_set = true;
      }
      Add(i, renderer->Render(views_[i]));
    }
    colors->resize(V_.rows(), 3);
    for (int v = 0; v < V_.rows(); ++v) {
      const Eigen::Vector3d c = weight_(v) > 0 ? Eigen::Vector3d(sum_.row(v) / weight_(v))
                                               : Eigen::Vector3d(128, 128, 128);
      for (int k = 0; k < 3; ++k) {
        (*colors)(v, k) = static_cast<uint8_t>(std::clamp(c(k), 0.0, 255.0));
      }
    }
  }

 private:
  const ViewSource& source_;
  const std::vector<PinholeView>& views_;
  const Eigen::MatrixXd& V_;
  const Eigen::MatrixXi& F_;
  const Eigen::MatrixXd N_;
  Eigen::MatrixXd sum_;
  Eigen::VectorXd weight_;
  std::vector<char> added_;
};

// The final mesh's mean similarity over all pairs at full resolution and
// its vertex colours, from one pass over the pairs; made for one (V, F) and
// dropped when the mesh changes.
struct FinalPass {
  FinalPass(const ViewSource& source, const std::vector<PinholeView>& views,
            const Eigen::MatrixXd& V, const Eigen::MatrixXi& F)
      : colors(source, views, V, F) {}
  VertexColorSampler colors;
  double similarity = 0;
};

struct Schedule {
  int num_levels = 1;
  double misalignment_px = 0;  // median image misalignment of the input
  std::string reason;
};

// How far the input surface is from the images, in full-resolution pixels:
// for each view pair (i, j), the image predicted for view i through the mesh
// (image j warped by the surface) is compared with image i by dense optical
// flow (Farneback); a surface that is off by d pixels shifts the prediction
// by about d. Only pixels where the prediction is valid and image i has more
// than its median gradient count (textureless pixels carry no flow). The
// median over the pixels of each pair, then the median over pairs. The flow
// is computed only around the predicted pixels. Of many pairs, at most
// kMaxPairs spread evenly over the list, so that the cost stops growing with
// the number of views. Measured: 100 views, 52 of 206 pairs, the same 0.2 px
// (setup 28.8 -> 13.2 s at 1280x960); 40 views, 41 of 82 pairs, 0.19 ->
// 0.18 px.
double MeasureMisalignmentPx(const std::vector<PinholeView>& views,
                             const std::vector<std::pair<int, int>>& pairs,
                             const MeshGeometry& geometry, const PairTermOptions& pair_options,
                             RenderCache* renders, ImageCache* images) {
  // Beyond the predicted pixels both images are image i: no flow, only the
  // margin that keeps the flow's window and pyramid away from the crop.
  constexpr int kMarginPx = 32;
  constexpr size_t kMaxPairs = 64;
  std::vector<double> per_pair;
  const size_t stride = std::max<size_t>(1, (pairs.size() + kMaxPairs - 1) / kMaxPairs);
  for (size_t k = 0; k < pairs.size(); k += stride) {
    const auto& [i, j] = pairs[k];
    const auto render_i = renders->Get(i);
    const auto render_j = renders->Get(j);
    cv::Mat predicted, mask;
    PredictImage(geometry, views[i], *render_i, views[j], *render_j, images->Gray(j, 0),
                 pair_options, &predicted, &mask);
    if (cv::countNonZero(mask) == 0) continue;
    cv::Rect box = cv::boundingRect(mask);
    box = cv::Rect(box.x - kMarginPx, box.y - kMarginPx, box.width + 2 * kMarginPx,
                   box.height + 2 * kMarginPx) &
          cv::Rect(0, 0, mask.cols, mask.rows);
    predicted = predicted(box);
    mask = mask(box);
    const cv::Mat image_i = images->Gray(i, 0)(box);
    cv::Mat erode;
    cv::erode(mask, erode, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
    if (cv::countNonZero(erode) < 500) continue;
    cv::Mat a8, b8, predicted32;
    predicted.convertTo(predicted32, CV_32F);
    image_i.copyTo(predicted32, mask == 0);  // no flow where nothing is predicted
    image_i.convertTo(a8, CV_8U, 255.0);
    predicted32.convertTo(b8, CV_8U, 255.0);
    cv::Mat flow;
    cv::calcOpticalFlowFarneback(a8, b8, flow, 0.5, 5, 15, 3, 5, 1.1, 0);
    cv::Mat gx, gy, gradient;
    cv::Sobel(image_i, gx, CV_32F, 1, 0);
    cv::Sobel(image_i, gy, CV_32F, 0, 1);
    cv::magnitude(gx, gy, gradient);
    std::vector<float> gradients;
    for (int r = 0; r < erode.rows; ++r) {
      for (int c = 0; c < erode.cols; ++c) {
        if (erode.at<uint8_t>(r, c)) gradients.push_back(gradient.at<float>(r, c));
      }
    }
    const float gradient_median = Median(&gradients);
    std::vector<float> shifts;
    for (int r = 0; r < erode.rows; ++r) {
      for (int c = 0; c < erode.cols; ++c) {
        if (!erode.at<uint8_t>(r, c) || gradient.at<float>(r, c) <= gradient_median) continue;
        const cv::Vec2f f = flow.at<cv::Vec2f>(r, c);
        shifts.push_back(std::hypot(f[0], f[1]));
      }
    }
    if (shifts.empty()) continue;
    per_pair.push_back(Median(&shifts));
  }
  return per_pair.empty() ? 0.0 : Median(&per_pair);
}

// Picks the number of pyramid levels from the input itself: its misalignment
// with the images in full-resolution pixels, d (MeasureMisalignmentPx). The
// gradient flow converges from within about a pixel of the optimum at its
// level, and level l divides the misalignment by 2^l, so the refinement
// starts at the coarsest level needed to bring d under
// schedule_misalignment_px, within the levels whose images keep
// min_level_image_px on their short side. A Poisson mesh is typically within
// a pixel (1 level, no decimation); a visual hull is several pixels off.
Schedule ChooseNumLevels(const ViewSource& source, const std::vector<std::pair<int, int>>& pairs,
                         const RefineOptions& options, const Eigen::MatrixXd& V,
                         const Eigen::MatrixXi& F, Renderer* renderer, size_t cache_bytes,
                         ImageCache* images) {
  Schedule schedule;
  const std::vector<PinholeView> views = source.Views();
  renderer->SetMesh(V, F);
  const MeshGeometry geometry{&V, &F, FaceNormals(V, F)};
  RenderCache renders(renderer, views, cache_bytes);
  schedule.misalignment_px =
      MeasureMisalignmentPx(views, pairs, geometry, options.pair, &renders, images);
  int max_levels = 1;
  while (max_levels < 6) {
    const PinholeView coarse = PyramidLevelView(views[0], max_levels);
    if (std::min(coarse.width, coarse.height) < options.min_level_image_px) break;
    ++max_levels;
  }
  int levels = 1;
  while (levels < max_levels &&
         schedule.misalignment_px / std::pow(2.0, levels - 1) > options.schedule_misalignment_px) {
    ++levels;
  }
  schedule.num_levels = levels;
  std::ostringstream reason;
  reason << levels << (levels == 1 ? " level" : " levels") << ": the input is "
         << std::setprecision(2) << schedule.misalignment_px
         << " px off the images (median optical flow between each image and its prediction "
            "through the mesh); "
         << (levels == 1 ? "within " : "above ") << options.schedule_misalignment_px << " px"
         << (levels == 1 ? ": a close start, full resolution only"
                         : ": a far-off start, coarse to fine");
  if (levels == max_levels && levels > 1) reason << " (the most levels the image size allows)";
  schedule.reason = reason.str();
  return schedule;
}

std::string FormatSeconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << s << " s";
  return out.str();
}

// RefineOptions::output_subdivisions, one step: SubdividePointNormal, each
// new vertex's colour the mean of its edge's ends. With `guarded` (the mesh
// is an oriented 2-manifold free of self-intersections), a new vertex whose
// faces would intersect or flip goes back to its edge's midpoint, where the
// surface is the unsplit one's.
void SubdivideResult(double normal_sigma, bool guarded, TriangleMesh* mesh) {
  const int nv = mesh->NumVertices();
  Eigen::MatrixXi E;  // the edge of each new vertex
  SubdividePointNormal(&mesh->V, &mesh->F, normal_sigma, &E);
  if (guarded) {
    Eigen::MatrixXd V_midpoints = mesh->V;
    for (int e = 0; e < E.rows(); ++e) {
      V_midpoints.row(nv + e) = 0.5 * (mesh->V.row(E(e, 0)) + mesh->V.row(E(e, 1)));
    }
    const UndoSelfIntersectionsSummary undone =
        UndoSelfIntersections(V_midpoints, mesh->F, {}, &mesh->V);
    if (undone.reset_vertices > 0) {
      MR_LOG(INFO) << "SubdividePointNormal: " << undone.reset_vertices
                   << " new vertices back on their edges' midpoints (" << undone.BriefReport()
                   << ")";
    }
  }
  if (mesh->C.rows() == nv) {
    mesh->C.conservativeResize(nv + E.rows(), 3);
    for (int e = 0; e < E.rows(); ++e) {
      for (int k = 0; k < 3; ++k) {
        mesh->C(nv + e, k) =
            static_cast<uint8_t>((int{mesh->C(E(e, 0), k)} + int{mesh->C(E(e, 1), k)} + 1) / 2);
      }
    }
  }
}

}  // namespace

double MeanResetFraction(const std::vector<int>& resets, int num_vertices) {
  if (resets.empty() || num_vertices <= 0) return 0.0;
  double sum = 0;
  for (const int r : resets) sum += r;
  return sum / (static_cast<double>(resets.size()) * num_vertices);
}

bool RefineOptions::Check() const {
  auto fail = [](const std::string& field, const std::string& value, const std::string& bound) {
    MR_THROW_INPUT << "RefineOptions::" << field << " = " << value
                   << ". Violated constraint: " << bound;
  };
  if (num_levels < 0 || num_levels > 6) fail("num_levels", std::to_string(num_levels), "0 <= num_levels <= 6 (0: chosen from the input)");
  if (!(min_improvement >= 0)) fail("min_improvement", std::to_string(min_improvement), "min_improvement >= 0");
  if (pair_halves_min_views < 0) {
    fail("pair_halves_min_views", std::to_string(pair_halves_min_views),
         "pair_halves_min_views >= 0");
  }
  if (!(best_iterate_giveback >= 0 && best_iterate_giveback <= 1)) {
    fail("best_iterate_giveback", std::to_string(best_iterate_giveback),
         "0 <= best_iterate_giveback <= 1");
  }
  if (!(schedule_misalignment_px > 0)) fail("schedule_misalignment_px", std::to_string(schedule_misalignment_px), "schedule_misalignment_px > 0");
  if (min_level_image_px < 16) fail("min_level_image_px", std::to_string(min_level_image_px), "min_level_image_px >= 16");
  if (iterations_per_level < 0) fail("iterations_per_level", std::to_string(iterations_per_level), "iterations_per_level >= 0");
  if (!(target_edge_px > 0)) fail("target_edge_px", std::to_string(target_edge_px), "target_edge_px > 0");
  if (max_image_size != -1 && max_image_size < 32) {
    fail("max_image_size", std::to_string(max_image_size), "max_image_size >= 32 or -1");
  }
  if (max_faces < 0) fail("max_faces", std::to_string(max_faces), "max_faces >= 0");
  if (output_subdivisions < 0 || output_subdivisions > 2) {
    fail("output_subdivisions", std::to_string(output_subdivisions),
         "0 <= output_subdivisions <= 2");
  }
  if (!(step > 0 && step <= 1)) fail("step", std::to_string(step), "0 < step <= 1");
  if (!(max_step_px > 0)) fail("max_step_px", std::to_string(max_step_px), "max_step_px > 0");
  if (!(damping >= 0)) fail("damping", std::to_string(damping), "damping >= 0");
  if (similarity != "dcv" && similarity != "zncc") fail("similarity", similarity, "one of dcv, zncc");
  if (color != "luminance" && color != "principal") fail("color", color, "one of luminance, principal");
  if (!(kappa >= 0)) fail("kappa", std::to_string(kappa), "kappa >= 0");
  if (refine_cameras != "none" && refine_cameras != "poses" && refine_cameras != "poses_intrinsics") {
    fail("refine_cameras", refine_cameras, "one of none, poses, poses_intrinsics");
  }
  if (average_last_iterates < 1) {
    fail("average_last_iterates", std::to_string(average_last_iterates), "average_last_iterates >= 1");
  }
  if (camera_rounds < 1) fail("camera_rounds", std::to_string(camera_rounds), "camera_rounds >= 1");
  if (refine_cameras != "none") {
    CameraRefinementOptions cameras = camera_refinement;
    cameras.mode = refine_cameras;
    cameras.Check();
  }
  if (regularizer != "lp" && regularizer != "laplacian" && regularizer != "bilateral_normal" &&
      regularizer != "none") {
    fail("regularizer", regularizer, "one of lp, laplacian, bilateral_normal, none");
  }
  if (!(silhouette_weight >= 0)) fail("silhouette_weight", std::to_string(silhouette_weight), "silhouette_weight >= 0");
  if (!std::isfinite(hull_margin_px)) {
    fail("hull_margin_px", std::to_string(hull_margin_px), "a finite number (< 0: off)");
  }
  if (open_border_rings < 0) {
    fail("open_border_rings", std::to_string(open_border_rings), "open_border_rings >= 0 (0: off)");
  }
  if (light != "world" && light != "headlight" && light != "auto") {
    fail("light", light, "one of world, headlight, auto");
  }
  if (!(light_ambient >= 0 && light_ambient <= 1)) {
    fail("light_ambient", std::to_string(light_ambient), "0 <= light_ambient <= 1");
  }
  if (cache_mb < 1) fail("cache_mb", std::to_string(cache_mb), "cache_mb >= 1");
  background_mask.Check();
  mask_outline.Check();
  view_selection.Check();
  similarity_options.Check();
  pair.Check();
  denoise.Check();
  return true;
}

std::string RefineSummary::BriefReport() const {
  std::ostringstream out;
  out << "DCV refinement: " << termination << ", " << iterations.size() << " iterations, "
      << initial_faces << " -> " << final_faces << " faces, mean similarity " << std::setprecision(4)
      << initial_similarity << " -> " << final_similarity << ", " << FormatSeconds(seconds);
  return out.str();
}

std::string RefineSummary::FullReport() const {
  std::ostringstream out;
  out << BriefReport() << "\n";
  if (!schedule.empty()) out << "  schedule: " << schedule << "\n";
  if (!masks.empty()) out << "  masks: " << masks << "\n";
  out << "  views " << num_views << ", pairs " << num_pairs << ", vertices " << initial_vertices
      << " -> " << final_vertices << ", flipped faces fixed " << flipped_faces_fixed
      << ", steps taken back " << steps_taken_back << ", levels ended on their best iterate "
      << levels_ended_on_best << " (" << iterations_dropped << " iterations dropped)"
      << ", iterates averaged " << iterates_averaged
      << ", intersecting pairs undone " << self_intersections_undone << " (" << vertices_reset
      << " vertex moves reset), self-intersections left " << self_intersections << "\n";
  out << "  surface moved: mean " << mean_displacement << ", max " << max_displacement
      << " (scene units; distance of the result's vertices to the input surface)\n";
  double data = 0, silhouette = 0, denoise = 0, cleanup = 0, cameras = 0, iterating = 0;
  for (const auto& it : iterations) {
    data += it.data_seconds;
    silhouette += it.silhouette_seconds;
    denoise += it.denoise_seconds;
    cleanup += it.cleanup_seconds;
    cameras += it.camera_seconds;
    iterating += it.seconds;
  }
  out << std::setprecision(3) << "  time: setup " << setup_seconds << " s, remeshing "
      << remesh_seconds << " s, iterations " << iterating << " s (data " << data
      << ", silhouette " << silhouette << ", denoise " << denoise << ", clean-up " << cleanup;
  if (cameras > 0) out << ", cameras " << cameras;
  out << "), final " << final_seconds << " s\n";
  out << "  level iter  faces  similarity  kappa  step_px(mean/max)  regulariser  seconds\n";
  bool any_half = false;
  for (const auto& it : iterations) {
    const bool half = it.num_pairs > 0 && it.num_pairs < num_pairs;
    any_half = any_half || half;
    out << "  " << std::setw(5) << it.level << std::setw(5) << it.iteration << std::setw(7)
        << it.faces << "  " << std::fixed << std::setprecision(4) << it.mean_similarity
        << (half ? "h " : "  ") << std::setprecision(3) << it.kappa << "  " << it.mean_step_px
        << "/" << it.max_step_px << "  " << it.regularizer_report << "  " << std::setprecision(2)
        << it.seconds << "\n";
    out.unsetf(std::ios::fixed);
  }
  if (any_half) out << "  h: the similarity over half of the pairs (the averaged iterations; with pair_halves_min_views views, the middle ones)\n";
  return out.str();
}

RefineSummary RefineMesh(const ViewSource& input_source, const RefineOptions& options,
                         TriangleMesh* mesh, Renderer* renderer) {
  options.Check();
  const double t_start = ElapsedSeconds();
  if (mesh->NumFaces() == 0 || mesh->NumVertices() == 0) {
    MR_THROW_INPUT << "the input mesh is empty (" << mesh->NumVertices() << " vertices, "
                   << mesh->NumFaces() << " faces)";
  }
  if (input_source.NumViews() < 2) {
    MR_THROW_INPUT << "refinement needs at least 2 views, got " << input_source.NumViews();
  }
  std::unique_ptr<Renderer> own_renderer;
  if (renderer == nullptr) {
    own_renderer = std::make_unique<Renderer>();
    renderer = own_renderer.get();
  }
  // Everything below works at the working resolution.
  const ResizedViewSource working(input_source, options.max_image_size);
  // Without masks, masks from a uniform background where they agree with the
  // input mesh, for the silhouette term (made at the working resolution).
  std::unique_ptr<ViewSource> masked;
  if (!working.HasMasks() && options.masks_from_background && options.silhouette_weight > 0) {
    BackgroundMaskReport report;
    masked = MakeBackgroundMasks(working, mesh->V, mesh->F, renderer, options.background_mask,
                                 &report);
    MR_LOG(INFO) << "No masks given: " << report.BriefReport();
  }
  // Given masks whose outline lies off the images' edges are moved onto them.
  MaskOutlineReport mask_report;
  if (working.HasMasks() && options.align_masks && options.silhouette_weight > 0) {
    mask_report = MeasureMaskOutline(working, options.mask_outline);
    MR_LOG(INFO) << "Masks: " << mask_report.BriefReport();
    if (mask_report.move) {
      masked = std::make_unique<MovedMaskViewSource>(working, mask_report.edge_offset_px);
    }
  }
  const ViewSource& masked_source = masked ? static_cast<const ViewSource&>(*masked) : working;
  std::unique_ptr<BlackOutsideMasksViewSource> blackened;
  if (working.HasMasks() && options.black_outside_masks) {
    blackened = std::make_unique<BlackOutsideMasksViewSource>(masked_source);
  }
  const ViewSource& source = blackened ? *blackened : masked_source;

  RefineSummary summary;
  summary.masks = mask_report.views_measured > 0 ? mask_report.BriefReport() : "";
  summary.num_views = source.NumViews();
  summary.initial_faces = mesh->NumFaces();
  summary.initial_vertices = mesh->NumVertices();
  Eigen::MatrixXd V = mesh->V;
  Eigen::MatrixXi F = mesh->F;

  const CleanMeshReport clean = CleanMesh(&V, &F);
  MR_LOG(INFO) << "Input mesh: " << clean.BriefReport();
  if (F.rows() == 0) MR_THROW_INPUT << "the input mesh has no valid faces after cleaning";
  if (!clean.IsCleanManifold()) {
    MR_THROW_INPUT << "the input mesh could not be made an oriented 2-manifold ("
                   << clean.BriefReport() << ")";
  }
  const Eigen::MatrixXd V_input = V;  // for the displacement in the summary
  const Eigen::MatrixXi F_input = F;

  const std::vector<PinholeView> full_views = source.Views();
  if (!(MedianFootprint(full_views, V, VertexNormals(V, F)) > 0)) {
    MR_THROW_INPUT << "the mesh is not visible in any view: no vertex faces a camera inside its "
                      "image (is the mesh in the same coordinate frame as the sparse model?)";
  }
  const auto neighbors = SelectNeighbors(full_views, V, VertexNormals(V, F), options.view_selection);
  const auto pairs = NeighborPairs(neighbors);
  summary.num_pairs = static_cast<int>(pairs.size());
  if (pairs.empty()) {
    MR_THROW_INPUT << "no two views overlap on the mesh: nothing to compare (check the cameras "
                      "and that the mesh lies in front of them)";
  }
  MR_LOG(INFO) << "Selected " << pairs.size() << " view pairs among " << source.NumViews()
               << " views";
  // The view pairs in two halves, each covering every view: the finest
  // level's averaged iterations take them in turn, and with many views the
  // middle iterations of every level too.
  const bool many_views =
      options.pair_halves_min_views > 0 && source.NumViews() >= options.pair_halves_min_views;
  const bool averaged_halves = options.average_pair_halves && options.average_last_iterates >= 2;
  std::vector<std::vector<std::pair<int, int>>> pair_halves;
  if (many_views || averaged_halves) {
    pair_halves = SplitPairsCoveringViews(pairs, 2);
    if (!many_views && !GroupsCoverEveryView(pairs, pair_halves)) pair_halves.clear();
  }
  if (!pair_halves.empty()) {
    std::vector<std::string> users;
    if (averaged_halves) {
      users.push_back("the finest level's averaged iterations");
    }
    if (many_views) {
      users.push_back("every level's middle iterations (" + std::to_string(source.NumViews()) +
                      " views >= " + std::to_string(options.pair_halves_min_views) + ")");
    }
    MR_LOG(INFO) << "Pairs in two halves of " << pair_halves[0].size() << " and "
                 << pair_halves[1].size() << ", taken in turn by " << users[0]
                 << (users.size() > 1 ? " and " + users[1] : std::string());
  }
  // The cameras at the working resolution; refine_cameras moves them.
  std::vector<PinholeView> cameras = full_views;
  std::vector<int> camera_of_view;
  for (int i = 0; i < source.NumViews(); ++i) camera_of_view.push_back(source.CameraId(i));

  const int max_faces = options.FaceBudget(summary.initial_faces);
  const size_t cache_bytes = static_cast<size_t>(options.cache_mb) << 20;
  ImageCache images(source, cache_bytes / 2);

  SimilarityOptions similarity = options.similarity_options;
  similarity.method = options.similarity;
  DenoiseOptions denoise = options.denoise;
  denoise.method = options.regularizer == "none" ? "lp" : options.regularizer;

  // Where the light is: given, or the candidate under which the input
  // explains the images best.
  PairTermOptions pair = options.pair;
  pair.headlight_ambient = options.light == "headlight" ? options.light_ambient : -1;
  if (options.light == "auto") {
    // At half resolution (a quarter of the full-resolution pass's pixels):
    // a fixed light against one at the camera with half the light ambient,
    // and only if the camera's wins, two more ambient shares.
    const double t0 = ElapsedSeconds();
    const int level = std::min(cameras[0].width, cameras[0].height) >= 256 ? 1 : 0;
    std::ostringstream tried;
    double best = -std::numeric_limits<double>::infinity();
    auto try_lights = [&](const std::vector<double>& ambients) {
      std::vector<PairTermOptions> candidates(ambients.size(), options.pair);
      for (size_t k = 0; k < ambients.size(); ++k) candidates[k].headlight_ambient = ambients[k];
      const std::vector<double> means = MeanSimilaritiesAtLevel(
          cameras, pairs, similarity, candidates, V, F, renderer, cache_bytes / 2, &images, level);
      for (size_t k = 0; k < ambients.size(); ++k) {
        tried << (ambients[k] < 0 ? "world " : ", headlight " + FormatShort(ambients[k]) + " ")
              << FormatShort(means[k], 4);
        if (means[k] > best) best = means[k], pair.headlight_ambient = ambients[k];
      }
    };
    try_lights({-1.0, 0.5});
    if (pair.headlight_ambient >= 0) try_lights({0.75, 0.25});
    summary.light = pair.headlight_ambient < 0
                        ? std::string("fixed in the world")
                        : "at the camera, ambient share " + FormatShort(pair.headlight_ambient);
    summary.light += " (auto: the input's mean similarity at pyramid level " +
                     std::to_string(level) + ", " + tried.str() + "; " +
                     FormatShort(ElapsedSeconds() - t0) + " s)";
    MR_LOG(INFO) << "Light: " << summary.light;
  } else {
    summary.light = options.light == "world"
                        ? "fixed in the world (given)"
                        : "at the camera, ambient share " + FormatShort(options.light_ambient) +
                              " (given)";
  }

  // The schedule: how many pyramid levels, from the input's similarity at
  // each level (ChooseNumLevels), unless num_levels is given.
  int num_levels = options.num_levels;
  std::unique_ptr<BackgroundRemesh> full_resolution_remesh;
  if (num_levels == 0) {
    full_resolution_remesh = std::make_unique<BackgroundRemesh>(LevelViews(cameras, 0), options,
                                                                max_faces, V, F);
    const Schedule schedule = ChooseNumLevels(source, pairs, options, V, F, renderer,
                                              cache_bytes / 2, &images);
    num_levels = schedule.num_levels;
    summary.schedule = schedule.reason;
    MR_LOG(INFO) << "Schedule: " << schedule.reason;
  }
  // A coarse level whose remeshed surface would have fewer than this many
  // faces cannot stand for the shape, and the finer levels do not bring it
  // back (num_levels 6 on a 160x120 synthetic workspace took its 130k-face
  // ground truth to 4 faces at 5x4 pixels and ended at similarity 0.29 from
  // 0.90; without levels 5-3, at 0.82): such levels are skipped.
  constexpr int kMinLevelFaces = 500;
  while (num_levels > 1) {
    const int faces = RemeshedFaceCount(LevelViews(cameras, num_levels - 1), V, F,
                                        options.target_edge_px, max_faces);
    if (faces >= kMinLevelFaces) break;
    MR_LOG(INFO) << "Level " << num_levels - 1 << " skipped: its mesh would have " << faces
                 << " faces, fewer than " << kMinLevelFaces;
    summary.schedule += std::string(summary.schedule.empty() ? "" : "; ") + "level " +
                        std::to_string(num_levels - 1) + " skipped (" + std::to_string(faces) +
                        " faces < " + std::to_string(kMinLevelFaces) + ")";
    --num_levels;
  }
  if (num_levels > 1) full_resolution_remesh.reset();  // cancelled: coarse to fine
  // With one level the first iteration measures the same thing (plain ZNCC
  // of all pairs at full resolution; κ does not enter m) on the input
  // remeshed to the working resolution, so it is taken from there.
  const bool initial_from_first_iteration = num_levels == 1 && options.iterations_per_level > 0;
  if (!initial_from_first_iteration) {
    summary.initial_similarity = FullResolutionSimilarity(
        cameras, pairs, similarity, pair, V, F, renderer, cache_bytes / 2, &images);
    MR_LOG(INFO) << "Initial mean similarity (ZNCC, full resolution): "
                 << summary.initial_similarity;
  }
  const int total_iterations = num_levels * options.iterations_per_level;
  int global_iteration = 0;
  bool guard_verified_clean = false;  // the last iteration's guard found no intersection
  // The final pass over (V, F) as it is now; measured on the finest level's
  // mean, or after the levels.
  std::unique_ptr<FinalPass> final_pass;
  double final_pass_seconds = 0;
  auto measure_final_pass = [&]() {
    const double t0 = ElapsedSeconds();
    final_pass = std::make_unique<FinalPass>(source, cameras, V, F);
    final_pass->similarity = FullResolutionSimilarity(
        cameras, pairs, similarity, pair, V, F, renderer, cache_bytes / 2, &images,
        [&](int i, const RenderBuffers& render) { final_pass->colors.Add(i, render); });
    final_pass_seconds += ElapsedSeconds() - t0;
  };
  summary.setup_seconds = ElapsedSeconds() - t_start;
  for (int level = num_levels - 1; level >= 0; --level) {
    std::vector<PinholeView> views = LevelViews(cameras, level);
    if (full_resolution_remesh) {
      full_resolution_remesh->Take(&V, &F);
      full_resolution_remesh.reset();
    } else {
      RemeshForLevel(views, options, max_faces, &V, &F);
    }
    double level_seconds = 0;  // of this level's iterations so far, for the ETA
    guard_verified_clean = false;
    // The iterations start from a mesh without self-intersections (what the
    // repair cannot remove is tolerated, and only new ones are undone).
    std::unique_ptr<SelfIntersectionGuard> guard;
    if (options.prevent_self_intersections) {
      guard = std::make_unique<SelfIntersectionGuard>(V, F);
      if (!guard->initial_pairs().empty()) {
        MR_LOG(INFO) << "Level " << level << " starts with " << guard->initial_pairs().size()
                     << " intersecting face pairs; repairing";
        RemoveSelfIntersections(&V, &F);
        guard = std::make_unique<SelfIntersectionGuard>(V, F);
      }
    }
    RenderCache renders(renderer, views, cache_bytes / 2);
    MR_LOG(INFO) << "Level " << level << ": " << views[0].width << "x" << views[0].height
                 << " images, " << F.rows() << " faces";
    // The finest level's camera rounds: before these iterations.
    const bool refines_cameras = level == 0 && options.refine_cameras != "none";
    const std::vector<int> camera_rounds =
        refines_cameras
            ? CameraRoundIterations(options.iterations_per_level, options.camera_rounds)
            : std::vector<int>();
    if (refines_cameras) {
      std::ostringstream at;
      for (size_t k = 0; k < camera_rounds.size(); ++k) {
        at << (k ? ", " : "") << camera_rounds[k];
      }
      MR_LOG(INFO) << "Cameras refined (" << options.refine_cameras << ") after iteration"
                   << (camera_rounds.size() == 1 ? " " : "s ")
                   << (camera_rounds.empty() ? "(none)" : at.str()) << " of "
                   << options.iterations_per_level
                   << (static_cast<int>(camera_rounds.size()) < options.camera_rounds
                           ? "; later rounds would fall past the last"
                           : "");
    }
    // Only at the finest level: at the coarser ones the images hold less and
    // the edges are longer, and over the coarse levels of a far-off start the
    // border retracted into the observed surface (cheburashka-grey-nomask
    // with --Refine.num_levels 3: completeness 20.9 points below the input).
    const VertexBand border_band =
        level == 0 ? OpenBorderBand(F, static_cast<int>(V.rows()), options.open_border_rings)
                   : VertexBand();
    if (border_band.num_border > 0) {
      MR_LOG(INFO) << "Open border: " << border_band.num_border << " vertices; "
                   << border_band.vertices.size() << " within " << options.open_border_rings
                   << " rings take a membrane step where the images see and contradict them"
                   << " (Refine.open_border_rings)";
    }
    const bool use_silhouettes = options.silhouette_weight > 0 && source.HasMasks();
    // The finest level's iterates from average_from on are summed. After a
    // camera round the surface settles again before any iterate is averaged
    // (one round at iteration 7 of 14 followed by the mean of the 7 iterates
    // after it: rocker-head-noise 1.45x the exact-camera run, 1.28x with 10
    // iterations and no mean).
    const int average_from =
        level == 0 ? FirstAveragedIteration(options.iterations_per_level,
                                            options.average_last_iterates, camera_rounds)
                   : options.iterations_per_level;
    const bool averages = options.iterations_per_level - average_from >= 2;
    // Whether iteration k of the level uses all pairs. The averaged
    // iterations take alternate halves: the mean sees every pair as often,
    // and each half's jitter is its own, so the mean averages more of it
    // (development corpus: better on 13 of 16 cases in each figure, for
    // about a third less data term in those iterations; docs/results.md). Only the similarities
    // of all pairs are compared with each other (min_improvement,
    // best_iterate_giveback).
    // The first iteration always takes all pairs (it measures the start).
    auto uses_all_pairs = [&](int k) {
      if (pair_halves.empty() || k == 0) return true;
      if (averaged_halves && averages && k >= average_from) return false;
      return !(many_views && k < options.iterations_per_level - 2);
    };
    double previous_similarity = 0;
    Eigen::MatrixXd V_last_iterate;  // the mesh whose similarity is previous_similarity
    // The level's similarities so far (reset when the cameras change) and its
    // best iterate, for best_iterate_giveback.
    std::vector<double> level_similarities;
    Eigen::MatrixXd V_best;
    int best_iteration = 0;
    double best_similarity = -std::numeric_limits<double>::infinity();
    Eigen::MatrixXd V_sum;
    int num_summed = 0;
    for (int it = 0; it < options.iterations_per_level; ++it, ++global_iteration) {
      const double t_iter = ElapsedSeconds();
      const long renders_before = renders.num_renders();
      RefineIteration record;
      record.level = level;
      record.iteration = it;
      record.faces = static_cast<int>(F.rows());
      record.kappa = options.similarity == "dcv"
                         ? options.kappa * (global_iteration + 1) / std::max(1, total_iterations)
                         : 0.0;
      similarity.kappa = record.kappa;

      // The cameras are refined only within the finest level, after 1, 3,
      // 6, ... of its iterations (camera_rounds), against the surface they
      // made: never against the input mesh or a coarse level's surface,
      // whose errors the images cannot tell from the cameras'. At the
      // coarser levels' starts too (the schedule until 5 December 2026),
      // COLMAP's cameras of templeSparseRing, 0.21 px from their tracks, were
      // pulled off and the held-out photo-consistency fell from 0.625 to
      // 0.443 (0.612 finest only; docs/camera_refinement.md).
      if (std::find(camera_rounds.begin(), camera_rounds.end(), it) != camera_rounds.end()) {
        const double t_cameras = ElapsedSeconds();
        RefineCamerasAtLevel(options, pairs, V, F, level, camera_of_view, renderer,
                             cache_bytes / 2, full_views, &images, &views, &cameras, &summary);
        record.camera_seconds = ElapsedSeconds() - t_cameras;
        level_similarities.clear();  // measured through other cameras
        best_similarity = -std::numeric_limits<double>::infinity();
      }
      const Eigen::MatrixXd V_before = V;
      renderer->SetMesh(V, F);
      renders.Invalidate();
      MeshGeometry geometry{&V, &F, FaceNormals(V, F)};
      // The silhouette term of each view is gathered while the data term
      // holds its render (a second pass re-rendered what the cache had
      // dropped: 16 of 40 views of 1280x960), the views that are in no pair
      // afterwards.
      Eigen::MatrixXd silhouette = Eigen::MatrixXd::Zero(V.rows(), 3);
      Eigen::VectorXd silhouette_count = Eigen::VectorXd::Zero(V.rows());
      std::vector<char> silhouette_done(views.size(), 0);
      double silhouette_seconds = 0;
      const Eigen::MatrixXd N = use_silhouettes ? VertexNormals(V, F) : Eigen::MatrixXd();
      auto add_silhouette = [&](int i, const RenderBuffers& render) {
        if (silhouette_done[i]) return;
        const double t0 = ElapsedSeconds();
        silhouette_done[i] = 1;
        const cv::Mat mask = images.Mask(i, level);
        if (!mask.empty()) {
          AccumulateSilhouetteTerm(V, F, N, views[i], render, mask, 3.0 * options.max_step_px,
                                   options.hull_margin_px, &silhouette, &silhouette_count);
        }
        silhouette_seconds += ElapsedSeconds() - t0;
      };
      std::function<void(int, const RenderBuffers&)> visit;
      if (use_silhouettes) visit = add_silhouette;
      const bool all_pairs = uses_all_pairs(it);
      const auto& iteration_pairs = all_pairs ? pairs : pair_halves[(it - 1) % 2];
      record.num_pairs = static_cast<int>(iteration_pairs.size());
      const DataTerm term = ComputeDataTerm(geometry, views, iteration_pairs, level, similarity,
                                            pair, &renders, &images,
                                            /*with_gradient=*/true, visit);
      record.data_seconds =
          ElapsedSeconds() - t_iter - record.camera_seconds - silhouette_seconds;
      record.mean_similarity = term.MeanSimilarity();
      if (initial_from_first_iteration && global_iteration == 0) {
        summary.initial_similarity = record.mean_similarity;
        MR_LOG(INFO) << "Initial mean similarity (ZNCC, full resolution, input remeshed to "
                     << F.rows() << " faces): " << summary.initial_similarity;
      }
      if (term.valid_pixels == 0) {
        MR_THROW_INPUT << "no pixel of any view pair sees a common surface point: the mesh is "
                          "not visible in overlapping views";
      }
      // The level has converged when the last step raised the similarity by
      // less than min_improvement; a step that lowered it is taken back.
      if (it >= 1 && options.min_improvement > 0 && all_pairs && uses_all_pairs(it - 1) &&
          record.mean_similarity - previous_similarity < options.min_improvement) {
        const bool worse = record.mean_similarity < previous_similarity;
        if (worse) V = V_last_iterate;
        MR_LOG(INFO) << "Level " << level << " converged after " << it << " iterations (similarity "
                     << previous_similarity << " -> " << record.mean_similarity << ", below +"
                     << options.min_improvement
                     << (worse ? "; the last step lowered it and is taken back" : "") << ")";
        if (worse) ++summary.steps_taken_back;
        num_summed = 0;  // converged: the level ends on its last iterate
        global_iteration += options.iterations_per_level - it;
        break;
      }
      previous_similarity = record.mean_similarity;
      if (options.min_improvement > 0) V_last_iterate = V;
      if (all_pairs) {
        level_similarities.push_back(record.mean_similarity);
        if (record.mean_similarity > best_similarity) {
          best_similarity = record.mean_similarity;
          V_best = V;
          best_iteration = it;
        }
      }

      // Gauss-Newton step down the reprojection error, clamped to max_step_px
      // footprints.
      // A vertex whose images hold less information than the rounding noise
      // of a constant image holds none. A textureless region scaled by a
      // non-dyadic factor (max_image_size) has a curvature of ~1e-7 per pixel
      // where an exactly constant one has 0; that noise pulled the median,
      // and so mu, down with it, and -G / (H + mu) sent a third of fandisk's
      // vertices to the step limit at 1600 px (normal error 28.8 deg, 9.4 at
      // 1500). The information per pixel, H fp^2 / w (fp the footprint, w the
      // coverage), is dimensionless: one grey level per pixel against the
      // similarity's variance floor gives about 0.16.
      constexpr double kMinInformationPerPixel = 1e-6;
      Eigen::VectorXd information = Eigen::VectorXd::Zero(V.rows());
      Eigen::VectorXd footprint = Eigen::VectorXd::Zero(V.rows());  // mean, of a pixel
      for (int v = 0; v < V.rows(); ++v) {
        if (!(term.weight(v) > 0)) continue;
        footprint(v) = term.footprint(v) / term.weight(v);
        const double per_pixel = term.curvature(v) * footprint(v) * footprint(v) / term.weight(v);
        if (per_pixel >= kMinInformationPerPixel) information(v) = term.curvature(v);
      }
      const double mu = options.damping * MedianPositive(information);
      Eigen::MatrixXd step = Eigen::MatrixXd::Zero(V.rows(), 3);
      for (int v = 0; v < V.rows(); ++v) {
        if (information(v) > 0) {
          step.row(v) = -options.step * term.gradient.row(v) / (term.curvature(v) + mu);
        }
      }
      double step_sum = 0, step_max = 0;
      long num_moved = 0;
      for (int v = 0; v < V.rows(); ++v) {
        const double norm = step.row(v).norm();
        if (!(norm > 0)) continue;
        const double limit = options.max_step_px * footprint(v);
        if (norm > limit) step.row(v) *= limit / norm;
        step_sum += std::min(norm, limit) / footprint(v);
        step_max = std::max(step_max, std::min(norm, limit) / footprint(v));
        ++num_moved;
      }
      record.mean_step_px = num_moved > 0 ? step_sum / num_moved : 0;
      record.max_step_px = step_max;

      const double t_silhouette = ElapsedSeconds();
      if (use_silhouettes) {
        for (const int i : renders.CachedFirst()) {
          if (!silhouette_done[i]) add_silhouette(i, *renders.Get(i));
        }
        for (int v = 0; v < V.rows(); ++v) {
          if (silhouette_count(v) > 0) {
            step.row(v) += options.step * options.silhouette_weight * silhouette.row(v) /
                           silhouette_count(v);
          }
        }
      }

      const double t_denoise = ElapsedSeconds();
      record.silhouette_seconds = silhouette_seconds + (t_denoise - t_silhouette);
      const Eigen::MatrixXd V_half = V + step;
      if (options.regularizer != "none") {
        const DenoiseResult denoised =
            Denoise(V_half, F, denoise, options.noise_from_step ? &V : nullptr);
        record.regularizer_report = denoised.BriefReport();
        V = denoised.V;
      } else {
        V = V_half;
      }
      if (!border_band.vertices.empty()) {
        record.border_similarity_bound = ContradictedSimilarity(term.similarity, term.weight);
        const Eigen::VectorXd unheld =
            UnheldBandVertices(border_band, term, record.border_similarity_bound);
        record.border_vertices_moved = static_cast<int>(unheld.sum());
        MembraneStep(border_band, kOpenBorderStep, &V, &unheld);
      }
      const double t_cleanup = ElapsedSeconds();
      record.denoise_seconds = t_cleanup - t_denoise;
      summary.flipped_faces_fixed += FixFlippedFaces(V_before, F, &V).initial_flipped;
      if (guard) {
        const UndoSelfIntersectionsSummary undone = guard->Undo(V_before, &V);
        summary.self_intersections_undone += undone.initial_pairs;
        summary.vertices_reset += undone.reset_vertices;
        record.vertices_reset = undone.reset_vertices;
        if (undone.initial_pairs > 0) {
          MR_LOG(INFO) << "UndoSelfIntersections: " << undone.BriefReport();
        }
      }
      guard_verified_clean = guard && guard->initial_pairs().empty();
      if (it >= average_from) {
        if (num_summed == 0) V_sum = Eigen::MatrixXd::Zero(V.rows(), 3);
        V_sum += V;
        ++num_summed;
      }

      record.cleanup_seconds = ElapsedSeconds() - t_cleanup;
      record.seconds = ElapsedSeconds() - t_iter;
      // ETA: this level's mean iteration for what is left of it; each finer
      // level has 4x the pixels and, at the same edge length in pixels, about
      // 4x the faces.
      level_seconds += record.seconds;
      const double mean_seconds = level_seconds / (it + 1);
      double eta = (options.iterations_per_level - it - 1) * mean_seconds;
      for (int finer = level - 1; finer >= 0; --finer) {
        eta += options.iterations_per_level * mean_seconds * std::pow(4.0, level - finer);
      }
      MR_LOG(INFO) << "Level " << level << " iteration " << it + 1 << "/"
                   << options.iterations_per_level << ": similarity " << record.mean_similarity
                   << (record.num_pairs < static_cast<int>(pairs.size())
                           ? " (" + std::to_string(record.num_pairs) + " of " +
                                 std::to_string(pairs.size()) + " pairs)"
                           : std::string())
                   << ", step " << record.mean_step_px << " px (max " << record.max_step_px
                   << "), " << record.regularizer_report
                   << (border_band.vertices.empty()
                           ? std::string()
                           : "; membrane on " + std::to_string(record.border_vertices_moved) +
                                 " of " + std::to_string(border_band.vertices.size()) +
                                 " band vertices (similarity below " +
                                 FormatShort(record.border_similarity_bound, 2) + ")")
                   << "; " << record.seconds
                   << " s (data " << record.data_seconds << ", silhouette "
                   << record.silhouette_seconds << ", denoise " << record.denoise_seconds
                   << ", clean-up " << record.cleanup_seconds
                   << (record.camera_seconds > 0
                           ? ", cameras " + FormatShort(record.camera_seconds, 3)
                           : std::string())
                   << "; " << renders.num_renders() - renders_before << " renders); ETA "
                   << FormatSeconds(eta);
      summary.iterations.push_back(record);
    }
    if (num_summed > 1) {
      // The mean of iterates without flipped faces may still flip one where
      // they disagree, or bring two sheets together: both are undone as
      // after any iterate, toward the last iterate. (The whole-mesh repair at
      // the end took 1.0 s for the example's 6 intersecting pairs.)
      const Eigen::MatrixXd V_last = V;
      V = V_sum / num_summed;
      summary.flipped_faces_fixed += FixFlippedFaces(V_last, F, &V).initial_flipped;
      if (guard) {
        const UndoSelfIntersectionsSummary undone = guard->Undo(V_last, &V);
        summary.self_intersections_undone += undone.initial_pairs;
        summary.vertices_reset += undone.reset_vertices;
        if (undone.initial_pairs > 0) {
          MR_LOG(INFO) << "UndoSelfIntersections (the mean): " << undone.BriefReport();
        }
      }
      guard_verified_clean = guard && guard->initial_pairs().empty();
      summary.iterates_averaged = num_summed;
      // The mean's own similarity over all pairs ends the level's sequence
      // for the best-iterate rule (the averaged iterations measured halves).
      // It is the final pass's, whose renders also give the vertex colours;
      // both stand unless the mesh changes again.
      renders.Invalidate();  // of the last iterate; the final pass renders within the same budget
      measure_final_pass();
      level_similarities.push_back(final_pass->similarity);
      MR_LOG(INFO) << "Level " << level << " ends on the mean of its last " << num_summed
                   << " iterates (Refine.average_last_iterates), similarity "
                   << final_pass->similarity;
    }
    // A level whose similarity fell well below its best while the
    // self-intersection guard was resetting much of the mesh ends on that
    // best: the guard, not the images, drove it (an open shell wrapped by
    // Poisson in a closed blob: docs/results.md).
    const int best = BestIterateToKeep(level_similarities, options.best_iterate_giveback);
    if (best >= 0) {
      std::vector<int> resets_after_best;
      for (const auto& r : summary.iterations) {
        if (r.level == level && r.iteration >= best_iteration) {
          resets_after_best.push_back(r.vertices_reset);
        }
      }
      const double reset_fraction =
          MeanResetFraction(resets_after_best, static_cast<int>(V.rows()));
      if (!(reset_fraction > kGuardOverrideFraction)) {
        MR_LOG(INFO) << "Level " << level << ": the similarity fell from " << best_similarity
                     << " (after " << best_iteration << " iterations) to "
                     << level_similarities.back()
                     << ", but the self-intersection guard reset only " << 100 * reset_fraction
                     << " % of the vertices per iteration after it ("
                     << 100 * kGuardOverrideFraction
                     << " % marks a level that the guard drove): the last iterate is kept";
      } else {
        const int dropped = static_cast<int>(resets_after_best.size());
        MR_LOG(INFO) << "Level " << level << " ends on the mesh after " << best_iteration
                     << " iterations: the similarity fell from " << best_similarity << " to "
                     << level_similarities.back() << ", more than "
                     << options.best_iterate_giveback << " of the gain "
                     << best_similarity - level_similarities.front()
                     << " up to it, while the self-intersection guard reset "
                     << 100 * reset_fraction << " % of the vertices per iteration (" << dropped
                     << " iterations dropped)";
        V = V_best;
        final_pass.reset();
        guard_verified_clean = false;
        ++summary.levels_ended_on_best;
        summary.iterations_dropped += dropped;
      }
    }
  }

  const double t_final = ElapsedSeconds();
  // Everything of the levels but their iterations: remeshing, guards, caches.
  // (A final pass made on the finest level's mean counts as final.)
  const double early_final_seconds = final_pass_seconds;
  summary.remesh_seconds = t_final - t_start - summary.setup_seconds - early_final_seconds;
  for (const auto& it : summary.iterations) summary.remesh_seconds -= it.seconds;
  // Leave no self-intersection behind (the flow can fold thin parts). When
  // the last iteration's guard already checked the mesh and found none, that
  // check stands.
  const SelfIntersectionReport intersections =
      guard_verified_clean ? SelfIntersectionReport() : CountSelfIntersections(V, F);
  summary.self_intersections = static_cast<int>(intersections.intersecting_pairs);
  if (intersections.intersecting_pairs > 0) {
    const RemoveSelfIntersectionsSummary repair = RemoveSelfIntersections(&V, &F);
    MR_LOG(INFO) << "Self-intersections: " << repair.BriefReport();
    summary.self_intersections = static_cast<int>(repair.final_pairs);
    final_pass.reset();
  }
  if (!final_pass) measure_final_pass();
  summary.final_similarity = final_pass->similarity;
  const SurfaceDisplacement moved = MeasureSurfaceDisplacement(V, V_input, F_input);
  summary.mean_displacement = moved.mean;
  summary.max_displacement = moved.max;
  mesh->V = V;
  mesh->F = F;
  mesh->N.resize(0, 3);
  mesh->values.resize(0);
  final_pass->colors.Colors(renderer, &mesh->C);
  for (int i = 0; i < options.output_subdivisions; ++i) {
    SubdivideResult(options.denoise.normal_sigma,
                    options.prevent_self_intersections && summary.self_intersections == 0, mesh);
  }
  if (options.refine_cameras != "none") {
    // Back to the resolution of the input source (max_image_size scaled it).
    for (int i = 0; i < source.NumViews(); ++i) {
      const PinholeView& input = input_source.View(i);
      summary.cameras.push_back(cameras[i].Resized(input.width, input.height));
    }
  }
  summary.final_faces = mesh->NumFaces();
  summary.final_vertices = mesh->NumVertices();
  summary.termination = "FINISHED";
  summary.final_seconds = ElapsedSeconds() - t_final + early_final_seconds;
  if (blackened) {
    const std::string backdrop = blackened->Report();
    if (!backdrop.empty()) {
      MR_LOG(INFO) << "Backdrop: " << backdrop;
      summary.masks += (summary.masks.empty() ? "" : "; ") + backdrop;
    }
  }
  summary.seconds = ElapsedSeconds() - t_start;
  return summary;
}

void RegisterRefineOptions(OptionManager* o, RefineOptions* r) {
  o->Add("Refine.num_levels", &r->num_levels,
         "image pyramid levels, coarse to fine (1..6; 0: chosen from the input's misalignment)");
  o->Add("Refine.schedule_misalignment_px", &r->schedule_misalignment_px,
         "num_levels 0: coarse levels until the input's misalignment is below this (pixels)");
  o->Add("Refine.min_level_image_px", &r->min_level_image_px,
         "num_levels 0: shortest image side a coarse level may have (pixels)");
  o->Add("Refine.min_improvement", &r->min_improvement,
         "a level ends when the mean ZNCC rose by less than this in one iteration (0: never)");
  o->Add("Refine.best_iterate_giveback", &r->best_iterate_giveback,
         "a level ends on its best iterate (mean similarity) when the last has fallen from it by "
         "more than this fraction of the level's gain up to it and the self-intersection guard "
         "reset over 10 % of the vertices per iteration after it, [0, 1]");
  o->Add("Refine.pair_halves_min_views", &r->pair_halves_min_views,
         "from this many views on, a level's iterations but its first and last two use "
         "alternate halves of the view pairs (0: all pairs always)");
  o->Add("Refine.iterations_per_level", &r->iterations_per_level,
         "gradient + denoising iterations per level (>= 0)");
  o->Add("Refine.average_last_iterates", &r->average_last_iterates,
         "the finest level ends on the mean of its last this many iterates, which averages out "
         "the flow's jitter (>= 1; 1: on the last)");
  o->Add("Refine.average_pair_halves", &r->average_pair_halves,
         "the averaged iterations take alternate halves of the view pairs (each covering every "
         "view), which the mean sees equally: less jitter for less time");
  o->Add("Refine.max_image_size", &r->max_image_size,
         "longest image side in pixels at which images are compared; larger images and their "
         "cameras are scaled down (-1: no limit)");
  o->Add("Refine.target_edge_px", &r->target_edge_px,
         "target triangle edge length in pixels at each level (> 0)");
  o->Add("Refine.max_faces", &r->max_faces, "face budget (0: 2x input faces, at least 100k)");
  o->Add("Refine.output_subdivisions", &r->output_subdivisions,
         "the result's faces are split in four this many times, the new vertices on the "
         "point-normal cubic curves of its edges (0..2; 0: the refined triangles as they are)");
  o->Add("Refine.step", &r->step, "fraction of the Gauss-Newton step per iteration (0, 1]");
  o->Add("Refine.max_step_px", &r->max_step_px,
         "largest vertex motion per iteration, in pixel footprints (> 0)");
  o->Add("Refine.damping", &r->damping, "Levenberg damping relative to the median curvature");
  o->Add("Refine.similarity", &r->similarity, "dcv (detail-preserving) or zncc");
  o->Add("Refine.interpolation", &r->pair.interpolation,
         "how the other view's image is sampled at the warped points: cubic or bilinear");
  o->Add("Refine.match_resolution", &r->pair.match_resolution,
         "compare each pixel at the coarser of the two views' resolutions on the surface (the "
         "sharper image blurred by the difference of their pixel footprints)");
  o->Add("Refine.light", &r->light,
         "where the light is: world (fixed), headlight (at the camera: flash, ring light) or "
         "auto (chosen by the input's similarity)");
  o->Add("Refine.light_ambient", &r->light_ambient,
         "light headlight: share of ambient light, [0, 1]");
  o->Add("Refine.color", &r->color,
         "images compared on: luminance, or principal (colour direction of most texture)");
  o->Add("Refine.kappa", &r->kappa, "final weight of the detail-preserving term (>= 0)");
  o->Add("Refine.regularizer", &r->regularizer,
         "bilateral_normal (normals filtered, vertices fitted), lp (content-aware L_p), laplacian "
         "or none");
  o->Add("Refine.refine_cameras", &r->refine_cameras,
         "photometric camera refinement within the finest level: none, poses, poses_intrinsics");
  o->Add("Refine.camera_rounds", &r->camera_rounds,
         "with refine_cameras: refinements within the finest level, after 1, 3, 6, 10, ... of its "
         "iterations (>= 1; rounds past its last iteration are not made)");
  o->Add("CameraRefinement.max_samples_per_pair", &r->camera_refinement.max_samples_per_pair,
         "pixels sampled per ordered view pair (>= 1)");
  o->Add("CameraRefinement.max_problem_mb", &r->camera_refinement.max_problem_mb,
         "memory for the least-squares problem (MB, >= 1): where max_samples_per_pair for every "
         "ordered pair would take more, each pair gets fewer (counting 1,150 bytes a sample and "
         "64 a mesh face)");
  o->Add("CameraRefinement.intensity_sigma", &r->camera_refinement.intensity_sigma,
         "1-sigma of an intensity residual, images in [0, 1]: the images' weight against the priors");
  o->Add("CameraRefinement.huber_delta", &r->camera_refinement.huber_delta,
         "Huber threshold on intensity residuals (> 0)");
  o->Add("CameraRefinement.prior_rotation_deg", &r->camera_refinement.prior_rotation_deg,
         "1-sigma of the prior keeping each rotation near its start (degrees)");
  o->Add("CameraRefinement.prior_center_px", &r->camera_refinement.prior_center_px,
         "1-sigma of the prior on each camera centre (pixel footprints)");
  o->Add("CameraRefinement.prior_focal_percent", &r->camera_refinement.prior_focal_percent,
         "1-sigma of the prior on fx, fy (percent; poses_intrinsics)");
  o->Add("CameraRefinement.surface_sigma_px", &r->camera_refinement.surface_sigma_px,
         "1-sigma of the prior on each face plane's offset (pixel footprints); 0 holds the mesh "
         "fixed");
  o->Add("CameraRefinement.max_iterations", &r->camera_refinement.max_iterations,
         "Ceres iterations (>= 1)");
  o->Add("CameraRefinement.function_tolerance", &r->camera_refinement.function_tolerance,
         "Ceres stops when an iteration lowers the cost by less than this fraction");
  o->Add("CameraRefinement.datum_sigma_px", &r->camera_refinement.datum_sigma_px,
         "1-sigma of the camera set's mean shift, rotation and scale from the input cameras "
         "(pixels); 0 leaves them to the per-view priors");
  o->Add("Refine.noise_from_step", &r->noise_from_step,
         "lp proximal step: noise estimated from what the gradient step added, not the surface");
  o->Add("Refine.silhouette_weight", &r->silhouette_weight,
         "weight of the silhouette term when masks exist (>= 0)");
  o->Add("Refine.hull_margin_px", &r->hull_margin_px,
         "with the silhouette term: pull back every vertex that projects more than this many "
         "pixels outside a mask (the visual hull); < 0: only contour vertices");
  std::ostringstream contradicted;
  contradicted << "mean similarity below " << kOpenBorderMaxSimilarity << ", and "
               << kOpenBorderOutlierSigmas << " robust deviations below the mesh's median";
  o->Add("Refine.open_border_rings", &r->open_border_rings,
         "at the finest level, vertices within this many edge rings of an open border that the "
         "images see and contradict (" + contradicted.str() + ") take a membrane step each "
         "iteration, which pulls in the skirts trimmed Poisson meshes end in (1: the border "
         "only; 0: off)");
  o->Add("Refine.masks_from_background", &r->masks_from_background,
         "without masks, make them from a uniform background where they agree with the input "
         "mesh (for the silhouette term)");
  o->Add("Refine.black_outside_masks", &r->black_outside_masks,
         "with given masks, compare the images as if shot against black: in every view whose "
         "backdrop is not dark already, every pixel outside the mask set to 0");
  o->Add("Refine.align_masks", &r->align_masks,
         "with given masks, move their outlines onto the images' edges when these lie clearly "
         "off them (masks grown for a visual hull)");
  o->Add("MaskOutline.min_offset_px", &r->mask_outline.min_offset_px,
         "the masks are moved when the images' edges lie at least this far from their outlines "
         "(pixels)");
  o->Add("BackgroundMask.min_agreement", &r->background_mask.min_agreement,
         "a view's background mask is used when its intersection over union with the input "
         "mesh's rendered coverage, both with their holes filled, is at least this");
  o->Add("BackgroundMask.min_clear_outline", &r->background_mask.min_clear_outline,
         "... and when at least this share of its outline is clearly unlike the background "
         "(the object beside it differs by 3 tolerances on average)");
  o->Add("BackgroundMask.max_offset", &r->background_mask.max_offset,
         "a background mask moves the input mesh's outline by at most this share of the "
         "image's longest side");
  o->Add("BackgroundMask.min_border_share", &r->background_mask.min_border_share,
         "share of the image border that must have the background colour");
  o->Add("Refine.prevent_self_intersections", &r->prevent_self_intersections,
         "undo, every iteration, the moves that make faces intersect");
  o->Add("Refine.cache_mb", &r->cache_mb, "memory budget for cached images and renders (MB)");
  o->Add("ViewSelection.num_neighbors", &r->view_selection.num_neighbors,
         "neighbour views per view (1..16)");
  o->Add("ViewSelection.ideal_angle_deg", &r->view_selection.ideal_angle_deg,
         "preferred triangulation angle (degrees)");
  o->Add("Similarity.sigma", &r->similarity_options.sigma,
         "Gaussian window sigma in pixels");
  o->Add("Similarity.epsilon", &r->similarity_options.epsilon,
         "variance regulariser (intensity^2, images in [0,1])");
  RegisterDenoiseOptions(o, &r->denoise, "Denoise");
}

double PhotoConsistency(const ViewSource& source, const std::vector<int>& eval_views,
                        const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Renderer* renderer,
                        int num_neighbors) {
  const std::vector<PinholeView> views = source.Views();
  ViewSelectionOptions selection;
  selection.num_neighbors = std::min(16, 2 * num_neighbors);
  const auto neighbors = SelectNeighbors(views, V, VertexNormals(V, F), selection);
  ImageCache images(source, size_t{512} << 20);
  RenderCache renders(renderer, views, size_t{512} << 20);
  renderer->SetMesh(V, F);
  MeshGeometry geometry{&V, &F, FaceNormals(V, F)};
  SimilarityOptions zncc;
  zncc.method = "zncc";
  // The measurement stays the one the figures in docs/ were taken with,
  // whatever the refiner's pair-term defaults.
  PairTermOptions pair;
  pair.interpolation = "bilinear";
  pair.match_resolution = false;
  DataTermAccumulator accumulator(static_cast<int>(V.rows()));
  const std::set<int> evaluated(eval_views.begin(), eval_views.end());
  for (int i : eval_views) {
    for (int j : neighbors.at(i)) {
      if (evaluated.count(j)) continue;  // compare only against views that were used
      accumulator.AddPair(geometry, views[i], *renders.Get(i), images.Gray(i, 0), views[j],
                          *renders.Get(j), images.Gray(j, 0), zncc, pair);
    }
  }
  return accumulator.Sum().MeanSimilarity();
}

}  // namespace mr
