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

std::vector<std::string> ChooseTestPhotos(const std::vector<std::string>& photo_ids, double test_fraction,
                                          uint64_t seed) {
  ORCHARD_CHECK_OPTION(test_fraction >= 0 && test_fraction <= 1, "test fraction must be in [0, 1], got ",
                       test_fraction);
  const std::set<std::string> unique(photo_ids.begin(), photo_ids.end());
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
  photos.resize(n_test);
  std::sort(photos.begin(), photos.end());
  return photos;
}

DatasetSplit SplitByPhoto(const Dataset& dataset, double test_fraction, uint64_t seed) {
  std::vector<std::string> all;
  for (const AnnotatedImage& image : dataset.images) all.push_back(PhotoId(image.name));
  DatasetSplit split;
  split.test_photos = ChooseTestPhotos(all, test_fraction, seed);
  const std::set<std::string> test(split.test_photos.begin(), split.test_photos.end());
  for (const std::string& photo : std::set<std::string>(all.begin(), all.end())) {
    if (!test.count(photo)) split.train_photos.push_back(photo);
  }
  split.train = SelectPhotos(dataset, split.train_photos);
  split.test = SelectPhotos(dataset, split.test_photos);
  return split;
}

}  // namespace orchard
