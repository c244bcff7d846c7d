#pragma once

// Runs the real `colmap stereo_fusion` and `colmap poisson_mesher` on a dense
// workspace, the way a user's COLMAP pipeline makes the initial surface.

#include <string>

namespace mr {

struct ColmapRunOptions {
  // `colmap` executable: a path, or a name looked up on PATH.
  std::string colmap_path = "colmap";
  // --StereoFusion.min_num_pixels (COLMAP's default 5 is too strict for
  // sparse rings). Range [1, 100].
  int fusion_min_num_pixels = 3;
  // --StereoFusion.max_image_size: the longest side at which colmap fuses
  // the depth maps (-1: their own size). For workspaces of tens of
  // megapixels per image, whose full-size fusion would hold every depth,
  // normal and colour map at once. Range -1 or >= 100.
  int fusion_max_image_size = -1;
  // --PoissonMeshing.trim. COLMAP's default 10 can delete every vertex of a
  // small cloud; if the mesh comes out empty the run is retried with lower
  // trims (logged). Range [0, 20].
  double poisson_trim = 5;
  // --PoissonMeshing.depth (octree depth). COLMAP's default is 13. On the
  // default workspace (~85k fused points) depths 8 to 13 gave meshes of
  // 300k-370k faces with the same accuracy (mean distance to the ground truth
  // 0.093 vs 0.096 units), but the solve took 29 s at depth 8 and 124-158 s
  // at depths 9-10 on a shared 2-core machine. Range [4, 16].
  int poisson_depth = 8;
  // Threads for both stages (-1: all). Range -1 or >= 1.
  int num_threads = -1;
  // Seconds one colmap run may take before it is killed and the run fails
  // with its log; 0 = no limit. Two colmap processes of 2 OpenMP threads each
  // on 2 cores made poisson_mesher 13x slower (3.4 -> 43.6 s), so test suites
  // that run several at once set a limit (and num_threads 1). Range [0, 1e6].
  double timeout_s = 0;

  bool Check() const;
};

struct ColmapRunSummary {
  long fused_points = 0;
  long poisson_vertices = 0;
  long poisson_faces = 0;
  double trim_used = 0;
  double fusion_seconds = 0;
  double poisson_seconds = 0;
};

// Resolves an executable: a name containing '/' must exist and be
// executable; a bare name is searched on PATH. Returns "" if not found.
std::string FindExecutable(const std::string& name_or_path);

// Counts of the `vertex` and `face` elements in a PLY header (-1 if the
// element is absent). Throws InputError if the file is not a PLY.
void ReadPlyElementCounts(const std::string& path, long* num_vertices, long* num_faces);

// Runs fusion (dense_path/fused.ply) and Poisson (dense_path/meshed-poisson.ply).
// Each tool's output goes to log_dir/<tool>.log. Throws std::runtime_error
// with the log's tail if a tool fails or writes an empty result.
ColmapRunSummary RunColmapFusionAndPoisson(const std::string& dense_path,
                                           const std::string& log_dir,
                                           const ColmapRunOptions& options);

}  // namespace mr
