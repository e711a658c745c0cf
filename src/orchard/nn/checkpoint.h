// Model files: a LibTorch archive holding the weights and a json header that
// says what the network is (kind, architecture options, training record), so a
// file can be checked against what a command expects before any weight is used.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>
#include <torch/torch.h>

namespace orchard::nn {

namespace fs = std::filesystem;

// Format version of the header; a file written by another version is refused.
inline constexpr int kCheckpointVersion = 1;

// Writes `module`'s parameters and buffers with `header` (which must hold
// "kind", e.g. "unet" or "counter", and "architecture") atomically to `path`.
void SaveCheckpoint(torch::nn::Module& module, nlohmann::json header, const fs::path& path);

// Reads the header of a model file and checks its kind and version. Throws
// orchard::Error when the file is missing, not a model file, of another kind or version.
nlohmann::json ReadCheckpointHeader(const fs::path& path, const std::string& expected_kind);

// Loads weights into `module` (built from the header's architecture). Throws
// orchard::Error when a tensor is missing or has another shape.
void LoadCheckpointWeights(torch::nn::Module& module, const fs::path& path);

// Keeps the best epoch of a training run in a hidden side file next to
// `model_path`, so an interrupted run leaves an earlier model there untouched;
// Finish() writes the best weights with the final header to `model_path`.
class BestCheckpoint {
 public:
  explicit BestCheckpoint(const fs::path& model_path);
  void Save(torch::nn::Module& module, const nlohmann::json& header);
  // Loads the best weights into `module` and writes them with `header`.
  void Finish(torch::nn::Module& module, const nlohmann::json& header);

 private:
  fs::path model_path_;
  fs::path side_path_;
};

}  // namespace orchard::nn
