// `orchard synth`: a synthetic apple-tree row filmed from both sides, with
// complete ground truth (see docs/synth.md).
#include <cstdio>
#include <memory>

#include <CLI/CLI.hpp>

#include "orchard/cli/commands.h"
#include "orchard/synth/synth.h"

namespace orchard {

void AddSynthCommand(CLI::App& app) {
  auto options = std::make_shared<synth::SynthOptions>();
  auto out = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "Generate a synthetic orchard row filmed from both sides, with complete ground truth");
  synth::SynthOptions& o = *options;
  cmd->add_option("--out", *out, "Output folder")->required();
  cmd->add_option("--seed", o.seed, "Random seed (same seed and options give identical output)")
      ->capture_default_str();
  // Scene.
  cmd->add_option("--trees", o.scene.num_trees, "Trees in the filmed row")->capture_default_str();
  cmd->add_option("--tree-spacing", o.scene.tree_spacing, "Distance between trunks (m)")->capture_default_str();
  cmd->add_option("--canopy", o.scene.canopy_shape, "Canopy shape: planar or round")->capture_default_str();
  cmd->add_option("--canopy-base", o.scene.canopy_base, "Lowest foliage (m)")->capture_default_str();
  cmd->add_option("--canopy-top", o.scene.canopy_top, "Top of the canopy (m)")->capture_default_str();
  cmd->add_option("--canopy-thickness", o.scene.canopy_thickness, "Canopy thickness across the row (m)")
      ->capture_default_str();
  cmd->add_option("--apples-per-tree", o.scene.apples_per_tree, "Mean apples per tree")->capture_default_str();
  cmd->add_option("--deep-fraction", o.scene.deep_fraction, "Fraction of clusters deep inside the canopy")
      ->capture_default_str();
  cmd->add_option("--apple-radius-min", o.scene.apple_radius_min, "Smallest apple radius (m)")->capture_default_str();
  cmd->add_option("--apple-radius-max", o.scene.apple_radius_max, "Largest apple radius (m)")->capture_default_str();
  cmd->add_option("--variety", o.scene.variety, "red, green, yellow, blush or mixed (one per tree)")
      ->capture_default_str();
  cmd->add_option("--fallen-fraction", o.scene.fallen_fraction, "Fallen apples per apple on the trees")
      ->capture_default_str();
  cmd->add_option("--leaf-density", o.scene.leaf_density, "Leaf count multiplier")->capture_default_str();
  cmd->add_option("--leaf-length", o.scene.leaf_length, "Leaf length (m)")->capture_default_str();
  cmd->add_option("--yellow-leaves", o.scene.yellow_leaf_fraction, "Fraction of yellowing leaves (late season)")
      ->capture_default_str();
  cmd->add_option("--row-spacing", o.scene.row_spacing, "Distance between rows (m)")->capture_default_str();
  cmd->add_flag("!--no-background-rows", o.scene.background_rows, "Leave out the neighbouring rows");
  cmd->add_option("--sun-elevation", o.scene.sun_elevation_deg, "Sun elevation (degrees)")->capture_default_str();
  cmd->add_option("--sun-azimuth", o.scene.sun_azimuth_deg,
                  "Sun azimuth from -y towards +x (degrees; 0 = sun on the front side)")
      ->capture_default_str();
  // Camera.
  cmd->add_option("--sides", o.camera.sides, "both, front or back")->capture_default_str();
  cmd->add_option("--distance", o.camera.distance, "Camera distance from the row centre (m)")->capture_default_str();
  cmd->add_option("--camera-height", o.camera.height, "Camera height (m)")->capture_default_str();
  cmd->add_option("--pitch", o.camera.pitch_deg, "Camera pitch (degrees, negative looks down)")
      ->capture_default_str();
  cmd->add_option("--fov", o.camera.hfov_deg, "Horizontal field of view (degrees)")->capture_default_str();
  cmd->add_option("--width", o.camera.width, "Image width (pixels)")->capture_default_str();
  cmd->add_option("--height", o.camera.height_px, "Image height (pixels)")->capture_default_str();
  cmd->add_option("--speed", o.camera.speed, "Camera speed along the row (m/s)")->capture_default_str();
  cmd->add_option("--fps", o.camera.fps, "Frames per second (frame step = speed / fps)")->capture_default_str();
  cmd->add_option("--jitter", o.camera.jitter_m, "Camera position shake (m, standard deviation)")
      ->capture_default_str();
  cmd->add_option("--jitter-deg", o.camera.jitter_deg, "Camera orientation shake (degrees, sd)")
      ->capture_default_str();
  // Rendering.
  cmd->add_option("--noise", o.render.noise_sigma, "Sensor noise (8-bit levels, sd)")->capture_default_str();
  cmd->add_option("--motion-blur", o.render.motion_blur_px, "Horizontal motion blur (pixels)")->capture_default_str();
  cmd->add_option("--lens-blur", o.render.lens_blur_sigma, "Optical blur (Gaussian sigma, pixels)")
      ->capture_default_str();
  cmd->add_option("--exposure", o.render.exposure, "Exposure multiplier")->capture_default_str();
  // Ground truth.
  cmd->add_option("--min-visible-pixels", o.min_visible_pixels,
                  "Unoccluded pixels for an apple to count as seen in a frame")
      ->capture_default_str();
  cmd->add_option("--patch-every", o.patch_every, "Cut counting patches from every n-th frame (0 = none)")
      ->capture_default_str();
  cmd->add_option("--patch-margin", o.patch_margin, "Patch margin (fraction of the group's size)")
      ->capture_default_str();
  cmd->add_option("--background-patches", o.background_patches, "Background patches per patch frame")
      ->capture_default_str();
  cmd->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
  cmd->add_flag("!--quiet", o.progress, "No progress on stderr");
  cmd->callback([options, out]() {
    const synth::SynthSummary s = synth::RunSynth(*options, *out);
    std::printf("harvested %d, visible front %d, back %d, any %d, both %d, fallen %d; %d frames per side -> %s\n",
                s.harvested, s.visible_front, s.visible_back, s.visible_any, s.visible_both, s.fallen,
                s.frames_per_side, out->c_str());
  });
}

}  // namespace orchard
