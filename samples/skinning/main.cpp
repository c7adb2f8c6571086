// skinning: the same pose skinned two ways, side by side. The forearm twists back and forth about its own axis;
// linear blend skinning (left) collapses the wrist into a "candy wrapper", dual quaternion skinning (right) keeps
// its volume. Shows the SkinningJob API: palette per frame, one job per method, no allocation per frame.
#include <cmath>

#include "deform/extras/builtin.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
#include "sample_app.hpp"

int main(int argc, char** argv) {
  const deform::Model model = deform::builtin_character();
  const deform::Skeleton& skeleton = model.skeleton;
  const std::int32_t forearm = skeleton.find("forearm_l");
  deform::Pose pose = skeleton.bind_pose();
  std::vector<glm::mat4> world(skeleton.bone_count()), palette(skeleton.bone_count());
  std::vector<deform::DualQuat> dual_quats(skeleton.bone_count());
  std::vector<glm::mat3> scales(skeleton.bone_count());
  std::vector<glm::vec3> lbs(model.mesh.point_count()), dqs(model.mesh.point_count());
  sample::PointMeshRenderer left, right;

  return sample::run_sample(
      argc, argv, "libdeform: LBS vs DQS",
      [&] {
        left.create(model.mesh);
        right.create(model.mesh);
      },
      [&](const sample::Frame& f) {
        // Twist the forearm about its bone axis (+Y in the built-in character) by up to ±150°, unclamped.
        const glm::vec3 bind = skeleton.bone(forearm).bind_rotation;
        skeleton.set_euler(pose, forearm, bind + glm::vec3(0.0f, 150.0f * std::sin(f.time), 0.0f), false);
        deform::LocalToWorldJob fk;
        fk.skeleton = &skeleton;
        fk.rotations = pose.rotations;
        fk.translations = pose.translations;
        fk.world = world;
        fk.palette = palette;
        fk.run();
        bool scaled = false;
        deform::compute_dual_quat_palette(palette, dual_quats, scales, scaled);

        deform::SkinningJob job;
        job.bone_indices = model.weights.bones;
        job.bone_weights = model.weights.weights;
        job.in_positions = deform::as_floats(std::span<const glm::vec3>(model.mesh.positions));
        job.matrices = palette;
        job.out_positions = deform::as_floats(std::span<glm::vec3>(lbs));
        job.run();
        job.method = deform::SkinningMethod::dqs;
        job.dual_quats = dual_quats;
        job.out_positions = deform::as_floats(std::span<glm::vec3>(dqs));
        job.run();

        const glm::mat4 shift(1.0f);
        left.draw(lbs, f, glm::translate(shift, glm::vec3(-0.9f, 0.0f, 0.0f)), glm::vec3(1.0f, 0.85f, 0.85f));
        right.draw(dqs, f, glm::translate(shift, glm::vec3(0.9f, 0.0f, 0.0f)), glm::vec3(0.85f, 0.9f, 1.0f));
      });
}
