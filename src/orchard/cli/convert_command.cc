// `orchard convert`: dataset annotations from one format to another
// (MinneApple masks, YOLO txt, COCO json; VIA json is read only).
#include <cstdio>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/data/dataset.h"

namespace orchard {
namespace {

struct ConvertOptions {
  std::string from;        // empty: detected from --in
  std::string to;          // minneapple | yolo | coco
  std::string input;       // dataset folder or json file
  std::string output;      // folder (minneapple, yolo) or .json file (coco)
  std::string image_dir;   // images of a COCO/VIA input; guessed beside the json when empty

  void Check() const {
    ORCHARD_CHECK_OPTION(!input.empty(), "--in is required");
    ORCHARD_CHECK_OPTION(!output.empty(), "--out is required");
    const DatasetFormat target = ParseDatasetFormat(to);
    ORCHARD_CHECK_OPTION(target != DatasetFormat::kVia,
                         "--to via: VIA is read only (write minneapple, yolo or coco)");
    if (target == DatasetFormat::kCoco) {
      ORCHARD_CHECK_OPTION(fs::path(output).extension() == ".json",
                           "--to coco writes one json file; --out must end in .json, got ", output);
    } else {
      ORCHARD_CHECK_OPTION(fs::path(output).extension() != ".json", "--to ", to,
                           " writes a folder; --out must not be a .json file, got ", output);
    }
    if (!from.empty()) ParseDatasetFormat(from);
  }
};

void RunConvert(const ConvertOptions& options) {
  options.Check();
  const DatasetFormat target = ParseDatasetFormat(options.to);
  const DatasetFormat source =
      options.from.empty() ? DetectDatasetFormat(options.input) : ParseDatasetFormat(options.from);
  const Dataset dataset = ReadDataset(options.input, source, options.image_dir);
  if (dataset.images.empty()) Fail("no images in ", options.input);
  switch (target) {
    case DatasetFormat::kMinneApple: WriteMinneApple(dataset, options.output); break;
    case DatasetFormat::kYolo: WriteYolo(dataset, options.output); break;
    case DatasetFormat::kCoco: WriteCoco(dataset, options.output); break;
    case DatasetFormat::kVia: Fail("VIA is read only");
  }
  std::printf("converted %zu images, %zu objects: %s (%s) -> %s (%s)\n", dataset.images.size(),
              dataset.NumObjects(), options.input.c_str(), DatasetFormatName(source).c_str(),
              options.output.c_str(), DatasetFormatName(target).c_str());
}

}  // namespace

void AddConvertCommand(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Convert dataset annotations between formats: MinneApple (images/ + instance masks/), "
      "YOLO (images/ + labels/*.txt), COCO json, VIA json (read only). Masks become boxes and "
      "polygons (COCO); boxes/polygons become filled instance masks (MinneApple).");
  cmd->add_option("--from", options->from,
                  "input format: minneapple, yolo, coco or via (default: detected from --in)");
  cmd->add_option("--to", options->to, "output format: minneapple, yolo or coco")->required();
  cmd->add_option("--in", options->input, "input dataset folder or json file")->required();
  cmd->add_option("--out", options->output,
                  "output folder (minneapple, yolo) or .json file (coco)")->required();
  cmd->add_option("--images", options->image_dir,
                  "image folder of a COCO/VIA input (default: images/ or ../images beside the json)");
  cmd->callback([options] { RunConvert(*options); });
}

}  // namespace orchard
