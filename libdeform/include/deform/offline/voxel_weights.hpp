#pragma once
// Automatic skin weights by geodesic voxel binding (after Dionne & de Lasa 2013, "Geodesic Voxel Binding for
// Production Character Meshes"): distances to the bones measured *inside the body's volume*, so a hand resting
// against a thigh is far from the thigh's bone (the path must go up the arm and down the leg). docs/weights.md
// describes it and measures it against the weights artists painted.
//
// The method:
//  1. Voxelise: a grid of `resolution` voxels along the longest side of the points' bounding box; voxels the
//     triangles pass through are surface, voxels reached from outside the grid without crossing the surface are
//     outside, the rest (surface and inside) is the volume. An open mesh leaks: its volume is then its surface shell.
//  2. Bones are segments as for heat weights (heat_weights.hpp, step 1; leaves end where they leave the mesh); the
//     volume voxels a bone passes through are its seeds (a bone outside the volume seeds the volume voxels next to
//     it).
//  3. For each bone, the geodesic distance from its seeds to every volume voxel (Dijkstra over the 26 neighbours,
//     steps of 1, √2, √3 voxels). A point's distance to a bone is that of its voxel plus half a voxel.
//  4. As for distance weights (weights.hpp, steps 3–5): only the geodesically nearest bone, its parent and its
//     children compete, each gets (d_nearest / d_bone)^falloff_power, the strongest `max_influences` are kept and
//     normalised, then `smoothing_iterations` passes of one-ring averaging.
// A point that no bone reaches through the volume (a piece of the mesh whose volume holds no bone and touches none
// that does) is bound rigidly to its nearest bone in a straight line; a warning names how many and the first.
// Cost: O(triangles × their area in voxels + resolution³) to voxelise, one Dijkstra per deforming bone over the
// volume voxels, O(points × bones); memory O(resolution³ + points × bones).
#include <cstdint>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/offline/heat_weights.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

struct VoxelWeightsOptions {
  int resolution = 128;          // 8 .. 1024: voxels along the longest side of the bounding box
  float falloff_power = 4.0f;    // > 0; higher = sharper transitions at the joints
  float leaf_length = 1.0f;      // >= 0: a leaf bone's length as a multiple of its distance to its parent
  int max_influences = 4;        // 1 .. deform::max_influences
  int smoothing_iterations = 2;  // >= 0: passes of one-ring averaging
  // Per bone id, 0 for a bone that must get no weight; empty = every bone deforms. At least one bone must deform.
  std::vector<std::uint8_t> deforming;
};

// Geodesic voxel weights for the mesh's points (mesh.point_count() entries), with warnings (bones that get no
// vertex, points no bone reaches through the volume). Throws deform::Error (kind argument) for invalid options, a
// non-finite point or a triangle index out of range.
DEFORM_OFFLINE_API WeightsResult compute_voxel_weights(const Mesh& mesh, const Skeleton& skeleton,
                                                       const VoxelWeightsOptions& options = {});

}  // namespace deform
