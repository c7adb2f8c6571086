// ik_reach: CCD inverse kinematics. A target circles in front of the built-in character; each frame the left arm's
// chain (clavicle to hand) is solved toward it from the current pose, within every joint's DOF limits, and the mesh
// is skinned with the result. The orange point is the target, the skeleton is drawn on top.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "sample_app.hpp"

int main(int argc, char** argv) {
  const deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  const deform::IkChain chain = deform::make_chain(skeleton, skeleton.find("clavicle_l"), skeleton.find("hand_l"));
  std::vector<std::byte> scratch(deform::IkJob::scratch_size(chain.joint_count()));
  std::uint32_t random_state = deform::ik_random_seed;
  deform::Pose pose = skeleton.bind_pose();
  std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
  std::vector<glm::vec3> points(model.mesh.point_count());
  sample::PointMeshRenderer renderer;

  return sample::run_sample(
      argc, argv, "libdeform: CCD reach", [&] { renderer.create(model.mesh); },
      [&](const sample::Frame& f) {
        const glm::vec3 target(0.45f + 0.25f * std::cos(f.time), 1.35f + 0.3f * std::sin(f.time), 0.35f);
        deform::IkResult result;
        deform::IkJob ik;
        ik.chain = &chain;
        deform::chain_base(chain, pose.rotations, pose.translations, ik.base);
        ik.rotations = pose.rotations;
        ik.translations = pose.translations;
        ik.target = target;
        ik.settings.tolerance = 1e-3f;
        ik.scratch = scratch;
        ik.random_state = &random_state;
        ik.result = &result;
        ik.run();

        deform::LocalToWorldJob fk;
        fk.skeleton = &skeleton;
        fk.rotations = pose.rotations;
        fk.translations = pose.translations;
        fk.world = world;
        fk.palette = palette;
        fk.run();
        deform::SkinningJob job;
        job.matrices = palette;
        job.bone_indices = model.weights.bones;
        job.bone_weights = model.weights.weights;
        job.in_positions = deform::as_floats(std::span<const glm::vec3>(model.mesh.positions));
        job.out_positions = deform::as_floats(std::span<glm::vec3>(points));
        job.run();
        renderer.draw(points, f);

        for (std::size_t b = 1; b < skeleton.bone_count(); ++b) {
          const glm::vec3 head(world[b][3]), parent(world[std::size_t(skeleton.bone(std::int32_t(b)).parent)][3]);
          f.overlay->line(parent, head, glm::vec3(1.0f, 0.9f, 0.3f));
        }
        f.overlay->point(target, result.reached ? glm::vec3(0.2f, 1.0f, 0.3f) : glm::vec3(1.0f, 0.5f, 0.0f), 12.0f);
      });
}
