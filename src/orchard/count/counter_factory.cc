#include "orchard/count/counter_factory.h"

#include "orchard/core/error.h"
#include "orchard/core/models_dir.h"
#include "orchard/count/cnn_counter.h"

namespace orchard {

void CounterChoice::Check() const {
  ORCHARD_CHECK_OPTION(method == "cnn" || method == "gmm", "unknown counter '", method, "' (available: cnn, gmm)");
  ORCHARD_CHECK_OPTION(threads >= 0, "threads must be >= 0, got ", threads);
}

std::filesystem::path DefaultCounterModel() { return DefaultModelsDir() / "counter.pt"; }

std::unique_ptr<Counter> MakeCounter(const CounterChoice& choice) {
  choice.Check();
  if (choice.method == "cnn") {
    return std::make_unique<CnnCounter>(choice.model.empty() ? DefaultCounterModel() : choice.model, choice.threads,
                                        choice.cnn);
  }
  std::shared_ptr<const ColourModel> colour;
  if (!choice.model.empty()) colour = std::make_shared<ColourModel>(ReadColourModel(choice.model));
  return std::make_unique<GmmCounter>(choice.gmm, colour);
}

}  // namespace orchard
