#include "orchard/core/file_io.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <opencv2/imgcodecs.hpp>

#include "orchard/core/error.h"

namespace orchard {
namespace {

// A temporary sibling of `path` that keeps its extension: "a.png" -> ".a.tmp123_0.png".
fs::path TemporarySibling(const fs::path& path) {
  static std::atomic<int> counter{0};
  const std::string name = "." + path.stem().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                           std::to_string(counter++) + path.extension().string();
  return path.parent_path() / name;
}

void EnsureParent(const fs::path& path) {
  const fs::path parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) Fail("cannot create folder ", parent.string(), ": ", ec.message());
}

}  // namespace

std::string ReadTextFile(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) Fail("file not found: ", path.string());
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail("cannot open ", path.string());
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

void WriteFileAtomic(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  EnsureParent(path);
  const fs::path tmp = TemporarySibling(path);
  try {
    write(tmp);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
  std::error_code ec;
  if (!fs::exists(tmp, ec)) Fail("writing ", path.string(), " produced no file");
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    Fail("cannot write ", path.string(), ": ", ec.message());
  }
}

void WriteTextFileAtomic(const fs::path& path, const std::string& content) {
  WriteFileAtomic(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) Fail("cannot write ", path.string());
    out << content;
    out.close();
    if (!out) Fail("cannot write ", path.string(), " (disk full?)");
  });
}

void WriteImageAtomic(const fs::path& path, const cv::Mat& image) {
  WriteFileAtomic(path, [&](const fs::path& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp.string(), image);
    } catch (const cv::Exception& e) {
      Fail("cannot write image ", path.string(), ": ", e.what());
    }
    if (!ok) Fail("cannot write image ", path.string());
  });
}

cv::Mat ReadImage(const fs::path& path, int flags) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) Fail("image not found: ", path.string());
  cv::Mat image;
  try {
    image = cv::imread(path.string(), flags);
  } catch (const cv::Exception&) {
    image.release();
  }
  if (image.empty()) Fail("cannot decode image: ", path.string());
  return image;
}

bool IsImageFile(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".tif" ||
         ext == ".tiff";
}

std::vector<fs::path> ListImages(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) Fail("not a folder: ", dir.string());
  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && IsImageFile(entry.path()) &&
        entry.path().filename().string().rfind('.', 0) != 0) {
      images.push_back(entry.path());
    }
  }
  std::sort(images.begin(), images.end(), [](const fs::path& a, const fs::path& b) {
    return NaturalLess(a.filename().string(), b.filename().string());
  });
  return images;
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  return fields;
}

bool NaturalLess(const std::string& a, const std::string& b) {
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      size_t ie = i, je = j;
      while (ie < a.size() && digit(a[ie])) ++ie;
      while (je < b.size() && digit(b[je])) ++je;
      // Compare the runs' values: skip leading zeros, then length, then digits.
      size_t iz = i, jz = j;
      while (iz + 1 < ie && a[iz] == '0') ++iz;
      while (jz + 1 < je && b[jz] == '0') ++jz;
      if (ie - iz != je - jz) return ie - iz < je - jz;
      const int c = a.compare(iz, ie - iz, b, jz, je - jz);
      if (c != 0) return c < 0;
      if (ie - i != je - j) return ie - i < je - j;  // same value: fewer leading zeros first
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::string PadDigitRuns(const std::string& name, int width) {
  std::string out;
  for (size_t i = 0; i < name.size();) {
    if (name[i] < '0' || name[i] > '9') {
      out += name[i++];
      continue;
    }
    size_t e = i;
    while (e < name.size() && name[e] >= '0' && name[e] <= '9') ++e;
    if (static_cast<int>(e - i) < width) out.append(static_cast<size_t>(width) - (e - i), '0');
    out.append(name, i, e - i);
    i = e;
  }
  return out;
}

std::string FileFingerprint(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a 64 offset basis
  std::vector<char> buffer(1 << 16);
  while (in.read(buffer.data(), static_cast<std::streamsize>(buffer.size())) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i)
      h = (h ^ static_cast<unsigned char>(buffer[i])) * 0x100000001b3ULL;  // FNV-1a 64 prime
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

}  // namespace orchard
