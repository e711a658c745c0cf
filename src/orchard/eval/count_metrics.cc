#include "orchard/eval/count_metrics.h"

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include "orchard/core/error.h"

namespace orchard {
namespace {

std::string Stem(const std::string& name) {
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

int CountClass(int count) { return count < kNumCountClasses - 1 ? count : kNumCountClasses - 1; }

}  // namespace

CountMetrics EvaluateCounts(const std::vector<ImageCount>& ground_truth,
                            const std::vector<ImageCount>& predictions) {
  if (ground_truth.empty()) Fail("the ground-truth counts are empty");
  std::map<std::string, size_t> by_name, by_stem;
  std::map<std::string, int> stem_uses;
  for (size_t i = 0; i < ground_truth.size(); ++i) {
    const ImageCount& g = ground_truth[i];
    if (g.count < 0) Fail("negative ground-truth count for '", g.name, "'");
    if (!by_name.emplace(g.name, i).second) Fail("image '", g.name, "' repeats in the ground truth");
    by_stem[Stem(g.name)] = i;
    ++stem_uses[Stem(g.name)];
  }
  std::vector<int> predicted(ground_truth.size(), -1);
  std::vector<std::string> predicted_as(ground_truth.size());
  for (const ImageCount& p : predictions) {
    if (p.count < 0) Fail("negative predicted count for '", p.name, "'");
    size_t i = 0;
    if (auto it = by_name.find(p.name); it != by_name.end()) {
      i = it->second;
    } else if (auto st = by_stem.find(Stem(p.name)); st != by_stem.end() && stem_uses[st->first] == 1) {
      i = st->second;
    } else {
      Fail("prediction for '", p.name, "', which is not in the ground truth");
    }
    if (predicted[i] >= 0) {
      Fail("two predictions for '", ground_truth[i].name, "' ('", predicted_as[i], "' and '", p.name,
           "')");
    }
    predicted[i] = p.count;
    predicted_as[i] = p.name;
  }

  CountMetrics m;
  m.images = static_cast<int>(ground_truth.size());
  std::array<int, kNumCountClasses> correct_per_class{};
  int correct = 0;
  double abs_error = 0;
  for (size_t i = 0; i < ground_truth.size(); ++i) {
    if (predicted[i] < 0) Fail("no prediction for '", ground_truth[i].name, "'");
    const int truth = ground_truth[i].count, pred = predicted[i];
    const int tc = CountClass(truth);
    ++m.confusion[tc][CountClass(pred)];
    ++m.images_per_class[tc];
    if (pred == truth) {
      ++correct;
      ++correct_per_class[tc];
    }
    abs_error += std::abs(pred - truth);
  }
  m.accuracy = static_cast<double>(correct) / m.images;
  m.mae = abs_error / m.images;
  for (int c = 0; c < kNumCountClasses; ++c) {
    m.accuracy_per_class[c] = m.images_per_class[c] > 0
                                  ? static_cast<double>(correct_per_class[c]) / m.images_per_class[c]
                                  : std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

}  // namespace orchard
