#include "orchard/data/split.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <random>
#include <set>

#include "orchard/core/error.h"

namespace orchard {

std::string PhotoId(const std::string& image_name) {
  std::string stem = fs::path(image_name).stem().string();
  const size_t underscore = stem.find_last_of('_');
  if (underscore == std::string::npos || underscore + 1 == stem.size()) return stem;
  const bool digits = std::all_of(stem.begin() + underscore + 1, stem.end(),
                                  [](unsigned char c) { return std::isdigit(c); });
  return digits ? stem.substr(0, underscore) : stem;
}

Dataset SelectPhotos(const Dataset& dataset, const std::vector<std::string>& photos) {
  const std::set<std::string> wanted(photos.begin(), photos.end());
  Dataset selected;
  selected.has_masks = dataset.has_masks;
  for (const AnnotatedImage& image : dataset.images) {
    if (wanted.count(PhotoId(image.name))) selected.images.push_back(image);
  }
  return selected;
}

DatasetSplit SplitByPhoto(const Dataset& dataset, double test_fraction, uint64_t seed) {
  ORCHARD_CHECK_OPTION(test_fraction >= 0 && test_fraction <= 1, "test fraction must be in [0, 1], got ",
                       test_fraction);
  std::set<std::string> unique;
  for (const AnnotatedImage& image : dataset.images) unique.insert(PhotoId(image.name));
  std::vector<std::string> photos(unique.begin(), unique.end());
  if (photos.empty()) Fail("cannot split an empty dataset");
  // Fisher-Yates with the raw generator: std::shuffle's algorithm is not
  // specified, so it could split differently with another standard library.
  std::mt19937_64 rng(seed);
  for (size_t i = photos.size(); i > 1; --i) std::swap(photos[i - 1], photos[rng() % i]);
  size_t n_test = static_cast<size_t>(std::lround(test_fraction * photos.size()));
  if (photos.size() >= 2 && test_fraction > 0 && test_fraction < 1) {
    n_test = std::clamp<size_t>(n_test, 1, photos.size() - 1);
  }
  DatasetSplit split;
  split.test_photos.assign(photos.begin(), photos.begin() + n_test);
  split.train_photos.assign(photos.begin() + n_test, photos.end());
  std::sort(split.test_photos.begin(), split.test_photos.end());
  std::sort(split.train_photos.begin(), split.train_photos.end());
  split.train = SelectPhotos(dataset, split.train_photos);
  split.test = SelectPhotos(dataset, split.test_photos);
  return split;
}

}  // namespace orchard
