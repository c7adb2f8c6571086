#pragma once
// Free-form deformation lattices (Sederberg & Parry 1986; thesis §8.2.4, §9.4.1): a trivariate Bézier volume of any
// degree, a uniform cubic B-spline volume of any resolution, vertex binding, per-frame evaluation with Jacobian
// normals, bone-bound lattices (eq. 42) and direct manipulation (Hsu, Hughes & Kaufman 1992). docs/lattices.md.
//
// Two steps, as everywhere in libdeform:
//  - bind (once, deform::offline: offline/lattice_binding.hpp): choose the points (inside the box, an index list, a
//  bone's skin weights) and precompute each one's
//    lattice parameters. Allocates; O(points).
//  - evaluate (per frame): LatticeEvaluateJob reads the control points — a plain flat array that any module (an
//    elastic solver, an editor) rewrites each frame — and writes the bound points only. No allocation, no locks.
//
// Control point order, both lattice kinds: i-fastest, P(i, j, k) = points[i + nu·(j + nv·k)] where (nu, nv, nw) are
//   the point counts per axis and i, j, k run along the frame's U, V, W axes.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "deform/runtime/error.hpp"
#include "deform/runtime/export.hpp"
#include "deform/runtime/isa.hpp"
#include "deform/runtime/skeleton.hpp"

namespace deform {

// Highest Bézier degree per axis. Evaluation costs (l+1)(m+1)(n+1) control points per vertex; the Bernstein basis
// loses its locality as the degree grows, so beyond this a B-spline lattice is the better tool.
inline constexpr int max_bezier_degree = 16;
// Most control points per axis of a B-spline lattice (each vertex still touches only 4×4×4 of them).
inline constexpr int max_bspline_points = 1024;

// The box a lattice spans: origin X0 and edge vectors U, V, W (not necessarily orthogonal). A point X has lattice
// parameters (u, v, w) with X = X0 + u·U + v·V + w·W; the box is (u, v, w) ∈ [0, 1]³. The frame must be finite and
// right-handed with positive volume, (U × V)·W > 0.
struct DEFORM_RUNTIME_API LatticeFrame {
  glm::vec3 origin{0.0f};
  glm::vec3 u_axis{1.0f, 0.0f, 0.0f};
  glm::vec3 v_axis{0.0f, 1.0f, 0.0f};
  glm::vec3 w_axis{0.0f, 0.0f, 1.0f};

  // The axis-aligned box [origin, origin + size] (thesis eq. 41). `size` must be positive for a valid frame.
  static LatticeFrame axis_aligned(glm::vec3 origin, glm::vec3 size) noexcept;
  // (u, v, w) of a point: thesis eq. 36, u = (V×W)·(X−X0) / (V×W)·U and cyclically; for an axis-aligned frame
  // exactly (X − X0) / size (eq. 41).
  glm::vec3 to_lattice(glm::vec3 point) const noexcept;
  // X0 + u·U + v·V + w·W.
  glm::vec3 to_world(glm::vec3 uvw) const noexcept;
  // Throws deform::Error naming `source` and `element` when the frame is not finite or not of positive volume.
  void require_valid(const std::string& source = "<memory>", const std::string& element = "frame") const;
};

// Which lattice a binding was made for; evaluation needs the same kind and point counts.
enum class LatticeKind : std::uint8_t { bezier, bspline };

// The per-vertex data of a lattice, computed once by bind(). Vertices are stored in blocks of `block_size` lanes
// (structure of arrays, so 16 vertices evaluate at once); all lanes of a block share one lattice cell (B-spline) and
// padding lanes carry the vertex index `no_vertex`. Read-only after bind; share it between threads freely.
struct DEFORM_RUNTIME_API LatticeBinding {
  static constexpr std::size_t block_size = 16;
  static constexpr std::uint32_t no_vertex = std::numeric_limits<std::uint32_t>::max();

  LatticeKind kind = LatticeKind::bezier;
  glm::ivec3 point_counts{0};    // control points per axis of the lattice it was made for
  glm::mat3 normal_basis{1.0f};  // maps an input normal to the lattice's parameter space (cofactor of the frame)
  std::size_t vertex_count = 0;  // bound vertices, padding lanes excluded
  std::uint32_t max_vertex = 0;  // largest bound vertex index (valid when vertex_count > 0)

  // Per lane (size = block_count() · block_size): the point index, or no_vertex; the parameters within the cell.
  std::vector<std::uint32_t> vertices;
  std::vector<float> u, v, w;
  // Per block: first control point of its 4×4×4 cell (B-spline), 0 for Bézier.
  std::vector<std::uint32_t> block_first_point;

  std::size_t block_count() const noexcept { return block_first_point.size(); }
  std::size_t control_point_count() const noexcept {
    return static_cast<std::size_t>(point_counts.x) * static_cast<std::size_t>(point_counts.y) *
           static_cast<std::size_t>(point_counts.z);
  }
};

// A trivariate Bézier volume of degree (l, m, n), 1..max_bezier_degree per axis, over a frame:
//   Q(u, v, w) = Σ P_ijk B_i,l(u) B_j,m(v) B_k,n(w),  B_i,l(u) = C(l, i) u^i (1 − u)^(l − i).
// At rest P_ijk = X0 + (i/l)·U + (j/m)·V + (k/n)·W, and Q is the identity (linear precision of the Bernstein basis).
class DEFORM_RUNTIME_API BezierLattice {
 public:
  // Throws deform::Error naming `source` for an invalid frame or a degree outside [1, max_bezier_degree].
  explicit BezierLattice(const LatticeFrame& frame, glm::ivec3 degree = glm::ivec3(3),
                         const std::string& source = "<memory>");

  const LatticeFrame& frame() const noexcept { return frame_; }
  glm::ivec3 degree() const noexcept { return point_counts_ - 1; }
  glm::ivec3 point_counts() const noexcept { return point_counts_; }
  std::size_t point_count() const noexcept { return points_.size(); }
  // Flat index of P(i, j, k), i-fastest; no range check.
  std::size_t index(int i, int j, int k) const noexcept {
    return static_cast<std::size_t>(i + point_counts_.x * (j + point_counts_.y * k));
  }
  // The control points, i-fastest (see the top of this file). Write them freely between evaluations.
  std::span<glm::vec3> control_points() noexcept { return points_; }
  std::span<const glm::vec3> control_points() const noexcept { return points_; }
  glm::vec3 rest_point(int i, int j, int k) const noexcept;
  // Puts every control point back on its rest position.
  void reset() noexcept;

  // Q(u, v, w) for one point, O(lmn), no allocation. For tools and tests; bind_lattice (offline) + LatticeEvaluateJob
  // for meshes.
  glm::vec3 evaluate(glm::vec3 uvw) const noexcept;
  // ∂Q/∂(u, v, w) as the columns of a matrix (derivatives of the Bernstein basis). O(lmn).
  glm::mat3 jacobian(glm::vec3 uvw) const noexcept;

  // Direct manipulation (Hsu, Hughes & Kaufman 1992): moves the control points by the minimum-norm displacement that
  // takes the embedded point at `uvw` (in [0, 1]³) to `target`: ΔP_ijk = B_ijk(uvw) / Σ B² · (target − Q(uvw)).
  void move_point(glm::vec3 uvw, glm::vec3 target) noexcept;

 private:
  LatticeFrame frame_;
  glm::ivec3 point_counts_;
  std::vector<glm::vec3> points_;
};

// A uniform cubic B-spline volume with (nu, nv, nw) control points, 4..max_bspline_points per axis, over a frame.
// The box [0, 1]³ holds (nu − 3)(nv − 3)(nw − 3) cells; a vertex touches only the 4×4×4 points of its cell however
// fine the lattice. At rest P_ijk = X0 + ((i − 1)/(nu − 3))·U + ..., so the grid overhangs the box by one cell on
// every side and Q is the identity (linear precision of uniform B-splines). docs/lattices.md.
class DEFORM_RUNTIME_API BsplineLattice {
 public:
  // Throws deform::Error naming `source` for an invalid frame or a point count outside [4, max_bspline_points].
  explicit BsplineLattice(const LatticeFrame& frame, glm::ivec3 point_counts = glm::ivec3(4),
                          const std::string& source = "<memory>");

  const LatticeFrame& frame() const noexcept { return frame_; }
  glm::ivec3 point_counts() const noexcept { return point_counts_; }
  glm::ivec3 cell_counts() const noexcept { return point_counts_ - 3; }
  std::size_t point_count() const noexcept { return points_.size(); }
  std::size_t index(int i, int j, int k) const noexcept {
    return static_cast<std::size_t>(i + point_counts_.x * (j + point_counts_.y * k));
  }
  std::span<glm::vec3> control_points() noexcept { return points_; }
  std::span<const glm::vec3> control_points() const noexcept { return points_; }
  glm::vec3 rest_point(int i, int j, int k) const noexcept;
  void reset() noexcept;

  // Q(u, v, w) and its Jacobian for one point; 64 control points, no allocation. Parameters outside [0, 1] are
  // evaluated on the nearest border cell's polynomial.
  glm::vec3 evaluate(glm::vec3 uvw) const noexcept;
  glm::mat3 jacobian(glm::vec3 uvw) const noexcept;

  // Direct manipulation over the 64 points of the cell holding `uvw` (same formula as BezierLattice::move_point).
  void move_point(glm::vec3 uvw, glm::vec3 target) noexcept;

 private:
  LatticeFrame frame_;
  glm::ivec3 point_counts_;
  std::vector<glm::vec3> points_;
};

// Per-frame evaluation of a bound lattice (ozz-style job). Writes positions[p] (and normals_out[p]) for each bound
// point p and touches nothing else, so unbound points keep their values bit for bit. The outputs come out in the
// space of the control points: pass them as they are for a free lattice, or carried by a matrix for a bone-bound
// one (transform_points; Bézier and B-spline maps commute with affine maps). The job's elements are the binding's
// blocks of 16 points: run(begin, end) evaluates blocks [begin, end), so disjoint block ranges run on different
// threads (run_parallel in parallel.hpp). Cost per vertex: 3·(l+1)(m+1)(n+1) fused multiply-adds (tricubic: ~250),
// about twice that with normals; the widest copy the CPU runs (isa.hpp).
struct DEFORM_RUNTIME_API LatticeEvaluateJob {
  const LatticeBinding* binding = nullptr;
  std::span<const glm::vec3> control_points;  // binding->control_point_count() points, i-fastest
  // Out: indexed by point; size > binding->max_vertex. May be empty when normals are asked for: then only the
  // normals are written.
  std::span<glm::vec3> positions;
  // Optional (both or neither): per-point normals in, deformed unit normals out (n' ∝ cofactor(J)·n, the inverse
  // transpose of the map's Jacobian up to a positive scale). May alias. Size > binding->max_vertex.
  std::span<const glm::vec3> normals_in;
  std::span<glm::vec3> normals_out;
  // Optional: one weight per binding lane (binding->vertices.size(); padding lanes' are not read). With weights the
  // map is a displacement field added to the points, each by its lane's weight: position += w·Q, and the normal
  // moved toward the deformed one by the same weight, normals_out = normalize(n + w·(n' − n)) with n the point's
  // normals_in (kept when that sum is below 1e-6 long). Each point at most once in the binding (bind_lattice binds
  // it so). DeformerHierarchy::apply sums its lattices' fields this way, without a per-lattice scratch array.
  std::span<const float> weights;
  // Takes normals_in into the space the binding was made in before the Jacobian sees them (identity by default):
  // for normals that have moved since, the inverse transpose of that motion up to a positive scale, such as the
  // transposed 3×3 of a skinned bone's world · inverse bind. The blend above and the outputs stay in normals_in's
  // space.
  glm::mat3 normals_in_to_binding{1.0f};
  // Added to the map's Jacobian ∂Q/∂(u, v, w) (as columns) before the normals are made; the positions do not see it.
  // Zero by default. With the Jacobian of an affine map x ↦ A·X(u, v, w), it gives the normals of A·X + Q from the
  // evaluation of Q alone: a displacement field over a skinned limb gives the limb's displacements and its deformed
  // normals in one pass (DeformerHierarchy::apply with normals).
  glm::mat3 normals_jacobian_offset{0.0f};
  Isa isa = Isa::automatic;  // the kernel copy: isa.hpp

  // run_parallel cuts ranges anywhere (blocks write disjoint points), in chunks of at least 64 blocks (1,024 points)
  // by default: below that a thread wake-up costs more than it saves.
  static constexpr std::size_t split_multiple = 1;
  static constexpr std::size_t min_parallel_chunk = 64;

  // Ok when the job can run, else why not: a binding ("no binding") of a known kind with point counts the kernels
  // take ("binding point counts invalid"), lanes of consistent sizes ("binding arrays differ in size"), every lane's
  // point at most max_vertex or no_vertex ("binding vertex out of range"), every B-spline block's cell inside the
  // lattice ("binding cell out of range"), finite parameters ("binding parameter is not finite"); the control point
  // count of the binding ("control point count differs from the binding"); positions and normals spans covering
  // max_vertex ("positions too short": empty is accepted with normals, "normals too short"; "normals_in and
  // normals_out: both or neither"); weights, if any, one per lane ("weights: one per binding lane"); the
  // ISA available. Cost: O(bound points); the binding is read-only after bind, so once per binding and job layout.
  Status validate() const noexcept;

  // The number of blocks of the binding (0 without one).
  std::size_t count() const noexcept { return binding ? binding->block_count() : 0; }

  // Evaluates every block — or blocks [begin, end) — on this thread. Checks only what is O(1) (the sizes and point
  // counts above, the ISA, the range: "range outside the job") and refuses, writing nothing, when that fails; the
  // binding's contents are validate()'s to check. A point's result does not depend on the range it is run in. No
  // allocation, no locks.
  Status run() const noexcept;
  Status run(std::size_t begin, std::size_t end) const noexcept;
};

// out[i] = matrix · (in[i], 1): carries lattice-space control points into another space (a bone's world or bind
// frame) once per frame, so the per-vertex work stays the same. `out` may alias `in`. Refuses, writing nothing,
// spans of different sizes. No allocation.
DEFORM_RUNTIME_API Status transform_points(std::span<const glm::vec3> in, const glm::mat4& matrix,
                                           std::span<glm::vec3> out) noexcept;

}  // namespace deform
