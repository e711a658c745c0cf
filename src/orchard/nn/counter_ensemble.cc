#include "orchard/nn/counter_ensemble.h"

#include <string>

#include "orchard/core/error.h"
#include "orchard/nn/checkpoint.h"

namespace orchard::nn {

std::vector<CounterMember> CounterMembers(const nlohmann::json& header) {
  std::vector<CounterMember> members;
  try {
    if (header.contains("members")) {
      for (const nlohmann::json& m : header.at("members")) {
        members.push_back({ResNetOptions::FromJson(m.at("architecture")), m.at("input_size").get<int>()});
      }
      if (members.empty()) Fail("counter ensemble without members");
    } else {
      members.push_back({ResNetOptions::FromJson(header.at("architecture")), header.at("input_size").get<int>()});
    }
  } catch (const nlohmann::json::exception&) {
    Fail("incomplete counter header");
  }
  return members;
}

double CounterBalancePower(const nlohmann::json& header) {
  const auto power = [](const nlohmann::json& h) {
    return h.contains("balance_power") && h.at("balance_power").is_number() ? h.at("balance_power").get<double>() : 1.0;
  };
  if (!header.contains("members")) return power(header);
  if (!header.at("members").is_array() || header.at("members").empty()) Fail("counter ensemble without members");
  const double first = power(header.at("members").front());
  for (const nlohmann::json& m : header.at("members"))
    if (power(m) != first) Fail("counter ensemble members trained with different class balance powers");
  return first;
}

CounterEnsembleImpl::CounterEnsembleImpl(const std::vector<CounterMember>& members) {
  for (size_t i = 0; i < members.size(); ++i) {
    ResNet net(members[i].architecture);
    if (i == 0) {
      for (const auto& child : net->named_children()) register_module(child.key(), child.value());
    } else {
      register_module("member" + std::to_string(i), net);
    }
    nets.push_back(net);
  }
}

void WriteCounterEnsemble(const std::vector<fs::path>& models, const fs::path& out) {
  if (models.size() < 2) Fail("an ensemble needs at least two counter models, got ", models.size());
  std::vector<CounterMember> members;
  nlohmann::json described = nlohmann::json::array();
  std::vector<int> class_counts;
  for (const fs::path& path : models) {
    const nlohmann::json header = ReadCheckpointHeader(path, "counter");
    if (header.contains("members")) Fail(path.string(), " is an ensemble already: give single counters");
    members.push_back(CounterMembers(header).front());
    nlohmann::json member = {{"source", path.filename().string()},
                             {"architecture", header.at("architecture")},
                             {"input_size", header.at("input_size")}};
    for (const char* key :
         {"data", "training", "train_class_counts", "copy_paste_probability", "ema_decay", "balance_power"}) {
      if (header.contains(key)) member[key] = header.at(key);
    }
    if (header.contains("train_class_counts")) {
      const auto counts = header.at("train_class_counts").get<std::vector<int>>();
      class_counts.resize(std::max(class_counts.size(), counts.size()), 0);
      for (size_t k = 0; k < counts.size(); ++k) class_counts[k] += counts[k];
    }
    described.push_back(member);
  }
  const double balance = CounterBalancePower(described[0]);
  for (const nlohmann::json& m : described)
    if (CounterBalancePower(m) != balance)
      Fail("counter ensemble: ", m.at("source").get<std::string>(), " was trained with class balance power ",
           CounterBalancePower(m), ", ", described[0].at("source").get<std::string>(), " with ", balance,
           "; give counters trained alike");
  CounterEnsemble ensemble(members);
  for (size_t i = 0; i < models.size(); ++i) LoadCheckpointWeights(*ensemble->nets[i], models[i]);
  // The first member's architecture and input stand at the top, as in a single counter's header.
  nlohmann::json header = {{"kind", "counter"},
                           {"architecture", described[0]["architecture"]},
                           {"input_size", described[0]["input_size"]},
                           {"members", described}};
  if (!class_counts.empty()) header["train_class_counts"] = class_counts;
  SaveCheckpoint(*ensemble, header, out);
}

}  // namespace orchard::nn
