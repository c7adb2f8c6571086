#pragma once
// Direct Delta Mush at bind time: each point's smoothed per-bone moments, for DirectDeltaMushJob
// (deform/runtime/direct_delta_mush.hpp; Le and Lewis 2019).
#include "deform/offline/export.hpp"
#include "deform/runtime/direct_delta_mush.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Which per-frame form a Character (Character::set_direct_delta_mush) or the CLI skins with: `full`, DirectDeltaMushJob
// on every influence's whole moments (10 floats) and the rotation fitted to each smoothed neighbourhood; `reduced`,
// DirectDeltaMushReducedJob on 4 floats an influence (reduce_direct_delta_mush) and the bones' rotations blended
// (deform/runtime/direct_delta_mush.hpp states both).
enum class DirectDeltaMushVariant : std::uint8_t { full, reduced };

struct DirectDeltaMushSettings {
  // The smoothing B = (I + λ L)⁻ᵖ: p = `iterations` implicit Laplacian steps of size λ = `step` over the point
  // adjacency (L = I − D⁻¹A, the uniform Laplacian: each point against its neighbours' mean, as Delta Mush smooths).
  // More of either widens the neighbourhood whose rotation a point takes: smoother bends, softer detail. Each step is
  // one sparse solve per moment and bone at bind time; none costs anything per frame. iterations in [1, 100], step > 0.
  int iterations = 4;
  float step = 2.0f;
  // The paper's translation/rotation split (its variants past 0): each moment becomes (1 − α) Ωᵢⱼ + α ψ'ᵢⱼ Ω̄ᵢ, where
  // ψ' are the weights smoothed with the smaller step κ = `translation_step` and Ω̄ᵢ is the point's smoothed centroid
  // alone (a single point: it adds position, not rotation). α = `translation_blend` in [0, 1): 0 is the paper's
  // variant 0 (κ unused); larger keeps more of the original weights' translation, sharper near joints.
  float translation_blend = 0.0f;
  float translation_step = 0.5f;
  // The isotropic spread added to every rest point (see runtime/direct_delta_mush.hpp): σᵢ² = `regularization` ·
  // (point i's neighbourhood variance per axis) + (1e-4 of the model's bounding-box diagonal)². In [0, 1]; 0 keeps
  // only the floor (the paper's equations, up to a spread far below the mesh's detail).
  float regularization = 0.05f;
  // Influences whose smoothed weight ψᵢⱼ is below `prune` times the point's total are dropped (implicit smoothing
  // reaches every bone a little), the rest kept however many: storage about (points · influences kept) · 42 bytes
  // for the rows, and as much again or a little more for the kernel's layout of them (DirectDeltaMushLanes: 46 bytes
  // a slot; 1.0 to 1.2 slots an influence on the benchmark's models). In [0, 0.5); 0 keeps every nonzero influence.
  float prune = 1e-3f;
  // The per-frame form its user runs (see DirectDeltaMushVariant). bind_direct_delta_mush ignores it: it always builds
  // the full binding, from which the reduced one is derived.
  DirectDeltaMushVariant variant = DirectDeltaMushVariant::full;
};

// Binds `mesh` (rest points: Mesh::positions) skinned by `weights` (one entry per point; any number of influences)
// for Direct Delta Mush. Points without neighbours are smoothed over themselves alone; points of zero weight take
// their neighbours' smoothed weights. Throws deform::Error (kind argument, element "direct delta mush") for settings
// out of range (naming the setting), weights not one per point, a weight not finite or negative or a bone index over
// 65535 (naming the point), rest points not finite (naming the point), a point whose whole connected part of the mesh
// has no weight ("point N: no bone influences it or any point connected to it"), moments beyond float range (a
// model of about 1e19 units and more: "point N: its moments overflow float ..."), and what build_point_topology
// throws. Cost: one sparse Cholesky factorisation, then iterations · 10 · bones sparse solves; allocates the binding.
DEFORM_OFFLINE_API DirectDeltaMushBinding bind_direct_delta_mush(const Mesh& mesh, const SkinWeights& weights,
                                                                 const DirectDeltaMushSettings& settings = {});

}  // namespace deform
