// MinneApple datasets: images/ + masks/<same stem>.png, one instance id per
// apple pixel, 0 = background.
#include <algorithm>
#include <limits>
#include <map>
#include <set>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/dataset_internal.h"
#include "orchard/data/minneapple.h"

namespace orchard {

cv::Mat ReadInstanceMask(const fs::path& path) {
  cv::Mat raw = ReadImage(path, cv::IMREAD_UNCHANGED);
  if (raw.channels() == 4) {
    std::vector<cv::Mat> channels;
    cv::split(raw, channels);
    double lo = 0, hi = 0;
    cv::minMaxLoc(channels[3], &lo, &hi);
    if (lo != hi) Fail("instance mask ", path.string(), " has a varying alpha channel; expected ids");
    channels.pop_back();
    cv::merge(channels, raw);
  }
  if (raw.channels() == 3) {
    std::vector<cv::Mat> channels;
    cv::split(raw, channels);
    if (cv::countNonZero(channels[0] != channels[1]) > 0 ||
        cv::countNonZero(channels[0] != channels[2]) > 0) {
      Fail("instance mask ", path.string(),
           " is a colour image with unequal channels; expected one instance id per pixel");
    }
    raw = channels[0];
  }
  if (raw.channels() != 1) {
    Fail("instance mask ", path.string(), " has ", raw.channels(), " channels; expected 1");
  }
  if (raw.depth() != CV_8U && raw.depth() != CV_16U) {
    Fail("instance mask ", path.string(), " is not an 8- or 16-bit image");
  }
  cv::Mat ids;
  raw.convertTo(ids, CV_32S);
  return ids;
}

std::vector<Annotation> InstancesFromMask(const cv::Mat& ids, bool with_polygons) {
  CV_Assert(ids.type() == CV_32S);
  struct Bounds {
    int x1 = std::numeric_limits<int>::max(), y1 = std::numeric_limits<int>::max();
    int x2 = -1, y2 = -1;
    long long count = 0;
  };
  std::map<int, Bounds> bounds;
  for (int y = 0; y < ids.rows; ++y) {
    const int* row = ids.ptr<int>(y);
    for (int x = 0; x < ids.cols; ++x) {
      const int id = row[x];
      if (id == 0) continue;
      Bounds& b = bounds[id];
      b.x1 = std::min(b.x1, x);
      b.x2 = std::max(b.x2, x);
      b.y1 = std::min(b.y1, y);
      b.y2 = std::max(b.y2, y);
      ++b.count;
    }
  }
  std::vector<Annotation> objects;
  objects.reserve(bounds.size());
  for (const auto& [id, b] : bounds) {
    Annotation object;
    object.box = Box{double(b.x1), double(b.y1), double(b.x2 + 1), double(b.y2 + 1)};
    object.area = static_cast<double>(b.count);
    if (with_polygons) {
      const cv::Rect roi(b.x1, b.y1, b.x2 - b.x1 + 1, b.y2 - b.y1 + 1);
      const cv::Mat binary = (ids(roi) == id);
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(binary, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE, roi.tl());
      for (const auto& contour : contours) {
        std::vector<double> polygon;
        for (const cv::Point& p : contour) {
          polygon.push_back(p.x);
          polygon.push_back(p.y);
        }
        // COCO polygons need three points; a one- or two-pixel piece repeats them.
        while (polygon.size() < 6) {
          polygon.push_back(contour.back().x);
          polygon.push_back(contour.back().y);
        }
        object.polygons.push_back(std::move(polygon));
      }
    }
    objects.push_back(std::move(object));
  }
  return objects;
}

cv::Mat RasteriseInstances(const std::vector<Annotation>& objects, cv::Size size) {
  if (objects.size() > 65535) {
    Fail("cannot write an instance mask with ", objects.size(), " objects (16-bit ids, at most 65535)");
  }
  cv::Mat ids(size, CV_16U, cv::Scalar(0));
  // Larger objects first, so a small apple overlapping a big box stays visible.
  std::vector<size_t> order(objects.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const double area_a = objects[a].area >= 0 ? objects[a].area : objects[a].box.Area();
    const double area_b = objects[b].area >= 0 ? objects[b].area : objects[b].box.Area();
    return area_a > area_b;
  });
  for (const size_t i : order) {
    const cv::Scalar id(static_cast<double>(i + 1));
    const Annotation& object = objects[i];
    if (!object.polygons.empty()) {
      std::vector<std::vector<cv::Point>> polys;
      for (const auto& polygon : object.polygons) {
        std::vector<cv::Point> points;
        for (size_t k = 0; k + 1 < polygon.size(); k += 2) {
          points.emplace_back(cvRound(polygon[k]), cvRound(polygon[k + 1]));
        }
        if (!points.empty()) polys.push_back(std::move(points));
      }
      for (const auto& points : polys) {
        cv::fillPoly(ids, std::vector<std::vector<cv::Point>>{points}, id);
        cv::polylines(ids, std::vector<std::vector<cv::Point>>{points}, true, id);
      }
    } else {
      // Box [x1, x2) covers pixels round(x1) .. round(x2)-1, at least one
      // pixel so that degenerate boxes (thinner than a pixel) are not lost.
      const int x1 = std::clamp(cvRound(object.box.x1), 0, size.width - 1);
      const int y1 = std::clamp(cvRound(object.box.y1), 0, size.height - 1);
      const int x2 = std::clamp(cvRound(object.box.x2), x1 + 1, size.width);
      const int y2 = std::clamp(cvRound(object.box.y2), y1 + 1, size.height);
      ids(cv::Rect(x1, y1, x2 - x1, y2 - y1)).setTo(id);
    }
  }
  return ids;
}

Dataset ReadMinneApple(const fs::path& dir) {
  std::error_code ec;
  const fs::path images_dir = dir / "images";
  const fs::path masks_dir = dir / "masks";
  if (!fs::is_directory(masks_dir, ec)) {
    Fail("not a MinneApple dataset: ", dir.string(), " has no masks/ folder");
  }
  const std::vector<fs::path> mask_paths = ListImages(masks_dir);
  std::map<std::string, fs::path> mask_by_stem;
  for (const fs::path& p : mask_paths) {
    if (!mask_by_stem.emplace(p.stem().string(), p).second) {
      Fail("two masks with the stem '", p.stem().string(), "' in ", masks_dir.string());
    }
  }
  Dataset dataset;
  dataset.has_masks = true;
  if (fs::is_directory(images_dir, ec)) {
    const std::vector<fs::path> image_paths = ListImages(images_dir);
    if (image_paths.empty()) Fail("no images in ", images_dir.string());
    std::set<std::string> used;
    for (const fs::path& image_path : image_paths) {
      const std::string stem = image_path.stem().string();
      const auto it = mask_by_stem.find(stem);
      if (it == mask_by_stem.end()) {
        Fail("image ", image_path.string(), " has no mask ", (masks_dir / (stem + ".png")).string());
      }
      if (!used.insert(stem).second) {
        Fail("two images with the stem '", stem, "' in ", images_dir.string());
      }
      const cv::Mat ids = ReadInstanceMask(it->second);
      const cv::Size size = data_internal::ReadImageSize(image_path);
      if (size != ids.size()) {
        Fail("mask ", it->second.string(), " is ", ids.cols, "x", ids.rows, " but image ",
             image_path.string(), " is ", size.width, "x", size.height);
      }
      AnnotatedImage image;
      image.name = image_path.filename().string();
      image.path = image_path;
      image.width = size.width;
      image.height = size.height;
      image.objects = InstancesFromMask(ids, /*with_polygons=*/true);
      dataset.images.push_back(std::move(image));
    }
    for (const auto& [stem, path] : mask_by_stem) {
      if (!used.count(stem)) {
        Fail("mask ", path.string(), " has no image ", stem, ".* in ", images_dir.string());
      }
    }
  } else {
    // Masks alone (no images/ folder): names are the mask file names.
    if (mask_paths.empty()) Fail("no masks in ", masks_dir.string());
    for (const fs::path& mask_path : mask_paths) {
      const cv::Mat ids = ReadInstanceMask(mask_path);
      AnnotatedImage image;
      image.name = mask_path.filename().string();
      image.width = ids.cols;
      image.height = ids.rows;
      image.objects = InstancesFromMask(ids, /*with_polygons=*/true);
      dataset.images.push_back(std::move(image));
    }
  }
  data_internal::FinishDataset(&dataset, dir.string(), /*renumber=*/true);
  return dataset;
}

void WriteMinneApple(const Dataset& dataset, const fs::path& dir) {
  std::set<std::string> stems;
  for (AnnotatedImage image : dataset.images) {
    const std::string stem = fs::path(image.name).stem().string();
    if (!stems.insert(stem).second) {
      Fail("cannot write MinneApple: two images share the stem '", stem, "'");
    }
    data_internal::EnsureImageSize(&image, "MinneApple (mask size)");
    const cv::Mat ids = RasteriseInstances(image.objects, cv::Size(image.width, image.height));
    WriteImageAtomic(dir / "masks" / (stem + ".png"), ids);
    std::error_code ec;
    if (!image.path.empty() && fs::is_regular_file(image.path, ec)) {
      data_internal::CopyFileAtomic(image.path, dir / "images" / image.name);
    }
  }
}

}  // namespace orchard
