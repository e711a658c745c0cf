// `orchard split`: the photo-wise train/test split of a dataset, written as
// two YOLO datasets and image lists, so any command (detect, eval, side) can
// run on exactly the photos that training never saw.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/split.h"

namespace orchard {

void AddSplitCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "split", "Split a dataset by photo: OUT/{train,test}/ as YOLO datasets (images/, labels/) and OUT/{train,test}.txt");
  struct Args {
    std::string data, out;
    double test_fraction = 0.25;
    uint64_t split_seed = 1;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--data", a->data, "Dataset (YOLO/MinneApple folder, COCO json)")->required();
  cmd->add_option("--out", a->out, "Output folder")->required();
  cmd->add_option("--test-fraction", a->test_fraction, "Fraction of the photos in the test set")->capture_default_str();
  cmd->add_option("--split-seed", a->split_seed, "Seed of the photo split (same as the other commands')")
      ->capture_default_str();
  cmd->callback([a]() {
    const Dataset dataset = ReadDataset(a->data);
    const DatasetSplit split = SplitByPhoto(dataset, a->test_fraction, a->split_seed);
    const fs::path out = a->out;
    for (const auto& [name, part] : {std::pair<std::string, const Dataset*>{"train", &split.train},
                                     std::pair<std::string, const Dataset*>{"test", &split.test}}) {
      // Each part becomes a YOLO dataset (image copies + labels) that every
      // command reads, `orchard eval detect --gt` included. A rerun replaces it.
      std::error_code ec;
      fs::remove_all(out / name, ec);
      WriteYolo(*part, out / name);
      std::string list;
      for (const AnnotatedImage& image : part->images) list += image.name + "\n";
      WriteTextFileAtomic(out / (name + ".txt"), list);
    }
    spdlog::info("{} photos -> train {} photos ({} images), test {} photos ({} images) in {}",
                 split.train_photos.size() + split.test_photos.size(), split.train_photos.size(),
                 split.train.images.size(), split.test_photos.size(), split.test.images.size(), a->out);
  });
}

}  // namespace orchard
