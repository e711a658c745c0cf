#include "orchard/data/text_format.h"

#include <cerrno>
#include <cmath>
#include <cctype>
#include <cstdlib>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"

namespace orchard {
namespace data_internal {
namespace {

std::string Trim(const std::string& s) {
  const char* ws = " \t\r\n\f\v";
  const size_t begin = s.find_first_not_of(ws);
  if (begin == std::string::npos) return "";
  const size_t end = s.find_last_not_of(ws);
  return s.substr(begin, end - begin + 1);
}

// Parses the whole token as a finite double; false otherwise.
bool TryParseDouble(const std::string& token, double* value) {
  if (token.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || errno == ERANGE || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

}  // namespace

std::vector<TextLine> ReadNonEmptyLines(const fs::path& path) {
  std::string content = ReadTextFile(path);
  if (content.size() >= 3 && content.compare(0, 3, "\xEF\xBB\xBF") == 0) content.erase(0, 3);
  std::vector<TextLine> lines;
  int number = 0;
  size_t start = 0;
  while (start <= content.size()) {
    size_t end = content.find('\n', start);
    if (end == std::string::npos) end = content.size();
    ++number;
    std::string text = Trim(content.substr(start, end - start));
    if (!text.empty()) lines.push_back({number, std::move(text)});
    start = end + 1;
  }
  return lines;
}

std::vector<std::string> SplitFields(const std::string& text, char separator) {
  std::vector<std::string> fields;
  if (separator == 0) {
    size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i >= text.size()) break;
      size_t j = i;
      while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      fields.push_back(text.substr(i, j - i));
      i = j;
    }
    return fields;
  }
  size_t start = 0;
  while (true) {
    const size_t end = text.find(separator, start);
    fields.push_back(Trim(text.substr(start, end == std::string::npos ? std::string::npos : end - start)));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return fields;
}

std::string Where(const fs::path& path, int line, const std::string& field) {
  return internal::Concat(path.string(), ":", line, ": field '", field, "': ");
}

bool IsNumber(const std::string& token) {
  double v;
  return TryParseDouble(token, &v);
}

double ParseNumber(const std::string& token, const fs::path& path, int line,
                   const std::string& field) {
  double value = 0;
  if (!TryParseDouble(token, &value)) {
    Fail(Where(path, line, field), "expected a number, got '", token, "'");
  }
  return value;
}

long long ParseInteger(const std::string& token, const fs::path& path, int line,
                       const std::string& field) {
  const double value = ParseNumber(token, path, line, field);
  if (value != std::floor(value) || std::fabs(value) > 9e15) {
    Fail(Where(path, line, field), "expected a whole number, got '", token, "'");
  }
  return static_cast<long long>(value);
}

}  // namespace data_internal
}  // namespace orchard
