// An engine that links deform::runtime alone: forward kinematics and skinning of one bone, in a translation unit whose
// GLM code uses the colour and texture names (v.r, v.s) that GLM_FORCE_XYZW_ONLY would take away.
#include <cstdio>
#include <vector>

#include <glm/glm.hpp>

#include <deform/runtime/skeleton.hpp>
#include <deform/runtime/skinning.hpp>
#include <deform/version.hpp>

int main() {
  const glm::vec4 colour(0.25f, 0.5f, 0.75f, 1.0f);
  const float red = colour.r + colour.s * 0.0f;  // the engine's own GLM code
  std::vector<deform::Bone> bones(2);
  bones[0].name = "root", bones[0].children = {1};
  bones[1].name = "tip", bones[1].parent = 0, bones[1].bind_translation = glm::vec3(0.0f, 1.0f, 0.0f);
  const deform::Skeleton skeleton(bones);
  deform::Pose pose = skeleton.bind_pose();
  pose.rotations[0] = deform::quat_from_euler(glm::vec3(0.0f, 0.0f, 90.0f));  // Rz(90°): +Y goes to -X
  std::vector<glm::mat4> world(2), palette(2);
  deform::LocalToWorldJob fk;
  fk.skeleton = &skeleton;
  fk.rotations = pose.rotations;
  fk.translations = pose.translations;
  fk.world = world;
  fk.palette = palette;
  if (!fk.validate() || !fk.run()) return 1;
  const std::vector<glm::u16vec4> ids(1, glm::u16vec4(1, 0, 0, 0));
  const std::vector<glm::vec4> weights(1, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  const std::vector<glm::vec3> in(1, glm::vec3(0.0f, 2.0f, 0.0f));
  std::vector<glm::vec3> out(1);
  deform::SkinningJob job;
  job.matrices = palette, job.bone_indices = ids, job.bone_weights = weights;
  job.in_positions = deform::as_floats(in), job.out_positions = deform::as_floats(out);
  if (!job.validate() || !job.run()) return 1;
  std::printf("libdeform %s runtime: (0, 2, 0) skinned to (%.3f, %.3f, %.3f); red %.2f\n", DEFORM_VERSION_STRING,
              out[0].x, out[0].y, out[0].z, red);
  return (out[0].x < -1.999f && out[0].x > -2.001f && red == 0.25f) ? 0 : 1;
}
