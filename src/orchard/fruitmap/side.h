// One side of a row in 3D: frames -> poses (COLMAP or given) -> per-frame
// fruit blobs and counts (cached) -> fruit points -> 3D clusters -> each
// cluster counted once from its best views -> fallen apples and the next row
// removed -> side.json, clusters.csv, fruit.ply and annotated frames.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "orchard/count/counter.h"
#include "orchard/detect/detector.h"
#include "orchard/fruitmap/clusters.h"
#include "orchard/fruitmap/edge_apples.h"
#include "orchard/fruitmap/glimpsed_apples.h"
#include "orchard/fruitmap/glimpsed_apples.h"
#include "orchard/fruitmap/fruit_points.h"
#include "orchard/sfm/camera_view.h"
#include "orchard/sfm/colmap_runner.h"
#include "orchard/sfm/frame_reach.h"
#include "orchard/sfm/frame_selection.h"
#include "orchard/sfm/ground_plane.h"
#include "orchard/sfm/reconstruction_check.h"

namespace orchard {

namespace fs = std::filesystem;

// What a side does with frames much denser than the 3D stage is tuned to
// (SideOptions::dense_frames).
enum class DenseFrames { kScale, kThin, kAll };
// What the side does with frames much sparser than the 3D stage is tuned to
// (SideOptions::sparse_frames).
enum class SparseFrames { kScale, kKeep };

struct ClusterOptions {
  FruitPointOptions points;
  // Fruit points closer than this (m) belong to one cluster: a bit more than
  // an apple's radius, so the points of one apple join while apples a hand
  // apart stay separate (touching apples form one cluster; the count from
  // its views says how many). 6.5 cm since the circle-fitted centres: on 22
  // rows 6 cm counted 0.9% high on average, 7 cm 1.2% low (docs/side.md).
  double link_distance = 0.065;
  // Fewest fruit points for a cluster. Every point has passed the support
  // check already; 2 drops chance pairings but also heavily occluded apples
  // (on the development row 1 gave the count closest to the truth).
  int min_points = 1;
  // Fewest frames in which a cluster wins a blob (is the cluster with most
  // points on it): a real apple is seen in many frames, a chance pairing of
  // different apples' blobs wins one or two.
  int min_views = 3;
  // Clusters whose points land mostly (more than this fraction of their
  // point-on-blob votes) on blobs that other clusters win are ghosts of
  // those clusters' apples: wrong pairings offset in depth (1 = keep all).
  double max_lost_fraction = 1.0;
  // Clusters whose largest blob shows an apple smaller than this fraction of
  // `points.apple_radius` at the cluster's depth are chance pairings of blobs
  // of the next row's apples (half as large in the image) or of small pieces
  // of partly hidden ones, placed in the filmed row. On 40 development sides
  // (exact masks) 74 of the 77 kept clusters that won mostly next-row blobs
  // showed less than 2 cm, and 47 of 6,644 clusters holding an apple
  // (docs/side.md). 0 = keep all; -1 (auto): 0.6 for instance masks, 0.5
  // for a detector's blobs (RunSide decides, ResolvedMinAppleFraction;
  // CountFruitClusters takes auto as 0.5). The next row's apples
  // seen through gaps in the leaves still showed 0.50-0.64 (a chance pairing
  // of them placed in the filmed row, fresh seed 530's front); with instance
  // masks, each blob one apple's visible part, 0.6 removed on 38 rows 33 of
  // the 56 clusters on no visible apple and 78 of the 329 apples counted
  // twice for 73 more missed: sides within 3% 71 -> 73 of 76, rows within 2%
  // 31 -> 33 of 38. With the U-Net's blobs it took the sides' mean from
  // -7.5% to -8.8% (14 rows; docs/side.md, forty-sixth session).
  double min_apple_fraction = -1;
  // Clusters whose points land on the same blobs are one apple triangulated
  // twice: the centre of a partly hidden apple's visible piece shifts as the
  // leaves in front of it change, which moves a short-baseline pairing
  // 10-30 cm in depth. A cluster with at least this fraction of its
  // point-on-blob votes on blobs that a cluster with more votes also votes
  // for joins that cluster (0 = never).
  double merge_shared_fraction = 0;
  // An apple triangulated twice shows as a small cluster that wins the
  // apple's blob in a few frames and its partner (the cluster it shares most
  // votes with, among those with more votes) in the others: the two rarely
  // win blobs in the same frame, while two neighbouring apples that share
  // votes both win their own blobs in most frames they are seen in. A
  // cluster with at least duplicate_shared_fraction of its votes on blobs
  // its partner also votes for, which wins blobs in the same frame as its
  // partner in fewer than duplicate_coview_fraction of the frames where it
  // wins any, joins the partner (0 = never). On 56 development sides (exact
  // masks, true poses) 0.5 and 0.4 took the apples counted twice from 313
  // to 218 and the missed ones from 498 to 488; the side count's sd fell
  // from 1.79 to 1.54 points (docs/side.md, twenty-fourth session).
  double duplicate_shared_fraction = 0.5;
  double duplicate_coview_fraction = 0.4;
  // ... and whose centre lies within this (m) of the partner's: a short-
  // baseline pairing moves an apple 10-30 cm in depth, while a chance
  // pairing far off may share a few blobs with any cluster.
  double duplicate_max_distance = 0.5;
  // A cluster of at most covered_max_points fruit points, in at least
  // covered_fraction of whose views a point of one kept cluster with more
  // points lands within an apple radius (points.apple_radius at that point's
  // depth) of one of its blobs' centres, that cluster's centre within
  // duplicate_max_distance, is that cluster's apple triangulated again (a
  // second track of a partly hidden apple, or one apple of a cluster of
  // several whose points fell apart): it is removed as `covered` (0 =
  // never). The apples counted twice that the duplicate join leaves are
  // such clusters of 1-7 points 0.1-0.5 m from the cluster holding the
  // apple; their points vote for blobs the other cluster's points do not.
  // Off: at 7 and 0.7, on 70 development rows (exact masks) it took the
  // apples counted twice from 566 to 466 for 21 more missed, which left
  // the sides' mean at -0.13% (from +0.27%) and 137 of 140 within 3%
  // (from 138), the rows 60 of 70 within 2% (from 61; MAE 1.14 -> 1.08%)
  // (docs/side.md, fiftieth session).
  int covered_max_points = 0;
  double covered_fraction = 0.7;
  // Find each cluster's cover (FruitCluster::cover_id) even with the rule
  // off; RunSide sets it when scoring against the truth.
  bool find_covers = false;
  // A point votes for the blob whose centre it is near (as in the support
  // check) before the blob under it: a partly hidden apple's centre often
  // lies on the apple in front of it, and voting for that blob left the
  // hidden apple's own piece unclaimed, so clusters of touching apples
  // counted one short (40 sides with exact masks: apples in clusters counted
  // short 216 -> 187, clusters counted above what they hold +144 -> +88;
  // docs/side.md).
  bool vote_near_first = true;
  // A point that is near no blob centre votes for the blob under it, or else
  // (when true, and the point lies on no blob) for the blob whose centre it is near.
  bool assign_near = true;
  // The cluster count is the median over this many best views.
  int best_views = 3;
  // Which views are best. kPixels: the most fruit pixels in the cluster's
  // region (the study's rule). kCount: the highest counts. With instance
  // masks and one apple per blob a view's count is the number of the
  // cluster's apples it shows, and a cluster of touching apples is counted
  // best where most of them show: by pixels it counted short wherever its
  // biggest views hide one (40 development sides: within 3% 33 -> 34, MAE
  // 2.06 -> 1.48%; 10 unseen sides: 6 -> 8, MAE 2.16 -> 2.20%; docs/side.md). A counter's counts are estimates, and the highest
  // of many estimates is too high (default pipeline: +23% on 18 rows).
  // kAuto: kCount when every blob is one apple (instance masks, a box
  // detector's boxes: no counter), else kPixels
  // (RunSide decides; CountFruitClusters takes kAuto as kPixels).
  enum class BestViews { kAuto, kPixels, kCount };
  BestViews best_views_by = BestViews::kAuto;
  // Clusters whose centre is less than this (m) above the ground are fallen apples.
  double fallen_height = 0.3;
  // Distance from the camera path to the filmed row's fruit (m); 0 = found
  // by RowFruitDistance: the 25 cm band with the most fruit pixels (each
  // kept cluster weighted by its largest view's) in the nearest stretch of
  // fruit holding at least row_min_share of the fullest stretch's pixels.
  // Stretches are split by an aisle (next_row_gap and next_row_sparse
  // below). Filming one tree, the next row fills the frame behind it: its
  // densest band won on 6 of 12 sides, and on 4 its stretch held more
  // pixels than the tree's (the tree's 0.70-0.91 of it; seed 5's front
  // counted 188 for 52 visible). Chance pairings in front of the row held
  // 0.33 of the row's (U-Net blobs, flat green seed 295): 0.5 lies between.
  // 81 four-tree rows count as with the densest band (docs/side.md). Near
  // the camera a chance pairing's blobs show many pixels for few apples
  // (fresh flat seed 497's back: 21 apples 0.4-1.3 m away held 0.55 of the
  // row's pixels; 27 counted for 256 visible), so a stretch must also hold
  // row_min_apple_share of the most apples any stretch holds: those 21 were
  // 0.12 of the row's, one tree's apples 0.21-0.23 of the next row's (exact
  // masks, seed 5, the dense-frames test); 0.15 lies between.
  double row_distance = 0;
  double row_min_share = 0.5;
  double row_min_apple_share = 0.15;
  // Where the next row begins. Binned by distance (25 cm) behind the row
  // distance, the fruit points of the clusters that pass the evidence checks
  // show the filmed row, then an empty aisle, then the next row: on 46
  // development sides (40 fruit walls, 6 round canopies) the row's fruit
  // ended 0.5-2.0 m behind the row distance and a gap of 1.5 m or more
  // followed. The cut lies in the middle of the first run of at least this
  // many metres (from the row distance on) whose bins each hold at most
  // next_row_sparse of the fullest bin's points; a run with no fruit behind
  // it ends half this length after it starts. 0 = always the fixed margin.
  double next_row_gap = 1.0;
  double next_row_sparse = 0.01;
  // Without such a gap, clusters farther from the camera path than the row
  // distance plus this (m) belong to the next row (the canopy thickness,
  // 1.2 m for the default synthetic row, plus a margin).
  double next_row_margin = 1.5;
  // Clusters nearer than the row distance minus this (m) float between the
  // camera and the row: wrong pairings, removed. On 40 development sides
  // (exact masks) no kept cluster more than 0.4 m in front held an apple,
  // nor more than 0.6 m on three round-canopy rows; those between 0.6 and
  // 1.0 m counted 65 chance apples (1.0 before: within 3% 34 -> 38 of 40,
  // MAE 1.48 -> 1.30%; docs/side.md).
  double near_margin = 0.6;
  // Apples seen only as slivers at the frames' top edge (edge_apples.h): each
  // is one more kept cluster of one apple, marked `edge`.
  EdgeAppleOptions edge;
  // Apples glimpsed through the leaves (glimpsed_apples.h): each is one more
  // kept cluster of one apple, marked `glimpsed`.
  GlimpsedAppleOptions glimpsed;
  // The frame counts above (partners, support window and support, views,
  // points, best views, the edge and glimpse windows and support) are tuned
  // to frames about 0.057 row distances apart; frames k times denser are
  // counted with them made k times larger (1: as given; k < 1: sparser;
  // SideOptions::dense_frames and sparse_frames set it from the spacing).
  // ScaledToFrameDensity applies it.
  double frame_scale = 1;
  void Check() const;
};

struct FruitCluster {
  int id = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
  std::vector<int> points;       // indices into the fruit points
  std::vector<ClusterView> views;  // frames where it is assigned blobs
  std::vector<std::vector<int>> view_blobs;  // blob ids per view (same order as views)
  std::vector<int> count_frames;  // the best views the count came from
  // Point-on-blob votes for blobs this cluster won, and for blobs another
  // cluster won.
  int votes_won = 0, votes_lost = 0;
  // The cluster with more points whose points land within an apple radius
  // of this cluster's blobs' centres in the most of its views (id, 0: none),
  // in how many of them, and how far its centre lies from this one's (m)
  // (ClusterOptions::covered_fraction).
  int cover_id = 0, cover_views = 0;
  double cover_distance = 0;
  // EquivalentRadius of its largest blob, in scene units at the cluster
  // centre's depth in that frame.
  double apple_radius_seen = 0;
  int count = 0;
  // The count under each best-views rule (ClusterOptions::BestViews; count is
  // the one the options chose): the merge counts a cluster the other side
  // does not link by the side's own rule (YieldOptions::unlinked_by_sides_rule).
  int count_by_pixels = 0, count_by_count = 0;
  double height = 0;    // centre above the ground (m)
  double distance = 0;  // centre from the camera path, across the row (m)
  // kept, too_few_points, no_views, few_views, ghost, small, fallen, next_row, too_near, covered
  std::string status = "kept";
  // Seen only as slivers at the frames' top edge (EdgeAppleOptions): one
  // apple, its points the slivers' rays at its distance.
  bool edge = false;
  // Seen only as small pieces in scattered frames (GlimpsedAppleOptions): one
  // apple, its points the pieces' rays at its distance.
  bool glimpsed = false;
  // An edge apple's sightings: each sliver's ray through the row's fruit
  // (EdgeAppleOptions' margins about the row distance), near end first. The
  // merge links it along these (side output edge_rays.csv).
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edge_rays;
  std::vector<double> edge_columns;  // each sliver's middle (COLMAP pixel x), as the views
};

struct ClusterResult {
  // The triangulated fruit points, then (from triangulated_points on) the
  // edge apples' points, one per sliver.
  std::vector<FruitPoint> points;
  int triangulated_points = 0;
  std::vector<int> point_cluster;  // cluster index of each point
  std::vector<FruitCluster> clusters;
  double row_distance = 0;
  double depth_cutoff = 0;
  bool depth_cutoff_from_gap = false;  // false: row distance + next_row_margin
  // The side's row frame in the poses' frame: origin = mean camera centre
  // dropped onto the ground, x along the camera path, y across it towards the
  // filmed row, z up (the ground normal). The two sides' merge works in it.
  Eigen::Vector3d row_origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d row_along = Eigen::Vector3d::UnitX(), row_across = Eigen::Vector3d::UnitY(),
                  row_up = Eigen::Vector3d::UnitZ();
  int count = 0;            // sum over kept clusters
  int single_frame_sum = 0; // sum of all blob counts over all frames
  int duplicates_joined = 0;  // components joined to a partner (ClusterOptions::duplicate_shared_fraction)
  int edge_apples = 0;        // kept clusters seen only at the frames' top edge (FruitCluster::edge)
  int glimpsed_apples = 0;    // kept clusters seen only as pieces through the leaves (FruitCluster::glimpsed)
};

// The next-row cut (ClusterOptions::next_row_gap) from the distances of
// fruit points from the camera path: the middle of the first sparse run of
// at least `gap` m behind the row distance; nothing when there is none.
std::optional<double> NextRowGapCut(const std::vector<double>& point_distances, double row_distance, double gap,
                                    double sparse_fraction);

// A kept cluster as RowFruitDistance sees it: its distance from the camera
// path, its largest view's fruit pixels and its apples.
struct RowFruit {
  double distance = 0;
  double pixels = 0;
  double apples = 0;
};

// The filmed row's distance from the camera path (ClusterOptions::
// row_distance) from the kept clusters; 0 when none.
double RowFruitDistance(const std::vector<RowFruit>& fruit, double gap, double sparse_fraction, double min_share,
                        double min_apple_share);

// "kept", or why the cluster's own evidence (points, views, votes; not its
// place in the row) is too weak: too_few_points, no_views, few_views, ghost.
std::string EvidenceStatus(const FruitCluster& cluster, const ClusterOptions& options);

// Point-on-blob votes of one frame: blob id -> cluster (or component) -> points.
using BlobVotes = std::map<int, std::map<int, int>>;

// Joins the components (0..k-1) that are one apple triangulated twice: a
// component with at least `fraction` of its votes on blobs that a component
// with more votes also votes for joins the one it shares most with (chains
// join too). Returns each component's representative: the smallest
// component of its group.
std::vector<int> MergeSharedComponents(const std::vector<BlobVotes>& votes, int k, double fraction);

// Joins the components that are one apple triangulated twice by the rule of
// ClusterOptions::duplicate_shared_fraction: won_frames[c] are the frames
// in which component c wins a blob, centres[c] its centre. Returns
// representatives as above.
std::vector<int> MergeDuplicateComponents(const std::vector<BlobVotes>& votes,
                                          const std::vector<std::vector<int>>& won_frames,
                                          const std::vector<Eigen::Vector3d>& centres, double fraction,
                                          double max_coview_fraction, double max_distance);

// The 3D stage on frames with known (metric) poses and a ground plane.
ClusterResult CountFruitClusters(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                                 const Plane& ground, const ClusterOptions& options);
// The same on fruit points already triangulated (options.points is not used),
// to count one set of points under other cluster rules.
ClusterResult CountFruitClusters(const std::vector<CameraView>& views, const std::vector<FruitFrame>& frames,
                                 const Plane& ground, const ClusterOptions& options, std::vector<FruitPoint> points);

// A ground plane given as "nx,ny,nz,d" or as a json file with
// {"ground_plane": {"normal": [..], "d": ..}} (the generator's scene.json).
Plane ParseGroundPlane(const std::string& text_or_file);

struct SideOptions {
  FrameSelectionOptions frames;
  ColmapRunnerOptions colmap;
  GroundPlaneOptions ground;
  // Signs of a broken reconstruction, reported as warnings (side.json).
  ReconstructionCheckOptions reconstruction_check;
  // When more fruit points than the check allows lie below a fitted ground
  // plane, fit it again with each fruit point below a candidate costing one
  // inlier, rescale and count again; the refit is kept when less fruit lies
  // below it (a plane tilted about the path or on the canopy's lower edge).
  bool refit_ground_below_fruit = true;
  // ... and only when it changes the scale by at most this factor either way:
  // the refits that mended seeds 11 and 12 changed it 0.54x and 0.98x, while on
  // a model COLMAP folded (seed 268's back, 29 of 41 frames) a plane through
  // the cameras changed it 180x.
  double max_refit_scale_change = 3;
  ClusterOptions clusters;
  // Give every frame the centres of circles fitted to its blobs' outlines
  // (FitAppleCentres) for the 3D stage to triangulate instead of the blob
  // centroids: a partly hidden apple's visible pixels are off its centre, its
  // outline is not (exact masks, true poses: clusters holding no apple 717 ->
  // 526 on 44 sides; docs/side.md).
  bool fit_apple_circles = true;
  // Split each blob the counter counts as k >= 2 apples into k pieces of one
  // apple each (SplitCountedBlobs) before the 3D stage, so that every apple
  // of a detector's merged blob gets a fruit point (exact instance masks have
  // no such blobs).
  bool split_counted_blobs = true;
  // Frames closer than ReconstructionCheckOptions::min_frame_spacing times
  // the tuned spacing (k times denser, k the nearest whole ratio, at least
  // 2): kThin counts the side again on every k-th (four fresh rows at 16
  // frames per second counted +3.0% on average with all frames as they
  // were, every 2nd of them -1.2%, like 8 frames per second; docs/side.md,
  // "Frame spacing"); kScale on all of them with the 3D stage's frame counts
  // made k times larger (ClusterOptions::frame_scale): on 22 rows at 16
  // frames per second (exact masks) a quarter fewer missed, duplicate and
  // chance apples, the sides' MAE 1.33 -> 1.08%, 42 against 41 of 44 within
  // 3%, but the rows 20 against 22 of 22 within 2% (MAE 0.86 -> 0.98%;
  // docs/side.md, fifty-second session); kAll counts them as they are.
  DenseFrames dense_frames = DenseFrames::kThin;
  // Frames farther apart than sparse_frames_from times the tuned spacing
  // cannot be thinned: kScale counts the side again with the 3D stage's frame
  // counts made k = (the tuned spacing / theirs) times as large, k < 1
  // (ClusterOptions::frame_scale), but not below min_sparse_frame_scale;
  // kKeep counts them as they are (warned about). Exact masks, true poses,
  // 24 rows filmed at 3-5 frames per second not used to choose the rule:
  // sides within 3% 19 -> 37 of 48 (mean -3.4 -> -0.3%), rows within 2% 18
  // -> 19 of 24. At 1.4 times the spacing (6 per second) the smaller counts
  // took sides 2-4 points high, and below k = 0.6 (the best views' median
  // becomes the best view at k < 0.5) rows at 4 per second 4% high
  // (docs/side.md, "Frames too sparse").
  SparseFrames sparse_frames = SparseFrames::kScale;
  double sparse_frames_from = 1.5;
  double min_sparse_frame_scale = 0.6;
  // Camera height above the ground (m), which fixes the scale of a COLMAP
  // reconstruction (the synthetic rows film from 1.5 m).
  double camera_height = 1.5;
  // Given poses are taken as metric unless this is set.
  bool rescale_given_poses = false;
  // Given poses without 3D points get COLMAP's points triangulated with the
  // poses held (when colmap can be run): the ground fit needs them when no
  // ground plane is given, and the row's trunks (per-tree counts, the
  // distance across the row) always do.
  bool triangulate_given_poses = true;
  // Annotated copies of every n-th frame (0 = none).
  int draw_every = 5;
  // Also count the side under these cluster rules, on the same fruit points
  // (their point options are not used): `orchard yield` keeps stricter
  // clusters for the merge and reports each side's own count under `orchard
  // side`'s rules (SideSummary::one_side_count).
  std::optional<ClusterOptions> one_side_clusters;
  void Check() const;
};

struct SideInputs {
  fs::path input;   // video file or folder of frames
  fs::path out;     // output folder
  fs::path poses;   // COLMAP text model of the frames; empty: run COLMAP
  std::optional<Plane> ground;  // given ground plane (in the poses' frame)
  // Fruit: instance masks (16-bit, id per apple, file stem = frame stem) or a detector.
  fs::path masks;
  Detector* detector = nullptr;
  std::string detector_name = "masks";
  // Apples per blob: a counter, or one per blob when null.
  Counter* counter = nullptr;
  std::string counter_name = "blob";
  // The generator's folder of this side (S/front or S/back: masks/ inside,
  // apples.csv one up): when set, the kept clusters are scored against its
  // apples (ScoreSideAgainstTruth; side.json "truth"). Empty: not scored.
  fs::path truth;
};

// options.best_views_by with kAuto decided for these inputs: kCount when
// blobs are counted one apple each (no counter: instance masks, boxes), else kPixels.
ClusterOptions::BestViews ResolvedBestViews(const ClusterOptions& options, const SideInputs& in);
// options.edge.min_pixels with 0 (auto) decided for these inputs: 20 for
// instance masks, 50 for a detector's blobs (EdgeAppleOptions::min_pixels).
int ResolvedEdgeMinPixels(const ClusterOptions& options, const SideInputs& in);
// options.min_apple_fraction with -1 (auto) decided for these inputs: 0.6 for
// instance masks, 0.5 for a detector's blobs.
double ResolvedMinAppleFraction(const ClusterOptions& options, const SideInputs& in);
// Whether the side looks for apples glimpsed through the leaves:
// glimpsed.enabled, and for a detector's blobs glimpsed.with_detector too.
bool ResolvedGlimpsedApples(const ClusterOptions& options, const SideInputs& in);
// `options` with its frame counts made options.frame_scale = k times larger
// (and frame_scale 1): spans in frames (partners, windows) k times, counts
// of frames over a stretch of the path (support, views, points, the rank of
// the best views' median) n -> k (n - 1) + 1, each rounded to whole frames
// and at least one (k < 1 shrinks them for sparser frames).
ClusterOptions ScaledToFrameDensity(ClusterOptions options);
// "auto", "pixels" or "count", as the command line and the outputs name them.
const char* BestViewsName(ClusterOptions::BestViews best_views);
// Whether a ground refit that takes the scale from `scale` to `refit_scale`
// stays within options.max_refit_scale_change either way.
bool RefitScaleIsPlausible(double scale, double refit_scale, const SideOptions& options);

struct SideSummary {
  int count = 0;
  // The count under SideOptions::one_side_clusters (= count when not set).
  int one_side_count = 0;
  int single_frame_sum = 0;
  int frames_used = 0, frames_registered = 0;
  // Where the poses came from, in words: "given (PATH)", or "COLMAP" with
  // the mapper's runs when it ran more than once (side.json: mapper_attempts).
  std::string poses;
  int clusters_kept = 0, clusters_removed = 0;
  // Wall-clock seconds of the stages (also in side.json): frames and poses,
  // fruit per frame (detection and counting, or the cache), the 3D stage,
  // writing the outputs.
  double poses_s = 0, fruit_s = 0, clusters_s = 0, outputs_s = 0;
  // How high the frames reach at the row's distance (row_distance): apples
  // above `top` are in no frame (side.json frames_reach).
  FrameReach frames_reach;
  std::vector<fs::path> frame_paths;  // the frames used, in sequence order
  std::vector<std::string> warnings;  // as in side.json
};

// Runs the side end to end and writes side.json, clusters.csv, fruit.ply,
// annotated/ frames, and the caches (frames/, sparse/, detections/) into
// inputs.out. Throws orchard::Error with the reason when the input or the
// reconstruction cannot give a count.
SideSummary RunSide(const SideInputs& inputs, const SideOptions& options);

}  // namespace orchard
