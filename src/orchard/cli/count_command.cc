// `orchard count`: apples per blob (and per image) from detected blobs, or per
// patch from a folder of blob patches.
#include <algorithm>
#include <map>
#include <sstream>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/count/counter_factory.h"
#include "orchard/data/count_patches.h"
#include "orchard/data/dataset.h"
#include "orchard/detect/detector.h"

namespace orchard {
namespace {

void AppendFruits(const std::string& name, int blob_id, const BlobCount& c, double ox, double oy,
                  std::ostringstream* out) {
  for (size_t i = 0; i < c.fruits.size(); ++i) {
    *out << name << ',' << blob_id << ',' << i + 1 << ',' << c.fruits[i].centre.x + ox << ','
         << c.fruits[i].centre.y + oy << ',' << c.fruits[i].radius << '\n';
  }
}

}  // namespace

void AddCountCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "count", "Count apples per blob: counts.csv (name,count per image) and fruits.csv beside it");
  struct Args {
    std::string images, blobs, masks, in, out, criterion = "coverage";
    CounterChoice counter;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--method", args->counter.method, "Counter: cnn (ResNet classifier, 0..6) or gmm (mixture fit)")
      ->capture_default_str();
  cmd->add_option("--images", args->images, "Folder of the frames the blobs were detected in");
  cmd->add_option("--blobs", args->blobs, "blobs.csv from `orchard detect`");
  cmd->add_option("--masks", args->masks, "Instance masks from `orchard detect` (default: masks/ beside --blobs)");
  cmd->add_option("--in", args->in, "Folder of patches, each one blob (instead of --images/--blobs)");
  cmd->add_option("--model", args->counter.model,
                  "cnn: counter model .pt (default: the shipped models/counter.pt); gmm: colour model json that "
                  "finds the fruit pixels of patches (needed with --in)");
  cmd->add_flag("!--no-flip-average", args->counter.cnn.flip_average,
               "cnn: one pass per patch instead of averaging it with its mirror image");
  cmd->add_option("--threads", args->counter.threads, "cnn: LibTorch threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--prior-weight", args->counter.cnn.prior_weight,
                  "cnn: the prior the decision assumes, training frequencies to this power (0 = all counts equally likely, "
                  "1 = the training data's own prior: more patches right, lower totals)")
      ->capture_default_str();
  cmd->add_option("--criterion", args->criterion, "gmm model selection: coverage (fruit discs cover the blob), bic or aic")->capture_default_str();
  cmd->add_option("--max-fruits", args->counter.gmm.max_fruits, "Largest count per blob")->capture_default_str();
  cmd->add_option("--min-separation", args->counter.gmm.min_separation,
                  "gmm: fruits closer than this times the sum of their radii are one fruit (0 = off)")
      ->capture_default_str();
  cmd->add_option("--max-points", args->counter.gmm.max_points, "gmm: fruit pixels the mixtures are fitted to")
      ->capture_default_str();
  cmd->add_option("--out", args->out, "counts.csv to write")->required();
  cmd->callback([args]() {
    args->counter.gmm.criterion = ParseModelSelection(args->criterion);
    const bool cnn = args->counter.method == "cnn";
    if (!cnn && !args->in.empty() && args->counter.model.empty()) {
      Fail("--in (patches) with the gmm counter needs --model (a colour model) to find the fruit pixels");
    }
    const std::unique_ptr<Counter> counter = MakeCounter(args->counter);
    std::vector<ImageCount> counts;
    std::ostringstream fruits;
    fruits << "name,blob_id,fruit,cx,cy,radius\n";
    if (!args->in.empty()) {
      // A patch folder keeps its images beside counts.csv or in images/.
      const fs::path patch_dir = fs::is_directory(fs::path(args->in) / "images") ? fs::path(args->in) / "images" : fs::path(args->in);
      // In chunks, so the CNN counts a batch per pass and memory stays bounded.
      const std::vector<fs::path> paths = ListImages(patch_dir);
      constexpr size_t kChunk = 256;
      for (size_t begin = 0; begin < paths.size(); begin += kChunk) {
        const size_t end = std::min(paths.size(), begin + kChunk);
        std::vector<cv::Mat> patches;
        for (size_t i = begin; i < end; ++i) patches.push_back(ReadImage(paths[i]));
        const std::vector<BlobCount> chunk = counter->CountMany(patches, {});
        for (size_t i = begin; i < end; ++i) {
          const BlobCount& c = chunk[i - begin];
          counts.push_back({paths[i].filename().string(), c.count});
          AppendFruits(paths[i].filename().string(), 1, c, 0, 0, &fruits);
        }
      }
      if (counts.empty()) Fail("no patches in ", args->in);
    } else {
      if (args->images.empty() || args->blobs.empty()) Fail("give --images DIR and --blobs FILE, or --in PATCHDIR");
      const fs::path masks = args->masks.empty() ? fs::path(args->blobs).parent_path() / "masks" : fs::path(args->masks);
      std::map<std::string, std::vector<Blob>> by_image;
      for (const BlobRecord& r : ReadBlobsCsv(args->blobs)) by_image[r.name].push_back(r.blob);
      for (const fs::path& p : ListImages(args->images)) by_image[p.filename().string()];  // images without blobs: 0
      for (const auto& [name, blobs] : by_image) {
        int total = 0;
        if (!blobs.empty()) {
          const fs::path image_path = fs::path(args->images) / name;
          const cv::Mat image = ReadImage(image_path);
          const cv::Mat ids = ReadImage(masks / (fs::path(name).stem().string() + ".png"), cv::IMREAD_UNCHANGED);
          if (ids.size() != image.size())
            Fail("mask of ", name, " is ", ids.cols, "x", ids.rows, ", the image ", image.cols, "x", image.rows);
          cv::Mat ids32;
          ids.convertTo(ids32, CV_32S);
          std::vector<cv::Mat> patches;
          std::vector<cv::Mat1b> fruit_masks;
          std::vector<cv::Rect> rois;
          for (const Blob& b : blobs) {
            // A CNN reads the blob with the margin its training patches had.
            const cv::Rect roi = counter->ReadsPatchMargin()
                                     ? ClusterPatchRect(b.box, image.cols, image.rows)
                                     : cv::Rect(static_cast<int>(std::floor(b.box.x1)), static_cast<int>(std::floor(b.box.y1)),
                                                static_cast<int>(std::ceil(b.box.Width())),
                                                static_cast<int>(std::ceil(b.box.Height()))) &
                                           cv::Rect(0, 0, image.cols, image.rows);
            if (roi.empty()) Fail(args->blobs, ": blob ", b.id, " of ", name, " lies outside the image");
            patches.push_back(image(roi));
            fruit_masks.push_back(ids32(roi) == b.id);
            rois.push_back(roi);
          }
          // One call per image: the CNN counts its blobs as a batch.
          const std::vector<BlobCount> blob_counts = counter->CountMany(patches, fruit_masks);
          for (size_t i = 0; i < blobs.size(); ++i) {
            total += blob_counts[i].count;
            AppendFruits(name, blobs[i].id, blob_counts[i], rois[i].x, rois[i].y, &fruits);
          }
        }
        counts.push_back({name, total});
      }
    }
    WriteCodaLabCounts(counts, args->out);
    WriteTextFileAtomic(fs::path(args->out).parent_path() / "fruits.csv", fruits.str());
    int total = 0;
    for (const ImageCount& c : counts) total += c.count;
    spdlog::info("{} images/patches, {} apples -> {}", counts.size(), total, args->out);
  });
}

}  // namespace orchard
