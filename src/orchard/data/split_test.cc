#include "orchard/data/split.h"

#include <gtest/gtest.h>

#include <set>

namespace orchard {
namespace {

TEST(Split, PhotoId) {
  EXPECT_EQ(PhotoId("DSC_1042_17kv1r16k_3.jpg"), "DSC_1042_17kv1r16k");
  EXPECT_EQ(PhotoId("DSC_1042_17kv1r16k_13.jpg"), "DSC_1042_17kv1r16k");
  EXPECT_EQ(PhotoId("dataset3_back_570.png"), "dataset3_back");
  EXPECT_EQ(PhotoId("frame.png"), "frame");
  EXPECT_EQ(PhotoId("a_b.png"), "a_b");
  EXPECT_EQ(PhotoId("a_.png"), "a_");
}

TEST(Split, KeepsPhotosTogetherAndIsDeterministic) {
  Dataset d;
  for (int photo = 0; photo < 10; ++photo) {
    for (int crop = 0; crop < 3; ++crop) {
      AnnotatedImage image;
      image.name = "P" + std::to_string(photo) + "_" + std::to_string(crop) + ".jpg";
      d.images.push_back(image);
    }
  }
  DatasetSplit a = SplitByPhoto(d, 0.3, 7);
  DatasetSplit b = SplitByPhoto(d, 0.3, 7);
  EXPECT_EQ(a.test_photos, b.test_photos);
  EXPECT_EQ(a.test_photos.size(), 3u);
  EXPECT_EQ(a.train.images.size() + a.test.images.size(), d.images.size());
  std::set<std::string> train_photos;
  for (const auto& image : a.train.images) train_photos.insert(PhotoId(image.name));
  for (const auto& image : a.test.images) EXPECT_EQ(train_photos.count(PhotoId(image.name)), 0u);
  // Tiny fractions still leave one photo on each side.
  EXPECT_EQ(SplitByPhoto(d, 0.01, 1).test_photos.size(), 1u);
  EXPECT_EQ(SplitByPhoto(d, 0.99, 1).train_photos.size(), 1u);
}

}  // namespace
}  // namespace orchard
