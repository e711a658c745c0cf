#include "orchard/eval/count_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

#include "orchard/core/error.h"

namespace orchard {
namespace {

TEST(CountMetrics, ByHand) {
  // truth a0 b1 c2 d6 e8; predicted a0 b2 c2 d7 e8 ("e" without extension).
  // exact: a, c, e -> 3/5; MAE (0+1+0+1+0)/5 = 0.4. Confusion (6 = 6+):
  // [0][0] [1][2] [2][2] and [6][6] twice (6->7 and 8->8). Per class:
  // 0: 1/1, 1: 0/1, 2: 1/1, 6: 1/2 (d is a near miss), 3..5: NaN.
  const std::vector<ImageCount> gt = {{"a.png", 0}, {"b.png", 1}, {"c.png", 2}, {"d.png", 6}, {"e.png", 8}};
  const std::vector<ImageCount> pred = {{"e", 8}, {"d.png", 7}, {"c.png", 2}, {"b.png", 2}, {"a.png", 0}};
  const CountMetrics m = EvaluateCounts(gt, pred);
  EXPECT_EQ(m.images, 5);
  EXPECT_DOUBLE_EQ(m.accuracy, 0.6);
  EXPECT_DOUBLE_EQ(m.mae, 0.4);
  EXPECT_EQ(m.confusion[0][0], 1);
  EXPECT_EQ(m.confusion[1][2], 1);
  EXPECT_EQ(m.confusion[2][2], 1);
  EXPECT_EQ(m.confusion[6][6], 2);
  int total = 0;
  for (const auto& row : m.confusion) {
    for (int v : row) total += v;
  }
  EXPECT_EQ(total, 5);
  EXPECT_EQ(m.accuracy_per_class[0], 1.0);
  EXPECT_EQ(m.accuracy_per_class[1], 0.0);
  EXPECT_EQ(m.accuracy_per_class[6], 0.5);
  EXPECT_TRUE(std::isnan(m.accuracy_per_class[3]));
  EXPECT_EQ(m.images_per_class[6], 2);
}

TEST(CountMetrics, BadInputsAreErrors) {
  const std::vector<ImageCount> gt = {{"a.png", 1}, {"b.png", 2}};
  EXPECT_THROW(EvaluateCounts(gt, {{"a.png", 1}}), Error);                             // b missing
  EXPECT_THROW(EvaluateCounts(gt, {{"a.png", 1}, {"b.png", 2}, {"z.png", 1}}), Error);  // unknown
  EXPECT_THROW(EvaluateCounts(gt, {{"a.png", 1}, {"a", 1}, {"b.png", 2}}), Error);      // twice
  EXPECT_THROW(EvaluateCounts(gt, {{"a.png", -1}, {"b.png", 2}}), Error);               // negative
  EXPECT_THROW(EvaluateCounts({}, {}), Error);
  EXPECT_THROW(EvaluateCounts({{"a.png", 1}, {"a.png", 2}}, {{"a.png", 1}}), Error);  // repeated gt
}

}  // namespace
}  // namespace orchard
