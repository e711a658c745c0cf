// Fruit in 3D from per-frame fruit blobs and known poses: each blob centre is
// matched to blob centres in frames a few steps ahead (within an epipolar
// tolerance), the pair is triangulated, and the point is kept only when it
// projects onto fruit in most frames around it that see it (the consistency
// check that rejects wrong pairings); kept points are refined by triangulating
// the centres of all blobs they project onto.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "orchard/detect/detector.h"
#include "orchard/sfm/camera_view.h"

namespace orchard {

// One frame's fruit: blob id per pixel, the blobs and the apples counted in each.
struct FruitFrame {
  cv::Mat1i labels;          // blob id per pixel (0 = none), frame size
  std::vector<Blob> blobs;   // ids 1..N in order
  std::vector<int> counts;   // apples per blob (same order as blobs)
  // Where each blob's apple centre is (same order; see FitAppleCentres): the
  // fruit points triangulate these, or the blob centroids when empty.
  std::vector<cv::Point2d> apple_centres;
  const Blob* FindBlob(int id) const { return id >= 1 && id <= static_cast<int>(blobs.size()) ? &blobs[id - 1] : nullptr; }
};

// Radius (pixels) of the disc with the blob's area: its size as an apple.
double EquivalentRadius(const Blob& blob);

struct FruitPointOptions {
  // Partner frames for the first triangulation: this many frames ahead (a
  // longer baseline gives better depth, a shorter one catches apples seen in
  // few frames; 1..6 counted best on the development row, docs/side.md).
  int min_partner_offset = 1;
  int max_partner_offset = 6;
  // Consistency check over the frames within this many of the blob's frame.
  int support_window = 6;
  // Largest distance (pixels) of a blob centre from its match's epipolar line
  // and of a refined point's reprojection from a supporting blob centre,
  // as a fraction of the image width (1% = ~10 px at 960 px).
  double max_error_fraction = 0.01;
  // A point is kept when it lands on fruit in at least this many frames and
  // in at least this fraction of the frames whose image it falls into. A
  // partly hidden apple shows through gaps in the leaves in a third to a half
  // of the frames; the clusters' own checks (min_views, max_lost_fraction,
  // min_apple_fraction in side.h) catch most chance pairings this lets
  // through. 3 since the size check removes the next row's chance pairings
  // (4 before; with the size check, 3 leaves 376 instead of 404 visible
  // apples without a cluster on 40 development sides; docs/side.md).
  int min_support = 3;
  double min_support_ratio = 0.3;
  // A frame supports a point only when the point projects within this
  // fraction of the blob's equivalent radius (sqrt(pixels / pi)) of the
  // blob's centre (0 = anywhere on the blob): wrong pairings land on fruit by
  // chance but rarely near blob centres.
  double centre_fraction = 0.7;
  // ... but never less than this fraction of an apple of `apple_radius`
  // (scene units) seen at the point's depth: a partly hidden apple's visible
  // piece is small, yet its centre lies up to an apple radius from the point
  // (0 = no floor).
  double apple_fraction = 0.7;
  double apple_radius = 0.03;
  // Depth range in front of the cameras (scene units: metres once scaled).
  double min_depth = 0.3;
  double max_depth = 15;
  // Explaining away (0 = off: each blob keeps its best pairing): pairings are
  // taken strongest first over all blobs; a pairing's hits on blobs that a
  // stronger kept point more than this far (scene units) from it already
  // lands on do not count for its support, a blob so explained keeps no
  // point of its own, and a blob whose best pairing then fails falls back to
  // its next best. Why: a chance pairing near the camera, or a second track
  // of a partly hidden apple, lands on blobs another apple's point explains.
  // 6 cm: the best of 4-10 cm on the development rows (fresh sides within
  // 3%: 43 -> 48 of 52; docs/side.md, "Explaining away").
  double explain_distance = 0.06;
  void Check() const;
};

// The centre of the apple a blob shows, in OpenCV pixel indices: a circle
// fitted to the blob's outline (RANSAC on three outline pixels, then least
// squares on the inliers), accepted when its inliers cover at least a quarter
// of the circle, the blob lies inside it and the blob is clearly less than the
// whole disc; otherwise the centroid (a whole apple, a blob of several apples,
// or too little outline to fit). Deterministic for a given blob.
cv::Point2d FitAppleCentre(const cv::Mat1i& labels, const Blob& blob);

// The blob's apple centre (apple_centres, else its centroid) in COLMAP pixel
// coordinates, as views project.
Eigen::Vector2d AppleCentrePixel(const FruitFrame& frame, const Blob& blob);

// Fills frame->apple_centres with FitAppleCentre for every blob.
void FitAppleCentres(FruitFrame* frame);

// Splits every blob counted as k >= 2 apples into k pieces (k-means on its
// pixel positions, started from k slabs along its longer side rather than a
// random draw), each counted as one apple; the frame's apple count is
// unchanged. A detector's blob of several touching apples gives one centre,
// hence one fruit point for all of them; its pieces give one each, so the
// apples are located, and the two sides' clusters of the same apples can meet
// in the merge. New pieces take ids after the frame's last blob. Call before
// FitAppleCentres.
void SplitCountedBlobs(FruitFrame* frame);

struct FruitPoint {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  int frame = 0;    // index of the frame of the blob it came from
  int blob_id = 0;
  int support = 0;  // frames where it lands on fruit
};

// A frame's blob centres bucketed in a grid, for finding the blob near a
// projected point without scanning every blob (a frame holds hundreds).
class BlobCentres {
 public:
  explicit BlobCentres(const FruitFrame& frame, int cell_pixels = 16);
  // The blob whose centre is nearest to X's projection within the tolerance
  // of `centre_fraction` / `apple_fraction`; 0 when none is near enough.
  int Near(const CameraView& view, const Eigen::Vector3d& X, const FruitPointOptions& options) const;

 private:
  const FruitFrame* frame_;
  int cell_, cols_ = 0, rows_ = 0;
  double max_radius_ = 0;               // largest equivalent radius of a blob
  std::vector<std::vector<int>> grid_;  // blob indices per cell
};

// Projects X into `view`: true when it falls in the image or at most an
// apple's radius (options.apple_radius at X's depth) beyond its edge, where
// the frame cuts an apple whose centre lies just outside it (the top of the
// canopy is above the frames of the synthetic rows); `inside` says which.
bool ProjectNearFrame(const CameraView& view, const Eigen::Vector3d& X, const FruitPointOptions& options,
                      Eigen::Vector2d* pixel, bool* inside);

// BlobCentres(frame).Near(view, X, options), for a single lookup.
int BlobNearPoint(const CameraView& view, const FruitFrame& frame, const Eigen::Vector3d& X,
                  const FruitPointOptions& options);

// One accepted pairing of a blob, refined: its point, the frames around it
// it falls into, the (frame, blob id) it lands on, and its mean
// reprojection error (pixels).
struct FruitPointCandidate {
  FruitPoint point;  // point.support = hits.size()
  int in_image = 0;
  std::vector<std::pair<int, int>> hits;
  double error = 0;
};

// The fruit points from every blob's candidates (`per_blob[b]`, any order):
// each blob's strongest (most hits, then least error), or with
// options.explain_distance > 0 the explaining-away choice described there.
// Points come in blob order.
std::vector<FruitPoint> ChooseFruitPoints(std::vector<std::vector<FruitPointCandidate>> per_blob,
                                          const FruitPointOptions& options);

// `views[i]` and `frames[i]` are the same frame; frames are in sequence order.
std::vector<FruitPoint> TriangulateFruitPoints(const std::vector<CameraView>& views,
                                               const std::vector<FruitFrame>& frames, const FruitPointOptions& options);

}  // namespace orchard
