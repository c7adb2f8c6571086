#pragma once
// Private to deform::import: an ImportedModel as bytes, sent by the importer process (tools/import_worker) to
// import_model_isolated. Both ends are built from the same sources, so the layout is not a file format: a magic and a
// version guard against a mismatched worker. The reader trusts nothing: every count is checked against the bytes
// left before anything is allocated, and the result is validated as import_model's would be.
#include <cstdint>
#include <string>
#include <vector>

#include "deform/import/import.hpp"

namespace deform::wire {

std::vector<std::uint8_t> encode(const ImportedModel& model);

// Throws deform::Error (naming `source`) when the bytes are cut short, malformed or not a valid model.
ImportedModel decode(const std::vector<std::uint8_t>& bytes, const std::string& source);

}  // namespace deform::wire
