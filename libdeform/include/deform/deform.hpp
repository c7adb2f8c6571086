#pragma once
// libdeform's facade: one include for an engine that wants the Character and what it is made of.
// The per-module headers (mesh.hpp, skeleton.hpp, skinning.hpp, ik.hpp, lattice.hpp, elastic.hpp, ...) stay usable
// on their own for finer control.
#include "deform/builtin.hpp"
#include "deform/character.hpp"
#include "deform/elastic.hpp"
#include "deform/error.hpp"
#include "deform/hierarchy.hpp"
#include "deform/ik.hpp"
#include "deform/lattice.hpp"
#include "deform/mesh.hpp"
#include "deform/model.hpp"
#include "deform/rig.hpp"
#include "deform/skeleton.hpp"
#include "deform/skinning.hpp"
