#pragma once
// Procedural props for the viewer's scene (a floor, a target ball) as deform::Mesh values, so they draw through the
// same MeshRenderer as the character.
#include "deform/runtime/mesh.hpp"

namespace sample {

// A square in the XZ plane at y = 0, `size` wide, `cells` checker cells per side (two materials alternate).
deform::Mesh make_floor(float size, int cells);
// A UV sphere of radius `radius` centred at the origin, one material of colour `colour`.
deform::Mesh make_sphere(float radius, int rings, int segments, glm::vec3 colour);

}  // namespace sample
