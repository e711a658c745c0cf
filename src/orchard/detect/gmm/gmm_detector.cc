#include "orchard/detect/gmm/gmm_detector.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"

namespace orchard {

void GmmDetectorOptions::Check() const {
  blobs.Check();
  ORCHARD_CHECK_OPTION(min_apple_posterior >= 0 && min_apple_posterior < 1,
                       "min_apple_posterior must be in [0, 1), got ", min_apple_posterior);
  ORCHARD_CHECK_OPTION(num_threads >= 1, "num_threads must be >= 1, got ", num_threads);
}

GmmDetector::GmmDetector(const ColourModel& model, const GmmDetectorOptions& options)
    : model_(model), options_(options), classifier_(model, options.min_apple_posterior) {
  options_.Check();
  segmentation_ = model.segmentation;
  segmentation_.superpixels.use_opencv = options.reference_slic;
  segmentation_.superpixels.num_threads = options.num_threads;
  segmentation_.Check();
}

namespace {

// The working column / row under each frame column / row: cv::resize's
// nearest-neighbour mapping (frame pixel i under floor(i * working / frame)),
// by which the working blob labels are scaled up.
std::vector<int> WorkingIndexOf(int frame, int working) {
  std::vector<int> w(frame);
  for (int i = 0; i < frame; ++i)
    w[i] = std::min(working - 1, static_cast<int>(std::floor(i * static_cast<double>(working) / frame)));
  return w;
}

// Fast path: redraws the blob edges at frame resolution. `d` holds the blobs
// found at working resolution with their labels scaled up (nearest), so
// their edges are quantised to 1 / scale frame pixels (2.7 px at the default
// scale), which costs tight blobs their IoU with the fruit. Each frame pixel
// under a working pixel at an edge of the blob mask (its 3x3 neighbourhood
// holds both decisions) goes to the nearest, by SLIC distance at frame
// resolution, of the superpixels of that neighbourhood, and takes its blob
// (or background); the blobs are then regrouped and measured at frame
// resolution (RegroupBlobsAtFrameResolution).
void RefineEdgesAtFrameResolution(const cv::Mat& bgr, const SegmentedFrame& f, const cv::Mat1i& working_blobs,
                                  const cv::Mat1f& working_scores, double compactness, double region_size,
                                  int min_pixels, FrameDetection* d) {
  const cv::Mat1i& labels = f.superpixels.labels;
  const int n = f.superpixels.num_labels, ww = labels.cols, wh = labels.rows;
  // Superpixel centres (frame pixels), mean colours (8-bit LAB) and blobs.
  std::vector<double> cx(n, 0.0), cy(n, 0.0), count(n, 0.0);
  std::vector<int> blob_of(n, 0);
  for (int y = 0; y < wh; ++y) {
    const int* l = labels.ptr<int>(y);
    const int* b = working_blobs.ptr<int>(y);
    for (int x = 0; x < ww; ++x) {
      cx[l[x]] += x, cy[l[x]] += y, count[l[x]] += 1;
      if (b[x]) blob_of[l[x]] = b[x];
    }
  }
  const double inv_x = static_cast<double>(bgr.cols) / ww, inv_y = static_cast<double>(bgr.rows) / wh;
  std::vector<Eigen::Vector3d> colour8(n);
  for (int k = 0; k < n; ++k) {
    const double c = std::max(1.0, count[k]);
    cx[k] = (cx[k] / c + 0.5) * inv_x - 0.5;
    cy[k] = (cy[k] / c + 0.5) * inv_y - 0.5;
    const Eigen::Vector3d& m = f.colours.mean[k];
    colour8[k] = Lab8BitFrom(m);
  }
  cv::Mat1b blob_mask, grown, shrunk, edge;
  cv::compare(working_blobs, 0, blob_mask, cv::CMP_GT);
  cv::dilate(blob_mask, grown, cv::Mat());
  cv::erode(blob_mask, shrunk, cv::Mat());
  cv::compare(grown, shrunk, edge, cv::CMP_NE);
  // Frame pixels [first[w], first[w + 1]) lie under working column / row w.
  auto first_of = [](int frame, int working) {
    const std::vector<int> working_of = WorkingIndexOf(frame, working);
    std::vector<int> first(working + 1, frame);
    for (int i = frame - 1; i >= 0; --i) first[working_of[i]] = i;
    for (int w = working - 1; w >= 0; --w) first[w] = std::min(first[w], first[w + 1]);
    return first;
  };
  const std::vector<int> first_x = first_of(bgr.cols, ww), first_y = first_of(bgr.rows, wh);
  // Visits the frame pixels under the edge working pixels, always in the same
  // order; enter_cell(working pixel) is called before the pixels under it.
  auto for_each_edge_pixel = [&](auto&& enter_cell, auto&& visit) {
    for (int wy = 0; wy < wh; ++wy) {
      const uchar* e = edge.ptr<uchar>(wy);
      for (int wx = 0; wx < ww; ++wx) {
        if (!e[wx]) continue;
        enter_cell(cv::Point(wx, wy));
        for (int y = first_y[wy]; y < first_y[wy + 1]; ++y)
          for (int x = first_x[wx]; x < first_x[wx + 1]; ++x) visit(cv::Point(x, y));
      }
    }
  };
  std::vector<cv::Vec3b> gathered;
  for_each_edge_pixel([](cv::Point) {}, [&](cv::Point p) { gathered.push_back(bgr.at<cv::Vec3b>(p)); });
  if (gathered.empty()) {  // no blob edge (no blob, or one covering the frame)
    RegroupBlobsAtFrameResolution(working_scores, min_pixels, d);
    return;
  }
  cv::Mat3b colours(static_cast<int>(gathered.size()), 1, gathered.data());
  cv::cvtColor(colours, colours, cv::COLOR_BGR2Lab);
  const double spatial = (compactness / region_size) * (compactness / region_size);
  // The distinct superpixels of the cell's 3x3 neighbourhood (usually 2-4 of
  // the 9), in scan order so that ties go the same way.
  int candidates[9], num_candidates = 0;
  auto enter_cell = [&](cv::Point w) {
    num_candidates = 0;
    for (int y = std::max(0, w.y - 1); y <= std::min(wh - 1, w.y + 1); ++y)
      for (int x = std::max(0, w.x - 1); x <= std::min(ww - 1, w.x + 1); ++x) {
        const int k = labels(y, x);
        if (std::find(candidates, candidates + num_candidates, k) == candidates + num_candidates)
          candidates[num_candidates++] = k;
      }
  };
  size_t i = 0;
  for_each_edge_pixel(enter_cell, [&](cv::Point p) {
    const cv::Vec3b c = gathered[i++];
    int best = candidates[0];
    double best_d = std::numeric_limits<double>::infinity();
    for (int j = 0; j < num_candidates; ++j) {
      const int k = candidates[j];
      const double dl = c[0] - colour8[k][0], da = c[1] - colour8[k][1], db = c[2] - colour8[k][2];
      const double dx = p.x - cx[k], dy = p.y - cy[k];
      const double dist = dl * dl + da * da + db * db + spatial * (dx * dx + dy * dy);
      if (dist < best_d) best_d = dist, best = k;
    }
    d->labels(p) = blob_of[best];
    d->mask(p) = blob_of[best] ? 255 : 0;
  });
  RegroupBlobsAtFrameResolution(working_scores, min_pixels, d);
}

}  // namespace

FrameDetection GmmDetector::Detect(const cv::Mat& bgr) {
  const SegmentedFrame f = SegmentFrame(bgr, segmentation_);
  const int n = f.superpixels.num_labels;
  std::vector<uchar> apple(n);
  std::vector<float> posterior(n);
  for (int i = 0; i < n; ++i) {
    bool is_apple = false;
    classifier_.Classify(f.colours.mean[i], f.colours.covariance[i], &is_apple, &posterior[i]);
    apple[i] = is_apple ? 255 : 0;
  }
  cv::Mat1b mask(f.lab8.size());
  cv::Mat1f scores(f.lab8.size());
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = f.superpixels.labels.ptr<int>(y);
    uchar* m = mask.ptr<uchar>(y);
    float* s = scores.ptr<float>(y);
    for (int x = 0; x < mask.cols; ++x) {
      m[x] = apple[l[x]];
      s[x] = posterior[l[x]];
    }
  }
  BlobOptions blob_options = options_.blobs;
  const double area_scale = f.scale * f.scale;
  blob_options.min_pixels = std::max(1, static_cast<int>(std::lround(options_.blobs.min_pixels * area_scale)));
  FrameDetection d = ExtractBlobs(mask, blob_options);
  const bool regroup = f.scale < 1.0 && options_.refine_edges;
  if (!regroup) ScoreBlobs(scores, &d);  // else the regrouped blobs are scored
  if (f.scale == 1.0) return d;
  // Back to frame resolution.
  const double inv = 1.0 / f.scale;
  for (Blob& b : d.blobs) {
    b.box = {b.box.x1 * inv, b.box.y1 * inv, std::min<double>(bgr.cols, b.box.x2 * inv),
             std::min<double>(bgr.rows, b.box.y2 * inv)};
    b.centroid = {(b.centroid.x + 0.5) * inv - 0.5, (b.centroid.y + 0.5) * inv - 0.5};
    b.pixels = static_cast<int>(std::lround(b.pixels / area_scale));
  }
  cv::Mat1i labels;
  cv::resize(d.labels, labels, bgr.size(), 0, 0, cv::INTER_NEAREST);
  const cv::Mat1i working_blobs = d.labels;
  d.labels = labels;
  cv::compare(labels, 0, d.mask, cv::CMP_GT);
  if (regroup)
    RefineEdgesAtFrameResolution(bgr, f, working_blobs, scores, segmentation_.superpixels.compactness,
                                 segmentation_.superpixels.region_size, options_.blobs.min_pixels, &d);
  return d;
}

void RegroupBlobsAtFrameResolution(const cv::Mat1f& working_scores, int min_pixels, FrameDetection* d) {
  const int width = d->labels.cols, height = d->labels.rows;
  const int ww = working_scores.cols, wh = working_scores.rows;
  if (ww < 1 || wh < 1 || ww > width || wh > height) Fail("working scores must not be larger than the frame");
  if (d->mask.size() != d->labels.size()) Fail("blob mask and labels differ in size");
  const std::vector<int> wx_of = WorkingIndexOf(width, ww), wy_of = WorkingIndexOf(height, wh);
  const int grow_x = (width + ww - 1) / ww + 1, grow_y = (height + wh - 1) / wh + 1;
  std::vector<Blob> blobs;
  std::vector<cv::Rect> rois;
  // Pass 1: new ids are written negated, so that a renumbered blob cannot be
  // mistaken for a later one with that id.
  for (const Blob& old : d->blobs) {
    const int x0 = std::max(0, static_cast<int>(old.box.x1) - grow_x);
    const int x1 = std::min(width, static_cast<int>(std::ceil(old.box.x2)) + grow_x);
    const int y0 = std::max(0, static_cast<int>(old.box.y1) - grow_y);
    const int y1 = std::min(height, static_cast<int>(std::ceil(old.box.y2)) + grow_y);
    const cv::Rect roi(x0, y0, x1 - x0, y1 - y0);
    cv::Mat1b own;
    cv::compare(d->labels(roi), old.id, own, cv::CMP_EQ);
    cv::Mat1i pieces;
    cv::Mat stats, centroids;
    const int n = cv::connectedComponentsWithStats(own, pieces, stats, centroids, 8, CV_32S);
    std::vector<int> id_of(n, 0);
    std::vector<double> score_sum(n, 0.0);
    for (int c = 1; c < n; ++c) {
      if (stats.at<int>(c, cv::CC_STAT_AREA) < min_pixels) continue;
      Blob b;
      b.id = static_cast<int>(blobs.size()) + 1;
      b.box = Box::FromXYWH(x0 + stats.at<int>(c, cv::CC_STAT_LEFT), y0 + stats.at<int>(c, cv::CC_STAT_TOP),
                            stats.at<int>(c, cv::CC_STAT_WIDTH), stats.at<int>(c, cv::CC_STAT_HEIGHT));
      b.pixels = stats.at<int>(c, cv::CC_STAT_AREA);
      b.centroid = {x0 + centroids.at<double>(c, 0), y0 + centroids.at<double>(c, 1)};
      id_of[c] = b.id;
      blobs.push_back(b);
    }
    rois.push_back(roi);
    for (int y = 0; y < roi.height; ++y) {
      const int* p = pieces.ptr<int>(y);
      int* l = d->labels.ptr<int>(y0 + y);
      uchar* m = d->mask.ptr<uchar>(y0 + y);
      const float* s = working_scores.ptr<float>(wy_of[y0 + y]);
      for (int x = 0; x < roi.width; ++x) {
        if (!p[x]) continue;
        const int id = id_of[p[x]];
        l[x0 + x] = -id;
        if (!id) m[x0 + x] = 0;
        score_sum[p[x]] += s[wx_of[x0 + x]];
      }
    }
    for (int c = 1; c < n; ++c)
      if (id_of[c]) blobs[id_of[c] - 1].score = score_sum[c] / blobs[id_of[c] - 1].pixels;
  }
  // Pass 2: ids back to positive (each blob's pixels lie inside its roi).
  for (const cv::Rect& roi : rois) {
    for (int y = roi.y; y < roi.y + roi.height; ++y) {
      int* l = d->labels.ptr<int>(y);
      for (int x = roi.x; x < roi.x + roi.width; ++x)
        if (l[x] < 0) l[x] = -l[x];
    }
  }
  d->blobs = std::move(blobs);
}

}  // namespace orchard
