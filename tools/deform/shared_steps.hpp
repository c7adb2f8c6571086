#pragma once
// Steps that more than one command takes, written once.
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "cli.hpp"
#include "model_loading.hpp"
#include "deform/character/character.hpp"
#include "deform/io/gltf_export.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"
namespace cli {

// The model a rig file names (`simulate`, `bake`), its paths taken relative to the rig file's folder; the loader's
// warnings go to stderr. Throws deform::Error naming the rig file when it names no model.
// The model's files are confined to the rig file's folder and `policy`'s (resolve_referenced_file), as any file a
// model names is.
model_loading::LoadedModel load_rig_model(const deform::RigModel& named, const std::string& rig_path,
                                          const deform::ReferencePolicy& policy = {});

// What a file holds, by its first bytes, in words for an error ("a glTF binary", "a skeleton (.sk)", "a rig JSON
// file", ...; "a folder", "an empty file", "a file that cannot be read"): so that a file given in the wrong place is
// named for what it is. Reads at most the first 64 KiB.
std::string describe_file(const std::string& path);

// The text of a rig file (`--rig FILE`, or a RIG.json positional). Throws deform::Error naming the file when it cannot
// be read or is plainly something else ("x.glb: expected a rig JSON file (--rig), got a glTF binary").
std::string read_rig_text(const std::string& path);

// The model and rig of a command that animates a character (`ik`, `simulate`, `bake`), from its arguments:
//   --builtin | MODEL | MESH.obj --skeleton S.sk --weights W.skw   (cli::load_model), with --rig FILE's rig, or else
//                                   the model's starting rig (model_loading::starting_rig);
//   RIG.json, or --rig FILE alone   the rig and the model its "model" key names (relative to the rig's folder).
// The command must accept rig_value_flags and model_switch_flags. Loader warnings go to stderr.
inline const std::vector<std::string> rig_value_flags = {"--skeleton", "--weights", "--max-influences", "--rig",
                                                         "--allow-outside"};
struct RiggedModel {
  model_loading::LoadedModel loaded;  // its clips: the file's for an import, builtin_clips for the built-in one
  deform::Rig rig;
  deform::RigModel named;    // the model's files as read (paths from the current folder), for save_rig
  std::string texture_root;  // the model's folder ("." for the built-in character)
};
// With `need_rig` false and no rig file, `rig` is left empty instead (a command that names its bones itself need not
// fail where the default rig would).
RiggedModel load_rigged_model(const Args& args, bool need_rig = true);

// --inertia F (`simulate`, `bake`): every lattice's inertia at F, in [0, 1], of its body part's tuned inertia
// (deform::scaled_inertia), so that each part keeps its tuned character; nothing without the option.
void apply_inertia_option(const Args& args, deform::Rig& rig);

// Writes `rig` as a rig file at `path` (atomically) whose "model" names `named`'s files relative to `path`'s folder,
// so that the file alone brings its model back (`deform simulate RIG.json`).
void save_rig(const std::string& path, deform::Rig rig, const deform::RigModel& named,
              const deform::Skeleton& skeleton);

// The clip named `name` among `clips`; UsageError listing the clips there are when none has that name.
const deform::Animation& find_clip_or_fail(const std::vector<deform::Animation>& clips, const std::string& name);

// Plays a clip on a character as `simulate` and `bake` do: set(t) poses it as the clip is at t seconds, moving as the
// clip does there (the clip a millisecond later as set_pose's `later`, so that the lattices and spring chains feel
// its motion). The poses are held here, so a call allocates nothing. UsageError for a clip that does not fit.
class ClipPlayer {
 public:
  ClipPlayer(deform::Character& character, const deform::Animation& clip);
  void set(double t);

 private:
  void sample(double t, deform::Pose& into) const;
  deform::Character& character_;
  const deform::Animation& clip_;
  deform::Pose bind_, pose_, later_;
};

// Gives the built-in character's material its texture in memory (Material::diffuse_image), as the PNG
// samples/data/builtin.png holds (deform::builtin_texture(512)), so that glTF export embeds it with no file to read;
// nothing for another model, or in a build without stb (a note says the texture is left out).
void embed_builtin_texture(model_loading::LoadedModel& loaded);

// Render-vertex normals of a mesh deformed by `lattice` (`ffd`, `bake`): n' ∝ cof(J)·n with
// J = ∂Q/∂(u,v,w) · diag(size)⁻¹ at each deformed point's rest position (the mesh's own positions); the normals of
// points where `deformed` (one flag per point) is false are the mesh's. O(render vertices · lattice cost).
std::vector<glm::vec3> ffd_normals(const deform::Mesh& mesh, const deform::BezierLattice& lattice,
                                   const std::vector<bool>& deformed);

}  // namespace cli
