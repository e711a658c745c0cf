// `orchard detect`: fruit masks and blobs for every frame of a folder or video.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/frame_source.h"
#include "orchard/count/gmm_counter.h"
#include "orchard/detect/detector_factory.h"
#include "orchard/detect/parallel_detection.h"

namespace orchard {

void AddDetectCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("detect", "Detect fruit: masks/*.png, blobs.csv, detections.csv (CodaLab)");
  struct Args {
    std::string in, out;
    DetectorChoice detector;
    FrameSourceOptions frames;
    bool fruit_boxes = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--method", args->detector.method,
                  "Detector: gmm (colour mixtures), unet (segmentation network) or retinanet (box detector: one blob "
                  "per apple)")
      ->capture_default_str();
  cmd->add_option("--model", args->detector.model,
                  "Model file: gmm colour model json (`orchard train gmm`), unet or retinanet .pt (`orchard train "
                  "unet|retinanet`); default: the shipped models/gmm_red.json, models/unet.pt or models/retinanet.pt");
  cmd->add_option("--in", args->in, "Folder of images or a video file")->required();
  cmd->add_option("--out", args->out, "Output folder")->required();
  cmd->add_flag("--whole-frame", args->detector.unet_whole_frame,
               "unet: one pass over the whole frame instead of tiles without overlap");
  cmd->add_option("--threshold", args->detector.unet_threshold,
                  "unet: apple probability threshold; retinanet: box score threshold (0.05 writes every candidate, "
                  "for precision-recall curves and AP)")
      ->capture_default_str();
  cmd->add_option("--input-scale", args->detector.retinanet_scale,
                  "retinanet: frames are resized by this before the network, boxes mapped back")
      ->capture_default_str();
  cmd->add_flag("--reference-slic", args->detector.reference_slic,
                "gmm: OpenCV's SLIC at full resolution (slow reference path)");
  cmd->add_flag("!--working-scale-edges", args->detector.gmm_refine_edges,
                "gmm fast path: keep the blob edges at working resolution (faster, coarser boxes) instead of "
                "redrawing them at frame resolution");
  cmd->add_option("--min-apple-posterior", args->detector.gmm_min_apple_posterior,
                  "gmm: a superpixel is apple when the KL rule says so and its apple posterior is at least this "
                  "(0 = the KL rule alone)")
      ->capture_default_str();
  cmd->add_option("--min-blob-pixels", args->detector.blobs.min_pixels, "Drop blobs smaller than this")
      ->capture_default_str();
  cmd->add_flag("--fruit-boxes", args->fruit_boxes,
                "detections.csv: one box per fruit (each blob split by the mixture counter: centre +- radius) "
                "instead of one per blob");
  cmd->add_option("--step", args->frames.step, "Keep every n-th frame")->capture_default_str();
  cmd->add_option("--max-frames", args->frames.max_frames, "Stop after this many frames (0 = all)")
      ->capture_default_str();
  cmd->add_option("--threads", args->detector.threads,
                  "Threads (0 = all cores): gmm detects this many frames at once, unet and retinanet run their "
                  "network on them")
      ->capture_default_str();
  cmd->callback([args]() {
    args->detector.retinanet_threshold = args->detector.unet_threshold;
    // Frames run in parallel (one colour detector per core); results arrive in order.
    const std::vector<std::unique_ptr<Detector>> detectors = MakeFrameDetectors(args->detector);
    FrameSource source(args->in, args->frames);
    const fs::path out = args->out;
    std::vector<NamedDetection> results;
    GmmCounter splitter{GmmCounterOptions()};
    Predictions fruits;
    DetectFrames(
        detectors, [&](Frame* frame) { return source.Next(frame); },
        [&](Frame& frame, FrameDetection& detection) {
          NamedDetection r{frame.name, std::move(detection)};
          if (args->fruit_boxes) fruits[frame.name] = FruitBoxes(frame.image, r.detection, splitter);
          WriteImageAtomic(out / "masks" / (fs::path(frame.name).stem().string() + ".png"), InstanceMask(r.detection));
          // Keep only the blob list in memory, not the masks.
          r.detection.mask.release();
          r.detection.labels.release();
          results.push_back(std::move(r));
          if (results.size() % 50 == 0) spdlog::info("{} frames", results.size());
        });
    if (args->fruit_boxes) WriteCodaLabDetections(fruits, out / "detections.csv");
    else WriteDetectionsCsv(results, out / "detections.csv");
    WriteBlobsCsv(results, out / "blobs.csv");
    size_t blobs = 0;
    for (const auto& r : results) blobs += r.detection.blobs.size();
    spdlog::info("{} frames, {} blobs -> {}", results.size(), blobs, out.string());
  });
}

}  // namespace orchard
