// COCO json datasets and COCO results files.
#include <cmath>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/dataset_internal.h"

namespace orchard {
namespace {

using json = nlohmann::json;

// "<file>: <where>: " for error messages about one json element.
std::string At(const fs::path& path, const std::string& where) {
  return path.string() + ": " + where + ": ";
}

const json& Member(const json& object, const char* key, const fs::path& path,
                   const std::string& where) {
  if (!object.is_object()) Fail(At(path, where), "expected an object");
  const auto it = object.find(key);
  if (it == object.end()) Fail(At(path, where), "missing field '", key, "'");
  return *it;
}

double Number(const json& value, const fs::path& path, const std::string& where) {
  if (!value.is_number()) Fail(At(path, where), "expected a number, got ", value.dump());
  const double v = value.get<double>();
  if (!std::isfinite(v)) Fail(At(path, where), "expected a finite number");
  return v;
}

std::int64_t Id(const json& value, const fs::path& path, const std::string& where) {
  if (!value.is_number_integer()) Fail(At(path, where), "expected an integer id, got ", value.dump());
  return value.get<std::int64_t>();
}

// bbox [x, y, w, h] with w, h >= 0.
Box ReadBbox(const json& value, const fs::path& path, const std::string& where) {
  if (!value.is_array() || value.size() != 4) {
    Fail(At(path, where), "expected [x, y, width, height], got ", value.dump());
  }
  const double x = Number(value[0], path, where + "[0]");
  const double y = Number(value[1], path, where + "[1]");
  const double w = Number(value[2], path, where + "[2]");
  const double h = Number(value[3], path, where + "[3]");
  if (w < 0) Fail(At(path, where + "[2]"), "expected a width >= 0, got ", w);
  if (h < 0) Fail(At(path, where + "[3]"), "expected a height >= 0, got ", h);
  return Box::FromXYWH(x, y, w, h);
}

json BboxJson(const Box& box) { return json::array({box.x1, box.y1, box.Width(), box.Height()}); }

}  // namespace

namespace data_internal {

Dataset ReadCocoImpl(const fs::path& json_path, const fs::path& image_dir, bool images_required) {
  const json root = ReadJsonFile(json_path);
  if (!root.is_object()) Fail(json_path.string(), ": expected a COCO object {images, annotations}");
  const json& images = Member(root, "images", json_path, "top level");
  const json& annotations = Member(root, "annotations", json_path, "top level");
  if (!images.is_array()) Fail(At(json_path, "images"), "expected a list");
  if (!annotations.is_array()) Fail(At(json_path, "annotations"), "expected a list");

  Dataset dataset;
  std::map<std::int64_t, size_t> index_by_id;
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string where = "images[" + std::to_string(i) + "]";
    const json& entry = images[i];
    AnnotatedImage image;
    image.id = Id(Member(entry, "id", json_path, where), json_path, where + ".id");
    const json& file_name = Member(entry, "file_name", json_path, where);
    if (!file_name.is_string() || file_name.get<std::string>().empty()) {
      Fail(At(json_path, where + ".file_name"), "expected a file name, got ", file_name.dump());
    }
    image.name = fs::path(file_name.get<std::string>()).filename().string();
    if (entry.contains("width")) image.width = static_cast<int>(Number(entry["width"], json_path, where + ".width"));
    if (entry.contains("height")) image.height = static_cast<int>(Number(entry["height"], json_path, where + ".height"));
    if (image.width < 0 || image.height < 0) Fail(At(json_path, where), "negative image size");
    image.path = ResolveImagePath(image_dir, file_name.get<std::string>(), images_required, json_path);
    if ((image.width <= 0 || image.height <= 0) && !image.path.empty()) {
      const cv::Size size = ReadImageSize(image.path);
      image.width = size.width;
      image.height = size.height;
    }
    if (!index_by_id.emplace(image.id, dataset.images.size()).second) {
      Fail(At(json_path, where + ".id"), "image id ", image.id, " appears more than once");
    }
    dataset.images.push_back(std::move(image));
  }

  for (size_t i = 0; i < annotations.size(); ++i) {
    const std::string where = "annotations[" + std::to_string(i) + "]";
    const json& entry = annotations[i];
    const std::int64_t image_id =
        Id(Member(entry, "image_id", json_path, where), json_path, where + ".image_id");
    const auto it = index_by_id.find(image_id);
    if (it == index_by_id.end()) {
      Fail(At(json_path, where + ".image_id"), "no image with id ", image_id);
    }
    if (entry.contains("iscrowd") && entry["iscrowd"].is_number() && entry["iscrowd"].get<double>() != 0) {
      Fail(At(json_path, where + ".iscrowd"), "crowd annotations are not supported (one object per apple)");
    }
    Annotation object;
    if (entry.contains("segmentation")) {
      const json& segmentation = entry["segmentation"];
      if (segmentation.is_array()) {
        for (size_t k = 0; k < segmentation.size(); ++k) {
          const std::string pwhere = where + ".segmentation[" + std::to_string(k) + "]";
          const json& polygon = segmentation[k];
          if (!polygon.is_array() || polygon.size() % 2 != 0 || polygon.size() < 6) {
            Fail(At(json_path, pwhere), "expected a polygon [x0, y0, x1, y1, ...] of 3 or more points");
          }
          std::vector<double> points;
          for (size_t m = 0; m < polygon.size(); ++m) {
            points.push_back(Number(polygon[m], json_path, pwhere + "[" + std::to_string(m) + "]"));
          }
          object.polygons.push_back(std::move(points));
        }
      } else if (!segmentation.is_object() && !segmentation.is_null()) {
        Fail(At(json_path, where + ".segmentation"), "expected a list of polygons or an RLE object");
      }
      // RLE objects (is_object) carry no polygons; the area field is used.
    }
    if (entry.contains("bbox")) {
      object.box = ReadBbox(entry["bbox"], json_path, where + ".bbox");
    } else if (!object.polygons.empty()) {
      object.box = PolygonsBounds(object.polygons);
    } else {
      Fail(At(json_path, where), "missing field 'bbox' (and no polygon to derive it from)");
    }
    if (entry.contains("area")) {
      object.area = Number(entry["area"], json_path, where + ".area");
      if (object.area < 0) Fail(At(json_path, where + ".area"), "expected an area >= 0");
    } else if (!object.polygons.empty()) {
      object.area = 0;
      for (const auto& polygon : object.polygons) object.area += PolygonArea(polygon);
    }
    if (!object.polygons.empty()) dataset.has_masks = true;
    dataset.images[it->second].objects.push_back(std::move(object));
  }
  FinishDataset(&dataset, json_path.string(), /*renumber=*/false);
  return dataset;
}

}  // namespace data_internal

Dataset ReadCoco(const fs::path& json_path, const fs::path& image_dir) {
  return data_internal::ReadCocoImpl(json_path, image_dir, /*images_required=*/!image_dir.empty());
}

void WriteCoco(const Dataset& dataset, const fs::path& json_path) {
  json images = json::array();
  json annotations = json::array();
  std::set<std::int64_t> used_ids;
  bool keep_ids = true;
  for (const auto& image : dataset.images) {
    if (image.id <= 0 || !used_ids.insert(image.id).second) keep_ids = false;
  }
  std::int64_t annotation_id = 1;
  for (size_t i = 0; i < dataset.images.size(); ++i) {
    AnnotatedImage image = dataset.images[i];
    data_internal::EnsureImageSize(&image, "COCO (image width and height)");
    const std::int64_t id = keep_ids ? image.id : static_cast<std::int64_t>(i + 1);
    images.push_back({{"id", id}, {"file_name", image.name}, {"width", image.width},
                      {"height", image.height}});
    for (const Annotation& object : image.objects) {
      json annotation = {{"id", annotation_id++},
                         {"image_id", id},
                         {"category_id", 1},
                         {"bbox", BboxJson(object.box)},
                         {"area", object.area >= 0 ? object.area : object.box.Area()},
                         {"iscrowd", 0}};
      if (!object.polygons.empty()) annotation["segmentation"] = object.polygons;
      annotations.push_back(std::move(annotation));
    }
  }
  const json root = {
      {"info", {{"description", "written by orchard"}, {"version", ORCHARD_VERSION}}},
      {"licenses", json::array()},
      {"images", std::move(images)},
      {"annotations", std::move(annotations)},
      {"categories", json::array({{{"id", 1}, {"name", "apple"}, {"supercategory", "fruit"}}})}};
  WriteTextFileAtomic(json_path, root.dump(1) + "\n");
}

// ----- COCO results ----------------------------------------------------------

Predictions ReadCocoResults(const fs::path& path, const Dataset& ground_truth) {
  const json root = data_internal::ReadJsonFile(path);
  if (!root.is_array()) {
    Fail(path.string(), ": expected a COCO results list [{\"image_id\", \"bbox\", \"score\"}, ...]");
  }
  std::map<std::int64_t, const AnnotatedImage*> by_id;
  for (const auto& image : ground_truth.images) by_id[image.id] = &image;
  Predictions predictions;
  for (size_t i = 0; i < root.size(); ++i) {
    const std::string where = "[" + std::to_string(i) + "]";
    const json& entry = root[i];
    const std::int64_t image_id =
        Id(Member(entry, "image_id", path, where), path, where + ".image_id");
    const auto it = by_id.find(image_id);
    if (it == by_id.end()) {
      Fail(At(path, where + ".image_id"), "no ground-truth image with id ", image_id);
    }
    ScoredBox detection;
    detection.box = ReadBbox(Member(entry, "bbox", path, where), path, where + ".bbox");
    detection.score = Number(Member(entry, "score", path, where), path, where + ".score");
    predictions[it->second->name].push_back(detection);
  }
  return predictions;
}

void WriteCocoResults(const Predictions& predictions, const Dataset& ground_truth,
                      const fs::path& path) {
  json root = json::array();
  for (const auto& [name, detections] : predictions) {
    const AnnotatedImage* image = ground_truth.Find(name);
    if (image == nullptr) {
      Fail("cannot write COCO results: image '", name, "' is not in the ground truth (or ambiguous)");
    }
    for (const ScoredBox& d : detections) {
      root.push_back({{"image_id", image->id}, {"category_id", 1}, {"bbox", BboxJson(d.box)},
                      {"score", d.score}});
    }
  }
  WriteTextFileAtomic(path, root.dump(1) + "\n");
}

}  // namespace orchard
