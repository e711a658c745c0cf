// Puts frames side by side in a grid and writes a small JPEG (the contact
// sheet in docs/images/). usage: bench_synth_contact_sheet OUT.jpg COLS WIDTH IMG...
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s OUT.jpg COLS TILE_WIDTH IMAGE...\n", argv[0]);
    return 2;
  }
  const int cols = std::atoi(argv[2]), tile_w = std::atoi(argv[3]);
  std::vector<cv::Mat> tiles;
  for (int i = 4; i < argc; ++i) {
    cv::Mat img = cv::imread(argv[i], cv::IMREAD_COLOR);
    if (img.empty()) {
      std::fprintf(stderr, "cannot read %s\n", argv[i]);
      return 1;
    }
    cv::resize(img, img, cv::Size(tile_w, img.rows * tile_w / img.cols), 0, 0, cv::INTER_AREA);
    tiles.push_back(img);
  }
  const int rows = (static_cast<int>(tiles.size()) + cols - 1) / cols, tile_h = tiles[0].rows, gap = 4;
  cv::Mat sheet(rows * tile_h + (rows - 1) * gap, cols * tile_w + (cols - 1) * gap, CV_8UC3, cv::Scalar(255, 255, 255));
  for (size_t i = 0; i < tiles.size(); ++i) {
    const int r = static_cast<int>(i) / cols, c = static_cast<int>(i) % cols;
    cv::Mat roi = sheet(cv::Rect(c * (tile_w + gap), r * (tile_h + gap), tile_w, std::min(tile_h, tiles[i].rows)));
    tiles[i](cv::Rect(0, 0, tile_w, roi.rows)).copyTo(roi);
  }
  cv::imwrite(argv[1], sheet, {cv::IMWRITE_JPEG_QUALITY, 82});
  return 0;
}
