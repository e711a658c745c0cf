// Internals shared by the dataset readers and writers (not part of the API).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>

#include "orchard/data/dataset.h"

namespace orchard {
namespace data_internal {

// Parses a JSON file; throws "<path>: invalid JSON: ..." on bad syntax.
nlohmann::json ReadJsonFile(const fs::path& path);

// COCO or VIA by the keys of a parsed json; nullopt when neither.
std::optional<DatasetFormat> JsonDatasetFormat(const nlohmann::json& json);

// Sorts images by name, rejects duplicate names (naming `source`), and numbers
// images 1..N in name order when `renumber`.
void FinishDataset(Dataset* dataset, const std::string& source, bool renumber);

// The folder holding the images of a COCO/VIA json when none is given: the
// first of <json dir>/images, <json dir>/../images, <json dir> with image
// files in it; empty when none has.
fs::path GuessImageDir(const fs::path& json_path);

// The image file for `file_name` (as written in an annotation file) in
// `image_dir`: image_dir/file_name, else image_dir/<file name part>. Empty when
// `image_dir` is empty or the file is absent and not `required`; throws when
// absent and `required`.
fs::path ResolveImagePath(const fs::path& image_dir, const std::string& file_name, bool required,
                          const fs::path& source);

// Width and height of an image file (from its header when PNG/JPEG, see
// image_size.h); throws naming the file.
cv::Size ReadImageSize(const fs::path& path);

// Copies `from` to `to` atomically (skips when they are the same file).
void CopyFileAtomic(const fs::path& from, const fs::path& to);

// Fills width/height of `image` from its file when unknown; throws naming
// `purpose` when neither is available.
void EnsureImageSize(AnnotatedImage* image, const std::string& purpose);

// Area of a flat polygon x0,y0,x1,y1,... (shoelace, absolute value).
double PolygonArea(const std::vector<double>& polygon);

// Tight box over all polygon vertices.
Box PolygonsBounds(const std::vector<std::vector<double>>& polygons);

// The image files that ReadCoco/ReadVia are required to find: only when the
// image folder was given by the user, not guessed.
Dataset ReadCocoImpl(const fs::path& json_path, const fs::path& image_dir, bool images_required);
Dataset ReadViaImpl(const fs::path& json_path, const fs::path& image_dir, bool images_required);

}  // namespace data_internal
}  // namespace orchard
