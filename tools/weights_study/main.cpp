// weights_study: automatic weights against the weights artists painted (docs/weights.md). For each model: import
// it, drop its weights, compute automatic ones by each method, pose it and compare the skinned points. Prints a
// Markdown table.
//
//   weights_study [--samples N | --random-poses N [--seed S]] [--all-bones] [--detail | --detail-bone B] [HEAT OPTIONS]
//                 [--resolution N] [--digits N] [--blender-export DIR] [--blender-weights DIR] MODEL...
//
// Poses: by default every clip of the model at N (--samples, 8) evenly spaced times; with --random-poses N, N seeded
// random poses (study.hpp, random_palettes: every bone the artist weighted turned by up to ±20° about each axis).
// --all-bones lets every bone of the imported skeleton take weight; by default only the bones the artist weighted
// deform (the rig's deform bones, as a rigger flags them), for every method. Heat options (HeatWeightsOptions):
// --heat C, --oblique K (oblique_penalty), --no-visibility, --max-influences N; --resolution: the voxel grid;
// --digits N: decimals of the figures (default 2; 0 to 6), for methods that differ in the third.
// Blender's bone heat, side by side (tools/weights_study/blender_study.sh): --blender-export DIR writes each model's
// bind mesh and bones as DIR/NAME.bind.json for blender_heat.py; --blender-weights DIR reads the weights it wrote,
// DIR/NAME.blender.json, and scores them as the method "blender" in the same poses.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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

// The 15 points that move farthest from the artist's skinning in any pose, with both weights, among those whose
// strongest artist bone is `only_bone` when it is given; before them, the summed distance shared by the artist's
// strongest bone (stderr).
void print_worst(const deform::Model& model, const std::vector<std::vector<glm::mat4>>& palettes,
                 const deform::SkinWeights& automatic, const std::string& only_bone) {
  std::vector<float> worst(model.mesh.point_count(), 0.0f);
  std::vector<double> by_bone(model.skeleton.bone_count(), 0.0);  // summed distances by the artist's strongest bone
  double total = 0.0;
  for (const std::vector<glm::mat4>& palette : palettes)
    for (std::size_t i = 0; i < worst.size(); ++i) {
      const glm::vec3 p = model.mesh.positions[i];
      const float d = glm::length(weights_study::skin_point(palette, model.weights, i, p) -
                                  weights_study::skin_point(palette, automatic, i, p));
      worst[i] = std::max(worst[i], d);
      by_bone[weights_study::strongest_bone(model.weights, i)] += d;
      total += d;
    }
  std::vector<std::size_t> bones(by_bone.size());
  for (std::size_t b = 0; b < bones.size(); ++b) bones[b] = b;
  std::sort(bones.begin(), bones.end(), [&](std::size_t a, std::size_t b) { return by_bone[a] > by_bone[b]; });
  std::fprintf(stderr, "share of the summed distance by the artist's strongest bone:");
  for (std::size_t k = 0; k < std::min<std::size_t>(24, bones.size()); ++k)
    std::fprintf(stderr, " %s %.1f%%", model.skeleton.key(static_cast<std::int32_t>(bones[k])).c_str(),
                 total > 0.0 ? 100.0 * by_bone[bones[k]] / total : 0.0);
  std::fprintf(stderr, "\n");
  std::vector<std::size_t> order(worst.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (!only_bone.empty())
    order.erase(std::remove_if(order.begin(), order.end(),
                               [&](std::size_t i) {
                                 return model.skeleton.key(weights_study::strongest_bone(model.weights, i)) !=
                                        only_bone;
                               }),
                order.end());
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
    const glm::vec3 p = model.mesh.positions[i];
    std::fprintf(stderr, "point %zu (%.4g, %.4g, %.4g) moved %.4g  artist %s| auto %s\n", i, double(p.x), double(p.y),
                 double(p.z), double(worst[i]), text(model.weights, i).c_str(), text(automatic, i).c_str());
  }
}

// Writes `text` to `path` atomically (a temporary beside it, then renamed over it).
void write_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error(temporary.string() + ": cannot write");
  }
  std::filesystem::rename(temporary, path);
}

// The points welded by exact position, in order of first appearance (as heat welds them): Blender's bone heat needs
// a connected surface, and a seam split into separate points would cut it (it then fails on the piece).
struct Welded {
  std::vector<glm::vec3> vertices;
  std::vector<std::uint32_t> point_vertex;  // per point
};

Welded weld(const deform::Mesh& mesh) {
  Welded w;
  std::map<std::array<float, 3>, std::uint32_t> index;
  for (const glm::vec3& p : mesh.positions) {
    const auto [at, added] = index.emplace(std::array<float, 3>{p.x, p.y, p.z}, std::uint32_t(w.vertices.size()));
    if (added) w.vertices.push_back(p);
    w.point_vertex.push_back(at->second);
  }
  return w;
}

// The tail given to Blender for bone b (docs/weights.md, "Side by side with Blender"): the head of its child, or the
// mean of its children's heads when it has several; a leaf (or a bone whose children all sit at its head) continues
// its parent's direction for the parent's length; a lone root points up by 5% of the mesh's diagonal. A tail at the
// head (Blender deletes such bones) gets the same 5% upwards.
glm::vec3 blender_tail(const deform::Skeleton& skeleton, std::size_t b, float diagonal) {
  const std::span<const glm::mat4> world = skeleton.bind_world();
  auto head = [&](std::size_t id) { return glm::vec3(world[id][3]); };
  const glm::vec3 h = head(b);
  const float tiny = 1e-5f * diagonal;
  glm::vec3 sum(0.0f);
  int count = 0;
  for (std::int32_t c : skeleton.bones()[b].children)
    if (glm::length(head(static_cast<std::size_t>(c)) - h) > tiny) {
      sum += head(static_cast<std::size_t>(c));
      ++count;
    }
  glm::vec3 tail = h;
  if (count > 0) tail = sum / float(count);
  const std::int32_t parent = skeleton.bones()[b].parent;
  if (glm::length(tail - h) <= tiny && parent >= 0) tail = h + (h - head(static_cast<std::size_t>(parent)));
  if (glm::length(tail - h) <= tiny) tail = h + glm::vec3(0.0f, 0.05f * diagonal, 0.0f);
  return tail;
}

// NAME.bind.json for blender_heat.py: the welded bind mesh, each point's welded vertex, and the bones (named "b<id>"
// in Blender, since imported names may be empty, shared or too long for it) with head, tail, parent and whether
// they deform.
void export_for_blender(const std::filesystem::path& dir, const std::string& name, const deform::Model& model,
                        const std::vector<std::uint8_t>& deforming) {
  const Welded w = weld(model.mesh);
  const deform::Bounds bounds = deform::compute_bounds(model.mesh.positions);
  const float diagonal = std::max(glm::length(bounds.max - bounds.min), 1e-30f);
  nlohmann::json j;
  j["model"] = name;
  j["vertices"] = nlohmann::json::array();
  for (const glm::vec3& v : w.vertices) j["vertices"].push_back({v.x, v.y, v.z});
  j["point_vertex"] = w.point_vertex;
  j["triangles"] = nlohmann::json::array();
  const deform::Mesh& mesh = model.mesh;
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    std::array<std::uint32_t, 3> c{};
    for (std::size_t k = 0; k < 3; ++k) c[k] = w.point_vertex.at(mesh.vertex_point.at(mesh.triangles[t + k]));
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    j["triangles"].push_back(c);
  }
  j["bones"] = nlohmann::json::array();
  const std::span<const glm::mat4> world = model.skeleton.bind_world();
  for (std::size_t b = 0; b < model.skeleton.bone_count(); ++b) {
    const glm::vec3 h(world[b][3]), t = blender_tail(model.skeleton, b, diagonal);
    j["bones"].push_back({{"name", "b" + std::to_string(b)},
                          {"key", model.skeleton.key(static_cast<std::int32_t>(b))},
                          {"head", {h.x, h.y, h.z}},
                          {"tail", {t.x, t.y, t.z}},
                          {"parent", model.skeleton.bones()[b].parent},
                          {"deform", deforming.empty() || deforming[b] != 0}});
  }
  std::filesystem::create_directories(dir);
  write_atomically(dir / (name + ".bind.json"), j.dump());
}

// Blender's weights from NAME.blender.json (blender_heat.py): per welded vertex, its vertex groups' weights. Every
// influence is kept (Blender's armature uses them all, normalised); a vertex Blender left in no group keeps no
// influence, so that it stays where it is, as it does in Blender. `seconds`: Blender's bind time.
deform::SkinWeights read_blender_weights(const std::filesystem::path& file, const deform::Model& model, double& seconds,
                                         std::string& version) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
    seconds = j.at("seconds").get<double>();
    version = j.at("blender").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(file.string() + ": " + e.what());
  }
  if (!j.contains("weights") || !j["weights"].is_array())
    throw std::runtime_error(file.string() + ": \"weights\" is not an array");
  const nlohmann::json& per_vertex = j["weights"];
  const Welded w = weld(model.mesh);
  if (per_vertex.size() != w.vertices.size())
    throw std::runtime_error(file.string() + ": " + std::to_string(per_vertex.size()) + " vertices, the model has " +
                             std::to_string(w.vertices.size()));
  deform::SkinWeights weights;
  for (std::uint32_t v : w.point_vertex) {
    std::vector<std::uint16_t> bones;
    std::vector<float> values;
    const nlohmann::json& groups = per_vertex.at(v);
    if (!groups.is_object())
      throw std::runtime_error(file.string() + ": vertex " + std::to_string(v) + ": not an object");
    for (const auto& [group, value] : groups.items()) {
      const bool named = group.size() > 1 && group[0] == 'b' &&
                         group.find_first_not_of("0123456789", 1) == std::string::npos && group.size() < 8;
      const unsigned long bone = named ? std::stoul(group.substr(1)) : ~0ul;
      if (bone >= model.skeleton.bone_count())
        throw std::runtime_error(file.string() + ": vertex " + std::to_string(v) + ": unknown group " + group);
      if (!value.is_number() || !std::isfinite(value.get<double>()))
        throw std::runtime_error(file.string() + ": vertex " + std::to_string(v) + ": group " + group +
                                 ": weight is not a finite number");
      if (value.get<float>() > 0.0f) {
        bones.push_back(static_cast<std::uint16_t>(bone));
        values.push_back(value.get<float>());
      }
    }
    if (bones.empty()) {
      weights.bones.emplace_back(0);
      weights.weights.emplace_back(0.0f);
    } else {
      deform::append_influences(weights, bones, values);
    }
  }
  return weights;
}

}  // namespace

int main(int argc, char** argv) {
  int samples = 8;
  int random_poses = 0;
  std::uint32_t seed = 1;
  bool all_bones = false;
  bool detail = false;
  std::string detail_bone;
  int voxel_resolution = 128;
  int digits = 2;
  std::string blender_export, blender_weights;
  deform::HeatWeightsOptions heat_options;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--samples" && i + 1 < argc) samples = std::atoi(argv[++i]);
    else if (a == "--random-poses" && i + 1 < argc) random_poses = std::atoi(argv[++i]);
    else if (a == "--seed" && i + 1 < argc) seed = static_cast<std::uint32_t>(std::strtoul(argv[++i], nullptr, 10));
    else if (a == "--all-bones") all_bones = true;
    else if (a == "--heat" && i + 1 < argc) heat_options.heat = std::strtof(argv[++i], nullptr);
    else if (a == "--no-visibility") heat_options.visibility = false;
    else if (a == "--oblique" && i + 1 < argc) heat_options.oblique_penalty = std::strtof(argv[++i], nullptr);
    else if (a == "--max-influences" && i + 1 < argc) heat_options.max_influences = std::atoi(argv[++i]);
    else if (a == "--detail") detail = true;
    else if (a == "--detail-bone" && i + 1 < argc) {
      detail = true;
      detail_bone = argv[++i];
    } else if (a == "--resolution" && i + 1 < argc) voxel_resolution = std::atoi(argv[++i]);
    else if (a == "--digits" && i + 1 < argc) digits = std::atoi(argv[++i]);
    else if (a == "--blender-export" && i + 1 < argc) blender_export = argv[++i];
    else if (a == "--blender-weights" && i + 1 < argc) blender_weights = argv[++i];
    else paths.push_back(a);
  }
  if (paths.empty() || samples < 1 || random_poses < 0 || digits < 0 || digits > 6) {
    std::fprintf(
        stderr,
        "usage: weights_study [--samples N | --random-poses N [--seed S]] [--all-bones] [--detail | --detail-bone B] "
        "[--heat C] "
        "[--oblique K] [--no-visibility] [--max-influences N] [--resolution N] [--digits N] [--blender-export DIR] "
        "[--blender-weights DIR] MODEL...\n");
    return 2;
  }
  if (random_poses > 0) std::printf("random poses: %d, seed %u\n\n", random_poses, seed);
  std::printf(
      "| model | points | bones (deforming) | clips (poses) | method | mean | p99 | max | strongest bone differs "
      "| bind time |\n|---|---|---|---|---|---|---|---|---|---|\n");
  int failures = 0;
  for (const std::string& path : paths) {
    try {
      const deform::ImportedModel imported = deform::import_model(path);
      const deform::Model& model = imported.model;
      const std::string name = file_name(path);
      const std::vector<std::uint8_t> weighted = deform::weighted_bones(model.weights, model.skeleton.bone_count());
      std::vector<std::uint8_t> deforming = weighted;
      std::size_t deforming_count = 0;
      for (std::uint8_t d : deforming) deforming_count += d;
      if (all_bones) {
        deforming.clear();
        deforming_count = model.skeleton.bone_count();
      }
      if (!blender_export.empty()) export_for_blender(blender_export, name, model, deforming);
      const std::vector<std::vector<glm::mat4>> palettes =
          random_poses > 0 ? weights_study::random_palettes(model.skeleton, weighted, random_poses, seed)
                           : weights_study::clip_palettes(model.skeleton, imported.clips, samples);

      struct Run {
        std::string method;
        deform::SkinWeights weights;
        double seconds;
      };
      std::vector<Run> runs;
      {
        deform::AutoWeightsOptions o;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::SkinWeights w = deform::compute_automatic_weights(model.mesh, model.skeleton, o);
        runs.push_back({"distance", std::move(w), seconds_since(start)});
      }
      {
        deform::HeatWeightsOptions o = heat_options;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::WeightsResult r = deform::compute_heat_weights(model.mesh, model.skeleton, o);
        const double took = seconds_since(start);
        for (const std::string& w : r.warnings) std::fprintf(stderr, "%s: heat: %s\n", name.c_str(), w.c_str());
        runs.push_back({"heat", std::move(r.weights), took});
      }
      {
        deform::VoxelWeightsOptions o;
        o.resolution = voxel_resolution;
        o.deforming = deforming;
        const auto start = std::chrono::steady_clock::now();
        deform::WeightsResult r = deform::compute_voxel_weights(model.mesh, model.skeleton, o);
        const double took = seconds_since(start);
        for (const std::string& w : r.warnings) std::fprintf(stderr, "%s: voxel: %s\n", name.c_str(), w.c_str());
        runs.push_back({"voxel", std::move(r.weights), took});
      }
      if (!blender_weights.empty()) {
        const std::filesystem::path file = std::filesystem::path(blender_weights) / (name + ".blender.json");
        if (std::filesystem::exists(file)) {
          double took = 0;
          std::string version;
          deform::SkinWeights w = read_blender_weights(file, model, took, version);
          runs.push_back({"blender " + version, std::move(w), took});
        } else {
          std::fprintf(stderr, "%s: no Blender weights (%s)\n", name.c_str(), file.string().c_str());
        }
      }
      if (detail)
        for (const Run& run : runs)
          if (run.method != "distance" && run.method != "voxel") {
            std::fprintf(stderr, "%s, %s:\n", name.c_str(), run.method.c_str());
            print_worst(model, palettes, run.weights, detail_bone);
          }
      for (const Run& run : runs) {
        const weights_study::Figures f = weights_study::compare_palettes(model, palettes, run.weights);
        std::printf("| %s | %zu | %zu (%zu) | %zu (%zu) | %s | %.*f%% | %.*f%% | %.*f%% | %.1f%% | %.3f s |\n",
                    name.c_str(), model.mesh.point_count(), model.skeleton.bone_count(), deforming_count,
                    random_poses > 0 ? std::size_t{0} : imported.clips.size(), f.poses, run.method.c_str(), digits,
                    f.mean_percent, digits, f.p99_percent, digits, f.max_percent, f.strongest_differs_percent,
                    run.seconds);
      }
      std::fflush(stdout);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", path.c_str(), e.what());
      ++failures;
    }
  }
  return failures == 0 ? 0 : 1;
}
