// CodaLab / MinneApple result files: detections `name,x1,y1,x2,y2,score`,
// counts `name,count`; and ReadPredictions, which picks the reader.
#include <cstdio>
#include <set>
#include <sstream>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"
#include "orchard/data/text_format.h"

namespace orchard {
namespace {

using data_internal::IsNumber;
using data_internal::ParseInteger;
using data_internal::ParseNumber;
using data_internal::Where;

// The first line is a header when none of its fields after the name is a
// number ("image,x1,y1,..."); a data line with one bad number is an error.
bool IsHeader(const std::vector<std::string>& fields) {
  for (size_t i = 1; i < fields.size(); ++i) {
    if (IsNumber(fields[i])) return false;
  }
  return fields.size() > 1;
}

std::string FormatNumber(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.10g", v);
  return buffer;
}

}  // namespace

Predictions ReadCodaLabDetections(const fs::path& path) {
  static const char* kFields[] = {"name", "x1", "y1", "x2", "y2", "score"};
  Predictions predictions;
  const auto lines = data_internal::ReadNonEmptyLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& line = lines[i];
    const std::vector<std::string> fields = data_internal::SplitFields(line.text, ',');
    if (i == 0 && IsHeader(fields)) continue;
    if (fields.size() != 6) {
      Fail(path.string(), ":", line.number, ": expected 6 fields 'name,x1,y1,x2,y2,score', got ",
           fields.size());
    }
    if (fields[0].empty()) Fail(Where(path, line.number, "name"), "empty image name");
    double v[5];
    for (int k = 0; k < 5; ++k) v[k] = ParseNumber(fields[k + 1], path, line.number, kFields[k + 1]);
    if (v[2] < v[0]) Fail(Where(path, line.number, "x2"), "x2 ", fields[3], " is less than x1 ", fields[1]);
    if (v[3] < v[1]) Fail(Where(path, line.number, "y2"), "y2 ", fields[4], " is less than y1 ", fields[2]);
    predictions[fields[0]].push_back(ScoredBox{Box{v[0], v[1], v[2], v[3]}, v[4]});
  }
  return predictions;
}

void WriteCodaLabDetections(const Predictions& predictions, const fs::path& path) {
  std::ostringstream out;
  for (const auto& [name, detections] : predictions) {
    if (name.find(',') != std::string::npos) Fail("cannot write image name with a comma: ", name);
    for (const ScoredBox& d : detections) {
      out << name << ',' << FormatNumber(d.box.x1) << ',' << FormatNumber(d.box.y1) << ','
          << FormatNumber(d.box.x2) << ',' << FormatNumber(d.box.y2) << ',' << FormatNumber(d.score)
          << '\n';
    }
  }
  WriteTextFileAtomic(path, out.str());
}

std::vector<ImageCount> ReadCodaLabCounts(const fs::path& path) {
  std::vector<ImageCount> counts;
  std::set<std::string> seen;
  const auto lines = data_internal::ReadNonEmptyLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto& line = lines[i];
    const std::vector<std::string> fields = data_internal::SplitFields(line.text, ',');
    if (i == 0 && IsHeader(fields)) continue;
    if (fields.size() != 2) {
      Fail(path.string(), ":", line.number, ": expected 2 fields 'name,count', got ", fields.size());
    }
    if (fields[0].empty()) Fail(Where(path, line.number, "name"), "empty image name");
    const long long count = ParseInteger(fields[1], path, line.number, "count");
    if (count < 0 || count > 1000000000) {
      Fail(Where(path, line.number, "count"), "expected a count >= 0, got '", fields[1], "'");
    }
    if (!seen.insert(fields[0]).second) {
      Fail(Where(path, line.number, "name"), "image '", fields[0], "' is counted twice");
    }
    counts.push_back({fields[0], static_cast<int>(count)});
  }
  return counts;
}

void WriteCodaLabCounts(const std::vector<ImageCount>& counts, const fs::path& path) {
  std::ostringstream out;
  for (const ImageCount& c : counts) {
    if (c.name.find(',') != std::string::npos) Fail("cannot write image name with a comma: ", c.name);
    out << c.name << ',' << c.count << '\n';
  }
  WriteTextFileAtomic(path, out.str());
}

Predictions ReadPredictions(const fs::path& path, const Dataset& ground_truth) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".json") return ReadCocoResults(path, ground_truth);
  // By content: a json list starts with '['.
  const std::string text = ReadTextFile(path);
  const size_t first = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  if (first != std::string::npos && text[first] == '[') return ReadCocoResults(path, ground_truth);
  return ReadCodaLabDetections(path);
}

}  // namespace orchard
