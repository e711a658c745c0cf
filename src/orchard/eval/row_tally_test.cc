#include "orchard/eval/row_tally.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

RowOutcome Row(const char* name, double front, double vf, double back, double vb, double total, double va) {
  RowOutcome r;
  r.name = name;
  r.front = front, r.visible_front = vf, r.back = back, r.visible_back = vb, r.total = total, r.visible_any = va;
  r.harvested = 2 * va;
  return r;
}

TEST(RowTally, CountsWithinTheTolerancesByHand) {
  // Sides: +3% (on the tolerance), -5%, 0%, +1%; rows: -2.5%, +2% (on it).
  const RowTally t = TallyRows({Row("a", 103, 100, 95, 100, 195, 200), Row("b", 200, 200, 101, 100, 204, 200)},
                               RowTallyOptions());
  EXPECT_EQ(t.sides.n, 4);
  EXPECT_EQ(t.sides.within, 3);
  EXPECT_NEAR(t.sides.mae, (3 + 5 + 0 + 1) / 4.0, 1e-9);
  EXPECT_NEAR(t.sides.mean, (3 - 5 + 0 + 1) / 4.0, 1e-9);
  EXPECT_NEAR(t.sides.min, -5, 1e-9);
  EXPECT_NEAR(t.sides.max, 3, 1e-9);
  EXPECT_EQ(t.merged.n, 2);
  EXPECT_EQ(t.merged.within, 1);
  EXPECT_NEAR(t.merged.mae, 2.25, 1e-9);
  EXPECT_NEAR(t.merged.mean, -0.25, 1e-9);
  EXPECT_NEAR(t.mean_percent_of_harvested, (48.75 + 51.0) / 2, 1e-9);
  const std::string csv = RowTallyCsv(t, RowTallyOptions());
  EXPECT_NE(csv.find("a,103.00,100.00,3.00,95.00,100.00,-5.00,195.00,200.00,-2.50,400.00,48.75,"), std::string::npos)
      << csv;
  EXPECT_NE(csv.find(",1,0,0\n"), std::string::npos) << csv;
  RowTallyOptions strict;
  strict.side_tolerance = 0.5;
  EXPECT_EQ(TallyRows(t.rows, strict).sides.within, 1);
  strict.row_tolerance = 0;
  EXPECT_THROW(TallyRows(t.rows, strict), Error);
  EXPECT_EQ(TallyRows({}, RowTallyOptions()).sides.n, 0);
}

TEST(RowTally, ReadsYieldJsonAndSaysWhatIsMissing) {
  const fs::path dir = test::FreshTempDir("orchard_row_tally");
  WriteTextFileAtomic(dir / "r1" / "yield.json",
                      R"({"total": 230, "front": 210, "back": 200, "sum_of_sides": 410,
                          "truth": {"visible_front": 217, "visible_back": 210, "visible_any": 225, "harvested": 274}})");
  const RowOutcome r = ReadRowOutcome(dir / "r1");
  EXPECT_EQ(r.name, "r1");
  EXPECT_EQ(r.total, 230);
  EXPECT_EQ(r.sum_of_sides, 410);
  EXPECT_EQ(r.visible_any, 225);
  EXPECT_EQ(r.harvested, 274);
  EXPECT_EQ(ReadRowOutcome(dir / "r1" / "").name, "r1");
  WriteTextFileAtomic(dir / "no_truth" / "yield.json", R"({"total": 230, "front": 210, "back": 200})");
  WriteTextFileAtomic(dir / "broken" / "yield.json", R"({"total": 2)");
  WriteTextFileAtomic(dir / "empty_side" / "yield.json",
                      R"({"total": 2, "front": 2, "back": 0,
                          "truth": {"visible_front": 2, "visible_back": 0, "visible_any": 2}})");
  fs::create_directories(dir / "not_a_run");
  for (const char* bad : {"no_truth", "broken", "empty_side", "not_a_run"}) {
    try {
      ReadRowOutcome(dir / bad);
      ADD_FAILURE() << bad << " was read";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("yield.json"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace orchard
