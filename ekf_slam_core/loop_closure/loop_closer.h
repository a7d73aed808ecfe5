// Loop-closing back end: a pose graph over key scans, fed with the front
// end's poses (the scan-matched odometry) and closed by matching the newest
// key scan against old ones.
//
// - Key scans: a scan becomes a key scan after keyscan_distance of travel or
//   keyscan_angle of turn; its points are kept in the robot frame.
// - Sequential edges join consecutive key scans with the front end's
//   relative motion; its covariance grows with the motion (a random walk:
//   variance linear in the distance and the turn, with a per-step floor).
// - Loop candidates: old key scans whose graph distance to the new one (the
//   shortest path through the graph, counting the travel along sequential
//   edges and nothing across loop edges) is at least min_loop_travel and
//   whose position lies within a search window of a few standard
//   deviations of the chain that links them. The window grows without a
//   practical bound with the distance (d^1.5): after a long loop it covers
//   the whole map, so a loop is found however far the front end drifted.
// - Verification: the new key scan (with the recent ones, query_keys) is
//   searched exhaustively (correlative, multi-level branch and bound) over
//   the whole window and any heading it allows against a submap of the
//   candidate and its neighbours, then refined by point-to-line ICP. The
//   LMS200 sees 180°: a place revisited the other way round shares little
//   with the candidate's own view, but what it sees the key scans before
//   the candidate saw ahead of them, so there the submap reaches back along
//   the candidate's path over the readings' reach (loopSubmapKeys). A loop
//   is accepted only when the correlative score, the ICP inlier fraction and
//   the residual are strong, the match constrains every direction (no
//   sliding along a corridor), and along its weakest direction it explains
//   the query's own structure there (a view down one corridor, whose end
//   wall the old view never saw, is not taken for a view along another).
// - Optimisation after each accepted loop; the loop edges carry a Cauchy
//   kernel. A new loop enters at full weight (the scan evidence passed),
//   and is judged by the kernel against the later ones; at the end loops
//   whose weight fell below min_final_weight are dropped.
// - Every scan's pose is its key scan's optimised pose composed with the
//   front end's increment since that key scan.
#pragma once

#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "ekf_slam_core/geometry/option_fields.h"
#include "ekf_slam_core/geometry/stamped_pose.h"
#include "ekf_slam_core/loop_closure/correlative_matcher.h"
#include "ekf_slam_core/pose_graph/pose_graph.h"
#include "ekf_slam_core/scan_matching/scan_matcher.h"
#include "ekf_slam_core/sensors/scan.h"

namespace ekf_slam {

struct LoopClosureOptions {
  // false: the pipeline runs no back end (a LoopCloser built disabled keeps
  // its key scans but searches no loop).
  bool enabled = true;
  double keyscan_distance = 0.4;  // m of front-end travel between key scans …
  double keyscan_angle = 0.35;    // rad … or this much turn (20 deg)
  double max_range = 15.0;        // m: farther readings are not kept in key scans
  // Sequential edge noise (1 sigma), a random walk in the motion:
  double step_sigma_translation = 0.01;            // m per key step (floor)
  double translation_sigma_per_sqrt_metre = 0.03;  // m per √m driven
  double step_sigma_rotation = 0.003;              // rad per key step (floor)
  double rotation_sigma_per_sqrt_metre = 0.01;     // rad per √m driven
  double rotation_sigma_per_sqrt_radian = 0.02;    // rad per √rad turned
  // Candidates: old key scans at least min_loop_travel of graph distance
  // away whose estimated position lies inside the search window. The window
  // is search_sigmas standard deviations of the relative pose predicted by
  // the chain that links the two (the sequential-edge random walk above:
  // the heading error integrates into a position error growing as d^1.5),
  // so it grows without bound with the graph distance d and a loop is found
  // however far the front end drifted; search_radius_max only bounds the
  // cost. The heading window likewise (at most a full turn).
  double min_loop_travel = 8.0;         // m of graph distance before a key scan may close a loop
  double search_sigmas = 3.0;           // window half-width in standard deviations
  double search_radius_min = 0.5;       // m: window floor
  double search_radius_max = 1000.0;    // m: window ceiling
  double search_angle_min = 0.1;        // rad, heading window floor
  double max_heading_difference = kPi;  // rad between the two key scans' estimated headings
  // Places verified per key scan, most likely first; the first that passes
  // is taken. Once the drift exceeds the spacing of look-alike places the
  // likeliest one is often not the right one, and the next ones are tried:
  // the uniqueness test below keeps a look-alike from passing.
  int max_candidates = 5;
  int submap_half_width = 5;  // key scans each side of the candidate in its submap
  // A place revisited the other way round (the candidate's heading and the
  // query's more than 90° apart): the query sees what the key scans before
  // the candidate saw ahead of them, not what the candidate saw, so its
  // submap also reaches back along the candidate's own path over this much
  // travel, about the readings' reach (max_range). 0: the usual submap.
  double reverse_submap_travel = 15.0;  // m
  int query_keys = 0;      // recent key scans merged into the query (0: the key scan alone)
  int retry_interval = 3;  // key scans to wait after a refused candidate
  // Memory over long runs. A key scan taken where max_keyscans_per_place
  // earlier key scans that hold readings already lie (within place_radius
  // and place_angle of its pose, after the loop search it triggered) keeps
  // its graph node but lets its readings go: a robot that drives the same
  // corridors for hours keeps the building's views, not every pass (one
  // pass puts about 3 key scans in a place at 0.4 m spacing). Key scans
  // without readings are never loop candidates (0: keep every one).
  int max_keyscans_per_place = 8;
  double place_radius = 1.0;  // m
  double place_angle = 0.5;   // rad (29 deg): the LMS200 sees the forward half
  // Confirmation. A loop found in a window wider than confirm_radius (the
  // graph cannot yet tell a true match from a look-alike place) is held as
  // a hypothesis. Each following key scan is then matched, in the smallest
  // window, where the hypothesis puts it against the old key scans; the
  // first such match confirms it and both loops enter the graph. No match
  // within confirm_keys key scans: the hypothesis is discarded.
  double confirm_radius = 1.0;  // m (a huge value: every loop enters at once)
  int confirm_keys = 10;        // key scans
  // Verification:
  CorrelativeMatcherOptions correlative;
  double search_point_spacing = 0.15;  // m: key-scan points thinned for the correlative search
  double min_score = 0.55;             // mean likelihood of the correlative match
  // Of the key scan's points paired by ICP: a place seen again an hour
  // later outdoors (parked cars, people) or the other way round (the far
  // sides of free-standing things) keeps fewer of its points than one seen
  // again indoors a minute on.
  double min_inlier_fraction = 0.6;
  double max_rms_residual = 0.04;      // m, ICP point-to-line
  double max_degenerate_sigma = 0.03;  // m: 1-sigma of the match along its weakest direction
  // Of the query's own structure along that weakest direction (its points
  // weighted by the square of their normal's component along it), the share
  // the match pairs with the submap.
  double min_directional_inlier_fraction = 0.5;
  double max_icp_shift = 0.3;  // m: ICP may move the correlative result this far
  // Uniqueness: the best pose of the search window at another place (more
  // than distinct_radius from the match) must score below
  // max_runner_up_ratio of the match's score, else the place is ambiguous
  // (doors repeating along a corridor, rooms alike) and the loop refused
  // (1: no test).
  double distinct_radius = 1.0;      // m
  double max_runner_up_ratio = 0.9;  // of the match's correlative score
  // Loop edge noise (1 sigma) and optimisation:
  double loop_sigma_translation = 0.05;  // m
  double loop_sigma_rotation = 0.01;     // rad
  double min_final_weight = 0.1;  // loops the kernel weighs below this are dropped at the end
  // Consistency test of a new loop against the graph: the rise of the
  // graph's optimised cost when the loop is added (for Gaussian errors, the
  // loop's squared Mahalanobis distance from what the chain of sequential
  // edges and the earlier loops predict) must stay below this χ²₃
  // quantile, else the loop is refused and the graph restored. A false loop
  // then never bends the map, whatever its scan score (0: no test).
  double consistency_probability = 0.9999999;  // χ²₃ quantile about 36
  // Heading loops. A key scan whose walls run in one direction modulo 90°
  // (wallDirection below: at least heading_min_normals wall normals,
  // concentrated to at least heading_min_concentration) carries that
  // direction α in its own frame. When an earlier such key scan lies
  // within heading_radius of its estimated position (the key scans'
  // reading range: closer than that, both can see the same walls) and at
  // least min_loop_travel of graph distance away, their walls are taken
  // to run the same way, as a place's do on a return: a heading-only edge says
  // θ_new + α_new = θ_old + α_old modulo 90°, with the quarter turn nearest
  // the graph's estimate, σ = √2 heading_sigma, Cauchy kernel. It is taken
  // when the estimate's disagreement lies within the loop search's heading
  // window for that graph distance (widened by the two directions' noise),
  // and never when that window reaches 45° (the quarter turn would be a
  // guess). The scans need not match, so the heading of a return seen from
  // the other direction closes too; of the building nothing is assumed but
  // that the walls of one place are parallel or perpendicular. The graph is
  // re-optimised after every heading_reoptimise such edges. 0 radius: off.
  double heading_radius = 15.0;            // m
  double heading_min_concentration = 0.8;  // of the normals' angles times 4 (1: all parallel)
  int heading_min_normals = 40;
  double heading_sigma = 0.05;  // rad: one key scan's wall direction (1 sigma)
  int heading_reoptimise = 10;
  // In the pipeline: after each optimisation the EKF takes the loop-closed
  // geometry (robot and landmarks move with their key scans).
  bool reanchor_filter = true;
  // When a correction of the back end takes effect, in scans (back_end.h):
  // -1, as soon as the back end has it (a live node never waits for it;
  // offline, at the scan that triggered it); d >= 0, at the d-th scan
  // after the one that triggered it, the same live and offline.
  int correction_delay = -1;
  PoseGraphOptions optimizer;

  template <class Visitor>
  void visitFields(Visitor& v) {
    v.flag("enabled", enabled);
    v.number("keyscan_distance", keyscan_distance, Bounds::above(0.0, "m"));
    v.number("keyscan_angle", keyscan_angle, Bounds::openClosed(0.0, 2.0 * kPi, "rad"));
    v.number("max_range", max_range, Bounds::above(0.0, "m"));
    v.number("step_sigma_translation", step_sigma_translation, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("translation_sigma_per_sqrt_metre", translation_sigma_per_sqrt_metre,
             Bounds::closed(0.0, 10.0, "m/√m"));
    v.number("step_sigma_rotation", step_sigma_rotation, Bounds::openClosed(0.0, kPi, "rad"));
    v.number("rotation_sigma_per_sqrt_metre", rotation_sigma_per_sqrt_metre,
             Bounds::closed(0.0, kPi, "rad/√m"));
    v.number("rotation_sigma_per_sqrt_radian", rotation_sigma_per_sqrt_radian,
             Bounds::closed(0.0, kPi, "rad/√rad"));
    v.number("min_loop_travel", min_loop_travel, Bounds::atLeast(0.0, "m"));
    v.number("search_sigmas", search_sigmas, Bounds::openClosed(0.0, 100.0, "sigmas"));
    v.number("search_radius_min", search_radius_min, Bounds::openClosed(0.0, 1e5, "m"));
    v.number("search_radius_max", search_radius_max, Bounds::openClosed(0.0, 1e5, "m"));
    v.number("search_angle_min", search_angle_min, Bounds::openClosed(0.0, kPi, "rad"));
    v.number("max_heading_difference", max_heading_difference, Bounds::openClosed(0.0, kPi, "rad"));
    v.integer("max_candidates", max_candidates, Bounds::closed(1, 1000));
    v.integer("submap_half_width", submap_half_width, Bounds::closed(0, 1000, "key scans"));
    v.number("reverse_submap_travel", reverse_submap_travel, Bounds::closed(0.0, 1000.0, "m"));
    v.integer("query_keys", query_keys, Bounds::closed(0, 1000, "key scans"));
    v.integer("retry_interval", retry_interval, Bounds::closed(0, 100000, "key scans"));
    v.integer("max_keyscans_per_place", max_keyscans_per_place,
              Bounds::closed(0, 100000, "key scans"));
    v.number("place_radius", place_radius, Bounds::openClosed(0.0, 1000.0, "m"));
    v.number("place_angle", place_angle, Bounds::openClosed(0.0, kPi, "rad"));
    v.number("confirm_radius", confirm_radius, Bounds::openClosed(0.0, 1e9, "m"));
    v.integer("confirm_keys", confirm_keys, Bounds::closed(1, 100000, "key scans"));
    v.section("correlative", correlative);
    v.number("search_point_spacing", search_point_spacing, Bounds::closed(0.0, 10.0, "m"));
    v.number("min_score", min_score, Bounds::openClosed(0.0, 1.0));
    v.number("min_inlier_fraction", min_inlier_fraction, Bounds::closed(0.0, 1.0));
    v.number("max_rms_residual", max_rms_residual, Bounds::openClosed(0.0, 10.0, "m"));
    v.number("max_degenerate_sigma", max_degenerate_sigma, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("min_directional_inlier_fraction", min_directional_inlier_fraction,
             Bounds::closed(0.0, 1.0));
    v.number("max_icp_shift", max_icp_shift, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("distinct_radius", distinct_radius, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("max_runner_up_ratio", max_runner_up_ratio, Bounds::openClosed(0.0, 1.0));
    v.number("loop_sigma_translation", loop_sigma_translation, Bounds::openClosed(0.0, 100.0, "m"));
    v.number("loop_sigma_rotation", loop_sigma_rotation, Bounds::openClosed(0.0, kPi, "rad"));
    v.number("min_final_weight", min_final_weight, Bounds::closed(0.0, 1.0));
    v.number("consistency_probability", consistency_probability, Bounds::closedOpen(0.0, 1.0));
    v.number("heading_radius", heading_radius, Bounds::closed(0.0, 1000.0, "m"));
    v.number("heading_min_concentration", heading_min_concentration, Bounds::closed(0.0, 1.0));
    v.integer("heading_min_normals", heading_min_normals, Bounds::closed(1, 100000));
    v.number("heading_sigma", heading_sigma, Bounds::above(0.0, "rad"));
    v.integer("heading_reoptimise", heading_reoptimise, Bounds::closed(1, 100000));
    v.flag("reanchor_filter", reanchor_filter);
    v.integer("correction_delay", correction_delay, Bounds::closed(-1, 100000, "scans"));
    v.section("optimizer", optimizer);
  }

  // Beyond each field's bounds: search_radius_max >= search_radius_min.
  std::string validate() const;  // empty when valid, else names the bad field
};

struct LoopClosureCounters {
  long key_scans = 0;
  long candidates = 0;             // verifications attempted
  long accepted = 0;               // loop edges added
  long refused = 0;                // failed verification, for one of the reasons below
  long refused_by_score = 0;       // the best correlative score under min_score
  long refused_by_fit = 0;         // ICP failed, too few inliers, residual or shift too large
  long refused_as_degenerate = 0;  // the match slides along a corridor, or leaves the
                                   // query's structure across it unexplained
  long ambiguous = 0;              // refused: another place of the window scored nearly as well
  long dropped = 0;                // loop edges the kernel rejected at the end
  long inconsistent = 0;           // loops refused by the consistency test (not in `accepted`)
  long unconfirmed = 0;            // wide-window hypotheses no later key scan confirmed
  long released = 0;               // key scans whose readings were let go (max_keyscans_per_place)
  long heading_loops = 0;          // heading-only edges between the walls of one place
  long optimisations = 0;
  double optimisation_seconds = 0.0;
  double verification_seconds = 0.0;
};

// The share of `query`'s own structure along `direction` (a unit vector in
// the reference frame) that a match at `pose` explains: each query point
// with a normal (fitted from the query's own neighbours, options'
// normal_radius) weighs (n · direction)², and counts as explained when a
// reference point lies within options' correspondence_distance of it at
// `pose`. 1 when the query holds less than one point's worth of structure
// along the direction (nothing there to explain).
double explainedStructure(const std::vector<Vector2>& query, const PointCloudReference& reference,
                          const Pose2& pose, const Vector2& direction,
                          const ScanMatcherOptions& options);

// The search window's half-widths for a relative pose over
// `graph_distance` metres of chain (the drift model above): m, and rad.
double loopSearchRadius(const LoopClosureOptions& options, double graph_distance);
double loopSearchAngle(const LoopClosureOptions& options, double graph_distance);

// The key scans first..last (inclusive, of key_count) of the submap a
// query is matched against when `candidate` is tried at relative heading
// `guess_heading` (the query's in the candidate's frame): submap_half_width
// each side, and for a reverse revisit (|guess_heading| > 90°) the
// candidate's path back over reverse_submap_travel. travel_from_previous(m)
// is the travel from key scan m − 1 to m.
struct KeyRange {
  int first = 0, last = -1;
};
KeyRange loopSubmapKeys(const LoopClosureOptions& options, int candidate, int key_count,
                        double guess_heading,
                        const std::function<double(int)>& travel_from_previous);

// What a loop verification decided (verifyLoop).
enum class LoopVerdict { kAccepted, kRefusedByScore, kRefusedByFit, kDegenerate, kAmbiguous };

// The loop closer's verification of one match, for LoopCloser and for any
// other place that must ask the same of a loop (ekf_slam_merge_states):
// `query` (points in its own frame; `sparse_query` the same thinned for the
// search) against `submap` (points in the candidate's frame) within
// ±radius and ±angle of `guess`: the correlative search must score
// options.min_score, ICP from its pose pair min_inlier_fraction within
// max_rms_residual and move it at most max_icp_shift, the match must not
// slide (max_degenerate_sigma, min_directional_inlier_fraction), and no
// other place of the window may score within max_runner_up_ratio of it.
// `grid` holds the search's grid (its storage reused between calls). On
// kAccepted, `relative` is the query's frame in the submap's.
LoopVerdict verifyLoop(const std::vector<Vector2>& query, const std::vector<Vector2>& sparse_query,
                       const std::vector<Vector2>& submap, const Pose2& guess, double radius,
                       double angle, const LoopClosureOptions& options,
                       const ScanMatcherOptions& icp, LikelihoodGrid* grid, Pose2* relative);

// The direction the walls of `points` (one scan, its own frame) run in,
// modulo 90°, in [−45°, 45°): the mean of the wall normals' angles times
// four (normals fitted as the scan matcher fits them, `options`), divided
// by four. `concentration` (may be null) gets the length of that mean, 1
// when every wall is parallel or perpendicular to the others, near 0 for
// walls at every angle; `normals` the number of normals (0: no direction).
double wallDirection(const std::vector<Vector2>& points, const ScanMatcherOptions& options,
                     double* concentration, int* normals);

// What a later run continues from (a saved SLAM state,
// pipeline/slam_state.h): the key scans with their readings, the graph with
// its loops and heading edges, and the loop search's bookkeeping. Not the
// per-scan entries: the scans of a resumed run hang off the restored key
// scans.
struct LoopCloserState {
  struct Key {
    Pose2 front_end;                    // front-end pose when it was taken
    std::vector<Vector2> points;        // robot frame; empty when released
    double travel_from_previous = 0.0;  // m
    int retry_after = 0;
    int scan_index = -1;  // of its scan, in addScan order
    double stamp = 0.0;
    double wall_direction = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<Key> keys;
  // The newest scans' entries (scanPoses(): each hangs off a key scan),
  // scans scan_count − scans.size() to scan_count − 1.
  struct ScanEntry {
    double stamp = 0.0;
    int key = -1;  // the key scan it hangs off (−1 before the first)
    Pose2 offset;  // front-end increment from that key scan
  };
  std::vector<ScanEntry> scans;
  PoseGraph graph;
  // Per key scan: its neighbours in graph distance and the travel to each.
  std::vector<std::vector<std::pair<int, double>>> adjacency;
  std::vector<int> heading_edges;  // graph edge indices, ascending
  LoopClosureCounters counters;
  int scan_count = 0;  // scans given to addScan
  int next_attempt = 0;
  int heading_loops_since_optimisation = 0;
  bool has_hypothesis = false;  // a wide-window loop awaiting confirmation
  int hypothesis_from = 0, hypothesis_to = 0;
  Pose2 hypothesis_relative;
};

class LoopCloser {
 public:
  // `matcher` gives the ICP settings (normals, gates, point noise) of the front end.
  // `scan_history` > 0 bounds the per-scan entries kept for scanPoses() to
  // at least that many of the newest (trimmed in steps of an eighth of it,
  // so at most 9/8 of it); 0 keeps every scan. The loop search works on key
  // scans only, so the bound never changes the graph.
  LoopCloser(const LoopClosureOptions& options, const ScanMatcherOptions& matcher,
             long scan_history = 0);

  // Every scan, in order, with its front-end pose (odom frame). A scan
  // without usable geometry (usable = false) never becomes a key scan.
  void addScan(double stamp, const Scan& scan, const Pose2& laser_pose, const Pose2& front_end,
               bool usable);

  // A loop found outside this closer (another place recognition, a human,
  // a test): key scan `to` seen from key scan `from` at `relative`. It is
  // handled as a verified loop: it enters at full weight, the graph is
  // optimised, and from then on the Cauchy kernel judges it against the
  // other loops (finish() drops it if they disagree). False when a key
  // index is out of range, the two are the same, or the consistency test
  // refused it.
  bool addLoop(int from, int to, const Pose2& relative);

  // Final optimisation: drops the loops the kernel rejects, re-optimises.
  void finish();

  // A snapshot to continue from, and the continuation: resume() replaces
  // everything this closer holds (on a closer built with the same options)
  // and numbers the next scan state.scan_count. Empty on success, else what
  // is inconsistent in `state` (the closer is then unchanged).
  LoopCloserState state() const;
  std::string resume(const LoopCloserState& state);

  // One pose per scan given to addScan and still kept (scans firstScan() to
  // scanCount() − 1), in the map frame of the first key scan.
  std::vector<StampedPose> scanPoses() const;
  // The pose of the latest scan given to addScan, from the graph as it
  // stands now (after any optimisation that scan triggered): the causal,
  // loop-closed estimate. Same frame as scanPoses().
  Pose2 latestPose() const;

  const LoopClosureCounters& counters() const { return counters_; }
  const PoseGraph& graph() const { return graph_; }
  // The graph as the last optimisation of finish() found it (the problem
  // that optimisation solved); empty when finish() did not optimise.
  const PoseGraph& finalProblem() const { return final_problem_; }
  // Scan `scan` (addScan order, counted from the first scan ever given)
  // hangs off key scan scanKey(scan) (−1 before the first) at
  // scanOffset(scan): scanPoses() composes the two. Scans before
  // firstScan() were let go (scan_history); scanCount() counts them too.
  int scanCount() const { return first_scan_ + static_cast<int>(scans_.size()); }
  int firstScan() const { return first_scan_; }
  int scanKey(int scan) const { return scans_[scan - first_scan_].key; }
  const Pose2& scanOffset(int scan) const { return scans_[scan - first_scan_].offset; }
  double scanStamp(int scan) const { return scans_[scan - first_scan_].stamp; }
  // Graph node `key` was taken at this scan (index in addScan order). Loop
  // and heading edges are the graph's robust edges (a heading edge informs
  // the heading alone); the sequential ones are not robust.
  int keyScanIndex(int key) const { return keys_[key].scan_index; }
  // Graph edge `edge` is a heading edge (a robust edge that is not).
  bool isHeadingEdge(int edge) const { return heading_edges_.count(edge) > 0; }
  int keyCount() const { return static_cast<int>(keys_.size()); }
  // A key scan's readings (≤ max_range, robot frame; empty when released,
  // max_keyscans_per_place) and its scan's stamp.
  const std::vector<Vector2>& keyPoints(int key) const { return *keys_[key].points; }
  // The same points, shared: they never change once the key scan is taken.
  std::shared_ptr<const std::vector<Vector2>> sharedKeyPoints(int key) const {
    return keys_[key].points;
  }
  Pose2 keyFrontEnd(int key) const { return keys_[key].front_end; }
  double keyStamp(int key) const { return keys_[key].stamp; }

 private:
  struct KeyScan {
    Pose2 front_end;                                     // front-end pose when it was taken
    std::shared_ptr<const std::vector<Vector2>> points;  // robot frame
    std::vector<Vector2> sparse;                         // thinned for the correlative search
    double travel_from_previous = 0.0;                   // m
    int retry_after = 0;  // key index before which it is not tried again
    int scan_index = -1;  // index of its scan in addScan order
    double stamp = 0.0;   // of its scan
    // Its walls' direction modulo 90° (own frame); NaN when they have none.
    double wall_direction = std::numeric_limits<double>::quiet_NaN();
  };
  void addHeadingLoop(int key);
  int heading_loops_since_optimisation_ = 0;
  using ScanEntry = LoopCloserState::ScanEntry;

  void addKeyScan(double stamp, const std::vector<Vector2>& points, const Pose2& front_end);
  // False when the consistency test refused it (the graph is then as before).
  bool addLoopEdge(int from, int to, const Pose2& relative);
  // Graph distances from `from` (Dijkstra); the last result is kept until
  // the graph's adjacency changes, since the loop search and the heading
  // loops of a key scan both ask for it.
  std::vector<double> graphDistances(int from) const;
  // Up to max_candidates key scans to verify, most likely first.
  std::vector<int> pickCandidates(int key, const std::vector<double>& distance) const;
  // Matches key scan `key` (with the recent ones) against the submap of
  // `candidate`, searching ±radius, ±angle around `guess` (key in candidate's frame).
  bool verify(int candidate, int key, const Pose2& guess, double radius, double angle,
              Pose2* relative);
  // The loop search for the new key scan `key`: a pending hypothesis's
  // confirmation, else the candidates' verification.
  void searchLoops(int key);
  // Lets the readings of key scan `key` go when its place holds
  // max_keyscans_per_place key scans with readings already.
  void releaseIfPlaceIsFull(int key);
  bool hasReadings(int key) const { return !keys_[key].points->empty(); }
  // A pending hypothesis: true when key scan `key` confirmed it (both loops entered).
  bool tryConfirm(int key);
  // Merged points of the recent key scans in the frame of key scan `key`.
  std::vector<Vector2> queryPoints(int key, bool sparse) const;
  PoseGraphSummary optimise();

  LoopClosureOptions options_;
  ScanMatcherOptions icp_;
  PoseGraph graph_;
  PoseGraph final_problem_;  // see finalProblem()
  std::vector<KeyScan> keys_;
  std::vector<ScanEntry> scans_;  // scans first_scan_ on
  int first_scan_ = 0;
  long scan_history_ = 0;                                       // see the constructor
  std::vector<std::vector<std::pair<int, double>>> adjacency_;  // graph distance edges
  mutable int distances_from_ = -1;  // graphDistances' cached source (-1: none)
  mutable std::vector<double> distances_;
  std::unordered_set<int> heading_edges_;  // graph edge indices of the heading loops
  LoopClosureCounters counters_;
  int next_attempt_ = 0;  // key index before which no loop is tried (after a refusal)
  struct Hypothesis {
    int from, to;
    Pose2 relative;
  };
  std::optional<Hypothesis> hypothesis_;  // a wide-window loop awaiting confirmation
  // verify()'s likelihood grid, rebuilt in place for each candidate: a
  // fresh grid of megabytes per candidate cost page faults and left the
  // back end thread's heap fragmented. Storage above kKeptGridBytes is not
  // kept between verifications.
  static constexpr size_t kKeptGridBytes = size_t{32} << 20;
  LikelihoodGrid verify_grid_;
};

}  // namespace ekf_slam
