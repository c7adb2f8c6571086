#pragma once
// glTF 2.0 out (docs/gltf-export.md): a Model as a skinned mesh with its skeleton and clips, or a mesh whose
// deformation over time is baked into morph targets, so that any glTF viewer plays what libdeform computed.
//  - PATH ending in .glb (any case): one binary glTF file. PATH ending in .gltf: PATH plus STEM.bin beside it (STEM:
//    PATH's file name without .gltf, characters outside [A-Za-z0-9._-] replaced by '_'), which PATH names by a
//    relative URI. Nothing else is written.
//  - every file is written atomically (io/atomic_file.hpp); a .gltf and its .bin land together as one FileTransaction:
//    a failure at any step leaves both previous files as they were.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deform/io/export.hpp"
#include "deform/io/referenced_file.hpp"
#include "deform/runtime/animation.hpp"
#include "deform/runtime/model.hpp"

namespace deform {

// A deformation sampled over time: the mesh's points at each frame. Written as one morph target per frame (the
// displacement from the model's bind positions, a sparse accessor holding only the render vertices that move) and
// one animation whose weights select frame k at times[k] (weight 1 on target k, 0 on the others) and blend two
// neighbouring frames linearly in between, which is the linear interpolation of the positions.
struct BakedFrames {
  std::string name = "bake";                      // the animation's name
  std::vector<float> times;                       // seconds, finite, >= 0, strictly increasing; one per frame
  std::vector<std::vector<glm::vec3>> positions;  // per frame: one position per mesh point (Mesh::positions)
  // Per frame: one normal per render vertex (Mesh::vertex_normals), or empty for no NORMAL targets (viewers then
  // shade every frame with the bind normals).
  std::vector<std::vector<glm::vec3>> normals;
  // A displacement whose every component is within this of zero is stored as zero (left out of the sparse
  // accessor): skinning by a rest palette reproduces a point only to float rounding, and those differences would
  // otherwise store every vertex of every frame. Model units; normals: unit vectors.
  float position_tolerance = 0.0f;
  float normal_tolerance = 0.0f;
};

struct GltfExportOptions {
  // Skeletal clips, written as animations of the skeleton's nodes (translation and rotation tracks; a Pose has no
  // scale, so scale tracks are left out). Each must pass Animation::validate for the model's skeleton.
  std::span<const Animation> clips;
  // When set, the file holds the mesh without skin or skeleton plus the baked morph-target animation, and `clips`
  // must be empty (the frames already contain whatever moved the skeleton).
  const BakedFrames* baked = nullptr;
  // The up direction of the model's data (ImportedModel::up: +Z for IQM, the axis an FBX declares). glTF is +Y up, so
  // when this is another direction the file holds the model turned about the origin by the shortest turn that takes
  // it to +Y (points, normals, morph deltas, the root bone's bind and clip tracks, baked frames), and viewers and
  // engines show it standing. Must be finite and not zero; its length does not matter.
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  // Written as asset.generator.
  std::string generator = "libdeform";
  // The only folder textures are embedded from: a material's diffuse texture (Material::diffuse_map) is embedded in
  // the buffer when, with every symbolic link resolved, it lies inside this folder and is a PNG or JPEG file (the
  // image formats glTF 2.0 defines, by their first bytes). Any other is left out with a warning naming it, so a model
  // naming /etc/passwd as its texture leaks nothing. Empty: no texture is embedded. Each distinct texture is checked
  // once, from its first bytes, and read whole only to be embedded.
  std::string texture_root;
  // Folders besides texture_root textures may be embedded from, on purpose (resolve_referenced_file's policy).
  ReferencePolicy references;
};

struct GltfWritten {
  std::string gltf;                   // PATH as given
  std::string bin;                    // the .bin beside a .gltf; empty for .glb
  std::uint64_t bytes = 0;            // of every file written, together
  std::size_t vertices = 0;           // glTF vertices, over the primitives (a render vertex per submesh using it)
  std::size_t morph_targets = 0;      // targets written: the baked frames, or the model's morph targets
  std::size_t sparse_values = 0;      // displacements stored, over every target (POSITION and NORMAL each count)
  std::size_t textures = 0;           // images embedded
  std::vector<std::string> warnings;  // textures, clips or tracks left out (e.g. keys before t = 0), one line each
};

// Writes `model` as glTF 2.0 at `path` (.gltf or .glb). The mesh: one primitive per non-empty submesh, holding the
// render vertices its triangles use (each: its point's position, its normal normalised, TEXCOORD_0 as (u, 1 - v)
// when the mesh has UVs), with its material's diffuse colour and opacity as the base colour, or its diffuse texture
// (see `texture_root`) times its opacity. Without `baked`: a skin whose joints are the bones (node i = bone i, named
// Skeleton::key(i), its bind translation and rotation as the node's TRS; inverseBindMatrices from
// Skeleton::inverse_bind_world), JOINTS_0 and WEIGHTS_0 from `model.weights`, the model's morph targets (sparse
// POSITION, and NORMAL when any target has normal deltas; names in mesh.extras.targetNames) and the clips, each
// clip's morph channels as one `weights` channel on the mesh node. Throws deform::Error of
// kind argument for another extension, a model whose weights do not match its points, a mesh without triangles,
// inconsistent `baked` frames or an `up` that is zero or not finite; deform::Error naming the file when a file cannot
// be written. Cost: O(vertices · (1 + frames) + frames² + keys) time and the file's size in memory.
DEFORM_IO_API GltfWritten write_gltf(const std::string& path, const Model& model,
                                     const GltfExportOptions& options = {});

}  // namespace deform
