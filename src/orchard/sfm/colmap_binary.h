// COLMAP sparse models in the binary format (cameras.bin, images.bin,
// points3D.bin, as the mapper writes them), and reading a model folder in
// either format.
#pragma once

#include <filesystem>

#include "orchard/sfm/colmap_model.h"

namespace orchard {

namespace fs = std::filesystem;

// Reads dir/cameras.bin, images.bin and points3D.bin; throws orchard::Error
// naming the file when one is missing, truncated or uses an unknown camera model.
ColmapModel ReadColmapBinaryModel(const fs::path& dir);
// Writes the three binary files into `dir` (created if missing), each atomically.
void WriteColmapBinaryModel(const ColmapModel& model, const fs::path& dir);
// A text model when dir/cameras.txt exists, else a binary one when
// dir/cameras.bin exists; otherwise an error that names both.
ColmapModel ReadColmapModel(const fs::path& dir);

}  // namespace orchard
