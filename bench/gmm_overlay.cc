// Looks at what the GMM detector finds: for a few annotated images, the apple
// mask (tinted blue, blob outlines cyan) with the ground-truth boxes (yellow),
// tiled into one PNG to open in an image viewer.
//
//   gmm_overlay MODEL.json YOLO_DIR OUT.png IMAGE_NAME...
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/detect/gmm/gmm_detector.h"

using namespace orchard;

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s MODEL.json YOLO_DIR OUT.png IMAGE_NAME...\n", argv[0]);
    return 2;
  }
  try {
    GmmDetector detector(ReadColourModel(argv[1]), GmmDetectorOptions());
    const Dataset data = ReadDataset(argv[2]);
    std::vector<cv::Mat> tiles;
    for (int i = 4; i < argc; ++i) {
      const AnnotatedImage* image = data.Find(argv[i]);
      if (!image) Fail("no image ", argv[i], " in ", argv[2]);
      cv::Mat bgr = ReadImage(image->path);
      const FrameDetection d = detector.Detect(bgr);
      cv::Mat view = bgr.clone();
      view.setTo(cv::Scalar(255, 0, 0), d.mask);
      cv::addWeighted(bgr, 0.55, view, 0.45, 0, view);
      std::vector<std::vector<cv::Point>> contours;
      cv::findContours(d.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
      cv::drawContours(view, contours, -1, cv::Scalar(255, 255, 0), 1);
      for (const Annotation& a : image->objects)
        cv::rectangle(view, cv::Rect(cv::Point(a.box.x1, a.box.y1), cv::Point(a.box.x2, a.box.y2)),
                      cv::Scalar(0, 255, 255), 1);
      cv::resize(view, view, {480, 480});
      tiles.push_back(view);
    }
    cv::Mat row;
    cv::hconcat(tiles, row);
    WriteImageAtomic(argv[3], row);
  } catch (const Error& e) {
    std::fprintf(stderr, "gmm_overlay: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
