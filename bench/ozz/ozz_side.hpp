#pragma once
// The ozz-animation half of the side-by-side benchmark (ozz_side.cpp), behind plain data: neither ozz nor GLM types
// cross this header, so ozz_side.cpp may be compiled with ozz's own instruction-set flags (OZZ_SIMD_FLAGS) while the
// libdeform half is compiled as the project compiles its callers, and no inline function is built two ways.
// Conventions: bones are libdeform's ids (the skeleton order); matrices are 16 floats, column-major; quaternions are
// (x, y, z, w).
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ozz_side {

struct RigData {
  std::vector<std::string> names;  // unique per bone
  std::vector<int> parents;        // -1 for the root; a parent precedes its children
  std::vector<std::array<float, 3>> rest_translations;
  std::vector<std::array<float, 4>> rest_rotations;
  std::vector<std::array<float, 16>> inverse_bind;  // the skeleton's inverse bind matrices
};

// Linear keys of one clip, one track per bone (every bone has at least one key of each kind: the rest value where
// the clip does not animate it, since ozz's AnimationBuilder would give an empty track the identity instead).
struct ClipData {
  std::string name;
  float duration = 0.0f;
  std::vector<std::vector<float>> translation_times, rotation_times;
  std::vector<std::vector<std::array<float, 3>>> translations;
  std::vector<std::vector<std::array<float, 4>>> rotations;
};

// The skinned mesh, 4 influences per point: indices and weights as libdeform holds them (u16 × 4 and float × 4 per
// point); ozz reads the first three weights of each point (its last weight is 1 minus their sum).
struct MeshData {
  std::span<const float> positions, normals;  // 3 floats per point
  std::span<const std::uint16_t> indices;     // 4 per point
  std::span<const float> weights;             // 4 per point
};

class Runner {
 public:
  // Builds ozz's skeleton and the two clips (blended at `blend`: weight 1 - blend on clips[0], blend on clips[1])
  // with ozz's offline builders, and per-character buffers for `characters` characters. Throws std::runtime_error
  // when a builder refuses the data.
  Runner(const RigData& rig, std::span<const ClipData> clips, const MeshData& mesh, float blend, int characters);
  ~Runner();
  Runner(const Runner&) = delete;
  Runner& operator=(const Runner&) = delete;

  // Skinning alone: set_palette converts `palette` (one matrix per bone) to ozz's matrices once; skin() runs
  // ozz::geometry::SkinningJob of the whole mesh with them into the outputs (3 floats per point, the mesh's size).
  // False when ozz's job refuses.
  void set_palette(std::span<const std::array<float, 16>> palette);
  bool skin(std::span<float> out_positions, std::span<float> out_normals) const;
  // The mesh split into parts by influence count as ozz's fbx2mesh does (a point's count: its last slot with a
  // nonzero weight), one ozz SkinningJob per part with influences_count 1 to 4 and the part's own copies of the
  // points' data; results in part order (part_points(): the whole mesh's point of each output, part by part).
  bool skin_parts(std::span<float> out_positions, std::span<float> out_normals) const;
  std::vector<std::uint32_t> part_points() const;
  // The number of points of 1, 2, 3 and 4 influences.
  std::vector<std::size_t> part_sizes() const;
  // The same without normals (positions only).
  bool skin_positions(std::span<float> out_positions) const;
  // The whole frame of character `c` at `seconds`: sample both clips, blend, local to model, the skinning palette
  // (model × inverse bind), skin into the character's own outputs. False when a job refuses.
  bool frame(int c, float seconds);
  // frame() without the skinning: the pose and the palette only.
  bool pose(int c, float seconds);
  std::span<const float> positions(int c) const;
  std::span<const float> normals(int c) const;
  // Character c's model-space matrix of libdeform bone b after frame().
  std::array<float, 16> model(int c, int b) const;
  // "SSE2", "AVX2+FMA", ...: the SIMD path ozz's math was compiled for.
  static const char* simd_name();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ozz_side
