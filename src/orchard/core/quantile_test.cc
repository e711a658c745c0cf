#include "orchard/core/quantile.h"

#include <gtest/gtest.h>

namespace orchard {
namespace {

TEST(Quantile, RanksWithoutInterpolation) {
  const std::vector<double> v = {5, 1, 4, 2, 3};
  EXPECT_EQ(Quantile(v, 0.5), 3);
  EXPECT_EQ(Quantile(v, 0), 1);
  EXPECT_EQ(Quantile(v, 1), 5);
  EXPECT_EQ(Quantile(v, 0.39), 2);  // floor(0.39 * 5) = 1
  EXPECT_EQ(Quantile({4, 1, 3, 2}, 0.5), 3);  // the upper median
  EXPECT_EQ(Quantile({}, 0.5), 0);
}

}  // namespace
}  // namespace orchard
