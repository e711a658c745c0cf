#include "orchard/eval/yield_metrics.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace {

TEST(YieldMetrics, ByHand) {
  // 180 estimated of 200 harvested: 90 %, error -20, |error| 20, relative 0.1.
  const YieldMetrics m = EvaluateYield(200, 180);
  EXPECT_DOUBLE_EQ(m.percent_of_truth, 90.0);
  EXPECT_DOUBLE_EQ(m.error, -20.0);
  EXPECT_DOUBLE_EQ(m.absolute_error, 20.0);
  EXPECT_DOUBLE_EQ(m.relative_error, 0.1);
  EXPECT_THROW(EvaluateYield(0, 10), Error);
  EXPECT_THROW(EvaluateYield(10, -1), Error);
}

TEST(YieldMetrics, ReadsNumbersAndKeys) {
  const fs::path dir = fs::temp_directory_path() / "orchard_eval_yield";
  fs::remove_all(dir);
  WriteTextFileAtomic(dir / "bare.json", "1234\n");
  WriteTextFileAtomic(dir / "both.json", R"({"total": 250, "harvested": 200})");
  WriteTextFileAtomic(dir / "total.json", R"({"total": 180, "per_tree": [1, 2]})");
  WriteTextFileAtomic(dir / "bad.json", "{\"total\": ");
  WriteTextFileAtomic(dir / "nokey.json", R"({"apples": 3})");
  WriteTextFileAtomic(dir / "string.json", R"({"total": "3"})");
  EXPECT_EQ(ReadYieldCount(dir / "bare.json", YieldFileRole::kTruth), 1234);
  EXPECT_EQ(ReadYieldCount(dir / "both.json", YieldFileRole::kTruth), 200);
  EXPECT_EQ(ReadYieldCount(dir / "both.json", YieldFileRole::kEstimate), 250);
  EXPECT_EQ(ReadYieldCount(dir / "total.json", YieldFileRole::kTruth), 180);
  for (const char* bad : {"bad.json", "nokey.json", "string.json", "missing.json"}) {
    EXPECT_THROW(ReadYieldCount(dir / bad, YieldFileRole::kTruth), Error) << bad;
  }
}

}  // namespace
}  // namespace orchard
