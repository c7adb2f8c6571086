#pragma once
// libdeform's facade: one include for an engine that wants the Character and what it is made of. Each target's
// headers (deform/runtime/..., deform/io/..., deform/offline/...) stay usable on their own; docs/architecture.md
// says which target holds what.
#include "deform/character/character.hpp"
#include "deform/extras/builtin.hpp"  // make_builtin_character(), which character.hpp's quick start calls
#include "deform/io/model_files.hpp"
#include "deform/io/rig_json.hpp"
#include "deform/offline/rig.hpp"
#include "deform/runtime/elastic.hpp"
#include "deform/runtime/error.hpp"
#include "deform/runtime/hierarchy.hpp"
#include "deform/runtime/ik.hpp"
#include "deform/runtime/lattice.hpp"
#include "deform/runtime/mesh.hpp"
#include "deform/runtime/model.hpp"
#include "deform/runtime/skeleton.hpp"
#include "deform/runtime/skinning.hpp"
