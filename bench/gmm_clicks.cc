// Simulated user clicks for the user-supervised GMM detector: a user clicks on
// the visible body of a few large apples in the first images. From the test
// photos of a photo split (the same SplitByPhoto as `--test-fraction F
// --split-seed S --subset test`), the first NUM_IMAGES images (by name) with
// at least CLICKS boxes get one click on each of their CLICKS largest boxes
// that do not touch the crop border. A click goes where a human would put it:
// on the fruit body, i.e. at the pixel of the inner half-size ellipse whose
// colour is closest to that ellipse's median colour, so highlights, shadows
// and leaves in front of the fruit (minorities of the ellipse) are avoided.
// No colour knowledge of apples is used.
//
//   gmm_clicks YOLO_DIR TEST_FRACTION SPLIT_SEED NUM_IMAGES CLICKS OUT.json [train|test]
// (train: the same on the training photos, to choose options without test data)
#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/split.h"
#include "orchard/detect/gmm/colour_model.h"

using namespace orchard;

namespace {

cv::Point ClickOnFruitBody(const cv::Mat& lab, const Box& box) {
  cv::Mat1b inner(lab.size(), uchar(0));
  const cv::Point2f centre(static_cast<float>(box.CenterX()), static_cast<float>(box.CenterY()));
  cv::ellipse(inner, cv::RotatedRect(centre, cv::Size2f(0.5f * box.Width(), 0.5f * box.Height()), 0), 255,
              cv::FILLED);
  std::vector<cv::Point> pts;
  cv::findNonZero(inner, pts);
  if (pts.empty()) return {static_cast<int>(centre.x), static_cast<int>(centre.y)};
  std::vector<uchar> ch[3];
  for (const cv::Point& p : pts)
    for (int c = 0; c < 3; ++c) ch[c].push_back(lab.at<cv::Vec3b>(p)[c]);
  int median[3];
  for (int c = 0; c < 3; ++c) {
    std::nth_element(ch[c].begin(), ch[c].begin() + ch[c].size() / 2, ch[c].end());
    median[c] = ch[c][ch[c].size() / 2];
  }
  // Closest to the median colour; ties go to the pixel nearest the centre.
  cv::Point best = pts[0];
  double best_d = 1e300;
  for (const cv::Point& p : pts) {
    const cv::Vec3b v = lab.at<cv::Vec3b>(p);
    double d = 0;
    for (int c = 0; c < 3; ++c) d += (v[c] - median[c]) * (v[c] - median[c]);
    d = d * 1000 + std::hypot(p.x - centre.x, p.y - centre.y);
    if (d < best_d) best_d = d, best = p;
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 7 && argc != 8) {
    std::fprintf(stderr, "usage: %s YOLO_DIR TEST_FRACTION SPLIT_SEED NUM_IMAGES CLICKS OUT.json [train|test]\n", argv[0]);
    return 2;
  }
  try {
    const DatasetSplit split = SplitByPhoto(ReadDataset(argv[1]), std::atof(argv[2]), std::strtoull(argv[3], nullptr, 10));
    const Dataset& test = argc == 8 && std::string(argv[7]) == "train" ? split.train : split.test;
    const int num_images = std::atoi(argv[4]), per_image = std::atoi(argv[5]);
    std::vector<Click> clicks;
    int used = 0;
    for (const AnnotatedImage& image : test.images) {
      if (used == num_images) break;
      std::vector<Box> boxes;
      for (const Annotation& a : image.objects) {
        const Box& b = a.box;
        if (b.x1 > 1 && b.y1 > 1 && b.x2 < image.width - 1 && b.y2 < image.height - 1) boxes.push_back(b);
      }
      if (static_cast<int>(boxes.size()) < per_image) continue;
      std::sort(boxes.begin(), boxes.end(), [](const Box& a, const Box& b) { return a.Area() > b.Area(); });
      cv::Mat lab;
      cv::cvtColor(ReadImage(image.path), lab, cv::COLOR_BGR2Lab);
      for (int i = 0; i < per_image; ++i) {
        const cv::Point p = ClickOnFruitBody(lab, boxes[i]);
        clicks.push_back({image.name, static_cast<double>(p.x), static_cast<double>(p.y)});
      }
      ++used;
    }
    if (used < num_images) Fail("only ", used, " test images have ", per_image, " boxes clear of the border");
    WriteClicks(clicks, argv[6]);
    std::printf("%zu clicks on %d images -> %s\n", clicks.size(), used, argv[6]);
  } catch (const Error& e) {
    std::fprintf(stderr, "gmm_clicks: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
