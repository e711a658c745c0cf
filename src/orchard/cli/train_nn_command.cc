// `orchard train counter`, `orchard train unet` and `orchard train retinanet`:
// the study's networks, trained from scratch on CPU; and `orchard patches`, real counting patches cut
// from box annotations.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "orchard/cli/commands.h"
#include "orchard/cli/dataset_subset.h"
#include "orchard/core/error.h"
#include "orchard/data/blob_patches.h"
#include "orchard/data/count_patches.h"
#include "orchard/data/dataset.h"
#include "orchard/nn/counter_ensemble.h"
#include "orchard/nn/counter_training.h"
#include "orchard/nn/detection_training.h"
#include "orchard/nn/segmentation_training.h"

namespace orchard {
namespace {

void AddTrainerOptions(CLI::App* cmd, nn::TrainerOptions* trainer, std::string* state_dir) {
  cmd->add_option("--epochs", trainer->max_epochs, "Most epochs")->capture_default_str();
  cmd->add_option("--patience", trainer->patience, "Stop after this many epochs without a better validation metric")
      ->capture_default_str();
  cmd->add_option("--batch", trainer->batch_size, "Batch size")->capture_default_str();
  cmd->add_option("--samples-per-epoch", trainer->samples_per_epoch,
                  "Training samples (patches, tiles) drawn per epoch, reshuffled each epoch (0 = all)")
      ->capture_default_str();
  cmd->add_option("--seed", trainer->seed, "Seed of initialisation, shuffling and augmentation")->capture_default_str();
  cmd->add_option("--threads", trainer->threads, "LibTorch threads (0 = all cores)")->capture_default_str();
  cmd->add_option("--ema", trainer->ema_decay,
                  "Validate and save an exponential moving average of the weights with this decay per step (0 = off)")
      ->capture_default_str();
  cmd->add_flag("--cosine-lr", trainer->cosine_lr,
               "Decay the learning rate along a half cosine from its initial value to 0 at the last epoch");
  cmd->add_option("--state", *state_dir, "Folder for resumable training state: rerun with it to resume");
}

nlohmann::json Describe(const std::vector<std::string>& data, const std::vector<std::string>& patches,
                        const SubsetArgs& subset) {
  return {{"datasets", data}, {"patch_folders", patches}, {"subset", subset.subset},
          {"test_fraction", subset.test_fraction}, {"split_seed", subset.split_seed}};
}

}  // namespace

void AddTrainNetworkCommands(CLI::App& app) {
  CLI::App* train = app.get_subcommand("train");

  // ---- counter ----
  CLI::App* counter = train->add_subcommand(
      "counter", "ResNet cluster counter (0..6 apples) from patch folders and/or box-annotated datasets");
  struct CounterArgs {
    std::vector<std::string> data, patches;
    std::string out, state;
    SubsetArgs subset;
    nn::CounterTrainingOptions options;
    CountPatchOptions patch_options;
  };
  auto c = std::make_shared<CounterArgs>();
  c->options.trainer.batch_size = 32;
  counter->add_option("--data", c->data, "Box-annotated dataset to cut cluster patches from (repeatable)");
  counter->add_option("--patches", c->patches, "Patch folder with counts.csv, e.g. a synthetic row's patches/ (repeatable)");
  counter->add_option("--out", c->out, "Model file to write (.pt)")->required();
  c->subset.AddOptions(counter, "train");
  counter->add_option("--depth", c->options.architecture.depth, "ResNet depth: 18, 34 or 50")->capture_default_str();
  counter->add_option("--width", c->options.architecture.base_width, "Channels of the first stage (paper: 64)")
      ->capture_default_str();
  counter->add_option("--input", c->options.input_size, "Input side in pixels (paper: 224)")->capture_default_str();
  counter->add_option("--lr", c->options.learning_rate, "Adam learning rate")->capture_default_str();
  counter->add_option("--val-fraction", c->options.validation_fraction,
                      "Fraction of training photos for validation (0: all train, the last epoch is kept)")
      ->capture_default_str();
  counter->add_option("--copy-paste", c->options.copy_paste.probability,
                      "Probability that a drawn 1..6-apple sample is replaced by a composite of real single apples "
                      "pasted on real background of one training photo (0 = off)")
      ->capture_default_str();
  counter->add_option("--balance-power", c->options.balance_power,
                      "Class balancing: 1 = every class up-sampled to the largest (the study's), 0.5 = halfway "
                      "(square root), 0 = the data's own class frequencies")
      ->capture_default_str();
  counter->add_option("--density-weight", c->options.density_weight,
                      "Weight of a density head trained on the apples' positions in box-annotated patches, a "
                      "second task that teaches the network where each apple is (0 = no head)")
      ->capture_default_str();
  counter->add_option("--density-sigma", c->options.density_sigma,
                      "Spread of each apple's target density, in cells of 1/8 of the input")
      ->capture_default_str();
  counter->add_option("--background", c->patch_options.background_per_image, "Background patches per image")
      ->capture_default_str();
  AddTrainerOptions(counter, &c->options.trainer, &c->state);
  counter->callback([c]() {
    if (c->data.empty() && c->patches.empty()) Fail("give --data and/or --patches");
    c->options.trainer.state_dir = c->state;
    std::vector<nn::LabelledPatch> patches;
    for (const std::string& path : c->data) {
      const Dataset dataset = c->subset.Select(ReadDataset(path));
      std::vector<nn::LabelledPatch> cut = nn::CutDatasetPatches(dataset, c->patch_options);
      spdlog::info("{}: {} images, {} patches ({} photos)", path, dataset.images.size(), cut.size(), c->subset.subset);
      patches.insert(patches.end(), cut.begin(), cut.end());
    }
    for (const std::string& dir : c->patches) {
      std::vector<nn::LabelledPatch> read = nn::ReadPatchFolder(dir);
      spdlog::info("{}: {} patches", dir, read.size());
      patches.insert(patches.end(), read.begin(), read.end());
    }
    const nn::CounterTrainingResult result =
        nn::TrainCounter(patches, c->options, Describe(c->data, c->patches, c->subset), c->out);
    if (result.validation_patches == 0) {
      spdlog::info("wrote {}: {} training patches, no validation, last epoch {} kept ({:.0f} s)", c->out,
                   result.train_patches, result.record.epochs_run, result.record.seconds);
      return;
    }
    spdlog::info("wrote {}: {} training / {} validation patches, best val accuracy {:.4f} at epoch {} of {} ({:.0f} s)",
                 c->out, result.train_patches, result.validation_patches, result.record.best_metric,
                 result.record.best_epoch, result.record.epochs_run, result.record.seconds);
  });

  // ---- counter ensemble ----
  CLI::App* ensemble = train->add_subcommand(
      "counter-ensemble", "One counter file from several trained counters, whose probabilities are averaged");
  auto e = std::make_shared<std::pair<std::vector<std::string>, std::string>>();
  ensemble->add_option("--model", e->first, "Counter model file (.pt) from `orchard train counter` (repeatable)")
      ->required();
  ensemble->add_option("--out", e->second, "Ensemble model file to write (.pt)")->required();
  ensemble->callback([e]() {
    nn::WriteCounterEnsemble(std::vector<fs::path>(e->first.begin(), e->first.end()), e->second);
    spdlog::info("wrote {}: {} counters", e->second, e->first.size());
  });

  // ---- unet ----
  CLI::App* unet = train->add_subcommand(
      "unet", "U-Net fruit segmentation from datasets with masks (MinneApple layout, synthetic sides) or boxes");
  struct UNetArgs {
    std::vector<std::string> data;
    std::string out, state;
    SubsetArgs subset;
    nn::UNetTrainingOptions options;
  };
  auto u = std::make_shared<UNetArgs>();
  u->options.trainer.batch_size = 8;
  u->options.trainer.samples_per_epoch = 800;
  u->options.trainer.patience = 4;
  unet->add_option("--data", u->data,
                   "Dataset: MinneApple folder / synthetic side (masks) or YOLO/COCO (boxes -> inscribed ellipses); "
                   "repeatable")
      ->required();
  unet->add_option("--out", u->out, "Model file to write (.pt)")->required();
  u->subset.AddOptions(unet, "train");
  unet->add_option("--width", u->options.architecture.base_width, "Channels of the first block (VGG-16: 64)")
      ->capture_default_str();
  unet->add_option("--blocks", u->options.architecture.blocks, "Encoder blocks (VGG-16: 5)")->capture_default_str();
  unet->add_option("--tile", u->options.tile, "Training tile side (the study: 224)")->capture_default_str();
  unet->add_option("--stride", u->options.stride, "Training tiles are cut every this many pixels (the study: 50)")
      ->capture_default_str();
  unet->add_option("--lr", u->options.learning_rate, "AdaDelta learning rate")->capture_default_str();
  unet->add_option("--val-fraction", u->options.validation_fraction, "Fraction of training photos for validation")
      ->capture_default_str();
  AddTrainerOptions(unet, &u->options.trainer, &u->state);
  unet->callback([u]() {
    u->options.trainer.state_dir = u->state;
    std::vector<nn::SegmentationSample> samples;
    for (const std::string& path : u->data) {
      const Dataset dataset = u->subset.Select(ReadDataset(path));
      std::vector<nn::SegmentationSample> loaded = nn::LoadSegmentationSamples(dataset);
      spdlog::info("{}: {} images ({} photos, {})", path, loaded.size(), u->subset.subset,
                   dataset.has_masks ? "masks" : "box ellipses");
      samples.insert(samples.end(), std::make_move_iterator(loaded.begin()), std::make_move_iterator(loaded.end()));
    }
    const nn::UNetTrainingResult result = nn::TrainUNet(samples, u->options, Describe(u->data, {}, u->subset), u->out);
    spdlog::info("wrote {}: {} training / {} validation tiles, best val apple IoU {:.4f} at epoch {} of {} ({:.0f} s)",
                 u->out, result.train_tiles, result.validation_tiles, result.record.best_metric,
                 result.record.best_epoch, result.record.epochs_run, result.record.seconds);
  });

  // ---- retinanet ----
  CLI::App* retina = train->add_subcommand(
      "retinanet", "RetinaNet-style box detector (feature pyramid, focal loss) from datasets with boxes or masks");
  struct RetinaArgs {
    std::vector<std::string> data;
    std::string out, state;
    SubsetArgs subset;
    nn::RetinaNetTrainingOptions options;
  };
  auto r = std::make_shared<RetinaArgs>();
  r->options.trainer.batch_size = 8;
  r->options.trainer.samples_per_epoch = 400;
  r->options.trainer.patience = 6;
  retina->add_option("--data", r->data,
                     "Dataset: YOLO/COCO (boxes) or MinneApple folder / synthetic side (each instance's box); "
                     "repeatable")
      ->required();
  retina->add_option("--out", r->out, "Model file to write (.pt)")->required();
  r->subset.AddOptions(retina, "train");
  retina->add_option("--depth", r->options.architecture.depth, "ResNet backbone depth: 18, 34 or 50")
      ->capture_default_str();
  retina->add_option("--width", r->options.architecture.base_width, "Backbone's first-stage channels (paper: 64)")
      ->capture_default_str();
  retina->add_option("--fpn-channels", r->options.architecture.fpn_channels, "Pyramid and subnet channels (paper: 256)")
      ->capture_default_str();
  retina->add_option("--head-convs", r->options.architecture.head_convs, "Convolutions per subnet (paper: 4)")
      ->capture_default_str();
  retina->add_option("--anchor-sizes", r->options.architecture.anchor_sizes,
                     "Anchor side in pixels at P3, P4, P5 (paper: 32 64 128)")
      ->expected(3)
      ->capture_default_str();
  retina->add_option("--tile", r->options.tile, "Training tile side, a multiple of 32")->capture_default_str();
  retina->add_option("--min-scale", r->options.min_scale, "Smallest random scale of a drawn image")
      ->capture_default_str();
  retina->add_option("--max-scale", r->options.max_scale, "Largest random scale of a drawn image")
      ->capture_default_str();
  retina->add_option("--lr", r->options.learning_rate, "Adam learning rate")->capture_default_str();
  retina->add_option("--val-fraction", r->options.validation_fraction,
                     "Fraction of training photos for validation (0: all train, the last epoch is kept)")
      ->capture_default_str();
  AddTrainerOptions(retina, &r->options.trainer, &r->state);
  retina->callback([r]() {
    r->options.trainer.state_dir = r->state;
    std::vector<nn::BoxSample> samples;
    for (const std::string& path : r->data) {
      const Dataset dataset = r->subset.Select(ReadDataset(path));
      std::vector<nn::BoxSample> loaded = nn::LoadBoxSamples(dataset);
      spdlog::info("{}: {} images, {} boxes ({} photos)", path, loaded.size(), dataset.NumObjects(), r->subset.subset);
      samples.insert(samples.end(), std::make_move_iterator(loaded.begin()), std::make_move_iterator(loaded.end()));
    }
    const nn::RetinaNetTrainingResult result =
        nn::TrainRetinaNet(samples, r->options, Describe(r->data, {}, r->subset), r->out);
    if (result.validation_images == 0) {
      spdlog::info("wrote {}: {} training images ({} boxes), no validation, last epoch {} kept ({:.0f} s)", r->out,
                   result.train_images, result.train_boxes, result.record.epochs_run, result.record.seconds);
      return;
    }
    spdlog::info("wrote {}: {} training images ({} boxes) / {} validation images, best val AP50 {:.4f} at epoch {} "
                 "of {} ({:.0f} s)",
                 r->out, result.train_images, result.train_boxes, result.validation_images, result.record.best_metric,
                 result.record.best_epoch, result.record.epochs_run, result.record.seconds);
  });
}

void AddPatchesCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "patches",
      "Counting patches: from box annotations (touching boxes form a cluster labelled with its box count), or from "
      "a detector's blobs labelled by true instance masks (--detections)");
  struct Args {
    std::string data, out, detections, images, masks, prefix;
    int every = 1;
    SubsetArgs subset;
    CountPatchOptions options;
    BlobPatchOptions blob_options;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--data", a->data, "Box-annotated dataset (YOLO folder, COCO json, MinneApple folder)");
  cmd->add_option("--out", a->out, "Output folder: images/*.png and counts.csv")->required();
  a->subset.AddOptions(cmd, "all");
  cmd->add_option("--margin", a->options.margin, "Margin around a cluster, fraction of its longer side")
      ->capture_default_str();
  cmd->add_option("--background", a->options.background_per_image, "Background patches (count 0) per image")
      ->capture_default_str();
  cmd->add_option("--seed", a->options.seed, "Seed of background placement")->capture_default_str();
  cmd->add_option("--detections", a->detections,
                  "Instead of --data: a folder of blob label masks (<frame>.png, e.g. a side's detections/ cache); "
                  "each blob's box is a patch, counted from --masks");
  cmd->add_option("--images", a->images, "With --detections: the frames (<frame>.png/.jpg)");
  cmd->add_option("--masks", a->masks, "With --detections: the frames' instance masks (apple id + 1 per pixel, "
                                       "as orchard synth writes them)");
  cmd->add_option("--every", a->every, "With --detections: every n-th frame")->capture_default_str();
  cmd->add_option("--prefix", a->prefix, "With --detections: prefix of the patch names (e.g. the row and side)");
  cmd->add_option("--min-apple-pixels", a->blob_options.min_apple_pixels,
                  "With --detections: apples with fewer visible pixels are not counted")
      ->capture_default_str();
  cmd->add_option("--min-share", a->blob_options.min_share,
                  "With --detections: an apple counts in the blob holding at least this share of its visible pixels")
      ->capture_default_str();
  cmd->callback([a]() {
    auto summarise = [](const std::vector<int>& histogram) {
      std::string summary;
      for (size_t k = 0; k < histogram.size(); ++k) summary += " " + std::to_string(k) + ":" + std::to_string(histogram[k]);
      return summary;
    };
    if (!a->detections.empty()) {
      if (!a->data.empty()) Fail("give --data or --detections, not both");
      if (a->images.empty() || a->masks.empty()) Fail("--detections needs --images and --masks");
      std::vector<ImageCount> counts;
      const std::vector<int> histogram =
          CutBlobPatches(a->detections, a->images, a->masks, a->out, a->prefix, a->every, a->blob_options, &counts);
      if (counts.empty()) Fail("no blobs in the detections of ", a->detections);
      WriteCodaLabCounts(counts, fs::path(a->out) / "counts.csv");
      spdlog::info("{} blobs -> {} (count:patches{})", counts.size(), a->out, summarise(histogram));
      return;
    }
    if (a->data.empty()) Fail("give --data (box annotations) or --detections (blobs and instance masks)");
    const Dataset dataset = a->subset.Select(ReadDataset(a->data));
    const std::vector<CountPatch> patches = MakeCountPatches(dataset, a->options);
    if (patches.empty()) Fail("no patches: the dataset has no clusters of 1..", a->options.max_count, " boxes");
    WriteCountPatches(dataset, patches, a->out);
    std::vector<int> histogram(a->options.max_count + 1, 0);
    for (const CountPatch& p : patches) ++histogram[p.count];
    spdlog::info("{} images -> {} patches in {} (count:patches{})", dataset.images.size(), patches.size(), a->out,
                 summarise(histogram));
  });
}

}  // namespace orchard
