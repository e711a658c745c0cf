#include "orchard/detect/detector.h"

#include <cstdio>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"

namespace orchard {

void BlobOptions::Check() const {
  ORCHARD_CHECK_OPTION(min_pixels >= 1, "minimum blob size must be >= 1 pixel, got ", min_pixels);
}

FrameDetection ExtractBlobs(const cv::Mat1b& mask, const BlobOptions& options) {
  options.Check();
  if (mask.empty()) Fail("cannot extract blobs from an empty mask");
  FrameDetection out;
  cv::Mat1i components;
  cv::Mat stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, components, stats, centroids, 8, CV_32S);
  // Map component -> blob id (0 for specks and background).
  std::vector<int> id_of(n, 0);
  for (int c = 1; c < n; ++c) {
    const int area = stats.at<int>(c, cv::CC_STAT_AREA);
    if (area < options.min_pixels) continue;
    Blob blob;
    blob.id = static_cast<int>(out.blobs.size()) + 1;
    const double x = stats.at<int>(c, cv::CC_STAT_LEFT), y = stats.at<int>(c, cv::CC_STAT_TOP);
    blob.box = Box::FromXYWH(x, y, stats.at<int>(c, cv::CC_STAT_WIDTH), stats.at<int>(c, cv::CC_STAT_HEIGHT));
    blob.pixels = area;
    blob.centroid = {centroids.at<double>(c, 0), centroids.at<double>(c, 1)};
    id_of[c] = blob.id;
    out.blobs.push_back(blob);
  }
  out.labels.create(mask.size());
  out.mask.create(mask.size());
  for (int y = 0; y < mask.rows; ++y) {
    const int* src = components.ptr<int>(y);
    int* dst = out.labels.ptr<int>(y);
    uchar* m = out.mask.ptr<uchar>(y);
    for (int x = 0; x < mask.cols; ++x) {
      dst[x] = id_of[src[x]];
      m[x] = dst[x] ? 255 : 0;
    }
  }
  return out;
}

void ScoreBlobs(const cv::Mat1f& pixel_scores, FrameDetection* d) {
  if (pixel_scores.size() != d->labels.size()) Fail("pixel scores and blob labels differ in size");
  std::vector<double> sum(d->blobs.size() + 1, 0.0), count(d->blobs.size() + 1, 0.0);
  for (int y = 0; y < d->labels.rows; ++y) {
    const int* l = d->labels.ptr<int>(y);
    const float* s = pixel_scores.ptr<float>(y);
    for (int x = 0; x < d->labels.cols; ++x) {
      sum[l[x]] += s[x];
      count[l[x]] += 1;
    }
  }
  for (Blob& b : d->blobs) b.score = count[b.id] > 0 ? sum[b.id] / count[b.id] : 0.0;
}

void WriteDetectionsCsv(const std::vector<NamedDetection>& frames, const fs::path& path) {
  Predictions predictions;
  for (const NamedDetection& f : frames) {
    std::vector<ScoredBox>& boxes = predictions[f.name];
    for (const Blob& b : f.detection.blobs) boxes.push_back({b.box, b.score});
  }
  WriteCodaLabDetections(predictions, path);
}

void WriteBlobsCsv(const std::vector<NamedDetection>& frames, const fs::path& path) {
  std::ostringstream out;
  out << "name,blob_id,x1,y1,x2,y2,pixels,cx,cy,score\n";
  char line[512];
  for (const NamedDetection& f : frames) {
    for (const Blob& b : f.detection.blobs) {
      std::snprintf(line, sizeof(line), "%s,%d,%.1f,%.1f,%.1f,%.1f,%d,%.2f,%.2f,%.4f\n", f.name.c_str(), b.id,
                    b.box.x1, b.box.y1, b.box.x2, b.box.y2, b.pixels, b.centroid.x, b.centroid.y, b.score);
      out << line;
    }
  }
  WriteTextFileAtomic(path, out.str());
}

std::vector<BlobRecord> ReadBlobsCsv(const fs::path& path) {
  std::istringstream in(ReadTextFile(path));
  std::vector<BlobRecord> records;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || (line_no == 1 && line.rfind("name,", 0) == 0)) continue;
    const std::vector<std::string> f = SplitCsvLine(line);
    if (f.size() != 10) Fail(path.string(), ":", line_no, ": expected 10 fields (name,blob_id,x1,y1,x2,y2,pixels,cx,cy,score), got ", f.size());
    BlobRecord r;
    r.name = f[0];
    try {
      size_t used = 0;
      auto num = [&](const std::string& s) {
        const double v = std::stod(s, &used);
        if (used != s.size()) throw std::invalid_argument(s);
        return v;
      };
      r.blob.id = static_cast<int>(num(f[1]));
      r.blob.box = {num(f[2]), num(f[3]), num(f[4]), num(f[5])};
      r.blob.pixels = static_cast<int>(num(f[6]));
      r.blob.centroid = {num(f[7]), num(f[8])};
      r.blob.score = num(f[9]);
    } catch (const std::exception&) {
      Fail(path.string(), ":", line_no, ": a field is not a number: ", line);
    }
    records.push_back(r);
  }
  return records;
}

cv::Mat InstanceMask(const FrameDetection& d) {
  cv::Mat out;
  d.labels.convertTo(out, CV_16U);
  return out;
}

}  // namespace orchard
