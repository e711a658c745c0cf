// Speed and accuracy of the GMM detector's two paths on the same 1920x1080
// frames, in one run: the fast superpixels on the downscaled frame vs OpenCV's
// SLIC at full resolution, each run as `orchard detect` runs it (one
// single-threaded detector per core, as many frames at once); the fast path
// also one frame at a time on every core (the latency of a frame). Frames are
// mosaics of 3x2 annotated 640x640 crops
// (held-out photos), cut to 1080 rows; boxes are shifted, and those cut by the
// frame edge are clipped (dropped when less than half remains).
//
//   bench_gmm MODEL.json YOLO_DIR [FRAMES=10 [TEST_FRACTION SPLIT_SEED [both|fast [MIN_APPLE_POSTERIOR]]]]
// With TEST_FRACTION, only the test photos of SplitByPhoto(TEST_FRACTION,
// SPLIT_SEED) are used (the split of `--test-fraction F --split-seed S`).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/split.h"
#include "orchard/detect/gmm/gmm_detector.h"
#include "orchard/detect/parallel_detection.h"
#include "orchard/eval/detection_metrics.h"

using namespace orchard;

namespace {

struct Mosaics {
  std::vector<cv::Mat> frames;
  Dataset truth;
};

Mosaics MakeMosaics(const Dataset& crops, int num_frames) {
  Mosaics m;
  const int tile = 640, cols = 3, rows = 2, width = 1920, height = 1080;
  size_t next = 0;
  for (int f = 0; f < num_frames; ++f) {
    cv::Mat frame(height, width, CV_8UC3, cv::Scalar::all(0));
    AnnotatedImage gt;
    gt.name = "mosaic_" + std::to_string(f) + ".png";
    gt.width = width;
    gt.height = height;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        const AnnotatedImage& crop = crops.images[next++ % crops.images.size()];
        cv::Mat image = ReadImage(crop.path);
        if (image.cols != tile || image.rows != tile) cv::resize(image, image, {tile, tile});
        const cv::Rect dst(c * tile, r * tile, tile, std::min(tile, height - r * tile));
        image(cv::Rect(0, 0, dst.width, dst.height)).copyTo(frame(dst));
        const double sx = static_cast<double>(tile) / crop.width, sy = static_cast<double>(tile) / crop.height;
        for (const Annotation& a : crop.objects) {
          Box b{a.box.x1 * sx + dst.x, a.box.y1 * sy + dst.y, a.box.x2 * sx + dst.x, a.box.y2 * sy + dst.y};
          const double full = b.Area();
          b.y2 = std::min<double>(b.y2, height);
          if (b.Area() < 0.5 * full) continue;
          gt.objects.push_back({b});
        }
      }
    }
    m.frames.push_back(frame);
    m.truth.images.push_back(gt);
  }
  return m;
}

struct PathResult {
  double fps = 0;
  DetectionMetrics metrics;
};

// `frames_at_once` = 0: one detector using every core, one frame after the
// other (the latency of one frame); n > 0: n single-threaded detectors on n
// frames at once through DetectFrames, as `orchard detect` runs them.
PathResult Run(const ColourModel& model, bool reference, double min_apple_posterior, bool refine_edges,
               int frames_at_once, const Mosaics& m) {
  GmmDetectorOptions options;
  options.reference_slic = reference;
  options.min_apple_posterior = min_apple_posterior;
  options.refine_edges = refine_edges;
  std::vector<std::unique_ptr<Detector>> detectors;
  if (frames_at_once > 0) options.num_threads = 1;
  for (int i = 0; i < std::max(1, frames_at_once); ++i) detectors.push_back(std::make_unique<GmmDetector>(model, options));
  for (auto& d : detectors) d->Detect(m.frames[0]);  // warm-up (thread pool, allocations)
  Predictions predictions;
  auto keep = [&](size_t i, const FrameDetection& d) {
    std::vector<ScoredBox>& boxes = predictions[m.truth.images[i].name];
    for (const Blob& b : d.blobs) boxes.push_back({b.box, b.score});
  };
  const auto start = std::chrono::steady_clock::now();
  if (frames_at_once == 0) {
    for (size_t i = 0; i < m.frames.size(); ++i) keep(i, detectors[0]->Detect(m.frames[i]));
  } else {
    size_t next = 0;
    DetectFrames(
        detectors,
        [&](Frame* frame) {
          if (next == m.frames.size()) return false;
          frame->index = static_cast<int>(next);
          frame->image = m.frames[next++];
          return true;
        },
        [&](Frame& frame, FrameDetection& d) { keep(frame.index, d); });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  PathResult r;
  r.fps = m.frames.size() / seconds;
  r.metrics = EvaluateDetections(m.truth, predictions);
  return r;
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s MODEL.json YOLO_DIR [FRAMES=10 [TEST_FRACTION SPLIT_SEED [both|fast [MIN_APPLE_POSTERIOR]]]]\n", argv[0]);
    return 2;
  }
  try {
    const ColourModel model = ReadColourModel(argv[1]);
    Dataset crops = ReadDataset(argv[2]);
    if (argc > 5) crops = SplitByPhoto(crops, std::atof(argv[4]), std::strtoull(argv[5], nullptr, 10)).test;
    const int frames = argc > 3 ? std::atoi(argv[3]) : 10;
    const Mosaics m = MakeMosaics(crops, frames);
    std::printf("%d frames 1920x1080 (3x2 mosaics of %zu crops from %s), %zu boxes\n", frames,
                crops.images.size(), argv[2], m.truth.NumObjects());
    // "fast" after the split arguments skips the reference path (for profiling).
    const bool fast_only = argc > 6 && std::string(argv[6]) == "fast";
    const double gate = argc > 7 ? std::atof(argv[7]) : GmmDetectorOptions().min_apple_posterior;
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const PathResult fast = Run(model, false, gate, true, cores, m);
    const PathResult one_at_a_time = Run(model, false, gate, true, 0, m);
    const PathResult ref = fast_only ? fast : Run(model, true, gate, false, cores, m);
    // The fast path without its frame-resolution edges, for comparison.
    const PathResult coarse = fast_only ? fast : Run(model, false, gate, false, cores, m);
    std::printf("%-30s %10s %8s %10s %10s %10s\n", "path", "frames/s", "F1@0.5", "P@0.5", "R@0.5", "meanF1");
    auto row = [](const char* name, const PathResult& r) {
      const int i50 = 49;  // iou[49] = 0.50
      std::printf("%-30s %10.2f %8.3f %10.3f %10.3f %10.3f\n", name, r.fps, r.metrics.f1_at_05,
                  r.metrics.curve.precision[i50], r.metrics.curve.recall[i50], Mean(r.metrics.curve.f1));
    };
    row(("fast, " + std::to_string(cores) + " frames at once").c_str(), fast);
    row("fast, one frame at a time", one_at_a_time);
    row(("reference (OpenCV SLIC), " + std::to_string(cores) + " at once").c_str(), ref);
    if (!fast_only) row("fast, edges at working scale", coarse);
    std::printf("speed ratio fast/reference (frames at once): %.1fx; F1@0.5 difference fast-reference: %+.4f\n", fast.fps / ref.fps,
                fast.metrics.f1_at_05 - ref.metrics.f1_at_05);
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_gmm: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
