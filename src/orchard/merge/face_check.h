// Do the two sides show opposite faces of the row? The front and back videos
// look at the row from opposite sides, so their frames share almost no image
// features (DESIGN.md), while two passes along the same side (or one video
// given twice) share hundreds. Feature matching tells the two apart before
// the registration, which can align a side with itself: a row looks much the
// same mirrored.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace orchard {

namespace fs = std::filesystem;

struct FaceCheckOptions {
  // Frames sampled evenly from each side; every front sample is matched with
  // every back sample. Neighbouring frames of the synthetic rows (12.5 cm
  // apart) share 74-268 consistent matches, frames 50 cm apart 9-59: 12
  // samples keep a second pass along the same side within reach.
  int frames = 12;
  // ORB features per frame (frames are first scaled to at most 960 px wide).
  int features = 1000;
  // Lowe's ratio test on the two nearest descriptors.
  double ratio = 0.8;
  // More matches consistent with one fundamental matrix (RANSAC, 2 px) than
  // this mean the two frames show the same scene. Opposite sides of the
  // synthetic rows reach 10-11 (RANSAC's chance level); the same side
  // sampled half a sample apart 238-292 (docs/yield.md).
  int max_inliers = 40;
  void Check() const;
};

struct FaceCheck {
  int best_inliers = 0;  // the most geometrically consistent matches of a frame pair
  fs::path front_frame, back_frame;  // that pair
  bool same_face = false;            // best_inliers > max_inliers
};

// Matches sampled frames of the two sides. Throws orchard::Error when a side
// has no frames or a frame cannot be read.
FaceCheck CheckOppositeFaces(const std::vector<fs::path>& front_frames, const std::vector<fs::path>& back_frames,
                             const FaceCheckOptions& options = {});

}  // namespace orchard
