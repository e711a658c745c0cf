// Dataset lookups, format names and detection, and the ReadDataset dispatcher.
#include "orchard/data/dataset.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset_internal.h"

namespace orchard {

const AnnotatedImage* Dataset::Find(const std::string& name) const {
  for (const AnnotatedImage& image : images) {
    if (image.name == name) return &image;
  }
  const AnnotatedImage* match = nullptr;
  for (const AnnotatedImage& image : images) {
    if (fs::path(image.name).stem().string() == name) {
      if (match != nullptr) return nullptr;  // ambiguous: "a" for a.jpg and a.png
      match = &image;
    }
  }
  return match;
}

size_t Dataset::NumObjects() const {
  size_t n = 0;
  for (const AnnotatedImage& image : images) n += image.objects.size();
  return n;
}

DatasetFormat ParseDatasetFormat(const std::string& name) {
  if (name == "minneapple") return DatasetFormat::kMinneApple;
  if (name == "yolo") return DatasetFormat::kYolo;
  if (name == "coco") return DatasetFormat::kCoco;
  if (name == "via") return DatasetFormat::kVia;
  Fail("unknown dataset format '", name, "' (expected minneapple, yolo, coco or via)");
}

std::string DatasetFormatName(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::kMinneApple: return "minneapple";
    case DatasetFormat::kYolo: return "yolo";
    case DatasetFormat::kCoco: return "coco";
    case DatasetFormat::kVia: return "via";
  }
  return "unknown";
}

namespace data_internal {

nlohmann::json ReadJsonFile(const fs::path& path) {
  const std::string text = ReadTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    Fail(path.string(), ": invalid JSON: ", e.what());
  }
}

std::optional<DatasetFormat> JsonDatasetFormat(const nlohmann::json& json) {
  if (!json.is_object()) return std::nullopt;
  if (json.contains("images") && json.contains("annotations")) return DatasetFormat::kCoco;
  if (json.contains("_via_img_metadata")) return DatasetFormat::kVia;
  if (json.contains("project") && json.contains("metadata") && json.contains("file")) {
    return DatasetFormat::kVia;  // VIA 3
  }
  // VIA 1/2 export: {"<file><size>": {"filename": ..., "regions": ...}, ...}
  if (!json.empty()) {
    bool all_via = true;
    for (const auto& item : json.items()) {
      if (!item.value().is_object() || !item.value().contains("filename") ||
          !item.value().contains("regions")) {
        all_via = false;
        break;
      }
    }
    if (all_via) return DatasetFormat::kVia;
  }
  return std::nullopt;
}

void FinishDataset(Dataset* dataset, const std::string& source, bool renumber) {
  std::sort(dataset->images.begin(), dataset->images.end(),
            [](const AnnotatedImage& a, const AnnotatedImage& b) { return a.name < b.name; });
  for (size_t i = 0; i < dataset->images.size(); ++i) {
    if (i > 0 && dataset->images[i].name == dataset->images[i - 1].name) {
      Fail(source, ": image '", dataset->images[i].name, "' appears more than once");
    }
    if (renumber) dataset->images[i].id = static_cast<std::int64_t>(i + 1);
  }
}

}  // namespace data_internal

namespace {

bool IsDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

}  // namespace

DatasetFormat DetectDatasetFormat(const fs::path& path) {
  std::error_code ec;
  if (IsDir(path)) {
    if (IsDir(path / "masks") || IsDir(path / "data" / "masks")) return DatasetFormat::kMinneApple;
    if (IsDir(path / "labels") || IsDir(path / "data" / "labels")) return DatasetFormat::kYolo;
    Fail("cannot tell the dataset format of folder ", path.string(),
         ": expected masks/ (MinneApple) or labels/ (YOLO), directly or under data/");
  }
  if (!fs::exists(path, ec)) Fail("dataset not found: ", path.string());
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".json") {
    Fail("cannot tell the dataset format of ", path.string(),
         ": expected a folder (MinneApple, YOLO) or a .json file (COCO, VIA)");
  }
  const nlohmann::json json = data_internal::ReadJsonFile(path);
  if (json.is_array()) {
    Fail(path.string(), " is a list, like a COCO results file, not an annotated dataset");
  }
  const std::optional<DatasetFormat> format = data_internal::JsonDatasetFormat(json);
  if (!format) {
    Fail("cannot tell the dataset format of ", path.string(),
         ": neither COCO (images, annotations) nor VIA (_via_img_metadata or filename/regions)");
  }
  return *format;
}

Dataset ReadDataset(const fs::path& path, std::optional<DatasetFormat> format,
                    const fs::path& image_dir) {
  const DatasetFormat f = format ? *format : DetectDatasetFormat(path);
  switch (f) {
    case DatasetFormat::kMinneApple:
      if (!IsDir(path / "masks") && IsDir(path / "data" / "masks")) {
        return ReadMinneApple(path / "data");
      }
      return ReadMinneApple(path);
    case DatasetFormat::kYolo:
      return ReadYolo(path);
    case DatasetFormat::kCoco:
    case DatasetFormat::kVia: {
      fs::path images = image_dir;
      if (images.empty()) images = data_internal::GuessImageDir(path);
      // A folder given by the user must hold every image; a guessed one need not.
      const bool required = !image_dir.empty();
      return f == DatasetFormat::kCoco ? data_internal::ReadCocoImpl(path, images, required)
                                       : data_internal::ReadViaImpl(path, images, required);
    }
  }
  Fail("unsupported dataset format");
}

}  // namespace orchard
