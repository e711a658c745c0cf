// Calibration against harvested rows: the ratio estimator, its leave-one-out
// error, the table and file formats, and their errors.
#include "orchard/merge/calibration.h"

#include <gtest/gtest.h>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/test_util.h"

namespace orchard {
namespace {

CalibrationRun Counted(const std::string& name, double estimate, double harvested, const std::string& detector = "unet",
                   const std::string& counter = "cnn") {
  return {name, estimate, harvested, detector, counter};
}

TEST(Calibrate, RatioOfSumsAndEachRunEstimatedFromTheOthers) {
  const Calibration c = Calibrate({Counted("a", 80, 100), Counted("b", 90, 108), Counted("c", 100, 130)});
  EXPECT_DOUBLE_EQ(c.factor, 338.0 / 270.0);
  ASSERT_EQ(c.loo_error_percent.size(), 3u);
  // a from b and c: 80 * 238 / 190 = 100.2 of 100.
  EXPECT_NEAR(c.loo_error_percent[0], 100.0 * (80.0 * 238.0 / 190.0 - 100.0) / 100.0, 1e-9);
  EXPECT_NEAR(c.loo_error_percent[2], 100.0 * (100.0 * 208.0 / 170.0 - 130.0) / 130.0, 1e-9);
  double mae = 0;
  for (double e : c.loo_error_percent) mae += std::abs(e) / 3;
  EXPECT_NEAR(c.loo_mean_absolute_error_percent, mae, 1e-9);

  const Calibration one = Calibrate({Counted("a", 80, 100)});
  EXPECT_DOUBLE_EQ(one.factor, 1.25);
  EXPECT_TRUE(one.loo_error_percent.empty());
}

TEST(Calibrate, BadRunsAreClearErrors) {
  EXPECT_THROW(Calibrate({}), Error);
  EXPECT_THROW(Calibrate({Counted("a", 80, 0)}), Error);
  EXPECT_THROW(Calibrate({Counted("a", -1, 10)}), Error);
  EXPECT_THROW(Calibrate({Counted("a", 0, 10), Counted("b", 0, 12)}), Error);
  try {
    Calibrate({Counted("a", 80, 100, "unet:models/unet.pt@11"), Counted("b", 90, 100, "gmm:models/gmm.yml@22")});
    FAIL() << "calibrated across detectors";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("detector"), std::string::npos) << e.what();
  }
  // The same model in another folder is the same detector.
  EXPECT_NO_THROW(Calibrate({Counted("a", 80, 100, "unet:models/unet.pt@11"), Counted("b", 90, 100, "unet:/opt/unet.pt@11")}));
  EXPECT_EQ(MethodKey("unet:/opt/m/unet.pt@1a2b threshold=0.3"), "unet@1a2b threshold=0.3");
  EXPECT_EQ(MethodKey("masks"), "masks");
}

TEST(CalibrationFiles, TableToFileAndBack) {
  const fs::path dir = test::FreshTempDir("calibration_test");
  WriteTextFileAtomic(dir / "r1/yield.json",
                      R"({"total": 200, "settings": {"detector": "unet:models/unet.pt@ab", "counter": "cnn:c@cd"}})");
  WriteTextFileAtomic(dir / "r2/yield.json",
                      R"({"total": 220, "settings": {"detector": "unet:models/unet.pt@ab", "counter": "cnn:c@cd"}})");
  // A folder or the file itself, relative to the table's folder; Windows line ends.
  WriteTextFileAtomic(dir / "table.csv", "yield,harvested\r\nr1,240\r\nr2/yield.json,270\r\n\r\n");
  const Calibration c = Calibrate(ReadCalibrationTable(dir / "table.csv"));
  EXPECT_DOUBLE_EQ(c.factor, 510.0 / 420.0);
  EXPECT_EQ(c.detector, "unet:models/unet.pt@ab");
  WriteTextFileAtomic(dir / "calibration.json", CalibrationJson(c));
  const Calibration back = ReadCalibration(dir / "calibration.json");
  EXPECT_DOUBLE_EQ(back.factor, c.factor);
  EXPECT_EQ(back.counter, "cnn:c@cd");
  ASSERT_EQ(back.runs.size(), 2u);
  EXPECT_DOUBLE_EQ(back.runs[1].harvested, 270);
  EXPECT_DOUBLE_EQ(back.loo_mean_absolute_error_percent, c.loo_mean_absolute_error_percent);

  WriteTextFileAtomic(dir / "bad_header.csv", "run,count\nr1,240\n");
  EXPECT_THROW(ReadCalibrationTable(dir / "bad_header.csv"), Error);
  WriteTextFileAtomic(dir / "bad_number.csv", "yield,harvested\nr1,many\n");
  EXPECT_THROW(ReadCalibrationTable(dir / "bad_number.csv"), Error);
  WriteTextFileAtomic(dir / "missing.csv", "yield,harvested\nr9,240\n");
  EXPECT_THROW(ReadCalibrationTable(dir / "missing.csv"), Error);
  WriteTextFileAtomic(dir / "empty.csv", "yield,harvested\n");
  EXPECT_THROW(ReadCalibrationTable(dir / "empty.csv"), Error);
  WriteTextFileAtomic(dir / "r3/yield.json", "{\"frames\": 3}");
  WriteTextFileAtomic(dir / "not_yield.csv", "yield,harvested\nr3,240\n");
  EXPECT_THROW(ReadCalibrationTable(dir / "not_yield.csv"), Error);
  EXPECT_THROW(ReadCalibration(dir / "r1/yield.json"), Error);
  EXPECT_THROW(ReadCalibration(dir / "nothing.json"), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace orchard
