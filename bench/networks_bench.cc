// Inference speed of the networks on this machine, side by side with the
// colour detector in the same run: U-Net seconds per 1920x1080 frame (goal:
// at most 1 s on 2 cores; the study's implementation took 4.5 s on a GPU) and
// CNN counter patches per second; with a RetinaNet model, its seconds per
// frame at input scales 1 and 2 beside the U-Net's.
//
//   bench_networks UNET.pt COUNTER.pt GMM.json IMAGE_DIR [FRAMES] [RETINANET.pt]
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/count/cnn_counter.h"
#include "orchard/detect/detector_factory.h"

namespace {

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace orchard;
  if (argc < 5) {
    std::fprintf(stderr, "usage: bench_networks UNET.pt COUNTER.pt GMM.json IMAGE_DIR [FRAMES] [RETINANET.pt]\n");
    return 2;
  }
  try {
    const int frames = argc > 5 ? std::stoi(argv[5]) : 5;
    std::vector<cv::Mat> images;
    for (const fs::path& p : ListImages(argv[4])) {
      cv::Mat frame;
      cv::resize(ReadImage(p), frame, cv::Size(1920, 1080));
      images.push_back(frame);
      if (static_cast<int>(images.size()) == frames) break;
    }
    if (images.empty()) Fail("no images in ", argv[4]);
    std::printf("machine: %u cores; %zu frames of 1920x1080\n", std::thread::hardware_concurrency(), images.size());

    DetectorChoice unet_choice;
    unet_choice.method = "unet";
    unet_choice.model = argv[1];
    DetectorChoice gmm_choice;
    gmm_choice.model = argv[3];
    size_t unet_blobs = 0, gmm_blobs = 0;
    auto unet = MakeDetector(unet_choice);
    auto gmm = MakeDetector(gmm_choice);
    unet->Detect(images[0]);  // warm-up (allocator, thread pool)
    auto start = std::chrono::steady_clock::now();
    std::vector<cv::Mat1b> tiled_masks;  // kept to compare with the whole-frame pass below
    for (const cv::Mat& image : images) {
      FrameDetection d = unet->Detect(image);
      unet_blobs += d.blobs.size();
      tiled_masks.push_back(d.mask);
    }
    const double unet_s = Seconds(start) / images.size();
    start = std::chrono::steady_clock::now();
    for (const cv::Mat& image : images) gmm_blobs += gmm->Detect(image).blobs.size();
    const double gmm_s = Seconds(start) / images.size();
    std::printf("U-Net detector: %.3f s/frame (%zu blobs); goal <= 1 s: %s\n", unet_s, unet_blobs,
                unet_s <= 1.0 ? "PASS" : "NOT MET");
    std::printf("GMM detector:   %.3f s/frame (%zu blobs); U-Net / GMM time ratio %.1f\n", gmm_s, gmm_blobs,
                unet_s / gmm_s);
    if (argc > 6) {
      for (double scale : {1.0, 2.0}) {
        DetectorChoice retina_choice;
        retina_choice.method = "retinanet";
        retina_choice.model = argv[6];
        retina_choice.retinanet_scale = scale;
        auto retina = MakeDetector(retina_choice);
        retina->Detect(images[0]);
        size_t boxes = 0;
        start = std::chrono::steady_clock::now();
        for (const cv::Mat& image : images) boxes += retina->Detect(image).blobs.size();
        const double retina_s = Seconds(start) / images.size();
        std::printf("RetinaNet detector, input scale %.0f: %.3f s/frame (%zu boxes); RetinaNet / U-Net time ratio %.2f\n",
                    scale, retina_s, boxes, retina_s / unet_s);
      }
    }
    // The same U-Net in one pass over the whole frame: time and agreement
    // with the tiled masks.
    unet_choice.unet_whole_frame = true;
    auto whole = MakeDetector(unet_choice);
    whole->Detect(images[0]);
    size_t whole_blobs = 0;
    start = std::chrono::steady_clock::now();
    std::vector<FrameDetection> whole_detections;
    for (const cv::Mat& image : images) whole_detections.push_back(whole->Detect(image));
    const double whole_s = Seconds(start) / images.size();
    double agree = 0, apple_tiled = 0, apple_whole = 0;
    for (size_t i = 0; i < images.size(); ++i) {
      whole_blobs += whole_detections[i].blobs.size();
      const cv::Mat1b a = tiled_masks[i] > 0, b = whole_detections[i].mask > 0;
      agree += 1.0 - cv::countNonZero(a != b) / static_cast<double>(a.total());
      apple_tiled += cv::countNonZero(a), apple_whole += cv::countNonZero(b);
    }
    std::printf("U-Net whole frame: %.3f s/frame (%zu blobs); whole / tiled time ratio %.3f; goal <= 1 s: %s; "
                "pixels agreeing with the tiled mask %.4f, apple pixels whole / tiled %.3f\n",
                whole_s, whole_blobs, whole_s / unet_s, whole_s <= 1.0 ? "PASS" : "NOT MET", agree / images.size(),
                apple_whole / std::max(apple_tiled, 1.0));

    CnnCounter counter(argv[2]);
    std::vector<cv::Mat> patches;
    for (const cv::Mat& image : images) {
      for (int y = 0; y + 120 <= image.rows && patches.size() < 512; y += 120) {
        for (int x = 0; x + 100 <= image.cols && patches.size() < 512; x += 100) patches.push_back(image(cv::Rect(x, y, 100, 120)));
      }
    }
    counter.CountBatch({patches.begin(), patches.begin() + 16});  // warm-up
    start = std::chrono::steady_clock::now();
    counter.CountBatch(patches);
    const double count_s = Seconds(start);
    std::printf("CNN counter: %.0f patches/s (%zu patches of 100x120, input %d)\n", patches.size() / count_s,
                patches.size(), counter.input_size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_networks: %s\n", e.what());
    return 1;
  }
  return 0;
}
