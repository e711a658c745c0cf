#include "orchard/data/blob_patches.h"

#include <algorithm>
#include <map>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"

namespace orchard {

void BlobPatchOptions::Check() const {
  ORCHARD_CHECK_OPTION(min_apple_pixels >= 1, "minimum apple pixels must be >= 1, got ", min_apple_pixels);
  ORCHARD_CHECK_OPTION(min_share > 0.5 - 1e-12 && min_share <= 1,
                       "an apple's share in its blob must be in [0.5, 1] (one blob per apple), got ", min_share);
  ORCHARD_CHECK_OPTION(max_count >= 1, "max count must be >= 1, got ", max_count);
}

std::vector<BlobPatch> LabelBlobPatches(const cv::Mat& blob_labels, const cv::Mat& apple_ids,
                                        const BlobPatchOptions& options) {
  options.Check();
  if (blob_labels.channels() != 1 || apple_ids.channels() != 1) Fail("blob labels and apple ids must be one channel");
  if (blob_labels.size() != apple_ids.size())
    Fail("blob labels are ", blob_labels.cols, "x", blob_labels.rows, ", the apple ids ", apple_ids.cols, "x",
         apple_ids.rows);
  cv::Mat1i blobs, apples;
  blob_labels.convertTo(blobs, CV_32S);
  apple_ids.convertTo(apples, CV_32S);
  std::map<int, cv::Rect> box;                  // blob -> bounding box
  std::map<int, int> apple_pixels;              // apple -> visible pixels
  std::map<std::pair<int, int>, int> in_blob;   // (apple, blob) -> pixels
  for (int y = 0; y < blobs.rows; ++y)
    for (int x = 0; x < blobs.cols; ++x) {
      const int b = blobs(y, x), a = apples(y, x);
      if (a > 0) ++apple_pixels[a];
      if (b <= 0) continue;
      auto [it, inserted] = box.emplace(b, cv::Rect(x, y, 1, 1));
      if (!inserted) it->second |= cv::Rect(x, y, 1, 1);
      if (a > 0) ++in_blob[{a, b}];
    }
  std::map<int, int> count;
  for (const auto& [key, n] : in_blob) {
    const int total = apple_pixels[key.first];
    if (total >= options.min_apple_pixels && n >= options.min_share * total) ++count[key.second];
  }
  std::vector<BlobPatch> patches;
  for (const auto& [b, rect] : box) patches.push_back({b, rect, std::min(count[b], options.max_count)});
  return patches;
}

std::vector<int> CutBlobPatches(const fs::path& detections, const fs::path& images, const fs::path& masks,
                                const fs::path& out, const std::string& prefix, int every,
                                const BlobPatchOptions& options, std::vector<ImageCount>* counts) {
  options.Check();
  ORCHARD_CHECK_OPTION(every >= 1, "--every must be >= 1, got ", every);
  std::map<std::string, fs::path> image_of;
  for (const fs::path& p : ListImages(images)) image_of.emplace(p.stem().string(), p);
  std::vector<fs::path> frames;
  for (const fs::path& p : ListImages(detections))
    if (p.extension() == ".png") frames.push_back(p);
  if (frames.empty()) Fail("no detection masks (*.png) in ", detections.string());
  std::vector<int> histogram(options.max_count + 1, 0);
  for (size_t k = 0; k < frames.size(); k += every) {
    const std::string stem = frames[k].stem().string();
    const auto image_path = image_of.find(stem);
    if (image_path == image_of.end()) Fail("no image for detection ", frames[k].filename().string(), " in ", images.string());
    const cv::Mat image = ReadImage(image_path->second);
    const cv::Mat labels = ReadImage(frames[k], cv::IMREAD_UNCHANGED);
    const cv::Mat ids = ReadImage(masks / (stem + ".png"), cv::IMREAD_UNCHANGED);
    if (labels.size() != image.size())
      Fail("detection ", frames[k].string(), " is ", labels.cols, "x", labels.rows, ", its image ", image.cols, "x",
           image.rows);
    for (const BlobPatch& p : LabelBlobPatches(labels, ids, options)) {
      const std::string name = prefix + stem + "_b" + std::to_string(p.blob) + ".png";
      WriteImageAtomic(out / "images" / name, image(p.crop));
      counts->push_back({name, p.count});
      ++histogram[p.count];
    }
  }
  return histogram;
}

}  // namespace orchard
