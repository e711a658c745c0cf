// Counting patches from box annotations: boxes that touch or overlap form a
// cluster, the cluster is cut with a margin and labelled with its number of
// boxes (the cluster counter's classes 0..6); background windows that hold no
// apple are labelled 0. This is how the study built real counting data.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "orchard/data/dataset.h"

namespace orchard {

struct CountPatchOptions {
  // Boxes whose gap is at most this many pixels touch and belong to one cluster.
  double touch_tolerance = 2.0;
  // Margin added on every side, as a fraction of the cluster box's longer side,
  // so the patch shows the fruit outline as a detector's blob crop would.
  double margin = 0.1;
  int min_margin = 3;  // pixels
  // Clusters with more boxes than this are left out (the classifier's top class).
  int max_count = 6;
  // Background patches (count 0) per image, placed where no box is.
  int background_per_image = 1;
  // Boxes smaller than this (either side, pixels) are annotation slivers: they
  // still join clusters, but a cluster made only of them is left out.
  double min_box_side = 4.0;
  uint64_t seed = 0;  // background placement

  void Check() const;
};

struct CountPatch {
  std::string image;  // name of the source image in the dataset
  cv::Rect crop;      // inside the image
  int count = 0;
  // Centres of the cluster's boxes in crop pixel coordinates (empty for
  // background): point supervision for a counter that also learns where.
  std::vector<cv::Point2f> centres;
};

// The crop of a cluster box as the counting patches cut it: `options.margin`
// of its longer side (at least `min_margin` pixels) on every side, clamped to
// the image. A counter trained on such patches reads a detector's blob the
// same way.
cv::Rect ClusterPatchRect(const Box& box, int image_width, int image_height, const CountPatchOptions& options = {});

// Groups of box indices that touch or overlap (transitively), each sorted.
std::vector<std::vector<int>> GroupTouchingBoxes(const std::vector<Box>& boxes, double tolerance);

// Patches of every image of `dataset`, in image order. Image sizes come from
// the dataset (width/height must be known).
std::vector<CountPatch> MakeCountPatches(const Dataset& dataset, const CountPatchOptions& options);

// Writes each patch as `dir/images/<image stem>_p<k>.png` (cut from the
// dataset's image files) and `dir/counts.csv` (CodaLab `name,count`): the
// layout of the synthetic generator's patches.
void WriteCountPatches(const Dataset& dataset, const std::vector<CountPatch>& patches, const fs::path& dir);

}  // namespace orchard
