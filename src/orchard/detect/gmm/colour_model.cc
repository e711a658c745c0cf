#include "orchard/detect/gmm/colour_model.h"

#include <algorithm>
#include <functional>
#include <cmath>
#include <limits>

#include <Eigen/LU>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/data/dataset.h"

namespace orchard {
namespace {

constexpr const char* kFormatName = "orchard-gmm-colour-model";

// Superpixel means of a frame as rows of an N x 3 matrix.
Eigen::MatrixXd MeansMatrix(const SuperpixelColours& colours) {
  Eigen::MatrixXd m(colours.mean.size(), 3);
  for (size_t i = 0; i < colours.mean.size(); ++i) m.row(i) = colours.mean[i].transpose();
  return m;
}

Eigen::MatrixXd Subsample(const Eigen::MatrixXd& x, int max_rows) {
  if (x.rows() <= max_rows) return x;
  Eigen::MatrixXd out(max_rows, x.cols());
  const double step = static_cast<double>(x.rows()) / max_rows;
  for (int i = 0; i < max_rows; ++i) out.row(i) = x.row(static_cast<Eigen::Index>(i * step));
  return out;
}

GaussianMixture FitClasses(const std::vector<Eigen::MatrixXd>& per_image, const ColourTrainingOptions& o) {
  Eigen::Index rows = 0;
  for (const auto& m : per_image) rows += m.rows();
  Eigen::MatrixXd all(rows, 3);
  Eigen::Index r = 0;
  for (const auto& m : per_image) {
    all.middleRows(r, m.rows()) = m;
    r += m.rows();
  }
  if (all.rows() < o.num_classes)
    Fail("only ", all.rows(), " superpixels in the training images, fewer than the ", o.num_classes, " colour classes");
  GaussianMixtureOptions em;
  em.num_components = o.num_classes;
  em.seed = o.seed;
  em.regularization = 0.05;  // LAB units^2: flat-coloured clusters stay invertible
  return FitGaussianMixture(Subsample(all, o.max_samples), em).mixture;
}

nlohmann::json SegmentationToJson(const SegmentationOptions& s) {
  return {{"region_size", s.superpixels.region_size},
          {"compactness", s.superpixels.compactness},
          {"iterations", s.superpixels.iterations},
          {"min_size_fraction", s.superpixels.min_size_fraction},
          {"working_region_size", s.working_region_size}};
}

}  // namespace

void SegmentationOptions::Check() const {
  superpixels.Check();
  ORCHARD_CHECK_OPTION(working_region_size >= 2, "working_region_size must be >= 2 pixels, got ",
                       working_region_size);
}

double SegmentationOptions::WorkingScale() const {
  if (superpixels.use_opencv) return 1.0;
  return std::min(1.0, static_cast<double>(working_region_size) / superpixels.region_size);
}

SegmentedFrame SegmentFrame(const cv::Mat& bgr, const SegmentationOptions& options) {
  options.Check();
  if (bgr.empty()) Fail("cannot detect in an empty image");
  if (bgr.type() != CV_8UC3) Fail("expected an 8-bit BGR image, got type ", bgr.type());
  SegmentedFrame f;
  f.scale = options.WorkingScale();
  SuperpixelOptions sp = options.superpixels;
  cv::Mat work = bgr;
  if (f.scale < 1.0) {
    const cv::Size size(std::max(1, static_cast<int>(std::lround(bgr.cols * f.scale))),
                        std::max(1, static_cast<int>(std::lround(bgr.rows * f.scale))));
    cv::resize(bgr, work, size, 0, 0, cv::INTER_AREA);
    sp.region_size = options.working_region_size;
  }
  cv::cvtColor(work, f.lab8, cv::COLOR_BGR2Lab);
  f.superpixels = ComputeSuperpixels(f.lab8, sp);
  f.colours = ComputeSuperpixelColours(f.lab8, f.superpixels, sp.num_threads);
  return f;
}

void ColourModel::Validate() const {
  mixture.Validate();
  if (mixture.Dim() != 3) Fail("colour model components must be 3-D (CIELAB), got ", mixture.Dim());
  if (apple.size() != mixture.components.size())
    Fail("colour model has ", apple.size(), " apple flags for ", mixture.components.size(), " classes");
  const int n = NumApple();
  if (n == 0) Fail("colour model has no apple class (did the clicks or annotations fall on apples?)");
  if (n == static_cast<int>(apple.size())) Fail("colour model marks every class as apple: nothing is background");
  segmentation.Check();
}

int ColourModel::NumApple() const { return static_cast<int>(std::count(apple.begin(), apple.end(), true)); }

void WriteColourModel(const ColourModel& model, const fs::path& path) {
  model.Validate();
  nlohmann::json classes = nlohmann::json::array();
  for (int j = 0; j < model.mixture.NumComponents(); ++j) {
    const Gaussian& g = model.mixture.components[j];
    std::vector<double> cov(g.covariance.data(), g.covariance.data() + 9);
    classes.push_back({{"weight", model.mixture.weights[j]},
                       {"mean", {g.mean[0], g.mean[1], g.mean[2]}},
                       {"covariance", cov},
                       {"apple", static_cast<bool>(model.apple[j])}});
  }
  nlohmann::json j = {{"format", kFormatName},
                      {"version", ColourModel::kFormatVersion},
                      {"colour_space", "CIELAB (L 0..100, a, b)"},
                      {"features", "superpixel mean colour"},
                      {"supervision", model.supervision},
                      {"trained_on", model.trained_on},
                      {"apple_rule", model.apple_rule},
                      {"segmentation", SegmentationToJson(model.segmentation)},
                      {"classes", classes}};
  WriteTextFileAtomic(path, j.dump(1) + "\n");
}

ColourModel ReadColourModel(const fs::path& path) {
  const std::string text = ReadTextFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    Fail(path.string(), ": not a json file (corrupt colour model?)");
  }
  if (!j.is_object() || j.value("format", std::string()) != kFormatName)
    Fail(path.string(), ": not an orchard GMM colour model (no \"format\": \"", kFormatName, "\")");
  if (!j.contains("version") || !j["version"].is_number_integer() || j["version"].get<int>() != ColourModel::kFormatVersion)
    Fail(path.string(), ": colour model format version ", j.contains("version") ? j["version"].dump() : "missing",
         " is not supported (this program reads version ", ColourModel::kFormatVersion, "); retrain it with `orchard train gmm`");
  ColourModel model;
  try {
    model.supervision = j.value("supervision", "");
    model.trained_on = j.value("trained_on", "");
    model.apple_rule = j.value("apple_rule", "");
    const nlohmann::json& s = j.at("segmentation");
    model.segmentation.superpixels.region_size = s.at("region_size").get<int>();
    model.segmentation.superpixels.compactness = s.at("compactness").get<double>();
    model.segmentation.superpixels.iterations = s.at("iterations").get<int>();
    model.segmentation.superpixels.min_size_fraction = s.at("min_size_fraction").get<double>();
    model.segmentation.working_region_size = s.at("working_region_size").get<int>();
    for (const nlohmann::json& c : j.at("classes")) {
      const auto mean = c.at("mean").get<std::vector<double>>();
      const auto cov = c.at("covariance").get<std::vector<double>>();
      if (mean.size() != 3 || cov.size() != 9) Fail("a class needs a 3-vector mean and a 3x3 covariance");
      Gaussian g;
      g.mean = Eigen::Map<const Eigen::Vector3d>(mean.data());
      g.covariance = Eigen::Map<const Eigen::Matrix3d>(cov.data());
      model.mixture.components.push_back(g);
      model.mixture.weights.push_back(c.at("weight").get<double>());
      model.apple.push_back(c.at("apple").get<bool>());
    }
    model.Validate();
  } catch (const nlohmann::json::exception& e) {
    Fail(path.string(), ": malformed colour model: ", e.what());
  } catch (const Error& e) {
    Fail(path.string(), ": invalid colour model: ", e.what());
  }
  return model;
}

void ColourTrainingOptions::Check() const {
  ORCHARD_CHECK_OPTION(num_classes >= 2, "need at least 2 colour classes, got ", num_classes);
  ORCHARD_CHECK_OPTION(max_samples >= num_classes, "max_samples must be >= num_classes, got ", max_samples);
  ORCHARD_CHECK_OPTION(apple_pixel_fraction >= 0 && apple_pixel_fraction < 1,
                       "apple_pixel_fraction must be in [0, 1) (0 = chosen for the best F1), got ", apple_pixel_fraction);
  ORCHARD_CHECK_OPTION(min_clicks_per_class >= 1, "min_clicks_per_class must be >= 1, got ", min_clicks_per_class);
  ORCHARD_CHECK_OPTION(min_apple_posterior >= 0 && min_apple_posterior < 1,
                       "min_apple_posterior must be in [0, 1), got ", min_apple_posterior);
  segmentation.Check();
}

std::vector<Click> ReadClicks(const fs::path& path) {
  const std::string text = ReadTextFile(path);
  std::vector<Click> clicks;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (!j.is_array()) Fail(path.string(), ": clicks must be a json list of {\"image\", \"x\", \"y\"}");
    for (const nlohmann::json& c : j)
      clicks.push_back({c.at("image").get<std::string>(), c.at("x").get<double>(), c.at("y").get<double>()});
  } catch (const nlohmann::json::exception& e) {
    Fail(path.string(), ": malformed clicks file (expected [{\"image\": name, \"x\": px, \"y\": px}, ...]): ", e.what());
  }
  if (clicks.empty()) Fail(path.string(), ": no clicks: click at least one apple");
  return clicks;
}

void WriteClicks(const std::vector<Click>& clicks, const fs::path& path) {
  nlohmann::json j = nlohmann::json::array();
  for (const Click& c : clicks) j.push_back({{"image", c.image}, {"x", c.x}, {"y", c.y}});
  WriteTextFileAtomic(path, j.dump(1) + "\n");
}

ColourModel TrainColourModelFromClicks(const std::vector<fs::path>& images, const std::vector<Click>& clicks,
                                       const ColourTrainingOptions& options) {
  options.Check();
  if (images.empty()) Fail("no training images");
  if (clicks.empty()) Fail("no clicks: click at least one apple");
  // Which image each click falls on (by file name, or name without extension).
  std::vector<int> click_image(clicks.size(), -1);
  for (size_t c = 0; c < clicks.size(); ++c) {
    for (size_t i = 0; i < images.size(); ++i) {
      if (images[i].filename().string() == clicks[c].image || images[i].stem().string() == clicks[c].image)
        click_image[c] = static_cast<int>(i);
    }
    if (click_image[c] < 0)
      Fail("click ", c + 1, " names image '", clicks[c].image, "', which is not among the ", images.size(),
           " training images");
  }
  std::vector<Eigen::MatrixXd> features;
  std::vector<std::vector<int>> clicked_superpixels(images.size());  // per image
  std::vector<Eigen::MatrixXd> clicked_means;
  for (size_t i = 0; i < images.size(); ++i) {
    // Classes come from the clicked frames only (the user clicks on the first few).
    if (std::find(click_image.begin(), click_image.end(), static_cast<int>(i)) == click_image.end()) continue;
    const cv::Mat bgr = ReadImage(images[i]);
    const SegmentedFrame f = SegmentFrame(bgr, options.segmentation);
    features.push_back(MeansMatrix(f.colours));
    for (size_t c = 0; c < clicks.size(); ++c) {
      if (click_image[c] != static_cast<int>(i)) continue;
      if (!(clicks[c].x >= 0 && clicks[c].y >= 0 && clicks[c].x < bgr.cols && clicks[c].y < bgr.rows))
        Fail("click ", c + 1, " at (", clicks[c].x, ", ", clicks[c].y, ") lies outside ", images[i].filename().string(),
             " (", bgr.cols, "x", bgr.rows, ")");
      const int x = std::min(f.lab8.cols - 1, static_cast<int>(clicks[c].x * f.scale));
      const int y = std::min(f.lab8.rows - 1, static_cast<int>(clicks[c].y * f.scale));
      clicked_superpixels[i].push_back(f.superpixels.labels(y, x));
    }
    Eigen::MatrixXd m(clicked_superpixels[i].size(), 3);
    for (size_t k = 0; k < clicked_superpixels[i].size(); ++k)
      m.row(k) = f.colours.mean[clicked_superpixels[i][k]].transpose();
    clicked_means.push_back(m);
  }
  ColourModel model;
  model.mixture = FitClasses(features, options);
  model.segmentation = options.segmentation;
  model.segmentation.superpixels.use_opencv = false;
  model.supervision = "clicks";
  std::vector<int> votes(model.mixture.NumComponents(), 0);
  for (const Eigen::MatrixXd& m : clicked_means) {
    if (m.rows() == 0) continue;
    const Eigen::MatrixXd post = model.mixture.Posteriors(m);
    for (Eigen::Index r = 0; r < post.rows(); ++r) {
      Eigen::Index best;
      post.row(r).maxCoeff(&best);
      ++votes[best];
    }
  }
  model.apple.assign(votes.size(), false);
  for (size_t j = 0; j < votes.size(); ++j) model.apple[j] = votes[j] >= options.min_clicks_per_class;
  if (model.NumApple() == 0)
    Fail("no colour class got ", options.min_clicks_per_class, " clicks (the ", clicks.size(),
         " clicks fall in ", std::count_if(votes.begin(), votes.end(), [](int v) { return v > 0; }),
         " different classes): click more apples or lower the agreement");
  model.trained_on = std::to_string(images.size()) + " images, " + std::to_string(clicks.size()) + " clicks";
  model.Validate();
  return model;
}

ColourModel TrainColourModelFromAnnotations(const Dataset& dataset, const ColourTrainingOptions& options) {
  options.Check();
  if (dataset.images.empty()) Fail("the annotated training set has no images");
  std::vector<Eigen::MatrixXd> features;
  std::vector<std::vector<double>> apple_pixels, total_pixels;  // per image, per superpixel
  std::vector<Eigen::Matrix3d> covariances;                     // all superpixels, in order
  for (const AnnotatedImage& image : dataset.images) {
    if (image.path.empty()) Fail("annotated image ", image.name, " has no image file");
    const cv::Mat bgr = ReadImage(image.path);
    const SegmentedFrame f = SegmentFrame(bgr, options.segmentation);
    // Apple pixels: ellipses inscribed in the boxes, drawn at working resolution.
    cv::Mat1b apples(f.lab8.size(), uchar(0));
    for (const Annotation& a : image.objects) {
      const cv::Point2d c(a.box.CenterX() * f.scale, a.box.CenterY() * f.scale);
      const cv::Size2d axes(0.5 * a.box.Width() * f.scale, 0.5 * a.box.Height() * f.scale);
      cv::ellipse(apples, cv::RotatedRect(c, cv::Size2f(2 * axes.width, 2 * axes.height), 0), 255, cv::FILLED);
    }
    std::vector<double> in(f.superpixels.num_labels, 0.0);
    for (int y = 0; y < apples.rows; ++y)
      for (int x = 0; x < apples.cols; ++x)
        if (apples(y, x)) in[f.superpixels.labels(y, x)] += 1;
    features.push_back(MeansMatrix(f.colours));
    covariances.insert(covariances.end(), f.colours.covariance.begin(), f.colours.covariance.end());
    apple_pixels.push_back(in);
    total_pixels.emplace_back(f.colours.pixels.begin(), f.colours.pixels.end());
  }
  ColourModel model;
  model.mixture = FitClasses(features, options);
  model.segmentation = options.segmentation;
  model.segmentation.superpixels.use_opencv = false;
  model.supervision = "annotations";
  const int k = model.mixture.NumComponents();
  std::vector<double> class_apple(k, 0.0), class_total(k, 0.0);
  for (size_t i = 0; i < features.size(); ++i) {
    const Eigen::MatrixXd post = model.mixture.Posteriors(features[i]);
    for (Eigen::Index r = 0; r < post.rows(); ++r) {
      Eigen::Index best;
      post.row(r).maxCoeff(&best);
      class_apple[best] += apple_pixels[i][r];
      class_total[best] += total_pixels[i][r];
    }
  }
  std::vector<double> fraction(k, 0.0);
  for (int j = 0; j < k; ++j) fraction[j] = class_total[j] > 0 ? class_apple[j] / class_total[j] : 0.0;
  auto mark = [&](double threshold) {
    model.apple.assign(k, false);
    for (int j = 0; j < k; ++j) model.apple[j] = fraction[j] > threshold;
  };
  if (options.apple_pixel_fraction > 0) {
    mark(options.apple_pixel_fraction);
  } else {
    // Candidate rules: the top-m classes by apple fraction, m = 1..k-1; each is
    // scored by the apple-pixel F1 of the detector's own superpixel decision
    // on (an even subsample of) the training superpixels.
    std::vector<double> sorted = fraction;
    std::sort(sorted.begin(), sorted.end(), std::greater<double>());
    std::vector<Eigen::Vector3d> means;
    std::vector<double> in, total;
    for (size_t i = 0; i < features.size(); ++i)
      for (Eigen::Index r = 0; r < features[i].rows(); ++r) {
        means.push_back(features[i].row(r).transpose());
        in.push_back(apple_pixels[i][r]);
        total.push_back(total_pixels[i][r]);
      }
    const size_t step = std::max<size_t>(1, means.size() / options.max_samples);
    double best_f1 = -1, best_threshold = 0.5;
    for (int m = 1; m < k; ++m) {
      const double threshold = 0.5 * (sorted[m - 1] + sorted[m]);
      if (!(sorted[m - 1] > sorted[m])) continue;
      mark(threshold);
      const ColourClassifier classifier(model, options.min_apple_posterior);
      double tp = 0, fp = 0, fn = 0;
      for (size_t i = 0; i < means.size(); i += step) {
        bool is_apple;
        float posterior;
        classifier.Classify(means[i], covariances[i], &is_apple, &posterior);
        if (is_apple) tp += in[i], fp += total[i] - in[i];
        else fn += in[i];
      }
      const double f1 = tp > 0 ? 2 * tp / (2 * tp + fp + fn) : 0;
      if (f1 > best_f1) best_f1 = f1, best_threshold = threshold;
    }
    mark(best_threshold);
    model.apple_rule = "apple fraction > " + std::to_string(best_threshold) +
                       " (best training apple-pixel F1 " + std::to_string(best_f1) + ")";
  }
  if (model.apple_rule.empty()) model.apple_rule = "apple fraction > " + std::to_string(options.apple_pixel_fraction);
  model.trained_on = std::to_string(dataset.images.size()) + " annotated images, " +
                     std::to_string(dataset.NumObjects()) + " boxes";
  model.Validate();
  return model;
}

ColourClassifier::ColourClassifier(const ColourModel& model, double min_apple_posterior)
    : min_apple_posterior_(min_apple_posterior) {
  model.Validate();
  double apple_total = 0, other_total = 0;
  for (int j = 0; j < model.mixture.NumComponents(); ++j)
    (model.apple[j] ? apple_total : other_total) += model.mixture.weights[j];
  for (int j = 0; j < model.mixture.NumComponents(); ++j) {
    const Gaussian& g = model.mixture.components[j];
    const Eigen::Matrix3d cov = g.covariance;
    ClassConstants c;
    c.inverse = cov.inverse();
    c.mean = g.mean;
    c.half_log_det = 0.5 * std::log(cov.determinant());
    const double w = std::max(model.mixture.weights[j], 1e-300);
    c.log_weight = std::log(w);
    c.log_group_weight = std::log(w / (model.apple[j] ? apple_total : other_total));
    c.apple = model.apple[j];
    classes_.push_back(c);
  }
}

void ColourClassifier::Classify(const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, bool* is_apple,
                                float* apple_posterior) const {
  // KL(s || c) up to terms common to all classes: 0.5 [tr(Ic S) + d' Ic d + ln det C].
  double best_apple = std::numeric_limits<double>::infinity(), best_other = best_apple;
  double max_log = -std::numeric_limits<double>::infinity();
  double log_p[64];
  const int k = static_cast<int>(classes_.size());
  double* lp = k <= 64 ? log_p : nullptr;
  std::vector<double> heap;
  if (!lp) {
    heap.resize(k);
    lp = heap.data();
  }
  for (int j = 0; j < k; ++j) {
    const ClassConstants& c = classes_[j];
    const Eigen::Vector3d d = mean - c.mean;
    const double maha = d.dot(c.inverse * d);
    const double trace = (c.inverse.array() * cov.array()).sum();  // both symmetric
    const double cost = 0.5 * (trace + maha) + c.half_log_det - c.log_group_weight;
    if (c.apple) best_apple = std::min(best_apple, cost);
    else best_other = std::min(best_other, cost);
    lp[j] = c.log_weight - c.half_log_det - 0.5 * maha;
    max_log = std::max(max_log, lp[j]);
  }
  double sum = 0, apple = 0;
  for (int j = 0; j < k; ++j) {
    const double e = std::exp(lp[j] - max_log);
    sum += e;
    if (classes_[j].apple) apple += e;
  }
  *apple_posterior = static_cast<float>(apple / sum);
  *is_apple = best_apple < best_other && *apple_posterior >= min_apple_posterior_;
}

int ColourClassifier::MostLikelyClass(const Eigen::Vector3d& mean) const {
  int best = 0;
  double best_lp = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < static_cast<int>(classes_.size()); ++j) {
    const ClassConstants& c = classes_[j];
    const Eigen::Vector3d d = mean - c.mean;
    const double lp = c.log_weight - c.half_log_det - 0.5 * d.dot(c.inverse * d);
    if (lp > best_lp) best_lp = lp, best = j;
  }
  return best;
}

}  // namespace orchard
