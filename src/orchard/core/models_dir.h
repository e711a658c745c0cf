// Where the shipped default models live: $ORCHARD_MODELS_DIR when set, else
// `models/` beside the build folder that holds the program (build/orchard ->
// models/), else the source tree's `models/`.
#pragma once

#include <filesystem>

namespace orchard {

std::filesystem::path DefaultModelsDir();

}  // namespace orchard
