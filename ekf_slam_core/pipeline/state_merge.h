// Two saved states of one building joined into one map: the second run's
// scans placed in the first run's map frame and both runs smoothed as one
// problem (ekf_slam_merge_states).
//
// 1. Alignment: the second state's key scans, in order and joined by their
//    front-end poses, are searched for over the first state's map by the
//    global localisation (global_localization.h) until one is found; the
//    place found gives the transform from the second map frame to the
//    first's.
// 2. The two key-scan graphs joined in the first map frame, and loops
//    between the runs: each key scan of the second run with readings is
//    matched against the first run's key scans near where the joined graph
//    puts it, nearest first (MergeOptions), as the loop closer verifies a
//    loop (verifyLoop: its submap from the graph's poses, the correlative
//    search, ICP and every gate; the window from the loop closer's drift
//    model over the travel from the nearest second-run key scan already
//    joined; a wide window's loop confirmed by one of the next key scans)
//    and with the loop edges' noise. In rounds: the joined graph optimised
//    with the loops found so far brings the rest nearer, until a round
//    finds none.
// 3. One smoothing problem: the first history, then the second (its poses
//    moved into the first frame, its landmark ids shifted past the first's;
//    its first iteration has no motion edge to the first run's last), each
//    run's own loops, the loops between them (each joins the two key scans'
//    iterations), started where the joined graph puts each iteration.
//    SmoothingProblem::solve then gives one pose per scan of both runs.
#pragma once

#include <optional>
#include <string>

#include "ekf_slam_core/pipeline/global_localization.h"
#include "ekf_slam_core/pipeline/pipeline_options.h"
#include "ekf_slam_core/pipeline/slam_state.h"
#include "ekf_slam_core/pipeline/smoothing_problem.h"

namespace ekf_slam {

struct MergeOptions {
  GlobalLocalizationOptions alignment;
  // Loops between the runs: a second-run key scan is matched against the
  // first run's key scans within its window (the loop closer's drift model
  // over its travel from the nearest second-run key scan already joined to
  // the first run; at least loop_radius) and turned at most loop_turn from
  // it (the LMS200 sees the forward half: a place passed the other way
  // round rarely matches).
  double loop_radius = 1.0;  // m
  double loop_turn = 1.0;    // rad
  // Rounds of that search, each after the joined key-scan graph was
  // optimised with the loops found so far (a key scan the runs' drift put
  // out of reach comes nearer); it stops at a round that finds none.
  int loop_rounds = 10;
};

struct StateMerge {
  std::string error;  // empty: merged
  // The alignment: which key scan of the second run was found, where, and
  // the second map frame in the first.
  int aligned_key = -1;
  GlobalPlacement placement;
  Pose2 first_from_second;
  int second_keys_tried = 0;  // key scans searched with until one was found
  // Loops between the runs: second-run key scans matched, and tried.
  int cross_loops = 0;
  int cross_tried = 0;  // matches tried, all rounds
  int loop_rounds = 0;  // rounds run
  // Each run's own loops, as constraints.
  int first_loops = 0;
  int second_loops = 0;
  long first_scans = 0;  // scans of each history
  long second_scans = 0;
  std::optional<SmoothingProblem> problem;  // set when merged
};

// Both states must hold key scans (loop closure was on) and a history.
// `options`: the configuration both runs were made with.
StateMerge mergeStates(const SlamState& first, const SlamState& second,
                       const PipelineOptions& options, const MergeOptions& merge = {});

}  // namespace ekf_slam
