// The .ini option files read by --config_path (util/options.h). The options
// registered are mesh_refiner's (names and types as its --help printed them),
// so the seeds written by `mesh_refiner --write_config` read through to the
// value parsers. One OptionManager serves every input: reading a config only
// sets values, which no later parse depends on.

#include <deque>
#include <string>

#include "fuzz/fuzz_util.h"
#include "util/options.h"

namespace {

const struct {
  const char* name;
  char type;  // b(ool), i(nt), d(ouble), s(tring)
} kOptions[] = {
    {"workspace_path", 's'},
    {"input_path", 's'},
    {"output_path", 's'},
    {"mask_path", 's'},
    {"image_path", 's'},
    {"holdout_path", 's'},
    {"dry_run", 'b'},
    {"verbose", 'b'},
    {"Refine.num_levels", 'i'},
    {"Refine.schedule_misalignment_px", 'd'},
    {"Refine.min_level_image_px", 'i'},
    {"Refine.min_improvement", 'd'},
    {"Refine.iterations_per_level", 'i'},
    {"Refine.target_edge_px", 'd'},
    {"Refine.max_faces", 'i'},
    {"Refine.step", 'd'},
    {"Refine.max_step_px", 'd'},
    {"Refine.damping", 'd'},
    {"Refine.similarity", 's'},
    {"Refine.color", 's'},
    {"Refine.kappa", 'd'},
    {"Refine.regularizer", 's'},
    {"Refine.noise_from_step", 'b'},
    {"Refine.silhouette_weight", 'd'},
    {"Refine.prevent_self_intersections", 'b'},
    {"Refine.cache_mb", 'i'},
    {"ViewSelection.num_neighbors", 'i'},
    {"ViewSelection.ideal_angle_deg", 'd'},
    {"Similarity.sigma", 'd'},
    {"Similarity.epsilon", 'd'},
    {"Denoise.method", 's'},
    {"Denoise.max_iterations", 'i'},
    {"Denoise.tolerance", 'd'},
    {"Denoise.p_min", 'd'},
    {"Denoise.p_max", 'd'},
    {"Denoise.p_step", 'd'},
    {"Denoise.lambda_scale", 'd'},
    {"Denoise.fixed_lambda", 'd'},
    {"Denoise.fixed_p", 'd'},
    {"Denoise.edge_length_exponent", 'd'},
    {"Denoise.beta_initial", 'd'},
    {"Denoise.beta_max", 'd'},
    {"Denoise.beta_factor", 'd'},
    {"Denoise.inner_iterations", 'i'},
    {"Denoise.linear_solver", 's'},
    {"Denoise.cg_tolerance", 'd'},
    {"Denoise.cg_max_iterations", 'i'},
    {"Denoise.estimate_iterations", 'i'},
    {"Denoise.warm_iterations", 'i'},
    {"Denoise.update_operator", 'b'},
    {"Denoise.laplacian_iterations", 'i'},
    {"Denoise.laplacian_weight", 'd'},
    {"Denoise.bilaplacian_weight", 'd'},
    {"Denoise.normal_iterations", 'i'},
    {"Denoise.vertex_iterations", 'i'},
    {"Denoise.normal_sigma", 'd'},
    {"Denoise.spatial_sigma", 'd'},
    {"Denoise.l0_lambda_factor", 'd'},
    {"Denoise.l0_lambda", 'd'},
    {"Denoise.l0_beta_initial", 'd'},
    {"Denoise.l0_beta_max", 'd'},
    {"Denoise.l0_beta_factor", 'd'},
    {"Denoise.l0_alpha_factor", 'd'},
    {"Denoise.l0_alpha_decay", 'd'},
    {"Denoise.l0_update_operator", 'b'},
    {"Denoise.verbose", 'b'},
};

mr::OptionManager* MakeOptions() {
  static std::deque<bool> bools;
  static std::deque<int> ints;
  static std::deque<double> doubles;
  static std::deque<std::string> strings;
  auto* options = new mr::OptionManager("mesh_refiner", "fuzzed");
  for (const auto& o : kOptions) {
    switch (o.type) {
      case 'b':
        bools.push_back(false);
        options->Add(o.name, &bools.back(), "");
        break;
      case 'i':
        ints.push_back(0);
        options->Add(o.name, &ints.back(), "");
        break;
      case 'd':
        doubles.push_back(0);
        options->Add(o.name, &doubles.back(), "");
        break;
      default:
        strings.emplace_back();
        options->Add(o.name, &strings.back(), "");
        break;
    }
  }
  return options;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static mr::OptionManager* const options = MakeOptions();
  return mr::fuzz::Run([&] { options->ReadConfigData("fuzz.ini", mr::fuzz::Bytes(data, size)); });
}
