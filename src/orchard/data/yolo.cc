// YOLO txt datasets: images/ + labels/<stem>.txt, lines `class cx cy w h`
// normalised to the image size (or `class x1 y1 x2 y2 ...`, the YOLO
// segmentation format, read as a polygon).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/dataset_internal.h"
#include "orchard/data/text_format.h"

namespace orchard {
namespace {

using data_internal::ParseInteger;
using data_internal::ParseNumber;
using data_internal::Where;

// Normalised values may overshoot [0,1] by this much (rounding in exporters).
constexpr double kValueTolerance = 1e-3;
// Box edges (cx +- w/2) may overshoot the image by this fraction.
constexpr double kEdgeTolerance = 1e-2;

double ParseNormalised(const std::string& token, const fs::path& path, int line,
                       const std::string& field) {
  const double v = ParseNumber(token, path, line, field);
  if (v < -kValueTolerance || v > 1 + kValueTolerance) {
    Fail(Where(path, line, field), "expected a value in [0,1], got '", token, "'");
  }
  return v;
}

std::vector<Annotation> ReadYoloLabels(const fs::path& path, int width, int height) {
  std::vector<Annotation> objects;
  for (const auto& line : data_internal::ReadNonEmptyLines(path)) {
    const std::vector<std::string> fields = data_internal::SplitFields(line.text);
    Annotation object;
    const long long cls = ParseInteger(fields[0], path, line.number, "class");
    if (cls < 0) Fail(Where(path, line.number, "class"), "expected a class id >= 0, got '", fields[0], "'");
    object.category = static_cast<int>(cls);
    if (fields.size() == 5) {
      const double cx = ParseNormalised(fields[1], path, line.number, "cx");
      const double cy = ParseNormalised(fields[2], path, line.number, "cy");
      const double w = ParseNormalised(fields[3], path, line.number, "w");
      const double h = ParseNormalised(fields[4], path, line.number, "h");
      if (w < 0) Fail(Where(path, line.number, "w"), "expected a width >= 0, got '", fields[3], "'");
      if (h < 0) Fail(Where(path, line.number, "h"), "expected a height >= 0, got '", fields[4], "'");
      if (cx - w / 2 < -kEdgeTolerance || cx + w / 2 > 1 + kEdgeTolerance) {
        Fail(Where(path, line.number, "w"), "box cx=", fields[1], " w=", fields[3],
             " extends outside the image");
      }
      if (cy - h / 2 < -kEdgeTolerance || cy + h / 2 > 1 + kEdgeTolerance) {
        Fail(Where(path, line.number, "h"), "box cy=", fields[2], " h=", fields[4],
             " extends outside the image");
      }
      object.box = Box{(cx - w / 2) * width, (cy - h / 2) * height, (cx + w / 2) * width,
                       (cy + h / 2) * height};
    } else if (fields.size() >= 7 && fields.size() % 2 == 1) {
      std::vector<double> polygon;
      for (size_t i = 1; i < fields.size(); ++i) {
        const bool is_x = (i % 2 == 1);
        const std::string field = std::string(is_x ? "x" : "y") + std::to_string((i - 1) / 2 + 1);
        polygon.push_back(ParseNormalised(fields[i], path, line.number, field) *
                          (is_x ? width : height));
      }
      object.area = data_internal::PolygonArea(polygon);
      object.box = data_internal::PolygonsBounds({polygon});
      object.polygons.push_back(std::move(polygon));
    } else {
      Fail(path.string(), ":", line.number, ": expected 5 fields 'class cx cy w h' (or a class and",
           " 3 or more x y pairs), got ", fields.size());
    }
    objects.push_back(std::move(object));
  }
  return objects;
}

std::string FormatNumber(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6f", v);
  return buffer;
}

}  // namespace

Dataset ReadYolo(const fs::path& dir) {
  std::error_code ec;
  fs::path root = dir;
  if (!fs::is_directory(root / "labels", ec) && fs::is_directory(root / "data" / "labels", ec)) {
    root = root / "data";
  }
  const fs::path images_dir = root / "images";
  const fs::path labels_dir = root / "labels";
  if (!fs::is_directory(labels_dir, ec)) {
    Fail("not a YOLO dataset: ", dir.string(), " has no labels/ folder (directly or under data/)");
  }
  if (!fs::is_directory(images_dir, ec)) {
    Fail("YOLO dataset ", dir.string(), " has no images/ folder beside ", labels_dir.string());
  }
  const std::vector<fs::path> image_paths = ListImages(images_dir);
  if (image_paths.empty()) Fail("no images in ", images_dir.string());

  std::set<std::string> stems;
  Dataset dataset;
  for (const fs::path& image_path : image_paths) {
    const std::string stem = image_path.stem().string();
    if (!stems.insert(stem).second) {
      Fail("two images with the stem '", stem, "' in ", images_dir.string(),
           ": their labels/", stem, ".txt would be shared");
    }
    AnnotatedImage image;
    image.name = image_path.filename().string();
    image.path = image_path;
    const cv::Size size = data_internal::ReadImageSize(image_path);
    image.width = size.width;
    image.height = size.height;
    const fs::path label_path = labels_dir / (stem + ".txt");
    if (fs::is_regular_file(label_path, ec)) {
      image.objects = ReadYoloLabels(label_path, image.width, image.height);
    }
    dataset.images.push_back(std::move(image));
  }
  // A label file without its image is a mistake (a renamed or deleted image);
  // labels.txt / classes.txt are class-name lists, not label files.
  for (const auto& entry : fs::directory_iterator(labels_dir)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".txt") continue;
    const std::string stem = entry.path().stem().string();
    if (stems.count(stem) || stem == "labels" || stem == "classes") continue;
    Fail("label file ", entry.path().string(), " has no image ", stem, ".* in ",
         images_dir.string());
  }
  for (const auto& image : dataset.images) {
    for (const auto& object : image.objects) {
      if (!object.polygons.empty()) dataset.has_masks = true;
    }
  }
  data_internal::FinishDataset(&dataset, dir.string(), /*renumber=*/true);
  return dataset;
}

void WriteYolo(const Dataset& dataset, const fs::path& dir) {
  std::set<std::string> stems;
  for (AnnotatedImage image : dataset.images) {
    const std::string stem = fs::path(image.name).stem().string();
    if (!stems.insert(stem).second) {
      Fail("cannot write YOLO: two images share the stem '", stem, "'");
    }
    data_internal::EnsureImageSize(&image, "YOLO (normalised coordinates)");
    std::ostringstream out;
    const double w = image.width, h = image.height;
    for (const Annotation& object : image.objects) {
      const Box& b = object.box;
      out << std::max(0, object.category) << ' ' << FormatNumber(b.CenterX() / w) << ' '
          << FormatNumber(b.CenterY() / h) << ' ' << FormatNumber(b.Width() / w) << ' '
          << FormatNumber(b.Height() / h) << '\n';
    }
    WriteTextFileAtomic(dir / "labels" / (stem + ".txt"), out.str());
    std::error_code ec;
    if (!image.path.empty() && fs::is_regular_file(image.path, ec)) {
      data_internal::CopyFileAtomic(image.path, dir / "images" / image.name);
    }
  }
}

}  // namespace orchard
