// middlebury_to_colmap: converts a Middlebury multi-view data set (images,
// *_par.txt, README.txt) into a COLMAP dense workspace with masks, a
// hold-out list and the README's bounding box. See docs/middlebury.md.

#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "init/middlebury.h"
#include "util/error.h"
#include "util/file.h"
#include "util/logging.h"
#include "util/options.h"
#include "util/program.h"

int main(int argc, char** argv) {
  return mr::RunProgram([&]() -> int {
    std::string input_path, output_path;
    mr::MiddleburyConversionOptions options;
    mr::OptionManager manager(
        "middlebury_to_colmap",
        "Converts a Middlebury data set folder into a COLMAP dense workspace (images/, sparse/, "
        "masks/, holdout.txt, bbox.txt), in millimetres by default.");
    manager.AddRequired("input_path", &input_path, "Middlebury data set folder (*_par.txt)");
    manager.AddRequired("output_path", &output_path, "workspace folder to write");
    manager.Add("scale", &options.scale, "workspace units per metre (1000: millimetres)");
    manager.Add("holdout", &options.holdout,
                "held-out images by 1-based index, e.g. \"2,9\" (empty: every holdout_every-th)");
    manager.Add("holdout_every", &options.holdout_every,
                "with an empty --holdout, hold out images k, 2k, ... (0: none)");
    manager.Add("Silhouette.threshold", &options.silhouette.threshold,
                "intensity threshold in [0, 1]");
    manager.Add("Silhouette.dilate_px", &options.silhouette.dilate_px, "dilation radius, pixels");
    manager.Add("Silhouette.erode_px", &options.silhouette.erode_px, "erosion radius, pixels");
    manager.Add("Silhouette.fill_holes_px", &options.silhouette.fill_holes_px,
                "fill mask holes of at most this many pixels (0: none)");
    bool verbose = false;
    manager.Add("verbose", &verbose, "per-image details");
    // The data set folder is input as a whole.
    manager.SetInputPaths([&] { return std::vector<std::string>{input_path}; });
    if (!manager.Parse(argc, argv)) return 0;
    if (verbose) mr::SetLogLevel(mr::LogLevel::kVerbose);
    mr::CheckOutputFolder("--output_path", output_path);
    const mr::MiddleburyConversionSummary summary =
        mr::ConvertMiddlebury(input_path, output_path, options);
    std::string held;
    for (const std::string& n : summary.holdout) held += (held.empty() ? "" : " ") + n;
    MR_LOG(INFO) << "Wrote " << output_path << ": " << summary.BriefReport();
    MR_LOG(INFO) << "Held out: " << (held.empty() ? "none" : held);
    if (summary.has_bbox) {
      MR_LOG(INFO) << "Bounding box (workspace units): " << summary.bbox.min().transpose()
                   << " .. " << summary.bbox.max().transpose();
    }
    return 0;
  });
}
