// The rig of the built-in character: the thesis' scene, three elastic lattices on one arm; and the same on every limb.
#include <initializer_list>

#include "deform/runtime/error.hpp"
#include "deform/offline/rig.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/extras/builtin.hpp"
namespace deform {
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
    rig.lattices.push_back(std::move(spec));
  }
  rig.reach_effector = bone("hand_l");
  rig.reach_root = bone("clavicle_l");
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
