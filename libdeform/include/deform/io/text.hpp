#pragma once
// Floats in text output, as libdeform's writers print them.
#include "deform/io/export.hpp"

namespace deform {

// The double whose shortest decimal form is `value`'s shortest round-trip form (std::to_chars), for writing a float
// through a JSON library that holds doubles: 0.1f gives 0.1, printed "0.1", where double(0.1f) prints as
// 0.10000000149011612. Reading the printed text back as a float gives `value` exactly. Both zeros give +0 (JSON
// output never shows "-0.0"); infinities and NaN are returned unchanged (nlohmann::json prints them as null).
// Cost: one std::to_chars and one std::from_chars, no allocation.
DEFORM_IO_API double shortest_double(float value);

}  // namespace deform
