// VIA (VGG Image Annotator) json: VIA 1/2 project files and annotation exports
// ({"<file><size>": {"filename", "regions"}}), and VIA 3 projects.
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "orchard/core/error.h"
#include "orchard/data/dataset.h"
#include "orchard/data/dataset_internal.h"

namespace orchard {
namespace {

using json = nlohmann::json;

std::string At(const fs::path& path, const std::string& where) {
  return path.string() + ": " + where + ": ";
}

double Number(const json& object, const char* key, const fs::path& path, const std::string& where) {
  if (!object.is_object() || !object.contains(key)) Fail(At(path, where), "missing field '", key, "'");
  const json& value = object[key];
  // VIA 1 sometimes stores numbers as strings.
  if (value.is_string()) {
    try {
      size_t used = 0;
      const double v = std::stod(value.get<std::string>(), &used);
      if (used == value.get<std::string>().size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
  }
  if (!value.is_number() || !std::isfinite(value.get<double>())) {
    Fail(At(path, where + "." + key), "expected a number, got ", value.dump());
  }
  return value.get<double>();
}

// Polygon of an axis-aligned or rotated ellipse, 64 vertices.
std::vector<double> EllipsePolygon(double cx, double cy, double rx, double ry, double theta) {
  constexpr int kVertices = 64;
  std::vector<double> polygon;
  const double c = std::cos(theta), s = std::sin(theta);
  for (int i = 0; i < kVertices; ++i) {
    const double t = 2 * M_PI * i / kVertices;
    const double x = rx * std::cos(t), y = ry * std::sin(t);
    polygon.push_back(cx + c * x - s * y);
    polygon.push_back(cy + s * x + c * y);
  }
  return polygon;
}

Annotation EllipseObject(double cx, double cy, double rx, double ry, double theta,
                         const fs::path& path, const std::string& where) {
  if (!(rx > 0) || !(ry > 0)) Fail(At(path, where), "expected positive radii, got ", rx, " and ", ry);
  Annotation object;
  object.polygons.push_back(EllipsePolygon(cx, cy, rx, ry, theta));
  // Exact bounds of the rotated ellipse.
  const double hx = std::sqrt(std::pow(rx * std::cos(theta), 2) + std::pow(ry * std::sin(theta), 2));
  const double hy = std::sqrt(std::pow(rx * std::sin(theta), 2) + std::pow(ry * std::cos(theta), 2));
  object.box = Box{cx - hx, cy - hy, cx + hx, cy + hy};
  object.area = M_PI * rx * ry;
  return object;
}

Annotation PolygonObject(std::vector<double> polygon, const fs::path& path, const std::string& where) {
  if (polygon.size() < 6) Fail(At(path, where), "a polygon needs 3 or more points");
  Annotation object;
  object.box = data_internal::PolygonsBounds({polygon});
  object.area = data_internal::PolygonArea(polygon);
  object.polygons.push_back(std::move(polygon));
  return object;
}

Annotation RectObject(double x, double y, double w, double h, const fs::path& path,
                      const std::string& where) {
  if (w < 0 || h < 0) Fail(At(path, where), "expected a width and height >= 0, got ", w, " and ", h);
  Annotation object;
  object.box = Box::FromXYWH(x, y, w, h);
  object.polygons.push_back({x, y, x + w, y, x + w, y + h, x, y + h});
  object.area = w * h;
  return object;
}

// VIA 1/2 region: {"shape_attributes": {"name": ..., ...}}.
Annotation ReadVia2Region(const json& region, const fs::path& path, const std::string& where) {
  if (!region.is_object() || !region.contains("shape_attributes")) {
    Fail(At(path, where), "missing field 'shape_attributes'");
  }
  const json& shape = region["shape_attributes"];
  const std::string swhere = where + ".shape_attributes";
  if (!shape.is_object() || !shape.contains("name") || !shape["name"].is_string()) {
    Fail(At(path, swhere), "missing shape 'name'");
  }
  const std::string name = shape["name"].get<std::string>();
  if (name == "polygon" || name == "polyline") {
    const json& xs = shape.value("all_points_x", json());
    const json& ys = shape.value("all_points_y", json());
    if (!xs.is_array() || !ys.is_array() || xs.size() != ys.size()) {
      Fail(At(path, swhere), "expected all_points_x and all_points_y lists of equal length");
    }
    std::vector<double> polygon;
    for (size_t i = 0; i < xs.size(); ++i) {
      if (!xs[i].is_number() || !ys[i].is_number()) {
        Fail(At(path, swhere + ".all_points[" + std::to_string(i) + "]"), "expected numbers");
      }
      polygon.push_back(xs[i].get<double>());
      polygon.push_back(ys[i].get<double>());
    }
    return PolygonObject(std::move(polygon), path, swhere);
  }
  if (name == "rect") {
    return RectObject(Number(shape, "x", path, swhere), Number(shape, "y", path, swhere),
                      Number(shape, "width", path, swhere), Number(shape, "height", path, swhere),
                      path, swhere);
  }
  if (name == "circle") {
    const double r = Number(shape, "r", path, swhere);
    return EllipseObject(Number(shape, "cx", path, swhere), Number(shape, "cy", path, swhere), r, r, 0,
                         path, swhere);
  }
  if (name == "ellipse") {
    const double theta = shape.contains("theta") ? Number(shape, "theta", path, swhere) : 0.0;
    return EllipseObject(Number(shape, "cx", path, swhere), Number(shape, "cy", path, swhere),
                         Number(shape, "rx", path, swhere), Number(shape, "ry", path, swhere), theta,
                         path, swhere);
  }
  Fail(At(path, swhere + ".name"), "unsupported region shape '", name,
       "' (expected polygon, rect, circle or ellipse)");
}

// VIA 3 shape: [type, coordinates...].
Annotation ReadVia3Shape(const json& xy, const fs::path& path, const std::string& where) {
  if (!xy.is_array() || xy.empty() || !xy[0].is_number_integer()) {
    Fail(At(path, where), "expected [shape type, coordinates...]");
  }
  std::vector<double> v;
  for (size_t i = 1; i < xy.size(); ++i) {
    if (!xy[i].is_number()) Fail(At(path, where + "[" + std::to_string(i) + "]"), "expected a number");
    v.push_back(xy[i].get<double>());
  }
  const int type = xy[0].get<int>();
  auto need = [&](size_t n) {
    if (v.size() != n) Fail(At(path, where), "shape ", type, " needs ", n, " numbers, got ", v.size());
  };
  switch (type) {
    case 2: need(4); return RectObject(v[0], v[1], v[2], v[3], path, where);
    case 3: need(3); return EllipseObject(v[0], v[1], v[2], v[2], 0, path, where);
    case 4: need(4); return EllipseObject(v[0], v[1], v[2], v[3], 0, path, where);
    case 6:
    case 7:
      if (v.size() % 2 != 0) Fail(At(path, where), "odd number of polygon coordinates");
      return PolygonObject(std::move(v), path, where);
    default:
      Fail(At(path, where), "unsupported VIA 3 shape type ", type,
           " (expected 2 rectangle, 3 circle, 4 ellipse, 6 polyline or 7 polygon)");
  }
}

AnnotatedImage NewImage(const std::string& file_name, const fs::path& image_dir, bool required,
                        const fs::path& path) {
  AnnotatedImage image;
  image.name = fs::path(file_name).filename().string();
  image.path = data_internal::ResolveImagePath(image_dir, file_name, required, path);
  if (!image.path.empty()) {
    const cv::Size size = data_internal::ReadImageSize(image.path);
    image.width = size.width;
    image.height = size.height;
  }
  return image;
}

}  // namespace

namespace data_internal {

Dataset ReadViaImpl(const fs::path& json_path, const fs::path& image_dir, bool images_required) {
  const json root = ReadJsonFile(json_path);
  if (!root.is_object()) Fail(json_path.string(), ": expected a VIA project object");
  Dataset dataset;
  if (root.contains("project") && root.contains("metadata") && root.contains("file")) {
    // VIA 3: metadata -> view -> file.
    const json& files = root["file"];
    const json& views = root.value("view", json::object());
    std::map<std::string, size_t> index_by_fid;
    for (const auto& [fid, file] : files.items()) {
      const std::string where = "file." + fid;
      if (!file.is_object() || !file.contains("fname") || !file["fname"].is_string()) {
        Fail(At(json_path, where), "missing field 'fname'");
      }
      index_by_fid[fid] = dataset.images.size();
      dataset.images.push_back(NewImage(file["fname"].get<std::string>(), image_dir, images_required, json_path));
    }
    for (const auto& [mid, meta] : root["metadata"].items()) {
      const std::string where = "metadata." + mid;
      if (!meta.is_object() || !meta.contains("vid") || !meta.contains("xy")) {
        Fail(At(json_path, where), "expected fields 'vid' and 'xy'");
      }
      if (meta.contains("z") && meta["z"].is_array() && !meta["z"].empty()) {
        Fail(At(json_path, where + ".z"), "temporal (video) annotations are not supported");
      }
      const std::string vid = meta["vid"].is_string() ? meta["vid"].get<std::string>() : meta["vid"].dump();
      const json* view = views.contains(vid) ? &views[vid] : nullptr;
      std::string fid = vid;  // VIA 3 image projects use vid == fid
      if (view != nullptr && view->contains("fid_list") && (*view)["fid_list"].is_array() &&
          !(*view)["fid_list"].empty()) {
        const json& f = (*view)["fid_list"][0];
        fid = f.is_string() ? f.get<std::string>() : f.dump();
      }
      const auto it = index_by_fid.find(fid);
      if (it == index_by_fid.end()) Fail(At(json_path, where + ".vid"), "no file for view ", vid);
      dataset.images[it->second].objects.push_back(ReadVia3Shape(meta["xy"], json_path, where + ".xy"));
    }
  } else {
    const json& entries = root.contains("_via_img_metadata") ? root["_via_img_metadata"] : root;
    if (!entries.is_object()) Fail(At(json_path, "_via_img_metadata"), "expected an object");
    for (const auto& [key, entry] : entries.items()) {
      const std::string where = key;
      if (!entry.is_object() || !entry.contains("filename") || !entry["filename"].is_string()) {
        Fail(At(json_path, where), "missing field 'filename'");
      }
      AnnotatedImage image = NewImage(entry["filename"].get<std::string>(), image_dir, images_required, json_path);
      const json& regions = entry.value("regions", json::array());
      if (regions.is_array()) {
        for (size_t i = 0; i < regions.size(); ++i) {
          image.objects.push_back(ReadVia2Region(regions[i], json_path, where + ".regions[" + std::to_string(i) + "]"));
        }
      } else if (regions.is_object()) {  // VIA 1: {"0": region, ...}
        for (const auto& [rid, region] : regions.items()) {
          image.objects.push_back(ReadVia2Region(region, json_path, where + ".regions." + rid));
        }
      } else {
        Fail(At(json_path, where + ".regions"), "expected a list of regions");
      }
      dataset.images.push_back(std::move(image));
    }
  }
  dataset.has_masks = true;  // areas come from the region shapes
  FinishDataset(&dataset, json_path.string(), /*renumber=*/true);
  return dataset;
}

}  // namespace data_internal

Dataset ReadVia(const fs::path& json_path, const fs::path& image_dir) {
  return data_internal::ReadViaImpl(json_path, image_dir, /*images_required=*/!image_dir.empty());
}

}  // namespace orchard
