// The rig of the built-in character: the thesis' scene, three elastic lattices on one arm; and the same on every limb.
#include <initializer_list>
#include <string_view>

#include "deform/runtime/error.hpp"
#include "deform/offline/rig.hpp"
#include "deform/extras/builtin.hpp"
namespace deform {

BodyPart builtin_body_part(std::string_view bone) noexcept {
  if (bone.starts_with("upperarm") || bone.starts_with("thigh")) return BodyPart::upper_limb;
  if (bone.starts_with("forearm") || bone.starts_with("shin")) return BodyPart::lower_limb;
  if (bone.starts_with("hand")) return BodyPart::hand;
  if (bone.starts_with("foot")) return BodyPart::foot;
  return BodyPart::torso;
}

namespace {

// A rig with a lattice on each named bone, builtin_rig()'s springs, reach chain clavicle_l → hand_l.
Rig rig_on(const Model& model, std::initializer_list<const char*> bones) {
  const Skeleton& skeleton = model.skeleton;
  const auto bone = [&](const char* name) {
    const std::int32_t id = skeleton.find(name);
    if (id < 0)
      throw Error::in_file(model.name, std::string("bone '") + name + "'", "the built-in rig needs this bone");
    return id;
  };
  Rig rig;
  rig.model.builtin = true;
  for (const char* name : bones) {
    LatticeSpec spec;
    spec.name = name;
    spec.bone = bone(name);
    // Rubber: about 2 Hz, visibly under-damped (a few decaying swings, settled within about 1.6 s).
    spec.elastic.oscillator = {150.0f, 0.2f, 1.0f};
    // Flesh when it moves (set the inertia to feel it: 0 by default, the thesis' rubber arm): the part's bound and
    // far face share (default_lattice_motion), at no inertia.
    spec.motion = default_lattice_motion(builtin_body_part(name));
    spec.motion.inertia = 0.0f;
    rig.lattices.push_back(std::move(spec));
  }
  rig.reach_effector = bone("hand_l");
  rig.reach_root = bone("clavicle_l");
  // The ponytail swings: a spring chain (about 2.75 Hz, under-damped, under gravity) kept out of the head, the neck
  // and the upper back by three capsules on those bones (bone-local, bind pose; docs/builtin-character.md).
  rig.colliders = {
      {bone("head"), {0.0f, 0.07f, 0.01f}, {0.0f, 0.15f, 0.0f}, 0.085f},
      {bone("neck"), {0.0f, 0.0f, 0.0f}, {0.0f, 0.10f, 0.0f}, 0.055f},
      {bone("chest"), {0.0f, 0.05f, 0.0f}, {0.0f, 0.25f, 0.0f}, 0.11f},
  };
  SpringChainSpec ponytail;
  ponytail.name = "ponytail";
  ponytail.bones = {bone("ponytail1"), bone("ponytail2"), bone("ponytail3"), bone("ponytail4")};
  ponytail.tip = {0.0f, 0.06f, 0.0f};
  ponytail.frequency = 2.75f;
  ponytail.damping_ratio = 0.4f;
  ponytail.gravity = {0.0f, -9.81f, 0.0f};
  ponytail.radius = 0.02f;
  ponytail.colliders = {0, 1, 2};
  rig.spring_chains.push_back(std::move(ponytail));
  return rig;
}

}  // namespace

Rig builtin_rig(const Model& model) { return rig_on(model, {"upperarm_l", "forearm_l", "hand_l"}); }

Rig builtin_full_rig(const Model& model) {
  return rig_on(model, {"upperarm_l", "forearm_l", "hand_l", "upperarm_r", "forearm_r", "hand_r", "thigh_l", "shin_l",
                        "foot_l", "thigh_r", "shin_r", "foot_r"});
}

Character make_builtin_character() {
  Model model = builtin_character();
  const Rig rig = builtin_rig(model);
  return Character(std::move(model), rig);
}

}  // namespace deform
