// weights_study: automatic weights against the weights artists painted (docs/weights.md). For each model: import
// it, drop its weights, compute automatic ones by each method, play every clip and compare the skinned points.
// Prints a Markdown table.
//
//   weights_study [--samples N] [--all-bones] [--detail] [HEAT OPTIONS] [--resolution N] MODEL...
//
// --all-bones lets every bone of the imported skeleton take weight; by default only the bones the artist weighted
// deform (the rig's deform bones, as a rigger flags them), for both methods. Heat options (HeatWeightsOptions):
// --heat C, --oblique K (oblique_penalty), --no-visibility, --max-influences N; --resolution: the voxel grid.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "deform/import/import.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/offline/weight_tools.hpp"
#include "deform/offline/voxel_weights.hpp"
#include "deform/offline/weights.hpp"
#include "deform/runtime/error.hpp"
#include "study.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string file_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The 15 points that move farthest from the artist's skinning in any sample, with both weights (stderr).
void print_worst(const deform::Model& model, const std::vector<deform::Animation>& clips,
                 const deform::SkinWeights& automatic, int samples) {
  std::vector<float> worst(model.mesh.point_count(), 0.0f);
  std::vector<glm::mat4> world(model.skeleton.bone_count()), palette(model.skeleton.bone_count());
  for (const deform::Animation& clip : clips)
    for (int s = 0; s < samples; ++s) {
      deform::Pose pose = model.skeleton.bind_pose();
      deform::SamplingJob sampling{&clip, clip.duration * (float(s) + 0.5f) / float(samples), pose.rotations,
                                   pose.translations};
      (void)sampling.run();
      deform::LocalToWorldJob fk{&model.skeleton, pose.rotations, pose.translations, world, palette};
      (void)fk.run();
      for (std::size_t i = 0; i < worst.size(); ++i) {
        const glm::vec3 p = model.mesh.positions[i];
        worst[i] = std::max(worst[i], glm::length(weights_study::skin_point(palette, model.weights, i, p) -
                                                  weights_study::skin_point(palette, automatic, i, p)));
      }
    }
  std::vector<std::size_t> order(worst.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return worst[a] > worst[b]; });
  auto text = [&](const deform::SkinWeights& w, std::size_t i) {
    std::string out;
    for (int k = 0; k < 4; ++k)
      if (w.weights[i][k] > 0.0f)
        out += model.skeleton.key(w.bones[i][k]) + ":" + std::to_string(w.weights[i][k]).substr(0, 4) + " ";
    return out;
  };
  for (std::size_t k = 0; k < std::min<std::size_t>(15, order.size()); ++k) {
    const std::size_t i = order[k];
    std::fprintf(stderr, "point %zu moved %.4g  artist %s| auto %s\n", i, double(worst[i]),
                 text(model.weights, i).c_str(), text(automatic, i).c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  int samples = 8;
  bool all_bones = false;
  bool detail = false;
  int voxel_resolution = 128;
  deform::HeatWeightsOptions heat_options;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--samples" && i + 1 < argc) samples = std::atoi(argv[++i]);
    else if (a == "--all-bones") all_bones = true;
    else if (a == "--heat" && i + 1 < argc) heat_options.heat = std::strtof(argv[++i], nullptr);
    else if (a == "--no-visibility") heat_options.visibility = false;
    else if (a == "--oblique" && i + 1 < argc) heat_options.oblique_penalty = std::strtof(argv[++i], nullptr);
    else if (a == "--max-influences" && i + 1 < argc) heat_options.max_influences = std::atoi(argv[++i]);
    else if (a == "--detail") detail = true;
    else if (a == "--resolution" && i + 1 < argc) voxel_resolution = std::atoi(argv[++i]);
    else paths.push_back(a);
  }
  if (paths.empty() || samples < 1) {
    std::fprintf(stderr,
                 "usage: weights_study [--samples N] [--all-bones] [--detail] [--heat C] [--oblique K] "
                 "[--no-visibility] [--max-influences N] [--resolution N] MODEL...\n");
    return 2;
  }
  std::printf(
      "| model | points | bones (deforming) | clips (poses) | method | mean | p99 | max | strongest bone differs "
      "| bind time |\n|---|---|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  for (const std::string& path : paths) {
    try {
      const deform::ImportedModel imported = deform::import_model(path);
      const deform::Model& model = imported.model;
      std::vector<std::uint8_t> deforming = deform::weighted_bones(model.weights, model.skeleton.bone_count());
      std::size_t deforming_count = 0;
      for (std::uint8_t d : deforming) deforming_count += d;
      if (all_bones) deforming.clear();

      struct Run {
        const char* method;
        deform::SkinWeights weights;
        double seconds;
        std::size_t warnings;
      };
      std::vector<Run> runs;
      {
        deform::AutoWeightsOptions o;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::SkinWeights w = deform::compute_automatic_weights(model.mesh, model.skeleton, o);
        runs.push_back({"distance", std::move(w), seconds_since(start), 0});
      }
      {
        deform::HeatWeightsOptions o = heat_options;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::WeightsResult r = deform::compute_heat_weights(model.mesh, model.skeleton, o);
        const double took = seconds_since(start);
        for (const std::string& w : r.warnings)
          std::fprintf(stderr, "%s: heat: %s\n", file_name(path).c_str(), w.c_str());
        runs.push_back({"heat", std::move(r.weights), took, r.warnings.size()});
      }
      {
        deform::VoxelWeightsOptions o;
        o.resolution = voxel_resolution;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::WeightsResult r = deform::compute_voxel_weights(model.mesh, model.skeleton, o);
        const double took = seconds_since(start);
        for (const std::string& w : r.warnings)
          std::fprintf(stderr, "%s: voxel: %s\n", file_name(path).c_str(), w.c_str());
        runs.push_back({"voxel", std::move(r.weights), took, r.warnings.size()});
      }
      if (detail) print_worst(model, imported.clips, runs[1].weights, samples);  // heat, the default
      for (const Run& run : runs) {
        const weights_study::Figures f = weights_study::compare(model, imported.clips, run.weights, samples);
        std::printf("| %s | %zu | %zu (%zu) | %zu (%zu) | %s | %.2f%% | %.2f%% | %.2f%% | %.1f%% | %.3f s |\n",
                    file_name(path).c_str(), model.mesh.point_count(), model.skeleton.bone_count(), deforming_count,
                    imported.clips.size(), f.poses, run.method, f.mean_percent, f.p99_percent, f.max_percent,
                    f.strongest_differs_percent, run.seconds);
      }
      std::fflush(stdout);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
      ++failures;
    }
  }
  return failures == 0 ? 0 : 1;
}
