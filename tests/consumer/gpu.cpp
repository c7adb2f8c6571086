// An engine that asked for COMPONENTS gpu: deform::gpu's header needs no GL header, and its classes link. Nothing
// here touches GL (no context in this test): empty lattices and skinnings are made, moved and destroyed.
#include <cstdio>
#include <utility>

#include <deform/gpu/lattice.hpp>
#include <deform/gpu/skinning.hpp>

int main() {
  deform::GpuBezierLattice lattice;
  deform::GpuBezierLattice moved = std::move(lattice);
  deform::GpuLatticeFields fields;
  deform::GpuSkinning skinning;
  deform::GpuSkinning moved_skinning = std::move(skinning);
  const bool ok = !moved.created() && moved.vertex_count() == 0 && fields.lattice_count() == 0 &&
                  !moved_skinning.created() && moved_skinning.bone_count() == 0 &&
                  deform::GpuVertexLayout{}.floats_per_vertex == 8;
  std::printf("gpu: %s\n", ok ? "ok" : "wrong");
  return ok ? 0 : 1;
}
