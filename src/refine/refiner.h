#pragma once

// DCV refinement (Li et al., TIP 2016): a proximal-gradient loop that
// alternates a reprojection-error gradient step (detail-preserving
// similarity) and a content-aware L_p denoising step, coarse to fine.

#include <algorithm>
#include <string>
#include <vector>

#include "colmap_io/ply.h"
#include "refine/background_mask.h"
#include "refine/camera_refinement.h"
#include "refine/mask_outline.h"
#include "denoise/denoiser.h"
#include "refine/photometric.h"
#include "refine/similarity.h"
#include "refine/view_selection.h"
#include "refine/view_source.h"

namespace mr {

class OptionManager;
class Renderer;

// The denoiser configuration of the proximal step: the content-aware L_p
// method with one estimation round and a faster penalty continuation (x4).
// One gradient step adds little noise, so this removes it at a third of the
// cost of the standalone defaults, with the same accuracy on the test scene.
// lambda_scale 10: the estimated lambda is for removing the noise of a mesh
// once; in the loop the jitter of every gradient step must be removed too.
// Chosen on the in-memory development scene (refine_lab: normal error 8.0 ->
// 5.2 deg, accuracy90 0.0276 -> 0.0262 at 320x240; the trend continued to
// x100 there, a smooth scene, so x10 is a conservative choice).
// For the Laplacian baseline (--Refine.regularizer laplacian) the proximal
// step is one first+second order smoothing pass per iteration, the explicit
// form of the proximal operator of a quadratic smoothness energy.
// For the default, bilateral_normal (the two-stage scheme: filter the face
// normals, then fit the vertices to them), 2 normal-filtering passes and 10
// vertex-update passes per iteration, range sigma 0.35 on |n_i - n_j|,
// spatial sigma the mesh's own mean distance between neighbouring face
// centroids: chosen on the 12-workspace development corpus by its worst case
// (docs/results.md). With the silhouette term corrected, 3/15 passes (the
// earlier choice) smoothed fine relief away (beast-contrast accuracy90 0.094
// against 0.085) and 1/5 left creases and shading-only surfaces rough.
// Then one second-order fairing step of weight 0.3 where the filter leaves
// faces unfiltered (fairing_weight): the thin features whose faces differ by
// more than the range sigma, where the normal error's tail was. On the
// 23-workspace corpus (docs/results.md, "Fairing where the filter does not
// reach"), chosen by the worst case: the worst normal error 0.976x -> 0.863x
// the input, the worst accuracy90 1.044x -> 0.812x, 14 cases on the floors
// instead of 13; the closed-surface worst accuracy90 0.630x -> 0.635x.
inline DenoiseOptions ProximalDenoiseOptions() {
  DenoiseOptions options;
  options.max_iterations = 1;
  options.estimate_iterations = 1;
  options.beta_initial = 0.5;
  options.beta_factor = 4.0;
  options.inner_iterations = 1;
  options.lambda_scale = 10.0;
  options.laplacian_iterations = 1;
  options.outer_iterations = 1;
  options.normal_iterations = 2;
  options.vertex_iterations = 10;
  options.normal_sigma = 0.35;
  options.fairing_weight = 0.3;
  return options;
}

struct RefineOptions {
  // Image pyramid levels (1 = full resolution only; 1..6), or 0: chosen
  // from the input (ChooseNumLevels in refiner.cc): from how many pixels the
  // input surface is off the images, measured by optical flow between each
  // image and its prediction through the mesh. A close start (a Poisson
  // mesh) keeps full resolution; a far-off one (a visual hull, a decimated
  // mesh) starts coarse. The choice and its reason are logged.
  int num_levels = 0;
  // num_levels 0: add coarse levels until the input's misalignment, divided
  // by 2 per level, is at most this (full-resolution pixels, > 0).
  double schedule_misalignment_px = 1.5;
  // num_levels 0: coarse levels keep at least this many pixels on the short
  // image side (>= 16).
  int min_level_image_px = 100;
  // Largest number of gradient + denoising iterations at each level (>= 0).
  int iterations_per_level = 14;
  // The finest level ends on the mean of its last this many iterates (>= 1;
  // 1: on the last). Near the fixed point the data step jitters from one
  // iteration to the next (0.05-0.08 px), and the mean averages the jitter
  // out. The first iterations_per_level - average_last_iterates iterations,
  // and as many after a camera round, let the surface settle and are never
  // averaged (FirstAveragedIteration); a level that min_improvement ended early
  // ends on its last iterate. On the development corpus 14 iterations
  // averaged over the last 8 beat 10 iterations on 13 of 15 closed surfaces
  // in both accuracy90 and normal error, and lost 0.4 % on one
  // (docs/results.md).
  int average_last_iterates = 8;
  // The averaged iterations take alternate halves of the view pairs, each
  // half covering every view (GroupsCoverEveryView; all pairs when the split
  // cannot). The mean sees every pair as often, each half's jitter is its
  // own, and those iterations cost about a third less data term. Against
  // all pairs, on the development corpus: better on 13 of 16 cases in
  // accuracy90 and on 13 in normal error, worst closed surface 0.630 / 0.800
  // against 0.638 / 0.806 (docs/results.md).
  bool average_pair_halves = true;
  // A level ends early when the last step raised the mean ZNCC of all pairs
  // by less than this (ZNCC units, >= 0; 0 = always run
  // iterations_per_level); a last step that lowered it is taken back.
  double min_improvement = 0.0;
  // A level ends on its best iterate (the mesh of highest mean similarity)
  // when, by its last iteration, the similarity has fallen from that best by
  // more than this fraction of what the level had gained up to it
  // (BestIterateToKeep; 1: only when it fell below the level's start) and
  // the self-intersection guard reset more than kGuardOverrideFraction of
  // the vertices per iteration after it (MeanResetFraction).
  // Range [0, 1]. On the corpus the flow gave
  // back 0-9 % of its gain on 11 of 12 cases and 53 % on the open shell
  // (beetle-both-sides), where the self-intersection guard overrode the
  // images; the baseline gave back 51 % on fandisk-shading after a dip while
  // its surface kept improving, with the guard resetting 0.2 % of the
  // vertices: the guard condition keeps its last iterate (docs/results.md).
  double best_iterate_giveback = 0.25;
  // From this many views on (0: never), the iterations of each level but
  // its first and its last two take alternate halves of the view pairs
  // (SplitPairsCoveringViews: each half covers every view in two or more
  // pairs), for about half the cost of their data terms. The similarities of
  // those iterations are not compared with the others': min_improvement and
  // best_iterate_giveback see only the all-pair iterations, so the guard
  // against a level that goes wrong is weaker. Forced on the whole corpus
  // (12-40 views) the halves changed accuracy90 by -1.3 % to +4 % on 11 of
  // 12 cases, but the open shell lost its guard (1.19x -> 1.63x the input);
  // 50 views (the low end of real captures) keeps them off the corpus and on
  // where the data term dominates (docs/results.md).
  int pair_halves_min_views = 50;
  // Longest image side, in pixels, at which the images are compared: larger
  // images are scaled down to it, their cameras with them (ResizedViewSource),
  // as COLMAP's PatchMatchStereo.max_image_size; pyramid levels, pixel
  // footprints and target_edge_px are then taken at this working resolution
  // (-1: no limit; else >= 32). 1280 was chosen on corpus cases rendered at
  // 1920x1440 and 2560x1920 (benchmark/refine/run_image_size.sh): accuracy
  // still improves above it, but per second spent 5-10 times less than
  // below it (docs/results.md).
  int max_image_size = 1280;
  // Target triangle edge length in pixels at every level (> 0). The mesh is
  // remeshed to it when a level starts.
  double target_edge_px = 2.5;
  // Upper bound on faces (>= 0; 0: 2x the input's faces, at least 100k).
  int max_faces = 0;
  // The result is subdivided this many times (0..2) before it is returned:
  // each time every face is split in four, the refined vertices kept and a
  // new vertex on every edge's point-normal (PN) cubic curve
  // (SubdividePointNormal, its normals weighted as the bilateral step's,
  // with denoise.normal_sigma, so that creases stay sharp); a new vertex that
  // would make faces intersect or flip goes back to its edge's midpoint.
  // The refinement itself runs on target_edge_px triangles, where each face
  // still covers enough pixels for the data term; the split puts its smooth
  // surface, not the triangles' facets, in the output. Default 1: on the
  // development corpus accuracy90 fell on 21 of 23 cases (up to 3.7 %; the
  // other two within 0.1 %), normal error on 22 (up to 5.1 %), and 13 cases
  // met the floors instead of 11; the example takes 3.5 % longer and its
  // output has 4x the faces (docs/results.md, "Subdividing the result").
  int output_subdivisions = 1;
  // Fraction of the Gauss-Newton step taken per iteration, η (0 < step <= 1).
  double step = 1.0;
  // Largest vertex motion per iteration in pixel footprints of the current
  // level (> 0).
  double max_step_px = 1.0;
  // Levenberg damping of the curvature, relative to its median (>= 0).
  double damping = 0.1;
  // What the images are compared on: "luminance" (the grey image, as
  // COLMAP reads it) or "principal" (the projection of the colour on the
  // direction of most texture, PrincipalTextureColor in view_source.h; for
  // grey images the same up to the grey weights). Applied by mesh_refiner to
  // the workspace's images.
  // "principal" is the default: on the corpus's colour-textured workspaces
  // it lowers accuracy90 on 2 of 3 and the worst of them (docs/results.md).
  std::string color = "principal";
  // Similarity: "dcv" (detail-preserving, the paper's) or "zncc".
  std::string similarity = "dcv";
  // Final κ of the detail-preserving term; κ grows linearly from
  // kappa / (total iterations) to kappa over the run (>= 0).
  double kappa = 0.5;
  // Regulariser of the proximal step: "bilateral_normal" (the default:
  // bilateral filtering of the face normals, then the vertices fitted to
  // them; piecewise smooth, so curved relief and creases stay), "lp" (the
  // paper's content-aware L_p prior on D X: piecewise flat, it rounds fine
  // relief off), "laplacian" (1st+2nd order, the isotropic baseline), or
  // "none".
  std::string regularizer = "bilateral_normal";
  // Photometric refinement of the cameras against the current mesh within
  // the finest level (camera_rounds times, CameraRoundIterations;
  // camera_refinement.h), with priors centred on the input cameras: "none",
  // "poses" (rotation and centre of every view) or "poses_intrinsics" (also
  // fx, fy, cx, cy, shared by the views of one camera). The grey images of
  // all views are held at once for it, at the finest level whose images fit
  // in half of cache_mb (CameraRefinementLevel: the surface's or the next
  // coarser; logged, and not refined if neither fits). Default "none": on
  // the corpus it helps where the cameras are 0.5-2 px off, but with exact
  // cameras it costs 0-4 % of accuracy90 and on COLMAP's own cameras of
  // templeSparseRing it lowers the held-out photo-consistency a little
  // (docs/camera_refinement.md).
  std::string refine_cameras = "none";
  // How often refine_cameras refines them within the finest level: after 1,
  // 3, 6, ... surface iterations (CameraRoundIterations; >= 1). The
  // placement was chosen at 1 px of pose error on four corpus cases. Two
  // rounds cost the example +23-28 % of wall time (issue #11 allows +25 %)
  // and bring the cameras within 0.15 px of the truth at 1 px; three lower
  // the worst accuracy90 at every level of camera error but cost +41 %
  // (docs/camera_refinement.md, thirty-second and thirty-sixth sessions).
  int camera_rounds = 2;
  CameraRefinementOptions camera_refinement;  // its mode follows refine_cameras
  // lp proximal step: estimate the noise to remove from what the gradient
  // step added (D applied to the step) instead of from the whole surface,
  // whose relief would count as noise (Denoise's noise_reference).
  // Measured on the development corpus (docs/results.md): better accuracy90
  // on 9 of 12 workspaces and the same worst case as the whole-surface
  // estimate, which erases fine relief.
  bool noise_from_step = true;
  // Weight of the silhouette (horizon) term when masks exist (>= 0; 0 = off).
  double silhouette_weight = 1.0;
  // With the silhouette term: a vertex that projects more than this many
  // pixels beyond the edge of a view's mask is pulled back toward it (no
  // surface point lies outside the visual hull; AccumulateSilhouetteTerm).
  // Negative: only the contour vertices feel the masks, as before 5 December
  // 2026. On the development corpus (docs/results.md) the pull retracts the
  // flaps that Poisson leaves at an open mesh's border (fandisk-shading
  // accuracy90 0.669x -> 0.593x the input); 0 was chosen over 0.5 and 1.5
  // by the corpus's worst accuracy90 and the floors met.
  double hull_margin_px = 0.0;
  // Without masks: make them from a uniform background, for the views whose
  // mask agrees with the input mesh, within a band around its outline and
  // where other views confirm (background_mask.h). On the corpus refined
  // without its masks plus three stress cases with black unlit sides
  // (docs/results.md), the worst closed case goes from 0.894x / 1.114x the
  // input (accuracy90 / normal error) to 0.801x / 0.981x.
  bool masks_from_background = true;
  // An open border (COLMAP's trimmed Poisson mesh, a cut-off visual hull)
  // ends where the surface was extrapolated: often a skirt flared away from
  // the object, inside every silhouette, that the data term does not
  // correct. With open_border_rings > 0, at the finest level, the vertices
  // within this many edge rings of an open border (1: the border's own) take
  // one step of a membrane flow each iteration (half-way to the mean of their
  // neighbours), which shortens the border and pulls the skirt in, but only
  // where the images see the vertex and contradict it (ContradictedSimilarity
  // below: a mean similarity below 0.5 that is also an outlier of the mesh's
  // own). On by default since 6 December 2026: on the development corpus 3
  // rings took cheburashka-grey-nomask from 0.502x to 0.394x the input's
  // accuracy90 (0.93x the baseline's, 1.19x without), left the worst case of
  // the 23 cases and that of the 18 held-out ones no worse, and cost chamfer
  // distance at most 3.9 % (5.7 % held out); the example's rises 3.5 %
  // (docs/results.md, "Open borders: an outlier of its own surface").
  int open_border_rings = 3;
  BackgroundMaskOptions background_mask;
  // With given masks: measure where the images' edges lie across the masks'
  // outlines and, when they lie clearly off (masks grown for a visual hull,
  // loose or tight segmentations), move the masks onto them for the
  // silhouette term (mask_outline.h). The corpus's exact masks measure
  // within half a pixel and are used as given (docs/results.md).
  bool align_masks = true;
  // With given masks: compare the images of every view whose backdrop is not
  // dark already with the pixels outside its mask set to black
  // (BlackOutsideMasksViewSource). On a grey backdrop, accuracy90 is then
  // within 4 % of the same scene shot on black, against 14 % worse as it is;
  // views on black keep their outline's anti-aliasing (docs/results.md).
  // Masks made from the background are not exact enough for this and are
  // not used so.
  bool black_outside_masks = true;
  MaskOutlineOptions mask_outline;
  // Check every iteration for faces that the step made intersect and move
  // their vertices back (UndoSelfIntersections), so that thin parts cannot
  // fold through each other. Off: only the final repair runs.
  bool prevent_self_intersections = true;
  // Memory budget for cached images and renders, in MB (>= 1). Half of it
  // also bounds the images camera refinement holds at once.
  int cache_mb = 1024;

  ViewSelectionOptions view_selection;
  SimilarityOptions similarity_options;
  PairTermOptions pair;
  // Where the light is, for the comparison of two views: "world" (fixed: the
  // sun, a room's lamps; a surface point looks alike in every view),
  // "headlight" (at the camera: a flash or ring light, with light_ambient the
  // share of ambient light; each view's image is relit to the other's by
  // the angles between the mesh's normals and the two cameras:
  // PairTermOptions::headlight_ambient) or "auto": a fixed light against one
  // at the camera with ambient share 0.5, by the input mesh's mean similarity
  // over all pairs at half resolution, and if the camera's wins, shares 0.75
  // and 0.25 too (logged). Default auto: on the development corpus it found
  // the light of all 16 cases (12 fixed, whose results stay as they were; 4
  // at the camera, whose accuracy90 improved 9-14 %), and it lit the temple
  // of templeSparseRing from the camera (held-out photo-consistency 0.530 ->
  // 0.536); docs/results.md.
  std::string light = "auto";
  double light_ambient = 0.3;  // headlight: ambient share, [0, 1]
  DenoiseOptions denoise = ProximalDenoiseOptions();

  bool Check() const;
  // max_faces, or its default for an input of `input_faces` faces.
  int FaceBudget(int input_faces) const {
    return max_faces > 0 ? max_faces : std::max(100000, 2 * input_faces);
  }
};

struct RefineIteration {
  int level = 0;
  int iteration = 0;
  int faces = 0;
  double mean_similarity = 0;  // before the step, over all valid pair pixels
  int num_pairs = 0;           // view pairs of the data term (pair_halves_min_views)
  int vertices_reset = 0;      // by the self-intersection guard after the step
  int border_vertices_moved = 0;  // by the open border's membrane step
  double border_similarity_bound = 0;  // below which they moved (ContradictedSimilarity)
  double kappa = 0;
  double mean_step_px = 0;     // mean |gradient step| in pixel footprints
  double max_step_px = 0;
  std::string regularizer_report;  // e.g. "p=0.5 theta=... sigma=... lambda=..."
  // Where the iteration's time went: renders and pair terms, the silhouette
  // term, the proximal (denoising) step, the clean-up (flipped faces and
  // self-intersections undone), and the camera refinement made before it
  // (refine_cameras; 0 in the iterations without one).
  double data_seconds = 0, silhouette_seconds = 0, denoise_seconds = 0, cleanup_seconds = 0;
  double camera_seconds = 0;
  double seconds = 0;
};

// The iterations of the finest level (of `iterations`) before which the
// cameras are refined, for camera_rounds = `rounds`: round k comes after
// k (k + 1) / 2 surface iterations (1, 3, 6, 10, ...), so the first comes as
// soon as the surface has taken one step from the input mesh, and the
// surface has one iteration longer to follow each round than the one before.
// Rounds that would fall at or after the last iteration are not made, so the
// list may be shorter than `rounds`.
std::vector<int> CameraRoundIterations(int iterations, int rounds);

// How many pyramid levels coarser than the surface's the cameras may be
// refined at when the surface's level does not fit the memory budget. At 1 px
// of pose error, one level coarser brought three cases to within 2-6 % of
// the rounds at the surface's level; two coarser made homer-color-small's
// accuracy90 worse than no camera refinement (1,272 samples a round;
// docs/camera_refinement.md, "Thirty-seventh session").
constexpr int kMaxCameraLevelsCoarser = 1;

// The pyramid level at which the cameras are refined while the surface is
// refined at `level`, with `level_views` the views at `level`: `level` itself
// if the grey images of all views (4 bytes a pixel) fit in `max_bytes`, else
// the first coarser level whose images do, at most kMaxCameraLevelsCoarser
// levels coarser; -1 if none does. Camera refinement holds all of them at once.
int CameraRefinementLevel(const std::vector<PinholeView>& level_views, int level,
                          size_t max_bytes);

// Iterations after a camera round in which the surface follows the new
// cameras before average_last_iterates may average its iterates.
constexpr int kCameraSettlingIterations = 4;

// The first iteration of the finest level whose iterate average_last_iterates
// averages, with all after it (`iterations` when fewer than two would be):
// the last `average_last` of `iterations`, and none of the
// kCameraSettlingIterations after the last of `camera_rounds`
// (CameraRoundIterations; empty without camera refinement). The mean of a
// surface still moving lags behind it.
int FirstAveragedIteration(int iterations, int average_last,
                           const std::vector<int>& camera_rounds);

// Which iterate of a level to keep. `similarities[k]` is the mean
// similarity of the level's mesh after k iterations (k = 0: its start), the
// last entry that of the mesh entering the last iteration. Returns the index
// of the best iterate when the last one has fallen from it by more than
// `giveback` times the gain from the start to the best, and -1 (keep the last
// iterate, the one after all the level's iterations) otherwise or with fewer
// than 2 entries.
int BestIterateToKeep(const std::vector<double>& similarities, double giveback);

// The mean share of a mesh of `num_vertices` vertices that the
// self-intersection guard reset per iteration, `resets` holding the counts of
// the iterations after a level's best iterate (0 if none). A level ends on
// its best iterate only when this exceeds kGuardOverrideFraction as well:
// then the guard, not the images, drove the surface after it.
double MeanResetFraction(const std::vector<int>& resets, int num_vertices);

// Measured per iteration (docs/results.md): the eleven closed corpus
// surfaces at most 2.3 %, the Middlebury visual hulls' finest level at most
// 5.6 %, the open shell 24-36 % after its best iterate; on the baseline's
// fandisk-shading the similarity fell by half its gain at 0.2 % while the
// surface kept improving.
constexpr double kGuardOverrideFraction = 0.10;

// An open border's band vertex takes the membrane step
// (RefineOptions::open_border_rings) only where the images see it and
// contradict it: its mean similarity over the iteration's pairs is below
// ContradictedSimilarity. A vertex that no pixel of the pairs sees is held:
// nothing says that it is wrong, and with such vertices moving the example's
// chamfer distance rose 7 % against 3 % with them held (docs/results.md,
// "Open borders: a membrane held by the images").
//
// The bound is kOpenBorderMaxSimilarity: on cheburashka-grey-nomask most of
// the band's skirt lay at 0-0.6 against a median of 0.92 over the mesh; on
// homer-color-small, where the border lay on the object, most of the band was
// at 0.8-1.
constexpr double kOpenBorderMaxSimilarity = 0.5;
// It is lower where a vertex below it would be no outlier of its own
// surface: at most kOpenBorderOutlierSigmas robust standard deviations below
// the median of the mesh's seen vertices. Where the whole surface scores low
// (shading only: builtin-shading-40's median 0.09, spread 0.14) a low border
// says nothing, and the step moved a correct border there (accuracy90 0.630
// -> 0.638 the input). On high-contrast texture this bound lies above 0.5;
// on bunny-color-hemi's smooth colour texture near 0 (docs/results.md, "Open
// borders: an outlier of its own surface").
constexpr double kOpenBorderOutlierSigmas = 3;

// The mean similarity below which a seen band vertex counts as contradicted,
// from the per-vertex sums of DataTerm: `similarity` (Σ w m) and `weight`
// (Σ w; a vertex is seen where it is > 0). -infinity when none is seen.
double ContradictedSimilarity(const Eigen::VectorXd& similarity, const Eigen::VectorXd& weight);

struct RefineSummary {
  std::string termination;  // "FINISHED" or why it stopped
  std::string schedule;     // num_levels 0: what was chosen and why
  std::string light;        // where the light was taken to be, and why
  std::string masks;        // given masks: where their outlines lie (align_masks), and
                            // their backdrop (black_outside_masks)
  int num_views = 0;
  int num_pairs = 0;
  int initial_faces = 0, final_faces = 0;
  int initial_vertices = 0, final_vertices = 0;
  // Mean ZNCC of all pairs at full resolution, before (with one pyramid
  // level: of the input remeshed to the working resolution, as measured by
  // the first iteration) and after refinement.
  double initial_similarity = 0;
  double final_similarity = 0;    // and after refinement
  int flipped_faces_fixed = 0;
  int steps_taken_back = 0;  // min_improvement: last steps of a level that lowered the similarity
  // best_iterate_giveback: levels that ended on an earlier iterate, and the
  // iterations they dropped.
  int levels_ended_on_best = 0, iterations_dropped = 0;
  int iterates_averaged = 0;  // average_last_iterates: how many the finest level ended on
  long self_intersections_undone = 0;  // new intersecting pairs undone during the iterations
  int vertices_reset = 0;              // vertex moves undone for them
  int self_intersections = -1;    // of the result (-1: not computed)
  // Distance of the result's vertices to the (cleaned) input surface, in
  // scene units: how far the refinement moved the surface.
  double mean_displacement = 0, max_displacement = 0;
  double seconds = 0;
  // Where the time went outside the iterations: loading the mesh, cleaning
  // it, view selection and the schedule; remeshing for the levels (and the
  // rest of their set-up: the self-intersection guard, the render cache;
  // with a chosen schedule the full-resolution remeshing runs alongside the
  // schedule's measurement, and only what is left of it after the
  // measurement counts here); the final self-intersection check, similarity
  // and vertex colours.
  double setup_seconds = 0, remesh_seconds = 0, final_seconds = 0;
  std::vector<RefineIteration> iterations;
  // refine_cameras: the refined cameras of the views (pose and intrinsics at
  // the resolution of the ViewSource given to RefineMesh), and one report
  // per refinement; empty when the cameras were not refined.
  std::vector<PinholeView> cameras;
  std::vector<std::string> camera_reports;

  std::string BriefReport() const;
  std::string FullReport() const;
};

// Registers every option as --Refine.*, --ViewSelection.*, --Similarity.*,
// --Denoise.* (shared by mesh_refiner and the benchmarks).
void RegisterRefineOptions(OptionManager* manager, RefineOptions* options);

// Refines `mesh` in place (positions, connectivity, vertex colours) against
// the views of `source`. Throws InputError if the mesh is empty, no face is
// visible in any view, or no two views overlap. `renderer` may be null (one
// is created).
RefineSummary RefineMesh(const ViewSource& source, const RefineOptions& options,
                         TriangleMesh* mesh, Renderer* renderer = nullptr);

// Mean similarity (plain ZNCC) of the predicted images of `eval_views`
// against their neighbours among `source`'s other views, through `mesh`:
// a photo-consistency score that needs no ground truth (held-out views).
double PhotoConsistency(const ViewSource& source, const std::vector<int>& eval_views,
                        const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, Renderer* renderer,
                        int num_neighbors = 3);

}  // namespace mr
