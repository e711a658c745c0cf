// The detection stage's interface: a Detector turns a BGR frame into a fruit
// mask and its blobs (connected clusters of fruit pixels, each possibly several
// touching apples). Implemented by the colour-GMM detector here and by the
// U-Net / RetinaNet detectors; the counters and the 3D stage consume the result.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "orchard/core/box.h"

namespace orchard {

namespace fs = std::filesystem;

// One connected cluster of fruit pixels.
struct Blob {
  int id = 0;          // 1..N within its frame; the value of its pixels in FrameDetection::labels
  Box box;             // tight pixel bounds [x_min, x_max + 1) x [y_min, y_max + 1)
  int pixels = 0;      // number of pixels
  cv::Point2d centroid;
  double score = 1.0;  // detector confidence in [0, 1] (GMM: mean apple posterior of its pixels)
};

struct FrameDetection {
  cv::Mat1b mask;           // 255 = fruit, 0 = background; frame size
  cv::Mat1i labels;         // blob id per pixel, 0 = none; frame size
  std::vector<Blob> blobs;  // ids 1..N in order
};

class Detector {
 public:
  virtual ~Detector() = default;
  // Detects fruit in an 8-bit BGR frame. Throws orchard::Error on an empty or
  // non-BGR image.
  virtual FrameDetection Detect(const cv::Mat& bgr) = 0;
};

struct BlobOptions {
  // Connected components (8-connected) smaller than this many pixels are specks
  // and dropped: 100 px is a disc of ~11 px diameter, below the smallest apple
  // annotated in the AppleBBCH crops at 640x640.
  int min_pixels = 100;
  void Check() const;
};

// Blobs of a fruit mask (non-zero = fruit): fills detection->labels and
// ->blobs (scores 1) and keeps `mask` with the dropped specks cleared.
FrameDetection ExtractBlobs(const cv::Mat1b& mask, const BlobOptions& options);

// Sets each blob's score to the mean of `pixel_scores` (CV_32F, frame size)
// over its pixels.
void ScoreBlobs(const cv::Mat1f& pixel_scores, FrameDetection* detection);

// One frame's result, with the frame's name as used in result files.
struct NamedDetection {
  std::string name;
  FrameDetection detection;
};

// detections.csv in CodaLab format (name,x1,y1,x2,y2,score), one line per blob.
void WriteDetectionsCsv(const std::vector<NamedDetection>& frames, const fs::path& path);
// blobs.csv: name,blob_id,x1,y1,x2,y2,pixels,cx,cy,score (with header).
void WriteBlobsCsv(const std::vector<NamedDetection>& frames, const fs::path& path);

// A blobs.csv row, as read back (e.g. by `orchard count`).
struct BlobRecord {
  std::string name;
  Blob blob;
};
// Reads blobs.csv; throws orchard::Error naming the file and line when malformed.
std::vector<BlobRecord> ReadBlobsCsv(const fs::path& path);

// The instance mask (16-bit PNG, blob id per pixel, 0 = background: the
// MinneApple convention) of a detection.
cv::Mat InstanceMask(const FrameDetection& detection);

}  // namespace orchard
