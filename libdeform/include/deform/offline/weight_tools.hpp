#pragma once
// The rigger's controls over skin weights (docs/weights.md, "Choosing the deforming bones" and "Weight tools"):
// which bones deform (glob patterns over bone names), and the tools a rigger applies to weights after binding —
// normalise, prune, limit, smooth over the surface, mirror left <-> right. All run once, offline; each allocates
// its result. Every tool leaves each point's weights normalised (summing to 1 within float rounding), strongest
// first, in SkinWeights' four slots and, past the fourth, its extras (skeleton.hpp). Every tool throws
// deform::Error (kind argument) for weights whose arrays disagree in size or hold a negative or non-finite weight
// (element "point N").
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "deform/offline/export.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/skeleton.hpp"
namespace deform {

// --- which bones deform ---

// Whether `name` matches the shell-style `pattern` as a whole (anchored at both ends, case-sensitive):
//   *        any run of characters, none included
//   ?        one character (a UTF-8 sequence counts as one)
//   [abc]    one of the listed bytes; [a-z] a range of bytes; [!abc] or [^abc] any byte not listed; a `]` right
//            after `[`, `[!` or `[^` is listed, not the end
//   \c       the character c itself (\*, \?, \[, \\)
// Throws deform::Error (kind argument, element "pattern 'P'") for an unclosed `[` or a trailing `\`. O(|pattern| ·
// |name|), no allocation.
DEFORM_OFFLINE_API bool glob_match(std::string_view pattern, std::string_view name);

// The deforming-bone mask the weight methods take (HeatWeightsOptions::deforming and the others): per bone id, 1
// when the bone matches one of `include` or is marked in `also` (all bones when both are empty) and matches none of
// `exclude`. `also` is empty or holds one entry per bone (weighted_bones(), say). A pattern that matches no bone is
// an error (kind argument, element "pattern 'P'", "matches no bone"): a misspelt name must not silently change
// nothing. So is a mask in which no bone is left (element "bones", "no bone deforms"). O(patterns × bones × name
// length).
DEFORM_OFFLINE_API std::vector<std::uint8_t> select_bones(const Skeleton& skeleton,
                                                          std::span<const std::string> include,
                                                          std::span<const std::string> exclude = {},
                                                          std::span<const std::uint8_t> also = {});

// Per bone id (bone_count entries), 1 when some point gives it a positive weight (in a slot or past the fourth):
// the bones a skin uses. A bone id at or past bone_count is ignored.
DEFORM_OFFLINE_API std::vector<std::uint8_t> weighted_bones(const SkinWeights& weights, std::size_t bone_count);

// --- weight tools ---

// Scales each point's weights to sum 1. A point with no positive weight is bound to bone 0 with weight 1 (a
// SkinWeights from read_skw or a weight method never has one). O(points).
DEFORM_OFFLINE_API void normalize_weights(SkinWeights& weights);

// Normalises each point, drops its influences below `threshold` and renormalises the rest; a point whose influences
// all lie below it keeps its strongest alone (ties: the lower bone id). Afterwards no weight is below `threshold`
// (within float rounding). Throws deform::Error (kind argument) unless 0 <= threshold <= 1. Returns the number of
// influences removed. O(points × influences).
DEFORM_OFFLINE_API std::size_t prune_weights(SkinWeights& weights, float threshold);

// Keeps each point's `count` strongest influences (ties: the lower bone id), renormalised. Throws deform::Error
// (kind argument) unless 1 <= count <= max_requested_influences. Returns the number of points that lost influences.
DEFORM_OFFLINE_API std::size_t limit_influences(SkinWeights& weights, int count);

struct SmoothWeightsOptions {
  int iterations = 1;   // 0 .. 1000 passes
  float factor = 0.5f;  // (0, 1]: each pass, w = (1 - factor) · own + factor · mean of the neighbours
  // 1 .. max_requested_influences: the strongest kept per point after the last pass (smoothing spreads a bone to
  // the neighbours of every point that has it), renormalised.
  int max_influences = deform::max_influences;
};

// Laplacian smoothing of the weights over the surface: points at exactly the same position are one vertex (a seam
// of split points stays closed: its points end with the same weights, their mean if they differed), two vertices
// are neighbours when a triangle joins them, and each pass sets every vertex's weights to (1 - factor) · its own +
// factor · the mean of its neighbours' (a vertex with no neighbour keeps its own). Sums stay 1, and before the final
// cut to `max_influences` no pass increases the energy Σ over edges and bones of (w_a − w_b)², the "gradient" a
// rigger sees as hard seams (the pass is (1 − f)·I + f·D⁻¹A, whose eigenvalues lie in [1 − 2f, 1]). Throws
// deform::Error (kind argument) for options out of range, weights not one per point, or a triangle index out of
// range. O(iterations × (edges + points) × influences).
DEFORM_OFFLINE_API void smooth_weights(SkinWeights& weights, const Mesh& mesh,
                                       const SmoothWeightsOptions& options = {});

// The energy smooth_weights lowers: Σ over the distinct edges {a, b} of the mesh's triangles (points welded by
// exact position as there, so an edge counts once) and over the bones of (w_a(bone) − w_b(bone))². O(edges ×
// influences).
DEFORM_OFFLINE_API double weight_gradient_energy(const SkinWeights& weights, const Mesh& mesh);

// The name of a bone's mirror partner: every side token of `name` swapped, or nullopt when it has none (a bone on
// the middle). With `pairs` empty the built-in rules apply:
//  - `L`/`R` and `l`/`r` standing alone between separators (`.`, `_`, `-`, space) or the name's ends:
//    `Hand.L` <-> `Hand.R`, `hand_l` <-> `hand_r`, `L_Hand` <-> `R_Hand`, `Arm.L.001` <-> `Arm.R.001`;
//  - the words `Left`/`Right`, `left`/`right`, `LEFT`/`RIGHT` (case kept): `LeftArm` <-> `RightArm`,
//    `B_Finger3_Left` <-> `B_Finger3_Right`. `Left`, `LEFT` begin a word: at the start, after a non-letter or after
//    a lower-case letter (`upperArmLeft`); `left` after no letter and before no lower-case letter; so `Bright` and
//    `Leftover` hold no side.
// With `pairs`, only those apply: each (A, B) swaps every occurrence of A with B and of B with A, plain substrings,
// the leftmost first. The mapping is its own inverse on any name the rules read the same way on both sides.
DEFORM_OFFLINE_API std::optional<std::string> mirrored_bone_name(
    std::string_view name, std::span<const std::pair<std::string, std::string>> pairs = {});

enum class MirrorMode {
  flip,           // every point takes its mirror point's weights with the sides swapped (twice = unchanged)
  from_positive,  // the points on the axis' negative side take their mirror's; the positive side is kept
  from_negative,  // the other way round
};

struct MirrorWeightsOptions {
  MirrorMode mode = MirrorMode::flip;
  int axis = -1;               // 0, 1, 2 = x, y, z; -1: the axis along which the bone pairs lie farthest apart
  std::optional<float> plane;  // the symmetry plane's coordinate on `axis`; default: the mean of the bone pairs'
                               // midpoints there, 0 when the skeleton has no pair
  float tolerance = -1.0f;     // > 0: a point's mirror lies this close to its reflection; < 0: 0.1% of the points'
                               // bounding-box diagonal (a point's partner on the plane is itself)
  std::vector<std::pair<std::string, std::string>> name_pairs;  // mirrored_bone_name's `pairs`
};

struct MirrorWeightsResult {
  SkinWeights weights;
  int axis = 0;                // the axis used
  float plane = 0.0f;          // the plane used
  std::size_t bone_pairs = 0;  // bones with a partner other than themselves, each pair counted once
  std::size_t points = 0;      // points that took their mirror's weights
};

// Mirrors the weights left <-> right. A point's mirror is the point nearest to its reflection across the plane
// (ties: the lower index), within `tolerance`. A bone's partner is the bone named mirrored_bone_name(name), itself
// for a middle bone. Throws deform::Error (kind argument) when the skeleton has no bone pair and `axis` is -1, for
// options out of range, weights not one per point, a point that takes its mirror's weights but has no mirror
// within the tolerance (element "point N", its position and the distance to the nearest), and a bone that carries
// weight on such a mirror point but has a side and no partner (element "bone 'NAME' (id N)", naming the name
// looked for) or a partner name that several bones share. O(points × influences + bones), a sort of the points.
DEFORM_OFFLINE_API MirrorWeightsResult mirror_weights(const SkinWeights& weights, const Mesh& mesh,
                                                      const Skeleton& skeleton,
                                                      const MirrorWeightsOptions& options = {});

}  // namespace deform
