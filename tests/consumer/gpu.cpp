// An engine that asked for COMPONENTS gpu: deform::gpu's header needs no GL header, and its classes link. Nothing
// here touches GL (no context in this test): empty lattices are made, moved and destroyed.
#include <cstdio>
#include <utility>

#include <deform/gpu/lattice.hpp>

int main() {
  deform::GpuBezierLattice lattice;
  deform::GpuBezierLattice moved = std::move(lattice);
  deform::GpuLatticeFields fields;
  const bool ok = !moved.created() && moved.vertex_count() == 0 && fields.lattice_count() == 0 &&
                  deform::GpuVertexLayout{}.floats_per_vertex == 8;
  std::printf("gpu: %s\n", ok ? "ok" : "wrong");
  return ok ? 0 : 1;
}
