// `orchard side`: one side of a row in 3D (frames, poses, fruit points, 3D
// clusters, tracked counts); see docs/side.md.
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/core/error.h"
#include "orchard/count/counter_factory.h"
#include "orchard/detect/detector_factory.h"
#include "orchard/fruitmap/side.h"

namespace orchard {

void AddSideCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand(
      "side", "Count one side of a row in 3D: side.json, clusters.csv, fruit.ply, annotated/ frames");
  struct Args {
    std::string in, out, poses, masks, ground, detector = "gmm", counter = "blob", model, counter_model;
    SideOptions options;
    int threads = 0;
  };
  auto a = std::make_shared<Args>();
  SideOptions& o = a->options;
  cmd->add_option("--in", a->in, "Video file or folder of frames")->required();
  cmd->add_option("--out", a->out, "Output folder (caches frames/, sparse/, detections/ for reruns)")->required();
  cmd->add_option("--poses", a->poses, "COLMAP text model of the frames (default: run COLMAP)");
  cmd->add_option("--ground-plane", a->ground,
                  "Ground plane nx,ny,nz,d or a json file with ground_plane {normal, d} (default: fit to the sparse points)");
  cmd->add_option("--detector", a->detector, "Fruit: gmm, unet, or masks (instance masks from --masks)")
      ->capture_default_str();
  cmd->add_option("--masks", a->masks, "Instance masks (16-bit, one id per apple) named like the frames");
  cmd->add_option("--model", a->model, "Detector model (default: the shipped model of the detector)");
  cmd->add_option("--counter", a->counter, "Apples per blob: blob (one each), cnn or gmm")->capture_default_str();
  cmd->add_option("--counter-model", a->counter_model, "Counter model (default: the shipped one)");
  cmd->add_option("--frame-selection", o.frames.method, "step or motion")->capture_default_str();
  cmd->add_option("--step", o.frames.step, "Keep every n-th frame (step)")->capture_default_str();
  cmd->add_option("--motion", o.frames.motion_fraction, "Keep a frame after this median flow (fraction of width)")
      ->capture_default_str();
  cmd->add_option("--max-frames", o.frames.max_frames, "Stop after this many frames (0 = all)")->capture_default_str();
  cmd->add_option("--camera-model", o.colmap.camera_model, "COLMAP camera model")->capture_default_str();
  cmd->add_option("--colmap", o.colmap.colmap, "COLMAP executable")->capture_default_str();
  cmd->add_option("--camera-height", o.camera_height, "Camera height above the ground (m): the scale")
      ->capture_default_str();
  cmd->add_flag("--rescale-poses", o.rescale_given_poses, "Scale given poses by the camera height too");
  cmd->add_option("--link-distance", o.clusters.link_distance, "Fruit points closer than this (m) form a cluster")
      ->capture_default_str();
  cmd->add_option("--min-support", o.clusters.points.min_support, "A fruit point must land on fruit in this many frames")
      ->capture_default_str();
  cmd->add_option("--support-ratio", o.clusters.points.min_support_ratio,
                  "... and in this fraction of the frames it falls into")
      ->capture_default_str();
  cmd->add_option("--support-window", o.clusters.points.support_window, "Frames either side checked for support")
      ->capture_default_str();
  cmd->add_option("--centre-fraction", o.clusters.points.centre_fraction,
                  "Support only near blob centres (fraction of the blob radius, 0 = anywhere on the blob)")
      ->capture_default_str();
  cmd->add_option("--partner-min", o.clusters.points.min_partner_offset, "Nearest partner frame for a first triangulation")
      ->capture_default_str();
  cmd->add_option("--partner-max", o.clusters.points.max_partner_offset, "Farthest partner frame")
      ->capture_default_str();
  cmd->add_option("--min-cluster-points", o.clusters.min_points, "Fewest fruit points of a cluster")
      ->capture_default_str();
  cmd->add_option("--fallen-height", o.clusters.fallen_height, "Clusters lower than this (m) are fallen apples")
      ->capture_default_str();
  cmd->add_option("--row-distance", o.clusters.row_distance, "Camera path to row centre (m), 0 = estimate")
      ->capture_default_str();
  cmd->add_option("--next-row-margin", o.clusters.next_row_margin, "Beyond row distance + this (m): next row")
      ->capture_default_str();
  cmd->add_option("--near-margin", o.clusters.near_margin, "Nearer than row distance - this (m): removed")
      ->capture_default_str();
  cmd->add_option("--draw-every", o.draw_every, "Annotate every n-th frame (0 = none)")->capture_default_str();
  cmd->add_option("--threads", a->threads, "Detector and counter threads (0 = all cores)")->capture_default_str();
  cmd->callback([a]() {
    SideInputs in;
    in.input = a->in;
    in.out = a->out;
    in.poses = a->poses;
    if (!a->ground.empty()) in.ground = ParseGroundPlane(a->ground);
    std::unique_ptr<Detector> detector;
    if (a->detector == "masks") {
      if (a->masks.empty()) Fail("--detector masks needs --masks DIR");
      in.masks = a->masks;
      in.detector_name = "masks";
    } else {
      DetectorChoice choice;
      choice.method = a->detector;
      choice.model = a->model;
      choice.threads = a->threads;
      detector = MakeDetector(choice);
      in.detector = detector.get();
      in.detector_name = a->detector + ":" + (a->model.empty() ? DefaultDetectorModel(a->detector).string() : a->model);
    }
    std::unique_ptr<Counter> counter;
    if (a->counter != "blob") {
      CounterChoice choice;
      choice.method = a->counter;
      choice.model = a->counter_model;
      choice.threads = a->threads;
      counter = MakeCounter(choice);
      in.counter = counter.get();
    }
    in.counter_name = a->counter + (a->counter_model.empty() ? "" : ":" + a->counter_model);
    const SideSummary s = RunSide(in, a->options);
    std::printf("count %d (single-frame sum %d), %d clusters kept, %d removed, %d frames -> %s\n", s.count,
                s.single_frame_sum, s.clusters_kept, s.clusters_removed, s.frames_used, a->out.c_str());
  });
}

}  // namespace orchard
