#include "orchard/cli/side_args.h"

#include <map>

#include <CLI/CLI.hpp>

#include "orchard/core/error.h"
#include "orchard/core/file_io.h"
#include "orchard/count/counter_factory.h"
#include "orchard/detect/detector_factory.h"

namespace orchard {

namespace fs = std::filesystem;

void AddSideOptions(CLI::App* cmd, SideOptions* options) {
  SideOptions& o = *options;
  cmd->add_option("--frame-selection", o.frames.method, "step or motion")->capture_default_str();
  cmd->add_option("--step", o.frames.step, "Keep every n-th frame (step)")->capture_default_str();
  cmd->add_option("--motion", o.frames.motion_fraction, "Keep a frame after this median flow (fraction of width)")
      ->capture_default_str();
  cmd->add_option("--max-frames", o.frames.max_frames, "Stop after this many frames (0 = all)")->capture_default_str();
  cmd->add_option("--camera-model", o.colmap.camera_model, "COLMAP camera model")->capture_default_str();
  cmd->add_option("--colmap", o.colmap.colmap, "COLMAP executable")->capture_default_str();
  cmd->add_option("--colmap-seed", o.colmap.random_seed, "Random seed of COLMAP's mapper (its first run)")
      ->capture_default_str();
  cmd->add_option("--mapper-attempts", o.colmap.mapper_attempts,
                  "Run COLMAP's mapper up to this many times, a new seed each, while the model looks broken or "
                  "leaves over 5% of the frames out; the best is kept")
      ->capture_default_str();
  cmd->add_option("--camera-height", o.camera_height, "Camera height above the ground (m): the scale")
      ->capture_default_str();
  cmd->add_option("--ground-below-penalty", o.ground.below_penalty,
                  "Ground fit: each sparse point well below a candidate plane costs this many inliers")
      ->capture_default_str();
  cmd->add_option("--ground-fine-fraction", o.ground.fine_inlier_fraction,
                  "Ground fit: inlier distance of the second fit within the first one's band, as a fraction of the "
                  "median distance to the points (the ground's thin layer; 0: the first band only)")
      ->capture_default_str();
  cmd->add_option("--ground-max-tilt", o.ground.max_tilt_deg,
                  "Ground fit: largest angle (degrees) between the plane's normal and the cameras' mean up")
      ->capture_default_str();
  cmd->add_flag("!--no-ground-refit", o.refit_ground_below_fruit,
                "Keep a fitted ground plane that too many fruit points lie below (default: refit it below the fruit)");
  cmd->add_flag("--rescale-poses", o.rescale_given_poses, "Scale given poses by the camera height too");
  cmd->add_flag("!--no-triangulate-poses", o.triangulate_given_poses,
                "Leave given poses without 3D points as they are (default: COLMAP triangulates points for them, "
                "for the ground fit and the trunks)");
  cmd->add_option("--dense-frames", o.dense_frames,
                  "Frames much denser than the 3D stage is tuned to: thin (default: every k-th used), scale (all "
                  "used, its frame counts made as many times larger) or all (used as they are)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, DenseFrames>{
              {"scale", DenseFrames::kScale}, {"thin", DenseFrames::kThin}, {"all", DenseFrames::kAll}},
          CLI::ignore_case));
  cmd->add_flag_callback(
      "--no-thin-frames", [&o] { o.dense_frames = DenseFrames::kAll; }, "Same as --dense-frames all");
  cmd->add_option("--sparse-frames", o.sparse_frames,
                  "Frames more than --sparse-frames-from times as far apart as the 3D stage is tuned to: scale "
                  "(default: its frame counts made as many times smaller, down to --min-sparse-frame-scale) or keep "
                  "(used as they are, warned about)")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, SparseFrames>{{"scale", SparseFrames::kScale}, {"keep", SparseFrames::kKeep}},
          CLI::ignore_case));
  cmd->add_option("--sparse-frames-from", o.sparse_frames_from,
                  "Frames this many times as far apart as the 3D stage is tuned to are sparse")
      ->capture_default_str();
  cmd->add_option("--min-sparse-frame-scale", o.min_sparse_frame_scale,
                  "Sparse frames make the 3D stage's frame counts at most this many times smaller")
      ->capture_default_str();
  cmd->add_option("--frame-scale", o.clusters.frame_scale,
                  "Make the 3D stage's frame counts this many times larger (spans in frames k times, counts of "
                  "frames over a stretch n -> k (n - 1) + 1, rounded), for frames this many times denser than it is "
                  "tuned to (below 1: sparser)")
      ->capture_default_str();
  cmd->add_option("--link-distance", o.clusters.link_distance, "Fruit points closer than this (m) form a cluster")
      ->capture_default_str();
  cmd->add_option("--min-support", o.clusters.points.min_support, "A fruit point must land on fruit in this many frames")
      ->capture_default_str();
  cmd->add_option("--min-views", o.clusters.min_views, "A cluster must win a blob in this many frames")
      ->capture_default_str();
  cmd->add_option("--support-ratio", o.clusters.points.min_support_ratio,
                  "... and in this fraction of the frames it falls into")
      ->capture_default_str();
  cmd->add_option("--explain-distance", o.clusters.points.explain_distance,
                  "Take pairings strongest first; hits on blobs a kept point farther than this (m) lands on do not "
                  "count (0 = off: each blob keeps its best pairing)")
      ->capture_default_str();
  cmd->add_option("--support-window", o.clusters.points.support_window, "Frames either side checked for support")
      ->capture_default_str();
  cmd->add_flag("--split-blobs,!--no-split-blobs", o.split_counted_blobs,
               "Split blobs counted as several apples into one piece per apple before triangulating (default)");
  cmd->add_flag("--fit-circles,!--no-fit-circles", o.fit_apple_circles,
               "Triangulate circles fitted to the blobs' outlines (default) or the blob centroids");
  cmd->add_option("--centre-fraction", o.clusters.points.centre_fraction,
                  "Support only near blob centres (fraction of the blob radius, 0 = anywhere on the blob)")
      ->capture_default_str();
  cmd->add_option("--apple-fraction", o.clusters.points.apple_fraction,
                  "... but at least this fraction of an apple's radius at the point's depth (0 = no floor)")
      ->capture_default_str();
  cmd->add_option("--apple-radius", o.clusters.points.apple_radius, "Smallest apple radius (m) for that floor")
      ->capture_default_str();
  cmd->add_option("--partner-min", o.clusters.points.min_partner_offset, "Nearest partner frame for a first triangulation")
      ->capture_default_str();
  cmd->add_option("--partner-max", o.clusters.points.max_partner_offset, "Farthest partner frame")
      ->capture_default_str();
  cmd->add_option("--min-cluster-points", o.clusters.min_points, "Fewest fruit points of a cluster")
      ->capture_default_str();
  cmd->add_option("--min-cluster-views", o.clusters.min_views, "Fewest frames in which a cluster wins a blob")
      ->capture_default_str();
  cmd->add_option("--max-lost-fraction", o.clusters.max_lost_fraction,
                  "Remove clusters whose points land mostly on blobs other clusters win (1 = keep all)")
      ->capture_default_str();
  cmd->add_option("--min-apple-fraction", o.clusters.min_apple_fraction,
                  "Remove clusters whose largest blob shows less than this fraction of --apple-radius (0 = keep all; "
                  "-1 = auto: 0.6 for instance masks, 0.5 for a detector's blobs)")
      ->capture_default_str();
  cmd->add_option("--merge-shared", o.clusters.merge_shared_fraction,
                  "Join a cluster to a larger one when at least this fraction of its votes fall on blobs both vote "
                  "for (0 = never)")
      ->capture_default_str();
  cmd->add_option("--duplicate-shared", o.clusters.duplicate_shared_fraction,
                  "Join a cluster to the larger one it shares most votes with when at least this fraction of its "
                  "votes fall on blobs both vote for and the two rarely win blobs in the same frame (0 = never)")
      ->capture_default_str();
  cmd->add_option("--duplicate-coviews", o.clusters.duplicate_coview_fraction,
                  "With --duplicate-shared: join only when the partner also wins a blob in fewer than this fraction "
                  "of the frames where the cluster wins one")
      ->capture_default_str();
  cmd->add_option("--duplicate-distance", o.clusters.duplicate_max_distance,
                  "With --duplicate-shared: join only clusters whose centres lie within this distance (m)")
      ->capture_default_str();
  cmd->add_option("--covered-max-points", o.clusters.covered_max_points,
                  "Remove clusters of at most this many fruit points whose blobs a larger cluster's points cover in "
                  "most of their views: that cluster's apple triangulated again (0 = never; 7 was measured)")
      ->capture_default_str();
  cmd->add_option("--covered-fraction", o.clusters.covered_fraction,
                  "With --covered-max-points: the fraction of the cluster's views the larger cluster must cover")
      ->capture_default_str();
  cmd->add_option("--assign-near", o.clusters.assign_near, "A point off every blob votes for the blob whose centre is near")
      ->capture_default_str();
  std::map<std::string, ClusterOptions::BestViews> best_views;
  for (auto b : {ClusterOptions::BestViews::kAuto, ClusterOptions::BestViews::kPixels, ClusterOptions::BestViews::kCount})
    best_views[BestViewsName(b)] = b;
  cmd->add_option("--best-views-by", o.clusters.best_views_by,
                   "Count a cluster in its views with the most fruit pixels (the study's rule) or the highest counts; "
                   "auto (default): counts when blobs are counted one apple each (instance masks, boxes), else pixels")
      ->transform(CLI::CheckedTransformer(best_views, CLI::ignore_case));
  cmd->add_option("--best-views", o.clusters.best_views,
                  "A cluster's count is the median of its counts in this many best views (the study's 3)")
      ->capture_default_str();
  cmd->add_flag("--vote-near-first,!--vote-under-first", o.clusters.vote_near_first,
                "A point votes for the blob whose centre is near before the blob under it (default), or the reverse");
  cmd->add_option("--fallen-height", o.clusters.fallen_height, "Clusters lower than this (m) are fallen apples")
      ->capture_default_str();
  cmd->add_option("--row-distance", o.clusters.row_distance, "Camera path to row centre (m), 0 = estimate")
      ->capture_default_str();
  cmd->add_option("--row-min-share", o.clusters.row_min_share,
                  "Row distance estimate: the nearest stretch of fruit holding this share of the fullest one's")
      ->capture_default_str();
  cmd->add_option("--row-min-apple-share", o.clusters.row_min_apple_share,
                  "... and this share of the apples of the stretch that holds the most (near the camera, chance "
                  "pairings show many pixels for few apples)")
      ->capture_default_str();
  cmd->add_option("--next-row-gap", o.clusters.next_row_gap,
                  "Next row: behind the middle of the first fruit-free gap this long (m) behind the row, 0 = margin")
      ->capture_default_str();
  cmd->add_option("--next-row-margin", o.clusters.next_row_margin,
                  "Without such a gap: beyond row distance + this (m) is the next row")
      ->capture_default_str();
  cmd->add_option("--near-margin", o.clusters.near_margin, "Nearer than row distance - this (m): removed")
      ->capture_default_str();
  cmd->add_flag("--edge-apples,!--no-edge-apples", o.clusters.edge.enabled,
                "Count apples seen only as slivers at the frames' top edge, grouped across frames where their rays "
                "cross (default)");
  cmd->add_option("--edge-min-pixels", o.clusters.edge.min_pixels,
                  "Edge apples: a sliver shows at least this many pixels in a frame (0 = auto: 20 for instance masks, "
                  "50 for a detector's blobs)")
      ->capture_default_str();
  cmd->add_option("--edge-window", o.clusters.edge.window,
                  "Edge apples: slivers at most this many frames apart may be one apple")
      ->capture_default_str();
  cmd->add_flag("--glimpsed-apples,!--no-glimpsed-apples", o.clusters.glimpsed.enabled,
                "Count apples glimpsed through the leaves: pieces no cluster explains that a sphere of apple size "
                "holds in several frames (default; for a detector's blobs only with --glimpsed-with-detector)");
  cmd->add_flag("--glimpsed-with-detector", o.clusters.glimpsed.with_detector,
                "Glimpsed apples among a detector's blobs too (off: a quarter of what the U-Net's add is an apple)");
  cmd->add_option("--glimpse-min-support", o.clusters.glimpsed.min_support,
                  "Glimpsed apples: frames whose sphere's disc holds a free piece")
      ->capture_default_str();
  cmd->add_option("--glimpse-min-pixels", o.clusters.glimpsed.min_pixels, "Glimpsed apples: smallest piece (pixels)")
      ->capture_default_str();
  cmd->add_option("--glimpse-min-extent", o.clusters.glimpsed.min_extent,
                  "Glimpsed apples: a piece's longest chord is at least this many times the disc's radius")
      ->capture_default_str();
  cmd->add_option("--glimpse-ray-margin", o.clusters.glimpsed.ray_margin,
                  "Glimpsed apples: the merge follows each piece's line of sight this far (m, across the row) in "
                  "front of and behind the sphere")
      ->capture_default_str();
  cmd->add_option("--draw-every", o.draw_every, "Annotate every n-th frame (0 = none)")->capture_default_str();
}

void AddFruitOptions(CLI::App* cmd, FruitArgs* a) {
  cmd->add_option("--detector", a->detector,
                  "Fruit: gmm, unet, retinanet (one blob per box), or masks (the generator's instance masks)")
      ->capture_default_str();
  cmd->add_option("--model", a->model, "Detector model (default: the shipped model of the detector)");
  cmd->add_option("--counter", a->counter,
                  "Apples per blob: cnn, gmm, blob (one each), or auto (blob for --detector masks and retinanet, else cnn)")
      ->capture_default_str();
  cmd->add_option("--counter-model", a->counter_model, "Counter model (default: the shipped one)");
  cmd->add_option("--threads", a->threads,
                  "Threads of the detector, the counter and COLMAP (0 = all the cores this process may use; give "
                  "each of several runs on one machine its share)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--min-blob-pixels", a->min_blob_pixels, "Detector blobs smaller than this (pixels) are dropped")
      ->capture_default_str();
  cmd->add_option("--unet-threshold", a->unet_threshold, "A pixel is apple above this U-Net probability")
      ->capture_default_str();
  cmd->add_option("--retinanet-threshold", a->retinanet_threshold, "A RetinaNet box is an apple above this score")
      ->capture_default_str();
  cmd->add_option("--retinanet-scale", a->retinanet_scale,
                  "Frames are resized by this before the RetinaNet (2: apples twice the size they show)")
      ->capture_default_str();
  cmd->add_option("--min-apple-posterior", a->gmm_min_apple_posterior,
                  "gmm: a superpixel is apple when the KL rule says so and its apple posterior is at least this")
      ->capture_default_str();
  cmd->add_option("--counter-prior-weight", a->counter_prior_weight,
                  "cnn: the prior the decision assumes, training frequencies to this power (0 = all counts equally "
                  "likely; 1 = the training data's own: more clusters right, lower totals)")
      ->capture_default_str();
}

std::string CounterName(const FruitArgs& args) {
  if (args.counter != "auto") return args.counter;
  // A box detector finds apples, not clusters: one apple per box.
  return args.detector == "masks" || args.detector == "retinanet" ? "blob" : "cnn";
}

void SetUpFruit(FruitArgs a, const std::string& masks, FruitTools* tools, SideInputs* in) {
  a.counter = CounterName(a);
  if (a.detector == "masks") {
    if (masks.empty()) Fail("--detector masks needs the instance-mask folder (--masks)");
    in->masks = masks;
    in->detector_name = "masks";
  } else {
    if (!tools->detector) {
      DetectorChoice choice;
      choice.method = a.detector;
      choice.model = a.model;
      choice.threads = a.threads;
      choice.blobs.min_pixels = a.min_blob_pixels;
      choice.unet_threshold = a.unet_threshold;
      choice.retinanet_threshold = a.retinanet_threshold;
      choice.retinanet_scale = a.retinanet_scale;
      choice.gmm_min_apple_posterior = a.gmm_min_apple_posterior;
      tools->detector = MakeDetector(choice);
    }
    in->detector = tools->detector.get();
    const fs::path model = a.model.empty() ? DefaultDetectorModel(a.detector) : fs::path(a.model);
    // The fingerprint redoes the per-frame cache when a model is retrained in place.
    in->detector_name = a.detector + ":" + model.string() + "@" + FileFingerprint(model);
    // Non-default settings change the blobs, so they are part of the cache key.
    if (a.min_blob_pixels != BlobOptions().min_pixels)
      in->detector_name += " min_blob_pixels=" + std::to_string(a.min_blob_pixels);
    if (a.detector == "unet" && a.unet_threshold != DetectorChoice().unet_threshold)
      in->detector_name += " threshold=" + std::to_string(a.unet_threshold);
    if (a.detector == "retinanet" && a.retinanet_threshold != DetectorChoice().retinanet_threshold)
      in->detector_name += " threshold=" + std::to_string(a.retinanet_threshold);
    if (a.detector == "retinanet" && a.retinanet_scale != DetectorChoice().retinanet_scale)
      in->detector_name += " scale=" + std::to_string(a.retinanet_scale);
    if (a.detector == "gmm" && a.gmm_min_apple_posterior != FruitArgs().gmm_min_apple_posterior)
      in->detector_name += " min_apple_posterior=" + std::to_string(a.gmm_min_apple_posterior);
  }
  if (a.counter != "blob" && !tools->counter) {
    CounterChoice choice;
    choice.method = a.counter;
    choice.model = a.counter_model;
    choice.threads = a.threads;
    choice.cnn.prior_weight = a.counter_prior_weight;
    tools->counter = MakeCounter(choice);
  }
  in->counter = tools->counter.get();
  in->counter_name = a.counter;
  if (a.counter == "cnn" || !a.counter_model.empty()) {
    const fs::path model = a.counter_model.empty() ? DefaultCounterModel() : fs::path(a.counter_model);
    in->counter_name += ":" + model.string() + "@" + FileFingerprint(model);
    if (a.counter == "cnn" && a.counter_prior_weight != CnnCounterOptions().prior_weight)
      in->counter_name += " prior_weight=" + std::to_string(a.counter_prior_weight);
  }
}

}  // namespace orchard
