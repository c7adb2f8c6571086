// deform::Character: reach, release, update, and views of what it shows.
#include <algorithm>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common.hpp"
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"

namespace deform_python {

std::string method_name(deform::SkinningMethod method);
deform::SkinningMethod parse_method(const std::string& name);

namespace {

// A morph target by index or by name (the first of that name); deform.Error when there is none.
std::size_t morph_index(const deform::Character& c, const py::object& target) {
  if (py::isinstance<py::str>(target)) {
    const std::string name = target.cast<std::string>();
    const std::int32_t k = deform::find_morph_target(c.model().morph_targets, name);
    if (k < 0) throw deform::Error::invalid_argument("morph target '" + name + "'", "no morph target of that name");
    return static_cast<std::size_t>(k);
  }
  const auto k = target.cast<std::int64_t>();
  if (k < 0 || static_cast<std::size_t>(k) >= c.morph_target_count())
    throw deform::Error::invalid_argument("morph target " + std::to_string(k), "morph target out of range");
  return static_cast<std::size_t>(k);
}

using CharacterClass = py::class_<deform::Character>;

void bind_reach_result(py::module_& m) {
  py::class_<deform::ReachResult>(m, "ReachResult")
      .def_property_readonly("ok", [](const deform::ReachResult& r) { return r.status.ok(); })
      .def_readonly("residual", &deform::ReachResult::residual, "|target - effector| after IK alone (model units)")
      .def_readonly("stretch", &deform::ReachResult::stretch, "total stretch asked of the lattices (model units)")
      .def_readonly("distance", &deform::ReachResult::distance, "|target - effector| once the stretch has settled")
      .def_readonly("iterations", &deform::ReachResult::iterations)
      .def("__repr__", [](const deform::ReachResult& r) {
        return "ReachResult(residual=" + std::to_string(r.residual) + ", stretch=" + std::to_string(r.stretch) +
               ", distance=" + std::to_string(r.distance) + ")";
      });
}

// The constructors, the model and skeleton it holds, the held pose.
void bind_character_construction(CharacterClass& character) {
  character
      .def(py::init([](const deform::Model& model, const deform::Rig* rig) {
             return rig ? std::make_unique<deform::Character>(model, *rig) : std::make_unique<deform::Character>(model);
           }),
           py::arg("model"), py::arg("rig") = py::none(),
           "Binds `rig`'s lattices to `model` (both copied into the character); without a rig, skinning and IK only.")
      .def_static(
          "builtin", []() { return std::make_unique<deform::Character>(deform::make_builtin_character()); },
          "The built-in character with its rig (three elastic lattices on the left arm).")
      .def_property_readonly(
          "model",
          [](py::object self) {
            return py::cast(std::make_shared<deform::Model>(self.cast<deform::Character&>().model()));
          },
          "A copy of the character's model (bind pose).")
      .def_property_readonly("skeleton",
                             [](py::object self) {
                               return py::cast(&self.cast<deform::Character&>().skeleton(),
                                               py::return_value_policy::reference_internal, self);
                             })
      .def_property_readonly("point_count", [](const deform::Character& c) { return c.positions().size(); })
      .def_property_readonly("lattice_count", [](const deform::Character& c) { return c.deformers().lattice_count(); })
      .def_property(
          "pose", [](const deform::Character& c) { return c.pose(); },
          [](deform::Character& c, const deform::Pose& p) { check(c.set_pose(p)); },
          "The held pose (get: a copy; set: clamped into the DOF limits, raises deform.Error when refused).")
      .def(
          "set_pose",
          [](deform::Character& c, const deform::Pose& pose, const std::optional<deform::Pose>& later, float lead) {
            check(later ? c.set_pose(pose, *later, lead) : c.set_pose(pose));
          },
          py::arg("pose"), py::arg("later") = py::none(), py::arg("lead") = 1e-3f,
          "Holds `pose`; with `later`, the same motion `lead` seconds later (a clip sampled a millisecond ahead), from "
          "which update() takes the bones' velocities for the lattices' inertia and the spring chains: the same "
          "motion at any frame rate. Raises deform.Error when refused.");
}

// Secondary motion: the lattices' inertia and gravity, the spring chains.
void bind_character_motion(CharacterClass& character) {
  character
      .def(
          "set_lattice_motion",
          [](deform::Character& c, float inertia, const std::optional<FloatArray>& gravity, float units_per_metre,
             std::optional<std::size_t> lattice) {
            const glm::vec3 pull = gravity ? to_vec3(*gravity, "gravity") : glm::vec3(0.0f);
            const std::size_t count = c.deformers().lattice_count();
            if (lattice && *lattice >= count)
              throw deform::Error::invalid_argument("lattice " + std::to_string(*lattice), "lattice out of range");
            // Inertia and gravity change; each lattice keeps its along-bone bound and far-face share. For every
            // lattice the inertia scales each one's tuned inertia, its part's (scaled_inertia); for one, it is its.
            const auto with = [&](deform::LatticeMotion motion) {
              motion.inertia = lattice ? inertia : deform::scaled_inertia(motion.part, inertia);
              motion.gravity = pull, motion.units_per_metre = units_per_metre;
              return motion;
            };
            for (std::size_t l = lattice ? *lattice : 0; l < (lattice ? *lattice + 1 : count); ++l)
              deform::require_valid_motion(with(c.deformers().spec(l).motion));  // before any lattice changes
            for (std::size_t l = lattice ? *lattice : 0; l < (lattice ? *lattice + 1 : count); ++l)
              c.deformers().set_motion(l, with(c.deformers().spec(l).motion));
          },
          py::arg("inertia"), py::arg("gravity") = py::none(), py::arg("units_per_metre") = 1.0f,
          py::arg("lattice") = py::none(),
          "Secondary motion of one lattice (or every one, lattice=None): inertia in [0, 1] (how much its control "
          "points lag behind their bone's motion), gravity in m/s² (model space; default none). For every lattice "
          "inertia is a scale of each one's tuned inertia, its body part's: 1 the tuned jiggle (limbs keep their "
          "length), 0 none; a lattice with no part takes it as its inertia. For one lattice it is its inertia.")
      .def_property_readonly("spring_chain_count", [](const deform::Character& c) { return c.springs().chain_count(); })
      .def(
          "spring_points",
          [](py::object self, std::size_t chain) {
            auto& c = self.cast<deform::Character&>();
            if (chain >= c.springs().chain_count())
              throw deform::Error::invalid_argument("chain " + std::to_string(chain), "spring chain out of range");
            return vec3_view(c.springs().points(chain), self, false);
          },
          py::arg("chain"), "(B + 1, 3) read-only view of a spring chain's first head and tails, as of update().");
}

// Settings: the skinning method, the reach solver and its limits, pole and softening, IK iterations.
void bind_character_settings(CharacterClass& character) {
  character
      .def_property(
          "skinning", [](const deform::Character& c) { return method_name(c.settings.skinning); },
          [](deform::Character& c, const std::string& name) { c.settings.skinning = parse_method(name); },
          "'lbs' or 'dqs'.")
      .def_property(
          "reach_solver",
          [](const deform::Character& c) {
            return std::string(c.settings.reach_solver == deform::Character::ReachSolver::ccd ? "ccd" : "two_bone");
          },
          [](deform::Character& c, const std::string& name) {
            if (name == "ccd") c.settings.reach_solver = deform::Character::ReachSolver::ccd;
            else if (name == "two_bone") c.settings.reach_solver = deform::Character::ReachSolver::two_bone;
            else throw deform::Error::invalid_argument("reach_solver", "expected 'ccd' or 'two_bone'");
          },
          "'ccd' (the rig's chain) or 'two_bone' (the limb ending at the effector).")
      .def_property(
          "reach_limits",
          [](const deform::Character& c) {
            return std::string(c.settings.reach_limits == deform::Character::JointLimits::euler ? "euler"
                                                                                                : "swing_twist");
          },
          [](deform::Character& c, const std::string& name) {
            if (name == "euler") c.settings.reach_limits = deform::Character::JointLimits::euler;
            else if (name == "swing_twist") c.settings.reach_limits = deform::Character::JointLimits::swing_twist;
            else throw deform::Error::invalid_argument("reach_limits", "expected 'euler' or 'swing_twist'");
          },
          "How reach() limits the joints: 'euler' (the skeleton's DOF limits) or 'swing_twist' (derived from them).")
      .def_property(
          "reach_pole",
          [](const deform::Character& c) -> py::object {
            if (!c.settings.use_reach_pole) return py::none();
            return py::make_tuple(c.settings.reach_pole.x, c.settings.reach_pole.y, c.settings.reach_pole.z);
          },
          [](deform::Character& c, std::optional<FloatArray> pole) {
            c.settings.use_reach_pole = pole.has_value();
            if (pole) c.settings.reach_pole = to_vec3(*pole, "reach_pole");
          },
          "A model-space point the chain's middle bends toward (an elbow hint), or None.")
      .def_property(
          "reach_soften", [](const deform::Character& c) { return c.settings.reach_soften; },
          [](deform::Character& c, float soften) { c.settings.reach_soften = soften; },
          "two_bone: softening in [0, 1].")
      .def_property(
          "ik_max_iterations", [](const deform::Character& c) { return c.settings.ik.max_iterations; },
          [](deform::Character& c, int n) {
            if (n < 1) throw deform::Error::invalid_argument("ik_max_iterations", "must be >= 1");
            c.settings.ik.max_iterations = n;
          })
      .def_property(
          "lattice_fields", [](const deform::Character& c) { return c.settings.lattice_fields; },
          [](deform::Character& c, bool on) { c.settings.lattice_fields = on; });
}

// Delta Mush after the lattices, Direct Delta Mush as the skinning.
void bind_character_mush(CharacterClass& character) {
  character
      .def(
          "set_delta_mush",
          [](deform::Character& c, int iterations, float step, std::optional<FloatArray> mask) {
            deform::DeltaMushSettings settings;
            settings.iterations = iterations;
            settings.step = step;
            if (mask) {
              if (mask->ndim() != 1) throw deform::Error::invalid_argument("mask", "expected one weight per point");
              settings.mask = std::span<const float>(mask->data(), static_cast<std::size_t>(mask->size()));
            }
            c.set_delta_mush(settings);
          },
          py::arg("iterations") = 10, py::arg("step") = 0.5f, py::arg("mask") = py::none(),
          "Delta Mush after the lattices (docs/skinning.md): `iterations` in [0, 10000] (0: off), `step` in (0, 1], "
          "`mask` None or one weight per point in [0, 1] (0 keeps a point as skinned). Binds at once (call it at "
          "set-up); raises deform.Error for a value out of range.")
      .def("clear_delta_mush", &deform::Character::clear_delta_mush, "Turns Delta Mush off (the default).")
      .def_property_readonly(
          "delta_mush_iterations",
          [](const deform::Character& c) { return c.delta_mush() ? c.delta_mush()->iterations : 0u; },
          "The Delta Mush stage's iterations, 0 when it is off.")
      .def(
          "set_direct_delta_mush",
          [](deform::Character& c, int iterations, float step, float translation_blend, float translation_step,
             float regularization, float prune, const std::string& variant) {
            if (variant != "full" && variant != "reduced")
              throw deform::Error::invalid_argument("variant", "expected 'full' or 'reduced'");
            c.set_direct_delta_mush({iterations, step, translation_blend, translation_step, regularization, prune,
                                     variant == "reduced" ? deform::DirectDeltaMushVariant::reduced
                                                          : deform::DirectDeltaMushVariant::full});
          },
          py::arg("iterations") = 4, py::arg("step") = 2.0f, py::arg("translation_blend") = 0.0f,
          py::arg("translation_step") = 0.5f, py::arg("regularization") = 0.05f, py::arg("prune") = 1e-3f,
          py::arg("variant") = "full",
          "Direct Delta Mush as the skinning (docs/skinning.md), in place of `skinning` while bound; the settings as "
          "deform.DirectDeltaMush's; variant 'full' (default) or 'reduced' (4 floats an influence, the bones' "
          "rotations blended: docs/skinning.md, Reduced storage). Binds at once (a sparse factorisation: call it at "
          "set-up); raises deform.Error for a value out of range, changing nothing.")
      .def("clear_direct_delta_mush", &deform::Character::clear_direct_delta_mush,
           "Back to `skinning` (LBS or DQS), the default.")
      .def_property_readonly(
          "direct_delta_mush_bound",
          [](const deform::Character& c) {
            return c.direct_delta_mush() != nullptr || c.direct_delta_mush_reduced() != nullptr;
          },
          "Whether Direct Delta Mush (either variant) skins the character.")
      .def_property_readonly(
          "direct_delta_mush_variant",
          [](const deform::Character& c) {
            return std::string(c.direct_delta_mush() ? "full" : c.direct_delta_mush_reduced() ? "reduced" : "");
          },
          "'full' or 'reduced' while Direct Delta Mush is bound, else ''.");
}

// Levels of detail (docs/skinning.md, "Levels of detail"): bone levels built here from counts and a motion.
void bind_character_levels(CharacterClass& character) {
  character
      .def(
          "set_levels",
          [](deform::Character& c, const std::vector<std::size_t>& bones_per_level,
             const std::vector<deform::Pose>& poses, const std::vector<py::object>& keep,
             std::optional<std::vector<bool>> deformers, std::optional<std::vector<std::uint32_t>> update_interval,
             std::uint32_t blend_frames, std::optional<std::vector<std::vector<std::uint32_t>>> points) {
            deform::BoneLodSettings settings;
            settings.bones_per_level = bones_per_level;
            settings.poses = poses;
            for (const py::object& bone : keep) settings.keep.push_back(resolve_bone(c.skeleton(), bone));
            const std::size_t levels = bones_per_level.size() + 1;
            if ((deformers && deformers->size() != levels) || (update_interval && update_interval->size() != levels) ||
                (points && points->size() != levels))
              throw deform::Error::invalid_argument("levels",
                                                    "deformers, update_interval and points need one entry per level, "
                                                    "level 0 included");
            std::vector<deform::Character::LevelOptions> options(levels);
            for (std::size_t l = 0; l < levels; ++l) {
              if (deformers) options[l].deformers = (*deformers)[l];
              if (update_interval) options[l].update_interval = (*update_interval)[l];
              if (points) options[l].points = (*points)[l];
            }
            c.set_levels(deform::build_bone_lod(c.model(), settings), options, blend_frames);
          },
          py::arg("bones_per_level"), py::arg("poses") = std::vector<deform::Pose>{},
          py::arg("keep") = std::vector<py::object>{}, py::arg("deformers") = py::none(),
          py::arg("update_interval") = py::none(), py::arg("blend_frames") = 8u, py::arg("points") = py::none(),
          "Levels of detail: level 0 the whole character, then one level per entry of `bones_per_level` (bones it "
          "skins with, non-increasing), merged on the motion of `poses` (deform.Pose, e.g. a clip sampled over its "
          "length; none: by weight alone), `keep` bones (names or ids) kept at every level. `deformers` and "
          "`update_interval` (1 to 64): one per level, level 0 included (default: on, every update). A switch blends "
          "over `blend_frames` deformed updates. `points`: one list per level of the mesh's point ids it deforms (a "
          "simplified mesh's; [] for all), where `deformers` runs the spring chains alone; positions and normals "
          "outside a level's points keep stale values. Raises deform.Error naming what is wrong; call it at set-up.")
      .def(
          "set_level", [](deform::Character& c, std::size_t level) { check(c.set_level(level)); }, py::arg("level"),
          "Shows `level` from the next update() on (deform.Error when out of range).")
      .def_property_readonly("level", &deform::Character::level, "The level the next update() shows.")
      .def_property_readonly("level_count", &deform::Character::level_count, "1 without levels.")
      .def(
          "level_cost",
          [](const deform::Character& c, std::size_t level) {
            const deform::Character::LevelCost cost = c.level_cost(level);
            py::dict d;
            d["points"] = cost.points, d["influences"] = cost.influences, d["bones"] = cost.bones;
            d["deformers"] = cost.deformers, d["update_interval"] = cost.update_interval;
            return d;
          },
          py::arg("level"), "What a level's deformed update skins: points, influences, bones; its options.")
      .def_property_readonly("next_update_deforms", &deform::Character::next_update_deforms,
                             "False while an update_interval level only interpolates (it reads no pose).");
}

// Reach, release and update, and the views of what the character shows.
void bind_character_reach(CharacterClass& character) {
  character
      .def(
          "set_max_stretch", [](deform::Character& c, float s) { check(c.set_max_stretch(s)); }, py::arg("max_stretch"),
          "The largest stretch reach() asks of a lattice, in multiples of its length, [0, 1000].")
      .def(
          "reach",
          [](deform::Character& c, const py::object& effector, const FloatArray& target) {
            const deform::ReachResult r = c.reach(resolve_bone(c.skeleton(), effector), to_vec3(target, "target"));
            check(r.status);
            return r;
          },
          py::arg("effector"), py::arg("target"),
          "Reaches for `target` (model space) with the head of `effector` (id or name): IK, then a stretch target "
          "for the chain's lattices that update() springs toward. Raises deform.Error when refused.")
      .def("release", &deform::Character::release, "Lets go: the stretch springs back to zero.")
      .def(
          "update", [](deform::Character& c, float dt) { check(c.update(dt)); }, py::arg("dt"),
          "Advances the springs dt seconds and deforms: FK, skinning, lattices.")
      .def_property_readonly(
          "positions",
          [](py::object self) { return vec3_view(self.cast<deform::Character&>().positions(), self, false); },
          "(N, 3) read-only view of the deformed positions (no copy; changes with each update()).")
      .def(
          "normals", [](py::object self) { return vec3_view(self.cast<deform::Character&>().normals(), self, false); },
          "(V, 3) read-only view of the per-render-vertex normals, brought up to date by this call (no copy): call it "
          "again after each update(), which leaves the storage in per-point order until then.")
      .def(
          "control_points",
          [](py::object self, std::size_t lattice) {
            auto& c = self.cast<deform::Character&>();
            if (lattice >= c.deformers().lattice_count())
              throw deform::Error::invalid_argument("lattice " + std::to_string(lattice), "lattice out of range");
            return vec3_view(c.control_points(lattice), self, false);
          },
          py::arg("lattice"), "(P, 3) read-only view of a lattice's world control points.")
      .def(
          "bone_position",
          [](const deform::Character& c, const py::object& bone) {
            const glm::vec3 p = c.bone_position(resolve_bone(c.skeleton(), bone));
            return py::make_tuple(p.x, p.y, p.z);
          },
          py::arg("bone"), "World head of a bone, lattices included.");
}

// Morph targets (Model.morph_targets: an import's blend shapes), one weight per target.
void bind_character_morphs(CharacterClass& character) {
  character.def_property_readonly("morph_target_count", &deform::Character::morph_target_count)
      .def_property_readonly(
          "morph_target_names",
          [](const deform::Character& c) {
            std::vector<std::string> names;
            for (const deform::MorphTarget& t : c.model().morph_targets) names.push_back(t.name);
            return names;
          },
          "The targets' names, in index order (names may repeat across meshes).")
      .def_property(
          "morph_weights",
          [](const deform::Character& c) {
            const std::span<const float> w = c.morph_weights();
            py::array_t<float> out(static_cast<py::ssize_t>(w.size()));
            std::copy(w.begin(), w.end(), out.mutable_data());
            return out;
          },
          [](deform::Character& c, const FloatArray& weights) {
            if (weights.ndim() != 1)
              throw deform::Error::invalid_argument("morph_weights", "expected a 1-D array, one weight per target");
            check(
                c.set_morph_weights(std::span<const float>(weights.data(), static_cast<std::size_t>(weights.size()))));
          },
          "The morph weights update() applies (get: a copy; set: one finite weight per target). A new character "
          "starts from the targets' default weights.")
      .def(
          "morph_weight",
          [](const deform::Character& c, const py::object& target) {
            return c.morph_weights()[morph_index(c, target)];
          },
          py::arg("target"), "A target's weight, by index or name (the first of that name).")
      .def(
          "set_morph_weight",
          [](deform::Character& c, const py::object& target, float weight) {
            if (py::isinstance<py::str>(target)) {
              check(c.set_morph_weight(std::string_view(target.cast<std::string>()), weight));
            } else {
              check(c.set_morph_weight(morph_index(c, target), weight));
            }
          },
          py::arg("target"), py::arg("weight"),
          "Sets a target's weight by index, or every target of a name; raises deform.Error for an unknown target or "
          "a weight that is not finite.")
      .def(
          "set_morph_weights_from_clip",
          [](deform::Character& c, const deform::Animation& clip, float time) {
            check(c.set_morph_weights(clip, time));
          },
          py::arg("clip"), py::arg("time"),
          "The clip's animated morph weights at `time` seconds (the targets it does not animate keep theirs).")
      .def("reset_morph_weights", &deform::Character::reset_morph_weights, "Every weight back to its default.")
      .def(
          "add_pose_driver",
          [](deform::Character& c, const deform::PoseDriverBinding& driver, const std::vector<std::uint32_t>& targets) {
            check(c.add_pose_driver(driver, targets));
          },
          py::arg("driver"), py::arg("targets"),
          "Pose-space correctives: each update() sets morph target targets[s] to the driver's shape s weight at the "
          "pose (docs/skinning.md). Raises deform.Error for a driver or targets that do not fit.")
      .def("clear_pose_drivers", &deform::Character::clear_pose_drivers,
           "No pose drivers any more (the rig's corrective groups included).")
      .def(
          "with_driven_weights",
          [](const deform::Character& c, const deform::Animation& clip, float frames_per_second) {
            return deform::with_driven_weights(c, clip, frames_per_second);
          },
          py::arg("clip"), py::arg("frames_per_second") = 30.0f,
          "The clip with the pose drivers' weights keyed frames_per_second times a second, as update() sets them, "
          "so that write_gltf(path, character.model, [...]) plays the correctives in any glTF viewer "
          "(docs/gltf-export.md). Raises deform.Error for a rate outside (0, 1000] or a clip the skeleton refuses.")
      .def_property_readonly(
          "palette", [](const deform::Character& c) { return matrices_out(c.palette()); },
          "(B, 4, 4) float32 row-major skinning matrices of the last update (a new array): what add_corrective takes.");
}

}  // namespace

void bind_character(py::module_& m) {
  bind_reach_result(m);
  CharacterClass character(
      m, "Character",
      "A rigged model with its skin and elastic lattices: reach(), release(), update(dt), positions.\n"
      "positions and normals() are read-only views of the character's storage (no copy): they change with each "
      "update() and stay valid while the character lives (the view keeps it alive).");
  bind_character_construction(character);
  bind_character_motion(character);
  bind_character_settings(character);
  bind_character_mush(character);
  bind_character_levels(character);
  bind_character_reach(character);
  bind_character_morphs(character);
  character
      .def_property_readonly("stretch", &deform::Character::stretch, "The stretch the lattices have now (model units).")
      .def_property_readonly("effector", &deform::Character::effector);
  m.def("screen_height", &deform::screen_height, py::arg("extent"), py::arg("distance"), py::arg("vertical_fov"),
        "The fraction of a perspective viewport's height that `extent` at `distance` covers (fov in radians).");
  m.def(
      "pick_level",
      [](const std::vector<float>& thresholds, float height) { return deform::pick_level(thresholds, height); },
      py::arg("thresholds"), py::arg("height"),
      "The level for a screen height: how many of the decreasing `thresholds` it is below.");
}

}  // namespace deform_python
