// End-to-end tests of the mesh_refiner program on a small workspace written
// with the project's own writers (images rendered from a bumpy sphere, a
// PINHOLE sparse model, a smooth sphere as the "Poisson" mesh).

#include <gtest/gtest.h>

#include <poll.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <opencv2/imgcodecs.hpp>

#include "colmap_io/mesh_io.h"
#include "colmap_io/ply.h"
#include "colmap_io/sparse_model.h"
#include "geometry/mesh.h"
#include "geometry/primitives.h"
#include "refine/test_scene.h"
#include "render/renderer.h"
#include "tests/command.h"
#include "tests/test_workspace.h"
#include "util/file.h"
#include "util/testing.h"

namespace mr {
namespace {

namespace fs = std::filesystem;

const std::string kRefiner = std::string(MR_BIN_DIR) + "/mesh_refiner";
// Small and quick: the point here is the program's behaviour, not accuracy.
const std::string kFast =
    " --Refine.num_levels 1 --Refine.iterations_per_level 2 --Refine.target_edge_px 4";

class MeshRefinerCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = FreshTestPath(
        "cli_ws_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    WriteRenderedTestWorkspace(dir_);
    TriangleMesh initial;
    MakeIcosphere(3, 1.0, &initial.V, &initial.F);
    WritePly(dir_ + "/meshed-poisson.ply", initial);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes a sentinel output so that tests can check it is left untouched.
  void WriteSentinelOutput() {
    std::ofstream(dir_ + "/meshed-refined.ply") << "sentinel";
  }
  bool SentinelIntact() { return ReadFileToString(dir_ + "/meshed-refined.ply") == "sentinel"; }

  std::string dir_;
};

TEST_F(MeshRefinerCli, Nominal) {
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("probably meaningless"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("covers only"), std::string::npos) << r.output;
  const TriangleMesh out = ReadPly(dir_ + "/meshed-refined.ply");
  EXPECT_GT(out.NumFaces(), 100);
  ASSERT_EQ(out.C.rows(), out.NumVertices()) << "vertex colours expected";
  // The colours come from the images: a vertex that no view saw is grey 128
  // (the ring of views at 25 degrees elevation misses the bottom: 688 of
  // 4480 vertices measured), and the texture varies (grey levels 0.15-0.95).
  int unseen = 0;
  double sum = 0, sum2 = 0;
  for (int v = 0; v < out.NumVertices(); ++v) {
    if (out.C(v, 0) == 128 && out.C(v, 1) == 128 && out.C(v, 2) == 128) ++unseen;
    sum += out.C(v, 0);
    sum2 += static_cast<double>(out.C(v, 0)) * out.C(v, 0);
  }
  const double mean = sum / out.NumVertices();
  EXPECT_LT(unseen, out.NumVertices() / 5);
  EXPECT_GT(std::sqrt(sum2 / out.NumVertices() - mean * mean), 20.0) << "mean " << mean;
  EXPECT_NE(r.output.find("DCV refinement: FINISHED"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Renderer:"), std::string::npos) << r.output;
  // Progress: each iteration's line ends with an ETA; the summary splits the time.
  EXPECT_NE(r.output.find("Level 0 iteration 2/2:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("; ETA 0.0 s"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  time: setup "), std::string::npos) << r.output;
  // No temporary file left behind.
  for (const auto& name : ListFiles(dir_)) EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
}

TEST_F(MeshRefinerCli, DryRunPrintsSummaryAndWritesNothing) {
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + " --dry_run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Images:      8 registered"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Faces:       1280"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("px at full resolution"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Working resolution: 160x120 (largest view; 0 of 8 views scaled down"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("Faces at the finest level: about"), std::string::npos) << r.output;
  EXPECT_FALSE(ExistsFile(dir_ + "/meshed-refined.ply"));
  // --Refine.max_image_size scales the images down; the mesh follows the
  // working resolution (a quarter of the pixels: about a quarter of the faces).
  const auto faces_in = [](const std::string& output) {
    const size_t at = output.find("Faces at the finest level: about ");
    return at == std::string::npos ? -1 : std::stoi(output.substr(at + 33));
  };
  const CommandResult half = RunCommand(kRefiner + " --workspace_path " + dir_ +
                                        " --dry_run --Refine.max_image_size 80");
  ASSERT_EQ(half.exit_code, 0) << half.output;
  EXPECT_NE(half.output.find("Working resolution: 80x60 (largest view; 8 of 8 views scaled down "
                             "to --Refine.max_image_size 80)"),
            std::string::npos)
      << half.output;
  EXPECT_NEAR(faces_in(half.output), faces_in(r.output) / 4.0, faces_in(r.output) * 0.05)
      << r.output << half.output;
}

TEST_F(MeshRefinerCli, DryRunWithTextModel) {
  const Reconstruction model = ReadSparseModel(dir_ + "/sparse");
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) fs::remove(dir_ + "/sparse/" + f);
  WriteSparseModelText(dir_ + "/sparse", model);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + " --dry_run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Images:      8 registered"), std::string::npos) << r.output;
}

TEST_F(MeshRefinerCli, MissingImageFailsCleanly) {
  WriteSentinelOutput();
  fs::remove(dir_ + "/images/view_3.png");
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("ERROR"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("view_3.png"), std::string::npos) << r.output;
  EXPECT_TRUE(SentinelIntact());
}

TEST_F(MeshRefinerCli, EmptyMeshFailsCleanly) {
  WriteSentinelOutput();
  TriangleMesh empty;
  empty.V.resize(0, 3);
  empty.F.resize(0, 3);
  WritePly(dir_ + "/meshed-poisson.ply", empty);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no faces"), std::string::npos) << r.output;
  EXPECT_TRUE(SentinelIntact());
}

TEST_F(MeshRefinerCli, MeshWithNoVisibleFacesFailsCleanly) {
  WriteSentinelOutput();
  TriangleMesh far_away;
  MakeIcosphere(2, 1.0, &far_away.V, &far_away.F);
  far_away.V.col(2).array() += 1000.0;
  WritePly(dir_ + "/meshed-poisson.ply", far_away);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("not visible"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("meshed-poisson.ply: the mesh is not visible"), std::string::npos)
      << r.output;
  EXPECT_TRUE(SentinelIntact());
}

TEST_F(MeshRefinerCli, ViewsWithoutOverlapFailCleanly) {
  WriteSentinelOutput();
  // Keep two opposite views only.
  Reconstruction model = ReadSparseModel(dir_ + "/sparse");
  for (uint32_t id = 1; id <= 8; ++id) {
    if (id != 1 && id != 5) model.images.erase(id);
  }
  WriteSparseModelBinary(dir_ + "/sparse", model);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("overlap"), std::string::npos) << r.output;
  EXPECT_TRUE(SentinelIntact());
}

TEST_F(MeshRefinerCli, NonManifoldInputIsRepairedWithAMessage) {
  // Two spheres sharing one vertex: a non-manifold vertex.
  TriangleMesh a;
  MakeIcosphere(3, 0.5, &a.V, &a.F);
  const Eigen::RowVector3d top = a.V.row(0);
  TriangleMesh mesh;
  mesh.V.resize(2 * a.V.rows() - 1, 3);
  mesh.V.topRows(a.V.rows()) = a.V.rowwise() - top;
  mesh.F.resize(2 * a.F.rows(), 3);
  mesh.F.topRows(a.F.rows()) = a.F;
  // Second sphere mirrored through the shared vertex, reusing vertex 0.
  std::vector<int> map(a.V.rows());
  map[0] = 0;
  int next = static_cast<int>(a.V.rows());
  for (int v = 1; v < a.V.rows(); ++v) {
    map[v] = next;
    mesh.V.row(next++) = -(a.V.row(v) - top);
  }
  for (int f = 0; f < a.F.rows(); ++f) {
    mesh.F.row(a.F.rows() + f) << map[a.F(f, 0)], map[a.F(f, 1)], map[a.F(f, 2)];
  }
  WritePly(dir_ + "/meshed-poisson.ply", mesh);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("non-manifold: 0 edges, 1 vertices"), std::string::npos) << r.output;
}

TEST_F(MeshRefinerCli, RefusesToOverwriteInput) {
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + " --output_path " +
                                     dir_ + "/meshed-poisson.ply" + kFast);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("refusing to overwrite"), std::string::npos) << r.output;
}

// A refused run: exit code 1, one ERROR line with `message`, and `kept` (an
// existing file) byte-identical afterwards, no temporary file left.
void ExpectRefused(const CommandResult& r, const std::string& message, const std::string& kept,
                   const std::string& kept_bytes) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("ERROR: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
  EXPECT_TRUE(ReadFileToString(kept) == kept_bytes) << kept << " was changed";
  for (const auto& name : ListFiles(GetParentDir(kept))) {
    EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
  }
}

// --write_config must never replace an input: the mesh (given or the
// default one), the sparse model, an image, however the path is spelled.
TEST_F(MeshRefinerCli, WriteConfigOverAnInputIsRefused) {
  const std::string mesh = dir_ + "/meshed-poisson.ply";
  const std::string mesh_bytes = ReadFileToString(mesh);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --input_path " + mesh +
                           " --write_config " + mesh),
                "refusing to overwrite", mesh, mesh_bytes);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --write_config " + mesh),
                "refusing to overwrite", mesh, mesh_bytes);
  ExpectRefused(RunCommand("cd " + dir_ + "/images && " + kRefiner + " --workspace_path " + dir_ +
                           " --write_config ../images/../meshed-poisson.ply"),
                "refusing to overwrite", mesh, mesh_bytes);
  fs::create_symlink(mesh, dir_ + "/link.ply");
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --input_path " + dir_ +
                           "/link.ply --write_config " + mesh),
                "refusing to overwrite", mesh, mesh_bytes);
  const std::string cameras = dir_ + "/sparse/cameras.bin";
  const std::string cameras_bytes = ReadFileToString(cameras);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --write_config " + cameras),
                "refusing to overwrite", cameras, cameras_bytes);
  const std::string image = dir_ + "/images/view_0.png";
  const std::string image_bytes = ReadFileToString(image);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --write_config " + image),
                "refusing to overwrite", image, image_bytes);
  // Elsewhere it is written.
  const CommandResult r =
      RunCommand(kRefiner + " --workspace_path " + dir_ + " --write_config " + dir_ + "/a.ini");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(ReadFileToString(dir_ + "/a.ini").find("[Refine]"), std::string::npos);
}

// The mesh output may not land on the model or images either, and its
// extension must be one that is written (.ply, .obj); refused before the
// workspace is read.
TEST_F(MeshRefinerCli, OutputOverAnInputOrWithAnUnknownExtensionIsRefused) {
  const std::string cameras = dir_ + "/sparse/cameras.bin";
  const std::string cameras_bytes = ReadFileToString(cameras);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + " --output_path " + cameras +
                           kFast),
                "refusing to overwrite", cameras, cameras_bytes);
  for (const std::string name : {"out.stl", "out.ply.txt", "out"}) {
    const std::string out = dir_ + "/" + name;
    std::ofstream(out) << "sentinel";
    const CommandResult r =
        RunCommand(kRefiner + " --workspace_path " + dir_ + " --output_path " + out + kFast);
    ExpectRefused(r, "expected .ply or .obj", out, "sentinel");
    EXPECT_NE(r.output.find(out), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("Workspace "), std::string::npos) << "work was done:\n" << r.output;
  }
}

// An output that cannot be written is refused before the workspace is read:
// a folder in a virtual file system (/proc, /sys: no file can be created
// there, even by root), an existing folder, a missing folder.
TEST_F(MeshRefinerCli, UnwritableOutputIsRefusedBeforeAnyWork) {
  WriteSentinelOutput();
  fs::create_directories(dir_ + "/folder.ply");
  for (const auto& [out, message] : std::vector<std::pair<std::string, std::string>>{
           {"/proc/refined.ply", "cannot create a file in folder /proc"},
           {"/sys/refined.ply", "cannot create a file in folder /sys"},
           {dir_ + "/folder.ply", "is a folder"},
           {dir_ + "/nope/refined.ply", "does not exist"}}) {
    const CommandResult r =
        RunCommand(kRefiner + " --workspace_path " + dir_ + " --output_path " + out + kFast);
    ExpectRefused(r, "--output_path " + out + ": " , dir_ + "/meshed-refined.ply", "sentinel");
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("Read "), std::string::npos) << "work was done:\n" << r.output;
  }
  const CommandResult r =
      RunCommand(kRefiner + " --workspace_path " + dir_ + " --write_config /proc/refine.ini");
  ExpectRefused(r, "--write_config /proc/refine.ini: cannot create a file in folder /proc",
                dir_ + "/meshed-refined.ply", "sentinel");
}

// --output_path x.obj writes OBJ (with the vertex colours), not PLY bytes.
TEST_F(MeshRefinerCli, ObjOutput) {
  const std::string out = dir_ + "/refined.obj";
  const CommandResult r =
      RunCommand(kRefiner + " --workspace_path " + dir_ + " --output_path " + out + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadFileToString(out).rfind("ply", 0), std::string::npos);
  const TriangleMesh mesh = ReadMesh(out);
  EXPECT_GT(mesh.NumFaces(), 100);
  EXPECT_EQ(mesh.C.rows(), mesh.NumVertices()) << "vertex colours expected";
}

// A held-out image name that the model does not have is an error naming it.
TEST_F(MeshRefinerCli, HoldoutNameNotInTheModel) {
  WriteSentinelOutput();
  std::ofstream(dir_ + "/holdout.txt") << "view_1.png\nview_9.png\n";
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + " --holdout_path " +
                                     dir_ + "/holdout.txt" + kFast);
  ExpectRefused(r, "view_9.png", dir_ + "/meshed-refined.ply", "sentinel");
  EXPECT_NE(r.output.find("not in the sparse model"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(dir_ + "/holdout.txt"), std::string::npos) << r.output;
}

// SIGINT in the middle of the iterations (a run of 1000 iterations): the
// program stops at once with status 130 and one line saying so; the existing
// output is untouched and nothing temporary is left.
TEST_F(MeshRefinerCli, SigintStopsPromptlyAndLeavesNothing) {
  WriteSentinelOutput();
  const std::string log = dir_ + "/../mr_cli_sigint.log";
  fs::remove(log);
  const pid_t pid = SpawnCommand({kRefiner, "--workspace_path", dir_, "--Refine.num_levels", "1",
                                  "--Refine.iterations_per_level", "1000",
                                  "--Refine.target_edge_px", "4"},
                                 log);
  ASSERT_GT(pid, 0);
  const bool started = WaitForLogText(pid, log, "iteration 1/1000", 300);
  if (!started) ::kill(pid, SIGKILL);
  ASSERT_TRUE(started) << ReadFileToString(log);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(::kill(pid, SIGINT), 0);
  const int status = WaitForExit(pid);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string output = ReadFileToString(log);
  fs::remove(log);
  EXPECT_EQ(status, 130) << output;
  EXPECT_LT(seconds, 5.0);
  EXPECT_NE(output.find("ERROR: interrupted by SIGINT"), std::string::npos) << output;
  EXPECT_TRUE(SentinelIntact());
  for (const auto& name : ListFiles(dir_)) EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
}

// SIGTERM while the output is being written: its temporary
// (meshed-refined.ply.tmp.<pid>) is made a FIFO before the program gets
// there, so the writer blocks half-way through the mesh (the pipe holds 4
// KB) and is interrupted there. Status 143, the temporary removed, the
// existing output untouched.
TEST_F(MeshRefinerCli, SigtermDuringTheWriteRemovesTheTemporary) {
  WriteSentinelOutput();
  const std::string log = dir_ + "/../mr_cli_sigterm.log";
  fs::remove(log);
  const pid_t pid = SpawnCommand({kRefiner, "--workspace_path", dir_, "--Refine.num_levels", "1",
                                  "--Refine.iterations_per_level", "1",
                                  "--Refine.target_edge_px", "4"},
                                 log);
  ASSERT_GT(pid, 0);
  // The program reads, refines and renders for seconds before it writes.
  const std::string tmp = dir_ + "/meshed-refined.ply.tmp." + std::to_string(pid);
  ASSERT_EQ(::mkfifo(tmp.c_str(), 0644), 0);
  const int reader = ::open(tmp.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  ::fcntl(reader, F_SETPIPE_SZ, 4096);
  // Readable: the writer has opened the temporary and written into it.
  // (Polled with a deadline and a sleep: a FIFO without a writer may report
  // POLLHUP at once, which is not data.)
  struct pollfd poll_fd = {reader, POLLIN, 0};
  bool writing = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (!writing && std::chrono::steady_clock::now() < deadline) {
    writing = ::poll(&poll_fd, 1, 100) > 0 && (poll_fd.revents & POLLIN);
    int status = 0;
    if (!writing && ::waitpid(pid, &status, WNOHANG) == pid) break;
    if (!writing) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!writing) ::kill(pid, SIGKILL);
  ASSERT_TRUE(writing) << ReadFileToString(log);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the pipe fills
  ASSERT_TRUE(fs::exists(tmp));
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const int status = WaitForExit(pid);
  ::close(reader);
  const std::string output = ReadFileToString(log);
  fs::remove(log);
  EXPECT_EQ(status, 143) << output;
  EXPECT_NE(output.find("ERROR: interrupted by SIGTERM"), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(tmp)) << "the temporary was left behind";
  fs::remove(tmp);
  EXPECT_TRUE(SentinelIntact());
  for (const auto& name : ListFiles(dir_)) EXPECT_EQ(name.find(".tmp."), std::string::npos) << name;
}

// A handful of triangles is not a surface to refine: a one-triangle mesh and
// a cube (12 faces) are refused with the count, before any rendering.
TEST_F(MeshRefinerCli, TooFewFacesAreRefused) {
  WriteSentinelOutput();
  TriangleMesh triangle;
  triangle.V.resize(3, 3);
  triangle.V << 0, 0, 0, 0.5, 0, 0, 0, 0.5, 0;
  triangle.F.resize(1, 3);
  triangle.F << 0, 1, 2;
  WritePly(dir_ + "/meshed-poisson.ply", triangle);
  ExpectRefused(RunCommand(kRefiner + " --workspace_path " + dir_ + kFast),
                "the mesh has 1 face; at least 20", dir_ + "/meshed-refined.ply", "sentinel");
  TriangleMesh cube;
  cube.V.resize(8, 3);
  cube.V << -1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1;
  cube.V *= 0.5;
  cube.F.resize(12, 3);
  cube.F << 0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6,
      5, 0, 4, 7, 0, 7, 3;
  WritePly(dir_ + "/meshed-poisson.ply", cube);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  ExpectRefused(r, "the mesh has 12 faces; at least 20", dir_ + "/meshed-refined.ply", "sentinel");
  EXPECT_EQ(r.output.find("Renderer:"), std::string::npos) << "work was done:\n" << r.output;
}

// --Refine.num_levels 6 on 160x120 images: the coarse levels would remesh
// the sphere to a few faces, which the finer levels cannot undo; they are
// skipped with a line each, and the result keeps its shape.
TEST_F(MeshRefinerCli, CoarseLevelsWithTooFewFacesAreSkipped) {
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ +
                                     " --Refine.num_levels 6 --Refine.iterations_per_level 1"
                                     " --Refine.target_edge_px 4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Level 5 skipped: its mesh would have"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("schedule: level 5 skipped"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Level 5: "), std::string::npos) << "level 5 ran:\n" << r.output;
  const TriangleMesh out = ReadPly(dir_ + "/meshed-refined.ply");
  EXPECT_GT(out.NumFaces(), 500);
  // Still the unit sphere: every vertex within 10 % of radius 1.
  const Eigen::VectorXd radius = out.V.rowwise().norm();
  EXPECT_GT(radius.minCoeff(), 0.9);
  EXPECT_LT(radius.maxCoeff(), 1.1);
  EXPECT_EQ(r.output.find("probably meaningless"), std::string::npos) << r.output;
}

// Images that do not agree with each other through the mesh (noise): the
// run finishes, but a WARNING line says that the result means nothing.
TEST_F(MeshRefinerCli, MeaninglessResultIsFlagged) {
  cv::RNG rng(7);
  for (const auto& name : ListFiles(dir_ + "/images")) {
    const cv::Mat image = cv::imread(dir_ + "/images/" + name, cv::IMREAD_GRAYSCALE);
    cv::Mat noise(image.size(), CV_8U);
    rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
    cv::imwrite(dir_ + "/images/" + name, noise);
  }
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("WARNING: the final mean similarity is"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("probably meaningless"), std::string::npos) << r.output;
}

// A mesh a tenth of the object's size (a mesh of another scale, say) covers
// a few dozen pixels: a WARNING names the file and the coverage before the
// refinement starts.
TEST_F(MeshRefinerCli, MeshCoveringFewPixelsIsFlagged) {
  TriangleMesh tiny;
  MakeIcosphere(3, 0.1, &tiny.V, &tiny.F);
  WritePly(dir_ + "/meshed-poisson.ply", tiny);
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast);
  EXPECT_NE(r.output.find("WARNING: " + dir_ + "/meshed-poisson.ply covers only"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("(expected at least 1 %)"), std::string::npos) << r.output;
}

// --Refine.refine_cameras: the refined model goes to <workspace>/sparse_refined
// with the same ids; sparse/ is left byte-identical. The test workspace's
// cameras are exact and the input is the true surface (the bumpy sphere the
// images show), so the cameras barely move: less than 0.05 scene units, about
// 4 pixel footprints (0.013 units per pixel at the surface).
TEST_F(MeshRefinerCli, RefinedCamerasAreWrittenBesideTheModel) {
  TriangleMesh truth;
  MakeBumpySphere(4, 0.06, &truth.V, &truth.F);
  WritePly(dir_ + "/meshed-poisson.ply", truth);
  std::map<std::string, std::string> sparse_before;
  for (const auto& name : ListFiles(dir_ + "/sparse")) {
    sparse_before[name] = ReadFileToString(dir_ + "/sparse/" + name);
  }
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + kFast +
                                     " --Refine.refine_cameras poses");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Level 0 cameras: Camera refinement (poses)"), std::string::npos)
      << r.output;
  // Two iterations leave room for the first of the default's two rounds only.
  EXPECT_NE(r.output.find("Cameras refined (poses) after iteration 1 of 2; later rounds would "
                          "fall past the last"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("Wrote the refined cameras to " + dir_ + "/sparse_refined"),
            std::string::npos)
      << r.output;
  for (const auto& [name, bytes] : sparse_before) {
    EXPECT_EQ(ReadFileToString(dir_ + "/sparse/" + name), bytes) << name;
  }
  const Reconstruction before = ReadSparseModel(dir_ + "/sparse");
  const Reconstruction after = ReadSparseModel(dir_ + "/sparse_refined");
  ASSERT_EQ(after.images.size(), before.images.size());
  EXPECT_EQ(after.points3D.size(), before.points3D.size());
  double largest_move = 0;
  for (const auto& [id, image] : before.images) {
    ASSERT_TRUE(after.images.count(id));
    EXPECT_EQ(after.images.at(id).name, image.name);
    largest_move = std::max(largest_move, (after.images.at(id).ProjectionCenter() -
                                           image.ProjectionCenter()).norm());
  }
  EXPECT_GT(largest_move, 0.0);   // refined, so not bit-identical
  EXPECT_LT(largest_move, 0.05);  // exact cameras stay put (scene radius 1, distance 4)
}

// --holdout_path scores the held-out views twice: at their SfM poses, and
// registered to the refined model. With exact cameras both agree.
TEST_F(MeshRefinerCli, HeldOutViewsAreScoredAtTheirPosesAndRegistered) {
  TriangleMesh truth;
  MakeBumpySphere(4, 0.06, &truth.V, &truth.F);
  WritePly(dir_ + "/meshed-poisson.ply", truth);
  std::ofstream(dir_ + "/holdout.txt") << "view_1.png\n";
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + " --holdout_path " +
                                     dir_ + "/holdout.txt" + kFast);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  double before = 0, after = 0, registered = 0;
  const size_t at = r.output.find("Held-out photo-consistency (mean ZNCC, 1 views): ");
  ASSERT_NE(at, std::string::npos) << r.output;
  ASSERT_EQ(std::sscanf(r.output.c_str() + at, "Held-out photo-consistency (mean ZNCC, 1 views): "
                        "%lf -> %lf", &before, &after), 2) << r.output;
  const std::string line = "registered to the refined model (their poses refined against the "
                           "mesh and the used views): ";
  const size_t reg = r.output.find(line);
  ASSERT_NE(reg, std::string::npos) << r.output;
  ASSERT_EQ(std::sscanf(r.output.c_str() + reg + line.size(), "%lf", &registered), 1);
  std::printf("held-out: %.4f -> %.4f, registered %.4f\n", before, after, registered);
  EXPECT_GT(after, 0.5);
  EXPECT_NEAR(registered, after, 0.02);
}

TEST_F(MeshRefinerCli, BadOptionNamesTheField) {
  const CommandResult r =
      RunCommand(kRefiner + " --workspace_path " + dir_ + " --Refine.similarity ssd");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("RefineOptions::similarity = ssd"), std::string::npos) << r.output;
}

TEST_F(MeshRefinerCli, MissingWorkspace) {
  const CommandResult r = RunCommand(kRefiner + " --workspace_path " + dir_ + "/nope");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("ERROR"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace mr
