// The `orchard` program's subcommands. Each Add*Command registers one
// subcommand (with its --help) on the app; its callback does the work and
// throws orchard::Error on bad input.
#pragma once

namespace CLI {
class App;
}

namespace orchard {

// --- registered commands (one line each; keep in data-flow order) ---
void AddDemoCommand(CLI::App& app);     // orchard demo: the end-to-end slice on a synthetic row
void AddConvertCommand(CLI::App& app);  // orchard convert: dataset formats
void AddSynthCommand(CLI::App& app);    // orchard synth: synthetic rows with ground truth
void AddEvalCommand(CLI::App& app);     // orchard eval: detection/segmentation/count/yield metrics
void AddTrainCommand(CLI::App& app);    // orchard train gmm: colour model of the GMM detector
void AddDetectCommand(CLI::App& app);   // orchard detect: fruit masks, blobs, detections
void AddCountCommand(CLI::App& app);    // orchard count: apples per blob
void AddSideCommand(CLI::App& app);     // orchard side: one side of a row in 3D, tracked count
void AddYieldCommand(CLI::App& app);    // orchard yield: both sides merged, the row's count and report
void AddCalibrateCommand(CLI::App& app);  // orchard calibrate: counted -> harvested factor from harvested rows
void AddTrainNetworkCommands(CLI::App& app);  // orchard train counter|unet (needs AddTrainCommand first)
void AddPatchesCommand(CLI::App& app);        // orchard patches: counting patches from box annotations
void AddSplitCommand(CLI::App& app);          // orchard split: photo-wise train/test lists and image folders

}  // namespace orchard
