// In-memory annotated datasets and prediction sets, and readers/writers for the
// formats users of this field exchange: MinneApple (images/ + instance masks/),
// YOLO txt, COCO json, VIA polygon json, CodaLab result files.
//
// Every reader throws orchard::Error with the file, line and field named when
// the input is malformed; nothing is silently skipped.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "orchard/core/box.h"

namespace orchard {

namespace fs = std::filesystem;

// One annotated object (an apple).
struct Annotation {
  Box box;
  // Object area in pixels when known from a mask or polygon; negative when only
  // the box is known (then metrics use the box area, as pycocotools does for
  // box-only ground truth).
  double area = -1;
  // COCO-style polygons: each a flat list x0,y0,x1,y1,... in pixels. Empty if none.
  std::vector<std::vector<double>> polygons;
  int category = 0;  // 0 = apple (the only class)
};

struct AnnotatedImage {
  std::string name;      // file name without folder, e.g. "DSC_1042_17kv1r16k_0.jpg"
  fs::path path;         // the image file when it is known to exist; may be empty (COCO json alone)
  std::int64_t id = -1;  // COCO image id; readers of other formats number images 1..N in name order
  int width = 0;
  int height = 0;
  std::vector<Annotation> objects;
};

struct Dataset {
  std::vector<AnnotatedImage> images;  // sorted by name
  // True when object areas come from instance masks (MinneApple) or polygons,
  // so COCO small/medium/large use them instead of box areas.
  bool has_masks = false;

  // Finds an image by file name, or by name without extension ("a" matches
  // "a.png"); nullptr when absent or ambiguous.
  const AnnotatedImage* Find(const std::string& name) const;
  size_t NumObjects() const;
};

enum class DatasetFormat { kMinneApple, kYolo, kCoco, kVia };

// "minneapple", "yolo", "coco", "via" -> format; throws on anything else.
DatasetFormat ParseDatasetFormat(const std::string& name);
std::string DatasetFormatName(DatasetFormat format);

// Guesses the format of `path`: a folder with masks/ is MinneApple; a folder
// with labels/ (directly or under data/) is YOLO; a .json file is COCO or VIA
// (by content). Throws with a clear message when it cannot tell.
DatasetFormat DetectDatasetFormat(const fs::path& path);

// Reads a dataset in the given (or detected) format. For COCO and VIA the
// images folder is optional (`image_dir`); without it image paths stay empty.
Dataset ReadDataset(const fs::path& path, std::optional<DatasetFormat> format = std::nullopt,
                    const fs::path& image_dir = {});

// MinneApple: `dir/images/*.png|jpg` and `dir/masks/<same stem>.png`, each mask
// one instance id per apple (8- or 16-bit), 0 = background. Boxes are the
// tight pixel bounds [xmin, xmax+1) of each id, areas the pixel counts.
Dataset ReadMinneApple(const fs::path& dir);
// Without images/, the masks alone are read (names = mask file names, no
// paths). An image without a mask, a mask without an image, or a size
// mismatch is an error. Polygons are the outer contours of each instance
// (see minneapple.h).
// Writes images (copied from their paths) and masks rasterised from polygons
// (or filled boxes when an object has no polygon) as 16-bit PNG; holes inside
// an instance are not kept (polygons have none).
void WriteMinneApple(const Dataset& dataset, const fs::path& dir);
// Reads one instance mask as CV_32S ids; throws when unreadable or multi-channel
// in a way that cannot be ids.
cv::Mat ReadInstanceMask(const fs::path& path);

// YOLO: `dir/images/` and `dir/labels/<stem>.txt` (also accepted under
// `dir/data/`), lines `class cx cy w h` normalised to [0,1]. An image without a
// label file has no objects; a label file without an image is an error
// (except labels.txt / classes.txt, class-name lists). Lines with a class and 3
// or more `x y` pairs (YOLO segmentation) become polygons. Values outside
// [0,1] by more than 1e-3, boxes reaching outside the image by more than 1%,
// negative sizes, NaN: errors naming file, line and field. Image sizes are
// read from the image files.
Dataset ReadYolo(const fs::path& dir);
// Writes `dir/labels/*.txt` (and `dir/images/` copies when the source paths exist).
void WriteYolo(const Dataset& dataset, const fs::path& dir);

// COCO json: images, annotations (bbox [x,y,w,h], optional polygon
// segmentation, area), categories. All categories are treated as apple.
// Image names drop any folder in file_name; ids are kept as in the file.
// Crowd annotations (iscrowd=1) are rejected; RLE segmentations keep only their
// area. Note: the per-image json files of AppleBBCH81 store the box CENTRE in
// bbox[0..1] (their YOLO labels are right); read the YOLO folder instead.
// WriteCoco writes info, licenses, images, annotations (id, image_id,
// category_id=1, bbox, area = pixel/polygon area or box area, iscrowd=0,
// segmentation only when polygons exist) and categories [{id:1,name:"apple"}];
// image ids are kept when positive and unique, else 1..N.
Dataset ReadCoco(const fs::path& json_path, const fs::path& image_dir = {});
void WriteCoco(const Dataset& dataset, const fs::path& json_path);

// VIA (VGG Image Annotator) project/export json with polygon, rect, circle or
// ellipse regions. Image sizes come from `image_dir` when given.
Dataset ReadVia(const fs::path& json_path, const fs::path& image_dir = {});

// ----- Predictions -----------------------------------------------------------

struct ScoredBox {
  Box box;
  double score = 1.0;
};

// Image name (as written in the file) -> detections in that image.
using Predictions = std::map<std::string, std::vector<ScoredBox>>;

// CodaLab/MinneApple detection results: lines `name,x1,y1,x2,y2,score`; an
// optional header line (a first line with no number after the name) is skipped.
Predictions ReadCodaLabDetections(const fs::path& path);
// Writes no header line: the MinneApple CodaLab servers expect data lines only.
// Images appear in name order, each image's boxes in the given order.
void WriteCodaLabDetections(const Predictions& predictions, const fs::path& path);

// COCO results json: [{"image_id", "bbox": [x,y,w,h], "score"}, ...]. Image ids
// are resolved to names through `ground_truth` (ids as its reader assigned them).
Predictions ReadCocoResults(const fs::path& path, const Dataset& ground_truth);
void WriteCocoResults(const Predictions& predictions, const Dataset& ground_truth,
                      const fs::path& path);

// Reads a CodaLab detection file or a COCO results json (by extension/content).
Predictions ReadPredictions(const fs::path& path, const Dataset& ground_truth);

// Counting results: lines `name,count` (optional header).
struct ImageCount {
  std::string name;
  int count = 0;
};
std::vector<ImageCount> ReadCodaLabCounts(const fs::path& path);
// Writes no header line (as for detections), counts in the given order.
void WriteCodaLabCounts(const std::vector<ImageCount>& counts, const fs::path& path);

}  // namespace orchard
