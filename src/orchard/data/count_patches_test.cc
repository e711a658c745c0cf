#include "orchard/data/count_patches.h"

#include <gtest/gtest.h>

namespace orchard {
namespace {

Annotation Object(const Box& box) {
  Annotation a;
  a.box = box;
  return a;
}

TEST(CountPatches, GroupsTouchingBoxesTransitively) {
  // 0 and 1 overlap, 1 and 2 touch within the tolerance, 3 is alone.
  std::vector<Box> boxes = {{0, 0, 10, 10}, {8, 0, 18, 10}, {19, 0, 29, 10}, {50, 50, 60, 60}};
  auto groups = GroupTouchingBoxes(boxes, 2.0);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0], (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(groups[1], (std::vector<int>{3}));
  // Without tolerance, 1 and 2 (gap of 1 px) are apart.
  EXPECT_EQ(GroupTouchingBoxes(boxes, 0.0).size(), 3u);
}

TEST(CountPatches, LabelsClustersLeavesOutLargeOnesAndAddsBackground) {
  Dataset d;
  AnnotatedImage image;
  image.name = "a_0.jpg";
  image.width = 400;
  image.height = 300;
  // A pair, a single on the border, and a cluster of seven in a row.
  for (Box b : {Box{100, 100, 120, 120}, Box{119, 100, 139, 120}, Box{0, 0, 15, 15}}) image.objects.push_back(Object(b));
  for (int i = 0; i < 7; ++i) image.objects.push_back(Object(Box{200.0 + 10 * i, 250, 211.0 + 10 * i, 261}));
  d.images.push_back(image);
  CountPatchOptions options;
  options.background_per_image = 2;
  auto patches = MakeCountPatches(d, options);
  std::vector<int> counts;
  for (const auto& p : patches) counts.push_back(p.count);
  ASSERT_EQ(counts.size(), 4u);
  // Groups come in order of their smallest box index: the pair, then the border box.
  EXPECT_EQ(counts[0], 2);
  // Pair box 100..139 x 100..120, margin 0.1 * 39 = 3.9 -> [96.1, 142.9] x [96.1, 123.9] -> 96..143 x 96..124.
  EXPECT_EQ(patches[0].crop, cv::Rect(96, 96, 47, 28));
  EXPECT_EQ(counts[1], 1);
  EXPECT_EQ(patches[1].crop, cv::Rect(0, 0, 18, 18));  // 0..15 box, minimum margin 3 -> [-3, 18], clamped at 0
  // Each cluster patch carries its boxes' centres in crop pixels (box 100..120 -> centre pixel 109.5).
  ASSERT_EQ(patches[0].centres.size(), 2u);
  EXPECT_FLOAT_EQ(patches[0].centres[0].x, 109.5f - 96);
  EXPECT_FLOAT_EQ(patches[0].centres[0].y, 109.5f - 96);
  EXPECT_FLOAT_EQ(patches[0].centres[1].x, 128.5f - 96);
  ASSERT_EQ(patches[1].centres.size(), 1u);
  EXPECT_FLOAT_EQ(patches[1].centres[0].x, 7.0f);
  EXPECT_EQ(counts[2], 0);
  EXPECT_EQ(counts[3], 0);
  for (int k = 2; k < 4; ++k) {
    EXPECT_TRUE(patches[k].centres.empty());
    for (const auto& o : image.objects) {
      const cv::Rect& c = patches[k].crop;
      EXPECT_EQ(IntersectionArea(o.box, Box{double(c.x), double(c.y), double(c.x + c.width), double(c.y + c.height)}), 0.0);
    }
  }
}

}  // namespace
}  // namespace orchard
