// Helpers shared by the line-based readers (YOLO txt, CodaLab csv): splitting a
// file into numbered lines and fields, and parsing numbers with errors that name
// the file, the line and the field.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace orchard {
namespace data_internal {

namespace fs = std::filesystem;

struct TextLine {
  int number = 0;    // 1-based line number in the file
  std::string text;  // without the line break and surrounding white space
};

// Non-empty lines of `path` (a UTF-8 byte-order mark and '\r' are dropped).
std::vector<TextLine> ReadNonEmptyLines(const fs::path& path);

// Fields separated by white space (`separator` == 0) or by `separator`, each
// trimmed of surrounding white space.
std::vector<std::string> SplitFields(const std::string& text, char separator = 0);

// "<path>:<line>: field '<field>': " for error messages.
std::string Where(const fs::path& path, int line, const std::string& field);

// A finite number, or throws "<path>:<line>: field '<field>': expected a number, got '<token>'".
double ParseNumber(const std::string& token, const fs::path& path, int line,
                   const std::string& field);
// True when `token` is a finite number (no throw).
bool IsNumber(const std::string& token);
// A whole number (no fraction), or throws like ParseNumber.
long long ParseInteger(const std::string& token, const fs::path& path, int line,
                       const std::string& field);

}  // namespace data_internal
}  // namespace orchard
