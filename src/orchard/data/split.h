// Train/test splits that keep every crop (or frame) of one photo (or video) on
// the same side: crops cut from one photo overlap, so splitting them would
// leak test pixels into training.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "orchard/data/dataset.h"

namespace orchard {

// The photo an image comes from: its file stem without a trailing
// "_<digits>" crop or frame index ("DSC_1042_17kv1r16k_3.jpg" ->
// "DSC_1042_17kv1r16k", "dataset3_back_570.png" -> "dataset3_back").
std::string PhotoId(const std::string& image_name);

struct DatasetSplit {
  Dataset train;
  Dataset test;
  std::vector<std::string> train_photos;  // sorted
  std::vector<std::string> test_photos;   // sorted
};

// Puts round(test_fraction * photos) photos (at least one on each side when
// there are two or more) in the test set, chosen by a seeded shuffle of the
// sorted photo ids, so the same seed gives the same split on any machine.
DatasetSplit SplitByPhoto(const Dataset& dataset, double test_fraction, uint64_t seed);

// The photos SplitByPhoto would put in the test set, from a list of photo ids
// (duplicates ignored), sorted.
std::vector<std::string> ChooseTestPhotos(const std::vector<std::string>& photos, double test_fraction,
                                          uint64_t seed);

// The images of `dataset` whose photo is in `photos`.
Dataset SelectPhotos(const Dataset& dataset, const std::vector<std::string>& photos);

}  // namespace orchard
