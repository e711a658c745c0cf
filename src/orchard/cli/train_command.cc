// `orchard train gmm`: fits the colour model of the GMM detector, supervised by
// clicks on apples or by annotated boxes.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/cli/dataset_subset.h"
#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/detect/gmm/colour_model.h"

namespace orchard {

void AddTrainCommand(CLI::App& app) {
  CLI::App* train = app.add_subcommand("train", "Train a detector or counter model");
  train->require_subcommand(1);
  CLI::App* gmm = train->add_subcommand("gmm", "Colour model of the GMM detector (colour classes + apple classes)");
  struct Args {
    std::string images, clicks, annotations, out;
    ColourTrainingOptions options;
    SubsetArgs subset;  // --annotations: train on these photos of the split
  };
  auto args = std::make_shared<Args>();
  gmm->add_option("--images", args->images, "Folder of training images (with --clicks)");
  CLI::Option* clicks = gmm->add_option("--clicks", args->clicks,
                                        "User-supervised: json list of {\"image\", \"x\", \"y\"} clicks on apples");
  CLI::Option* annotations = gmm->add_option(
      "--annotations", args->annotations, "Semi-supervised: annotated dataset (YOLO/MinneApple folder, COCO/VIA json)");
  clicks->excludes(annotations);
  gmm->add_option("--out", args->out, "Colour model json to write")->required();
  gmm->add_option("--classes", args->options.num_classes, "Number of colour classes")->capture_default_str();
  gmm->add_option("--region-size", args->options.segmentation.superpixels.region_size,
                  "Superpixel size in image pixels")->capture_default_str();
  gmm->add_option("--apple-fraction", args->options.apple_pixel_fraction,
                  "Annotations: a class is apple when more than this fraction of its pixels lie in apples "
                  "(0 = the fraction that maximises the apple-pixel F1 on the training images)")
      ->capture_default_str();
  args->subset.AddOptions(gmm, "train");
  gmm->add_option("--min-clicks", args->options.min_clicks_per_class,
                  "Clicks: a class is apple when at least this many clicks fall in it")
      ->capture_default_str();
  gmm->add_option("--min-apple-posterior", args->options.min_apple_posterior,
                  "Annotations: the detector's superpixel decision the apple classes are chosen for "
                  "(as `orchard detect --min-apple-posterior`)")
      ->capture_default_str();
  gmm->add_option("--seed", args->options.seed, "EM initialisation seed")->capture_default_str();
  gmm->callback([args]() {
    ColourModel model;
    if (!args->clicks.empty()) {
      if (args->images.empty()) Fail("--clicks needs --images (the folder the clicks refer to)");
      model = TrainColourModelFromClicks(ListImages(args->images), ReadClicks(args->clicks), args->options);
      model.trained_on = args->images + " (" + model.trained_on + " from " + args->clicks + ")";
    } else if (!args->annotations.empty()) {
      const Dataset dataset = args->subset.Select(ReadDataset(args->annotations));
      model = TrainColourModelFromAnnotations(dataset, args->options);
      model.trained_on = args->annotations + " (" + model.trained_on + "; photos: " + args->subset.subset +
                         ", test fraction " + std::to_string(args->subset.test_fraction) + ", split seed " +
                         std::to_string(args->subset.split_seed) + ")";
    } else {
      Fail("give --clicks FILE (with --images DIR) or --annotations PATH");
    }
    WriteColourModel(model, args->out);
    spdlog::info("wrote {}: {} colour classes, {} apple", args->out, model.mixture.NumComponents(), model.NumApple());
  });
}

}  // namespace orchard
