// A contact sheet of copy-paste composites (rows: 2..6 apples, 10 each), to
// look at what `orchard train counter --copy-paste` feeds the counter.
//   copy_paste_sheet OUT.png PATCH_DIR...
#include <cstdio>
#include <random>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "orchard/nn/copy_paste.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/patch_input.h"

int main(int argc, char** argv) {
  try {
    if (argc < 3) {
      std::fprintf(stderr, "usage: copy_paste_sheet OUT.png PATCH_DIR...\n");
      return 2;
    }
    std::vector<cv::Mat> images;
    std::vector<int> counts;
    std::vector<std::string> photos;
    for (int a = 2; a < argc; ++a) {
      for (const auto& p : orchard::nn::ReadPatchFolder(argv[a])) {
        images.push_back(p.bgr);
        counts.push_back(p.count);
        photos.push_back(p.photo);
      }
    }
    const orchard::nn::CopyPasteSource source(images, counts, photos, orchard::nn::CopyPasteOptions{});
    std::printf("%zu photos with background and single apples\n", source.num_photos());
    const int cell = 96, columns = 10;
    cv::Mat sheet(5 * cell, columns * cell, CV_8UC3, cv::Scalar::all(255));
    std::mt19937_64 rng(7);
    for (int n = 2; n <= 6; ++n) {
      for (int c = 0; c < columns; ++c) {
        orchard::nn::LetterboxPatch(source.Compose(n, rng), cell).copyTo(sheet(cv::Rect(c * cell, (n - 2) * cell, cell, cell)));
      }
    }
    cv::imwrite(argv[1], sheet);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "copy_paste_sheet: %s\n", e.what());
    return 1;
  }
  return 0;
}
