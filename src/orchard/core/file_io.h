// File helpers shared by every stage: atomic writes (write to a temporary name,
// rename when complete, so an interrupted run never leaves a half file or
// clobbers an earlier result), reading text and images with clear errors.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace orchard {

namespace fs = std::filesystem;

// Reads a whole text file; throws orchard::Error naming the path if it cannot.
std::string ReadTextFile(const fs::path& path);

// A short fingerprint of a file's bytes (64-bit FNV-1a, hex), "" when it
// cannot be read: caches keyed on a model's path also change when the model
// is retrained in place.
std::string FileFingerprint(const fs::path& path);

// Writes `content` to `path` atomically (temporary file in the same folder,
// then rename). Creates missing parent folders.
void WriteTextFileAtomic(const fs::path& path, const std::string& content);

// Calls `write(tmp_path)` to produce the file under a temporary name in the
// same folder, then renames it to `path`. For writers that need a path (cv::imwrite,
// gnuplot). The temporary keeps the extension so format-by-extension writers work.
void WriteFileAtomic(const fs::path& path, const std::function<void(const fs::path&)>& write);

// Writes an image atomically; the format follows the extension (.png, .jpg).
void WriteImageAtomic(const fs::path& path, const cv::Mat& image);

// Reads an image (cv::imread flags); throws orchard::Error when the file is
// missing or cannot be decoded.
cv::Mat ReadImage(const fs::path& path, int flags = 1 /* cv::IMREAD_COLOR */);

// Image files (.png .jpg .jpeg .bmp .tif .tiff, any case) directly in `dir`,
// in NaturalLess order of their names. Throws when `dir` is not a folder.
std::vector<fs::path> ListImages(const fs::path& dir);

// Name order with runs of digits compared as numbers ("frame_9" before
// "frame_10"), so frames exported without leading zeros (ffmpeg's
// frame_%d.png) stay in sequence; equal numbers with more leading zeros come
// later, other characters compare bytewise. Agrees with plain string order
// on zero-padded names.
bool NaturalLess(const std::string& a, const std::string& b);

// `name` with every run of digits shorter than `width` padded with leading
// zeros ("frame_7.png" -> "frame_000007.png"): names whose plain string
// order is their natural order, for tools that sort by name (COLMAP).
std::string PadDigitRuns(const std::string& name, int width = 6);

// True when the extension is one of the image extensions above.
bool IsImageFile(const fs::path& path);

// The comma-separated fields of one line of the project's CSV files (no
// quoting: none of its fields holds a comma); a trailing empty field is dropped.
std::vector<std::string> SplitCsvLine(const std::string& line);

}  // namespace orchard
