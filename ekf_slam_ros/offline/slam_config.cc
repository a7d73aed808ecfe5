#include "ekf_slam_ros/offline/slam_config.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>

#include "ekf_slam_ros/offline/yaml_binder.h"

namespace ekf_slam {
namespace {

constexpr double kHuge = std::numeric_limits<double>::max();

void bindFeatures(YamlBinder b, FeatureOptions* f) {
  std::string mode = f->cluster_mode == ClusterMode::kFixed ? "fixed" : "adaptive";
  b.text("cluster_mode", &mode, {"fixed", "adaptive"});
  f->cluster_mode = mode == "fixed" ? ClusterMode::kFixed : ClusterMode::kAdaptive;
  b.number("range_sigma", &f->range_sigma, 1e-6, 10.0);
  b.number("bearing_sigma", &f->bearing_sigma, 0.0, 1.0);
  b.number("cluster_threshold", &f->cluster_threshold, 1e-3, 10.0);
  b.number("cluster_incidence_angle", &f->cluster_incidence_angle, 0.0, kPi / 2);
  b.integer("cluster_max_invalid_beams", &f->cluster_max_invalid_beams, 0, 1000);
  b.number("split_threshold", &f->split_threshold, 1e-4, 10.0);
  b.number("merge_chi2", &f->merge_chi2, 0.0, 1e6);
  b.integer("min_line_points", &f->min_line_points, 2, 100000);
  b.number("min_line_length", &f->min_line_length, 0.0, 100.0);
  b.integer("break_guard_points", &f->break_guard_points, 0, 100);
  b.integer("end_trim_points", &f->end_trim_points, 0, 100);
  b.number("corner_min_angle", &f->corner_min_angle, 0.0, kPi / 2);
  b.number("corner_max_distance", &f->corner_max_distance, 0.0, 10.0);
  b.number("endpoint_max_gap", &f->endpoint_max_gap, 0.0, 10.0);
  b.number("point_model_sigma", &f->point_model_sigma, 0.0, 1.0);
  b.rejectUnknownKeys();
}

void bindMotionNoise(YamlBinder noise, MotionNoiseOptions* n) {
  noise.number("rot_per_rot", &n->rot_per_rot, 0.0, kHuge);
  noise.number("rot_per_trans", &n->rot_per_trans, 0.0, kHuge);
  noise.number("trans_per_trans", &n->trans_per_trans, 0.0, kHuge);
  noise.number("trans_per_rot", &n->trans_per_rot, 0.0, kHuge);
  noise.number("min_rot_sigma", &n->min_rot_sigma, 0.0, kHuge);
  noise.number("min_trans_sigma", &n->min_trans_sigma, 0.0, kHuge);
  noise.number("rot_per_metre", &n->rot_per_metre, 0.0, kHuge);
  noise.number("trans_per_metre", &n->trans_per_metre, 0.0, kHuge);
  noise.number("rot_per_radian", &n->rot_per_radian, 0.0, kHuge);
  noise.rejectUnknownKeys();
}

void bindFilter(YamlBinder b, FilterOptions* f, bool* laser_pose_given) {
  std::vector<double> laser;
  if (*laser_pose_given) laser = {f->laser_pose.x, f->laser_pose.y, f->laser_pose.theta};
  b.numbers("laser_pose", &laser, 3);
  if (!laser.empty()) {
    f->laser_pose = Pose2(laser[0], laser[1], laser[2]);
    *laser_pose_given = true;
  }
  b.number("max_step_translation", &f->max_step_translation, 1e-6, kHuge);
  b.boolean("first_estimate_jacobians", &f->first_estimate_jacobians);
  b.number("max_step_rotation", &f->max_step_rotation, 1e-6, 2 * kPi);
  b.integer("tentative_max_age", &f->tentative_max_age, 0L, 1000000L);
  bindMotionNoise(b.child("motion_noise"), &f->motion_noise);
  b.rejectUnknownKeys();
}

void bindScanMatching(YamlBinder b, PipelineOptions* p) {
  ScanMatcherOptions& s = p->scan_matching;
  b.boolean("enabled", &s.enabled);
  b.number("initial_correspondence_distance", &s.initial_correspondence_distance, 1e-4, 100.0);
  b.number("correspondence_distance", &s.correspondence_distance, 1e-4, 100.0);
  b.number("huber_delta", &s.huber_delta, 1e-6, 100.0);
  b.number("point_sigma", &s.point_sigma, 1e-6, 100.0);
  b.number("prior_sigma_translation", &s.prior_sigma_translation, 1e-6, kHuge);
  b.number("prior_sigma_rotation", &s.prior_sigma_rotation, 1e-6, kHuge);
  b.integer("max_iterations", &s.max_iterations, 1, 10000);
  b.number("convergence_step", &s.convergence_step, 1e-12, 1.0);
  b.number("min_point_spacing", &s.min_point_spacing, 0.0, 10.0);
  b.number("max_range", &s.max_range, 1e-3, kHuge);
  b.number("normal_radius", &s.normal_radius, 1e-3, 10.0);
  b.integer("min_correspondences", &s.min_correspondences, 3, 100000);
  b.number("min_inlier_fraction", &s.min_inlier_fraction, 0.0, 1.0);
  b.number("max_correction_translation", &s.max_correction_translation, 1e-6, kHuge);
  b.number("max_correction_rotation", &s.max_correction_rotation, 1e-6, 2 * kPi);
  b.text("map_mode", &s.map_mode, {"local", "global"});
  b.number("map_point_spacing", &s.map_point_spacing, 0.0, 10.0);
  b.integer("local_map_scans", &s.local_map_scans, 1, 10000);
  b.number("keyscan_distance", &s.keyscan_distance, 0.0, kHuge);
  b.number("keyscan_angle", &s.keyscan_angle, 0.0, 2 * kPi);
  b.number("odometry_gate_probability", &s.odometry_gate_probability, 0.0, 0.999999999);
  b.number("odometry_check_sigma_translation", &s.odometry_check_sigma_translation, 1e-6, kHuge);
  b.number("odometry_check_sigma_rotation", &s.odometry_check_sigma_rotation, 1e-6, 2 * kPi);
  b.number("odometry_check_sigma_time", &s.odometry_check_sigma_time, 0.0, 100.0);
  bindMotionNoise(b.child("motion_noise"), &p->scan_matched_motion_noise);
  b.rejectUnknownKeys();
}

void bindLoopClosure(YamlBinder b, LoopClosureOptions* l) {
  b.boolean("enabled", &l->enabled);
  b.number("keyscan_distance", &l->keyscan_distance, 1e-3, kHuge);
  b.number("keyscan_angle", &l->keyscan_angle, 1e-3, 2 * kPi);
  b.number("max_range", &l->max_range, 1e-3, kHuge);
  b.number("step_sigma_translation", &l->step_sigma_translation, 1e-6, 10.0);
  b.number("translation_sigma_per_sqrt_metre", &l->translation_sigma_per_sqrt_metre, 0.0, 10.0);
  b.number("step_sigma_rotation", &l->step_sigma_rotation, 1e-6, kPi);
  b.number("rotation_sigma_per_sqrt_metre", &l->rotation_sigma_per_sqrt_metre, 0.0, kPi);
  b.number("rotation_sigma_per_sqrt_radian", &l->rotation_sigma_per_sqrt_radian, 0.0, kPi);
  b.number("min_loop_travel", &l->min_loop_travel, 0.0, kHuge);
  b.number("search_sigmas", &l->search_sigmas, 1e-3, 100.0);
  b.number("search_radius_min", &l->search_radius_min, 1e-3, 1e5);
  b.number("search_radius_max", &l->search_radius_max, 1e-3, 1e5);
  b.number("search_angle_min", &l->search_angle_min, 1e-4, kPi);
  b.number("max_heading_difference", &l->max_heading_difference, 1e-3, kPi);
  b.integer("max_candidates", &l->max_candidates, 1, 1000);
  b.integer("submap_half_width", &l->submap_half_width, 0, 1000);
  b.integer("query_keys", &l->query_keys, 0, 1000);
  b.integer("retry_interval", &l->retry_interval, 0, 100000);
  b.number("confirm_radius", &l->confirm_radius, 1e-3, 1e9);
  b.integer("confirm_keys", &l->confirm_keys, 1, 100000);
  YamlBinder c = b.child("correlative");
  c.number("resolution", &l->correlative.resolution, 1e-3, 10.0);
  c.number("sigma", &l->correlative.sigma, 1e-3, 10.0);
  c.integer("levels", &l->correlative.levels, 1, 16);
  c.number("angular_step", &l->correlative.angular_step, 1e-4, 0.5);
  c.rejectUnknownKeys();
  b.number("search_point_spacing", &l->search_point_spacing, 0.0, 10.0);
  b.number("min_score", &l->min_score, 1e-3, 1.0);
  b.number("min_inlier_fraction", &l->min_inlier_fraction, 0.0, 1.0);
  b.number("max_rms_residual", &l->max_rms_residual, 1e-6, 10.0);
  b.number("max_degenerate_sigma", &l->max_degenerate_sigma, 1e-6, 100.0);
  b.number("max_icp_shift", &l->max_icp_shift, 1e-6, 100.0);
  b.number("loop_sigma_translation", &l->loop_sigma_translation, 1e-6, 100.0);
  b.number("loop_sigma_rotation", &l->loop_sigma_rotation, 1e-6, kPi);
  b.number("min_final_weight", &l->min_final_weight, 0.0, 1.0);
  b.number("consistency_probability", &l->consistency_probability, 0.0, 0.999999999);
  b.boolean("reanchor_filter", &l->reanchor_filter);
  YamlBinder o = b.child("optimizer");
  o.integer("max_iterations", &l->optimizer.max_iterations, 1, 10000);
  o.number("convergence_step", &l->optimizer.convergence_step, 1e-12, 1.0);
  o.number("robust_kernel_width", &l->optimizer.robust_kernel_width, 1e-3, 1000.0);
  o.number("initial_lambda", &l->optimizer.initial_lambda, 0.0, 1e6);
  o.rejectUnknownKeys();
  b.rejectUnknownKeys();
}

void bindAssociation(YamlBinder b, AssociationOptions* a) {
  std::string method = a->method == AssociationMethod::kJointCompatibility ? "jcbb" : "nn";
  b.text("method", &method, {"nn", "jcbb"});
  a->method = method == "jcbb" ? AssociationMethod::kJointCompatibility
                               : AssociationMethod::kNearestNeighbour;
  b.number("gate_probability", &a->gate_probability, 1e-9, 1.0 - 1e-12);
  b.number("new_landmark_probability", &a->new_landmark_probability, 1e-9, 1.0 - 1e-12);
  b.number("merge_probability", &a->merge_probability, 0.0, 1.0 - 1e-12);
  b.number("merge_distance", &a->merge_distance, 0.0, 1e3);
  b.number("merge_bias_sigma", &a->merge_bias_sigma, 0.0, 1.0);
  b.integer("jcbb_max_nodes", &a->jcbb_max_nodes, 1, 100000000);
  b.rejectUnknownKeys();
}

void bindSmoother(YamlBinder b, FullSmootherOptions* s) {
  auto kernel = [&b](const char* key, RobustKernel* k) {
    std::string name = *k == RobustKernel::kCauchy  ? "cauchy"
                       : *k == RobustKernel::kHuber ? "huber"
                                                    : "none";
    b.text(key, &name, {"none", "huber", "cauchy"});
    *k = name == "cauchy"  ? RobustKernel::kCauchy
         : name == "huber" ? RobustKernel::kHuber
                           : RobustKernel::kNone;
  };
  kernel("observation_kernel", &s->observation_kernel);
  kernel("loop_kernel", &s->loop_kernel);
  b.number("kernel_width", &s->optimizer.kernel_width, 1e-3, 1000.0);
  b.integer("max_iterations", &s->optimizer.max_iterations, 1, 100000);
  b.number("min_relative_decrease", &s->optimizer.min_relative_decrease, 0.0, 1.0);
  b.integer("revisit_gap", &s->revisit_gap, 1, 100000000);
  b.number("revisit_gate_probability", &s->revisit_gate_probability, 1e-9, 1.0 - 1e-12);
  b.integer("max_verification_rounds", &s->max_verification_rounds, 0, 100);
  b.boolean("reassociate", &s->reassociate);
  b.number("reassociation_position_sigma", &s->reassociation_position_sigma, 0.0, 100.0);
  b.number("reassociation_heading_sigma", &s->reassociation_heading_sigma, 0.0, kPi);
  b.number("reassociation_gate_probability", &s->reassociation_gate_probability, 1e-9, 1.0 - 1e-12);
  b.rejectUnknownKeys();
}

void bindPipeline(YamlBinder b, PipelineOptions* p) {
  b.number("min_travel_distance", &p->min_travel_distance, 0.0, kHuge);
  b.number("min_travel_angle", &p->min_travel_angle, 0.0, 2 * kPi);
  b.number("max_landmark_range", &p->max_landmark_range, 1e-3, kHuge);
  b.number("min_landmark_range", &p->min_landmark_range, 0.0, kHuge);
  b.integer("prune_min_observations", &p->prune_min_observations, 0, 1000000);
  b.integer("prune_age_steps", &p->prune_age_steps, 1L, 100000000L);
  const Vector3 variance = p->initial_pose_covariance.diagonal();
  std::vector<double> sigma = {std::sqrt(variance(0)), std::sqrt(variance(1)),
                               std::sqrt(variance(2))};
  b.numbers("initial_pose_sigma", &sigma, 3);
  if (!sigma.empty()) {
    p->initial_pose_covariance =
        Vector3(sigma[0] * sigma[0], sigma[1] * sigma[1], sigma[2] * sigma[2]).asDiagonal();
  }
  b.rejectUnknownKeys();
}

void bindMap(YamlBinder b, OccupancyGridOptions* m) {
  b.number("resolution", &m->resolution, 1e-3, 10.0);
  b.number("hit_probability", &m->hit_probability, 0.5, 1.0);
  b.number("miss_probability", &m->miss_probability, 0.0, 0.5);
  b.number("clamp_log_odds", &m->clamp_log_odds, 1e-3, 100.0);
  b.number("max_insert_range", &m->max_insert_range, 1e-3, kHuge);
  b.number("no_return_free_range", &m->no_return_free_range, 0.0, kHuge);
  b.number("max_cells", &m->max_cells, 1.0, 1e10);
  b.rejectUnknownKeys();
}

void bindInput(YamlBinder b, InputOptions* in) {
  b.text("scan_topic", &in->scan_topic);
  b.text("odom_topic", &in->odom_topic);
  b.text("odometry_source", &in->odometry_source, {"odom", "tf"});
  b.text("odom_frame", &in->odom_frame);
  b.text("base_frame", &in->base_frame);
  b.number("max_odometry_gap", &in->max_odometry_gap, 1e-6, kHuge);
  b.rejectUnknownKeys();
}

// Binds every key of `root` onto `c`; errors and (if given) the final values
// are collected.
void bindAll(const YAML::Node& root, SlamConfig* config,
             std::shared_ptr<std::vector<std::string>> errors,
             std::shared_ptr<YamlBinder::Values> values) {
  YamlBinder top(root, "", errors, values);
  SlamConfig& c = *config;
  bindFeatures(top.child("features"), &c.pipeline.features);
  bindFilter(top.child("filter"), &c.pipeline.filter, &c.laser_pose_given);
  bindAssociation(top.child("association"), &c.pipeline.association);
  bindPipeline(top.child("pipeline"), &c.pipeline);
  bindScanMatching(top.child("scan_matching"), &c.pipeline);
  bindLoopClosure(top.child("loop_closure"), &c.pipeline.loop_closure);
  bindSmoother(top.child("smoother"), &c.pipeline.smoother);
  bindMap(top.child("map"), &c.map);
  bindInput(top.child("input"), &c.input);
  top.rejectUnknownKeys();
}

}  // namespace

std::string loadSlamConfig(const YAML::Node& root, SlamConfig* config) {
  auto errors = std::make_shared<std::vector<std::string>>();
  SlamConfig c = *config;
  bindAll(root, &c, errors, nullptr);
  if (errors->empty()) {
    // Cross-field checks of the components themselves.
    const std::string pipeline = c.pipeline.validate();
    if (!pipeline.empty()) errors->push_back(pipeline);
    const std::string map = c.map.validate();
    if (!map.empty()) errors->push_back("map: " + map);
  }
  if (!errors->empty()) {
    std::string all;
    for (const std::string& e : *errors) all += (all.empty() ? "" : "\n") + e;
    return all;
  }
  *config = c;
  return "";
}

std::string describeSlamConfig(const SlamConfig& config) {
  auto errors = std::make_shared<std::vector<std::string>>();
  auto values = std::make_shared<YamlBinder::Values>();
  SlamConfig copy = config;
  bindAll(YAML::Node(), &copy, errors, values);
  std::string out;
  for (const auto& [key, value] : *values) out += key + ": " + value + "\n";
  return out;
}

std::string loadSlamConfigFile(const std::string& path, SlamConfig* config) {
  try {
    return loadSlamConfig(YAML::LoadFile(path), config);
  } catch (const YAML::Exception& e) {
    return path + ": " + e.what();
  }
}

}  // namespace ekf_slam
