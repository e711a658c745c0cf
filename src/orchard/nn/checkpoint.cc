#include "orchard/nn/checkpoint.h"

#include <map>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard::nn {
namespace {

constexpr char kHeaderKey[] = "orchard_header";

torch::serialize::InputArchive OpenArchive(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) Fail("model file not found: ", path.string());
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path.string());
  } catch (const c10::Error&) {
    Fail("not a model file (cannot be read as a LibTorch archive): ", path.string());
  }
  return archive;
}

}  // namespace

void SaveCheckpoint(torch::nn::Module& module, nlohmann::json header, const fs::path& path) {
  if (!header.contains("kind") || !header.contains("architecture")) {
    Fail("internal: checkpoint header needs 'kind' and 'architecture'");
  }
  header["version"] = kCheckpointVersion;
  torch::serialize::OutputArchive archive;
  archive.write(kHeaderKey, c10::IValue(header.dump()));
  module.save(archive);
  WriteFileAtomic(path, [&](const fs::path& tmp) { archive.save_to(tmp.string()); });
}

nlohmann::json ReadCheckpointHeader(const fs::path& path, const std::string& expected_kind) {
  torch::serialize::InputArchive archive = OpenArchive(path);
  c10::IValue value;
  if (!archive.try_read(kHeaderKey, value) || !value.isString()) {
    Fail("not an orchard model file (no header): ", path.string());
  }
  nlohmann::json header;
  try {
    header = nlohmann::json::parse(value.toStringRef());
  } catch (const nlohmann::json::exception&) {
    Fail("corrupt model header in ", path.string());
  }
  const int version = header.value("version", -1);
  if (version != kCheckpointVersion) {
    Fail("model file ", path.string(), " has format version ", version, ", this program reads version ",
         kCheckpointVersion, ": retrain it with this version");
  }
  const std::string kind = header.value("kind", "");
  if (kind != expected_kind) {
    Fail("model file ", path.string(), " holds a '", kind, "' network, expected '", expected_kind, "'");
  }
  return header;
}

void LoadCheckpointWeights(torch::nn::Module& module, const fs::path& path) {
  // Module::load replaces tensors whatever their shape, so remember the shapes
  // the architecture expects and compare afterwards.
  std::map<std::string, std::vector<int64_t>> expected;
  for (const auto& item : module.named_parameters()) expected[item.key()] = item.value().sizes().vec();
  for (const auto& item : module.named_buffers()) expected[item.key()] = item.value().sizes().vec();
  torch::serialize::InputArchive archive = OpenArchive(path);
  try {
    module.load(archive);
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    Fail("model file ", path.string(), " does not match the architecture: ", what.substr(0, what.find('\n')));
  }
  for (const auto& item : module.named_parameters()) {
    if (item.value().sizes().vec() != expected[item.key()]) {
      Fail("model file ", path.string(), " does not match the architecture: tensor '", item.key(),
           "' has another shape");
    }
  }
  for (const auto& item : module.named_buffers()) {
    if (item.value().sizes().vec() != expected[item.key()]) {
      Fail("model file ", path.string(), " does not match the architecture: buffer '", item.key(),
           "' has another shape");
    }
  }
}

BestCheckpoint::BestCheckpoint(const fs::path& model_path)
    : model_path_(model_path),
      side_path_(model_path.parent_path() / ("." + model_path.filename().string() + ".best")) {}

void BestCheckpoint::Save(torch::nn::Module& module, const nlohmann::json& header) {
  SaveCheckpoint(module, header, side_path_);
}

void BestCheckpoint::Finish(torch::nn::Module& module, const nlohmann::json& header) {
  LoadCheckpointWeights(module, side_path_);
  SaveCheckpoint(module, header, model_path_);
  std::error_code ec;
  fs::remove(side_path_, ec);
}

}  // namespace orchard::nn
