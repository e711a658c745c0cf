// Counting patches from a detector's blobs, labelled from true instance masks:
// each blob's crop is the one the one-side stage hands the counter (the blob's
// own box), its count the apples whose visible pixels lie mostly in the blob.
// A counter trained on them learns the detector's blobs as the 3D stage sees
// them (touching apples, pieces of apples and leaves), not annotators' boxes.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"

namespace orchard {

struct BlobPatchOptions {
  // Apples with fewer visible pixels in the frame are not counted in any blob
  // (the generator's truth of "visible" needs as many).
  int min_apple_pixels = 20;
  // An apple belongs to the blob that holds at least this share of its
  // visible pixels; an apple split more evenly belongs to none, so the blobs'
  // counts never add up to more than the apples in the frame.
  double min_share = 0.5;
  // Counts above this are clipped to it (the counter's top class).
  int max_count = 6;

  void Check() const;
};

struct BlobPatch {
  int blob = 0;   // the blob's label in the detection mask
  cv::Rect crop;  // the blob's box
  int count = 0;  // apples it holds, clipped to max_count
};

// One patch per blob of `blob_labels` (16- or 32-bit labels, 0 = background),
// in label order, counted against `apple_ids` (the generator's instance mask:
// apple id + 1 per visible pixel, 0 elsewhere; same size).
std::vector<BlobPatch> LabelBlobPatches(const cv::Mat& blob_labels, const cv::Mat& apple_ids,
                                        const BlobPatchOptions& options);

// Patches of every frame that has a detection mask (`detections/<stem>.png`,
// e.g. a side's cache), its image (`images/<stem>.*`) and its instance mask
// (`masks/<stem>.png`), every `every`-th such frame in name order, written as
// `out/images/<prefix><stem>_b<blob>.png` and appended to `counts` (name,
// count). Frames without an image or mask are an error. Returns the patches'
// count histogram 0..max_count.
std::vector<int> CutBlobPatches(const fs::path& detections, const fs::path& images, const fs::path& masks,
                                const fs::path& out, const std::string& prefix, int every,
                                const BlobPatchOptions& options, std::vector<ImageCount>* counts);

}  // namespace orchard
