// `orchard detect`: fruit masks and blobs for every frame of a folder or video.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/core/frame_source.h"
#include "orchard/detect/gmm/gmm_detector.h"

namespace orchard {

void AddDetectCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("detect", "Detect fruit: masks/*.png, blobs.csv, detections.csv (CodaLab)");
  struct Args {
    std::string method = "gmm", model, in, out;
    GmmDetectorOptions gmm;
    FrameSourceOptions frames;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--method", args->method, "Detector: gmm")->capture_default_str();
  cmd->add_option("--model", args->model, "Model file (gmm: colour model json from `orchard train gmm`)")->required();
  cmd->add_option("--in", args->in, "Folder of images or a video file")->required();
  cmd->add_option("--out", args->out, "Output folder")->required();
  cmd->add_flag("--reference-slic", args->gmm.reference_slic,
                "gmm: OpenCV's SLIC at full resolution (slow reference path)");
  cmd->add_option("--min-blob-pixels", args->gmm.blobs.min_pixels, "Drop blobs smaller than this")
      ->capture_default_str();
  cmd->add_option("--step", args->frames.step, "Keep every n-th frame")->capture_default_str();
  cmd->add_option("--max-frames", args->frames.max_frames, "Stop after this many frames (0 = all)")
      ->capture_default_str();
  cmd->add_option("--threads", args->gmm.num_threads, "Threads")->capture_default_str();
  cmd->callback([args]() {
    if (args->method != "gmm")
      Fail("detector method '", args->method, "' is not available (available: gmm)");
    const ColourModel model = ReadColourModel(args->model);
    GmmDetector detector(model, args->gmm);
    FrameSource source(args->in, args->frames);
    const fs::path out = args->out;
    std::vector<NamedDetection> results;
    Frame frame;
    while (source.Next(&frame)) {
      NamedDetection r{frame.name, detector.Detect(frame.image)};
      WriteImageAtomic(out / "masks" / (fs::path(frame.name).stem().string() + ".png"), InstanceMask(r.detection));
      // Keep only the blob list in memory, not the masks.
      r.detection.mask.release();
      r.detection.labels.release();
      results.push_back(std::move(r));
      if (results.size() % 50 == 0) spdlog::info("{} frames", results.size());
    }
    WriteDetectionsCsv(results, out / "detections.csv");
    WriteBlobsCsv(results, out / "blobs.csv");
    size_t blobs = 0;
    for (const auto& r : results) blobs += r.detection.blobs.size();
    spdlog::info("{} frames, {} blobs -> {}", results.size(), blobs, out.string());
  });
}

}  // namespace orchard
