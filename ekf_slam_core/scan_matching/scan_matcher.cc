#include "ekf_slam_core/scan_matching/scan_matcher.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "ekf_slam_core/filter/chi_square.h"

namespace ekf_slam {

std::string ScanMatcherOptions::validate() const {
  const std::string error = checkFields(*this);
  if (!error.empty()) return error;
  if (initial_correspondence_distance < correspondence_distance) {
    return "initial_correspondence_distance must be >= correspondence_distance (m)";
  }
  return "";
}

// ---------------------------------------------------------------------------
// Reference point set

bool fitNormal(const Vector2& sum, const Matrix2& sum_sq, int n, Vector2* normal) {
  // Three points (the point and two neighbours) are the fewest that say
  // whether they lie on a line.
  if (n < 3) return false;
  const Vector2 mean = sum / n;
  const Matrix2 covariance = sum_sq / n - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Matrix2> eigen(covariance);
  // A blob with no dominant direction (both spreads alike) has no tangent line.
  if (eigen.eigenvalues()(0) > 0.25 * eigen.eigenvalues()(1)) return false;
  *normal = eigen.eigenvectors().col(0).normalized();
  return true;
}

PointCloudReference::PointCloudReference(const std::vector<Vector2>& points, double normal_radius,
                                         double cell_size)
    : cell_size_(cell_size) {
  // A first grid over all points to find neighbours for the normals.
  points_ = points;
  buildGrid();
  const double radius2 = normal_radius * normal_radius;
  std::vector<Vector2> kept_points, kept_normals;
  kept_points.reserve(points.size());
  kept_normals.reserve(points.size());
  const int reach = static_cast<int>(std::ceil(normal_radius / cell_size_));
  for (const Vector2& p : points) {
    int cx, cy;
    cellOf(p, &cx, &cy);
    Vector2 sum = Vector2::Zero();
    Matrix2 sum_sq = Matrix2::Zero();
    int n = 0;
    for (int ix = cx - reach; ix <= cx + reach; ++ix) {
      for (int iy = cy - reach; iy <= cy + reach; ++iy) {
        const std::vector<int>* members = cell(ix, iy);
        if (!members) continue;
        for (int j : *members) {
          const Vector2& q = points_[j];
          if ((q - p).squaredNorm() > radius2) continue;
          sum += q;
          sum_sq += q * q.transpose();
          ++n;
        }
      }
    }
    Vector2 normal;
    if (!fitNormal(sum, sum_sq, n, &normal)) continue;
    kept_points.push_back(p);
    kept_normals.push_back(normal);
  }
  points_ = std::move(kept_points);
  normals_ = std::move(kept_normals);
  buildGrid();
}

namespace {
// The hash grids' cell of p and its key: the same bits as ix · 2³² + iy
// mod 2⁶⁴, shifted as unsigned (shifting a negative signed value is
// undefined).
void gridCell(const Vector2& p, double cell_size, int* ix, int* iy) {
  *ix = static_cast<int>(std::floor(p.x() / cell_size));
  *iy = static_cast<int>(std::floor(p.y() / cell_size));
}

long long gridKey(int ix, int iy) {
  const uint64_t high = static_cast<uint64_t>(static_cast<uint32_t>(ix)) << 32;
  return static_cast<long long>(high | static_cast<uint32_t>(iy));
}
}  // namespace

PointCloudReference::CellKey PointCloudReference::key(int ix, int iy) const {
  return gridKey(ix, iy);
}

void PointCloudReference::cellOf(const Vector2& p, int* ix, int* iy) const {
  gridCell(p, cell_size_, ix, iy);
}

// ---------------------------------------------------------------------------
// Cell index

size_t CellIndex::slotOf(Key key) const {
  // Fibonacci hashing: the top bits of the key times 2⁶⁴/φ spread
  // neighbouring cells over the table.
  return static_cast<size_t>((static_cast<uint64_t>(key) * 0x9E3779B97F4A7C15ull) >> shift_);
}

int CellIndex::find(Key key) const {
  if (cells_.empty()) return -1;
  const size_t mask = cells_.size() - 1;
  for (size_t slot = slotOf(key);; slot = (slot + 1) & mask) {
    if (cells_[slot] < 0) return -1;
    if (keys_[slot] == key) return cells_[slot];
  }
}

int CellIndex::findOrAdd(Key key) {
  if (2 * (count_ + 1) > static_cast<int>(cells_.size())) grow();
  const size_t mask = cells_.size() - 1;
  size_t slot = slotOf(key);
  for (; cells_[slot] >= 0; slot = (slot + 1) & mask) {
    if (keys_[slot] == key) return cells_[slot];
  }
  keys_[slot] = key;
  cells_[slot] = count_;
  return count_++;
}

void CellIndex::grow() {
  const std::vector<Key> keys = std::move(keys_);
  const std::vector<int> cells = std::move(cells_);
  const size_t size = std::max<size_t>(16, 2 * cells.size());
  keys_.assign(size, 0);
  cells_.assign(size, -1);
  shift_ = 64;
  for (size_t s = size; s > 1; s >>= 1) --shift_;
  const size_t mask = size - 1;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] < 0) continue;
    size_t slot = slotOf(keys[i]);
    while (cells_[slot] >= 0) slot = (slot + 1) & mask;
    keys_[slot] = keys[i];
    cells_[slot] = cells[i];
  }
}

void CellIndex::clear() {
  keys_.clear();
  cells_.clear();
  count_ = 0;
  shift_ = 64;
}

// ---------------------------------------------------------------------------

const std::vector<int>* PointCloudReference::cell(int ix, int iy) const {
  const int c = cell_index_.find(key(ix, iy));
  return c < 0 ? nullptr : &cells_[c];
}

void PointCloudReference::addToGrid(int index) {
  int ix, iy;
  cellOf(points_[index], &ix, &iy);
  const int c = cell_index_.findOrAdd(key(ix, iy));
  if (c == static_cast<int>(cells_.size())) cells_.emplace_back();
  cells_[c].push_back(index);
}

void PointCloudReference::buildGrid() {
  cell_index_.clear();
  cells_.clear();
  for (int i = 0; i < static_cast<int>(points_.size()); ++i) addToGrid(i);
}

void PointCloudReference::insert(const std::vector<Vector2>& points,
                                 const std::vector<Vector2>& normals, double min_spacing) {
  for (size_t i = 0; i < points.size(); ++i) {
    if (min_spacing > 0.0 && anyWithin(points[i], min_spacing)) continue;
    points_.push_back(points[i]);
    normals_.push_back(normals[i]);
    addToGrid(static_cast<int>(points_.size()) - 1);
  }
}

// Distance along one axis from coordinate v to cell i's interval
// [i·size, (i+1)·size]: zero inside it.
static double gapToCell(double v, int i, double size) {
  return std::max({0.0, i * size - v, v - (i + 1) * size});
}

int PointCloudReference::nearest(const Vector2& p, double max_distance) const {
  int cx, cy;
  cellOf(p, &cx, &cy);
  const int reach = static_cast<int>(std::ceil(max_distance / cell_size_));
  // The nearest point of p's own cell bounds the answer: a neighbouring cell
  // whose box lies farther cannot hold it and is not searched. (The slack
  // covers rounding between cellOf's division and the box's products;
  // the cells are searched in their usual order, so ties go as before.)
  double bound = max_distance * max_distance;
  const std::vector<int>* own = cell(cx, cy);
  if (own) {
    for (int j : *own) bound = std::min(bound, (points_[j] - p).squaredNorm());
  }
  bound = bound * (1.0 + 1e-9) + 1e-12;
  int best = -1;
  double best_d2 = max_distance * max_distance;
  for (int ix = cx - reach; ix <= cx + reach; ++ix) {
    const double dx = gapToCell(p.x(), ix, cell_size_);
    if (dx * dx > bound) continue;
    for (int iy = cy - reach; iy <= cy + reach; ++iy) {
      const double dy = gapToCell(p.y(), iy, cell_size_);
      if (dx * dx + dy * dy > bound) continue;
      const std::vector<int>* members = ix == cx && iy == cy ? own : cell(ix, iy);
      if (!members) continue;
      for (int j : *members) {
        const double d2 = (points_[j] - p).squaredNorm();
        if (d2 <= best_d2) {
          best_d2 = d2;
          best = j;
        }
      }
    }
  }
  return best;
}

bool PointCloudReference::anyWithin(const Vector2& p, double distance) const {
  int cx, cy;
  cellOf(p, &cx, &cy);
  const int reach = static_cast<int>(std::ceil(distance / cell_size_));
  const double d2 = distance * distance;
  // p's own cell first: where a close point usually is.
  const std::vector<int>* own = cell(cx, cy);
  if (own) {
    for (int j : *own) {
      if ((points_[j] - p).squaredNorm() <= d2) return true;
    }
  }
  for (int ix = cx - reach; ix <= cx + reach; ++ix) {
    const double dx = gapToCell(p.x(), ix, cell_size_);
    for (int iy = cy - reach; iy <= cy + reach; ++iy) {
      if (ix == cx && iy == cy) continue;
      const double dy = gapToCell(p.y(), iy, cell_size_);
      // The slack covers rounding between cellOf's division and the box's products.
      if (dx * dx + dy * dy > d2 * (1.0 + 1e-9) + 1e-12) continue;
      const std::vector<int>* members = cell(ix, iy);
      if (!members) continue;
      for (int j : *members) {
        if ((points_[j] - p).squaredNorm() <= d2) return true;
      }
    }
  }
  return false;
}

// ---------------------------------------------------------------------------
// Sliding local map

SlidingNormals::SlidingNormals(double normal_radius)
    : radius2_(normal_radius * normal_radius), cell_size_(normal_radius) {}

SlidingNormals::CellKey SlidingNormals::cellKey(int ix, int iy) const { return gridKey(ix, iy); }

void SlidingNormals::cellOf(const Vector2& p, int* ix, int* iy) const {
  gridCell(p, cell_size_, ix, iy);
}

template <class F>
void SlidingNormals::forNeighbours(const Vector2& p, F f) {
  int cx, cy;
  cellOf(p, &cx, &cy);
  for (int ix = cx - 1; ix <= cx + 1; ++ix) {
    for (int iy = cy - 1; iy <= cy + 1; ++iy) {
      const auto it = grid_.find(cellKey(ix, iy));
      if (it == grid_.end()) continue;
      for (const Entry& e : it->second) {
        Point& q = at(e);
        if ((q.p - p).squaredNorm() <= radius2_) f(e, q);
      }
    }
  }
}

void SlidingNormals::push(const std::vector<Vector2>& points) {
  const long serial = front_serial_ + static_cast<long>(scans_.size());
  scans_.emplace_back();
  std::vector<Point>& scan = scans_.back();
  scan.reserve(points.size());
  for (const Vector2& p : points) {
    Point point;
    point.p = p;
    scan.push_back(point);
  }
  for (int i = 0; i < static_cast<int>(scan.size()); ++i) {
    int ix, iy;
    cellOf(scan[i].p, &ix, &iy);
    grid_[cellKey(ix, iy)].emplace_back(serial, i);
  }
  // Each entering point sums its neighbours (itself and the other entering
  // points included) and adds itself to the sums of the points already in.
  for (Point& point : scan) {
    const Vector2 p = point.p;
    const Matrix2 pp = p * p.transpose();
    forNeighbours(p, [&](const Entry& e, Point& q) {
      point.sum += q.p;
      point.sum_sq += q.p * q.p.transpose();
      ++point.n;
      if (e.first != serial) {
        q.sum += p;
        q.sum_sq += pp;
        ++q.n;
        q.stale = true;
      }
    });
  }
}

void SlidingNormals::popOldest() {
  if (scans_.empty()) return;
  const long serial = front_serial_;
  for (const Point& point : scans_.front()) {
    const Vector2 p = point.p;
    const Matrix2 pp = p * p.transpose();
    forNeighbours(p, [&](const Entry& e, Point& q) {
      if (e.first == serial) return;
      q.sum -= p;
      q.sum_sq -= pp;
      --q.n;
      q.stale = true;
    });
  }
  for (const Point& point : scans_.front()) {
    int ix, iy;
    cellOf(point.p, &ix, &iy);
    const auto it = grid_.find(cellKey(ix, iy));
    if (it == grid_.end()) continue;
    auto& entries = it->second;
    entries.erase(std::remove_if(entries.begin(), entries.end(),
                                 [serial](const Entry& e) { return e.first == serial; }),
                  entries.end());
    if (entries.empty()) grid_.erase(it);
  }
  scans_.pop_front();
  ++front_serial_;
}

void SlidingNormals::fitted(std::vector<Vector2>* points, std::vector<Vector2>* normals) const {
  points->clear();
  normals->clear();
  for (const std::vector<Point>& scan : scans_) {
    for (const Point& point : scan) {
      if (point.stale) {
        point.has_normal = fitNormal(point.sum, point.sum_sq, point.n, &point.normal);
        point.stale = false;
      }
      if (!point.has_normal) continue;
      points->push_back(point.p);
      normals->push_back(point.normal);
    }
  }
}

// ---------------------------------------------------------------------------
// ICP

MatchResult matchPoints(const std::vector<Vector2>& points, const PointCloudReference& reference,
                        const Pose2& guess, const ScanMatcherOptions& options) {
  MatchResult result;
  result.pose = guess;
  if (static_cast<int>(points.size()) < options.min_correspondences ||
      static_cast<int>(reference.size()) < options.min_correspondences) {
    result.message = "too few points to match";
    return result;
  }
  Vector3 x = guess.vector();
  const Vector3 prior_information(
      1.0 / (options.prior_sigma_translation * options.prior_sigma_translation),
      1.0 / (options.prior_sigma_translation * options.prior_sigma_translation),
      1.0 / (options.prior_sigma_rotation * options.prior_sigma_rotation));
  // The gate shrinks linearly over the first kShrinkSteps iterations.
  constexpr int kShrinkSteps = 5;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const double shrink = std::max(0.0, 1.0 - static_cast<double>(iteration) / kShrinkSteps);
    const double gate =
        options.correspondence_distance +
        shrink * (options.initial_correspondence_distance - options.correspondence_distance);
    const double c = std::cos(x.z()), s = std::sin(x.z());
    Matrix3 H = Matrix3::Zero();
    Vector3 b = Vector3::Zero();
    int pairs = 0;
    double sum_r2 = 0.0;
    for (const Vector2& p : points) {
      const Vector2 rotated(c * p.x() - s * p.y(), s * p.x() + c * p.y());
      const Vector2 q = rotated + x.head<2>();
      const int j = reference.nearest(q, gate);
      if (j < 0) continue;
      const Vector2& n = reference.normals()[j];
      const double r = n.dot(q - reference.points()[j]);
      // ∂q/∂θ = (−rotated.y, rotated.x)
      const Vector3 J(n.x(), n.y(), n.x() * -rotated.y() + n.y() * rotated.x());
      const double w = std::abs(r) <= options.huber_delta ? 1.0 : options.huber_delta / std::abs(r);
      H += w * J * J.transpose();
      b += w * J * r;
      ++pairs;
      sum_r2 += r * r;
    }
    result.iterations = iteration + 1;
    result.correspondences = pairs;
    result.rms_residual = pairs ? std::sqrt(sum_r2 / pairs) : 0.0;
    if (pairs < options.min_correspondences) break;
    // The prior on the odometry guess keeps a direction the scan does not
    // constrain (motion along a corridor) where the odometry puts it.
    Vector3 offset = x - guess.vector();
    offset.z() = wrapAngle(offset.z());
    const double point_information = 1.0 / (options.point_sigma * options.point_sigma);
    const Matrix3 H_total = point_information * H + prior_information.asDiagonal().toDenseMatrix();
    const Vector3 b_total = point_information * b + prior_information.cwiseProduct(offset);
    const Vector3 step = H_total.ldlt().solve(-b_total);
    if (!step.allFinite()) break;
    x += step;
    x.z() = wrapAngle(x.z());
    if (shrink == 0.0 && step.head<2>().norm() < options.convergence_step &&
        std::abs(step.z()) < options.convergence_step) {
      break;
    }
  }
  result.pose = Pose2::fromVector(x);
  result.inlier_fraction = static_cast<double>(result.correspondences) / points.size();
  if (result.correspondences < options.min_correspondences) {
    std::ostringstream m;
    m << result.correspondences << " point pairs, fewer than min_correspondences "
      << options.min_correspondences;
    result.message = m.str();
    return result;
  }
  if (result.inlier_fraction < options.min_inlier_fraction) {
    std::ostringstream m;
    m << "inlier fraction " << result.inlier_fraction << " below min_inlier_fraction "
      << options.min_inlier_fraction;
    result.message = m.str();
    return result;
  }
  result.ok = true;
  return result;
}

std::vector<Vector2> scanPointsInRobotFrame(const Scan& scan, const Pose2& laser_pose,
                                            const ScanMatcherOptions& options) {
  std::vector<Vector2> out;
  out.reserve(scan.ranges.size());
  const double spacing2 = options.min_point_spacing * options.min_point_spacing;
  for (int i = 0; i < scan.size(); ++i) {
    if (!scan.isValid(i) || scan.ranges[i] > options.max_range) continue;
    const double a = scan.angle(i);
    const Vector2 p = transformFrom(
        laser_pose, Vector2(scan.ranges[i] * std::cos(a), scan.ranges[i] * std::sin(a)));
    // A beam whose bearing is not finite (angle_min + i · angle_increment
    // beyond the range of a double) has no place.
    if (!p.allFinite()) continue;
    if (!out.empty() && (p - out.back()).squaredNorm() < spacing2) continue;
    out.push_back(p);
  }
  return out;
}

// ---------------------------------------------------------------------------
// Scan-matched odometry

ScanMatchingOdometry::ScanMatchingOdometry(const ScanMatcherOptions& options,
                                           const MotionNoiseOptions& wheel_noise)
    : options_(options),
      wheel_noise_(wheel_noise),
      odometry_gate_(options.odometry_gate_probability > 0.0
                         ? chiSquareQuantile(options.odometry_gate_probability, 3.0)
                         : 0.0),
      local_map_(options.normal_radius) {}

bool ScanMatchingOdometry::isOdometryJump(const Pose2& raw_odometry, double max_translation,
                                          double max_rotation) const {
  if (!initialised_) return false;
  const OdometryControl u = controlFromOdometry(last_raw_, raw_odometry);
  return !(std::abs(u.trans) <= max_translation &&
           std::abs(wrapAngle(u.rot1 + u.rot2)) <= max_rotation);
}

double ScanMatchingOdometry::odometryDisagreement(const Pose2& raw_odometry, const Pose2& matched,
                                                  double dt) const {
  // Both increments in the frame of the last corrected pose; the odometry
  // increment's covariance from the control (rot1, trans, rot2) through G.
  const OdometryControl u = controlFromOdometry(last_raw_, raw_odometry);
  Matrix3 G;
  const Pose2 wheels = applyControl(Pose2(), u, nullptr, &G);
  const Pose2 laser = between(last_corrected_, matched);
  Vector3 d(laser.x - wheels.x, laser.y - wheels.y, wrapAngle(laser.theta - wheels.theta));
  Matrix3 covariance = G * controlCovariance(u, wheel_noise_) * G.transpose();
  const double st = options_.odometry_check_sigma_translation;
  const double sr = options_.odometry_check_sigma_rotation;
  covariance += Vector3(st * st, st * st, sr * sr).asDiagonal().toDenseMatrix();
  if (dt > 0.0 && options_.odometry_check_sigma_time > 0.0) {
    // A stamp error τ moves the odometry pose by τ times the step's velocity.
    const Vector3 velocity = wheels.vector() / dt;
    const double s = options_.odometry_check_sigma_time;
    covariance += s * s * velocity * velocity.transpose();
  }
  return d.dot(covariance.ldlt().solve(d));
}

std::optional<ScanMatchingOdometryState> ScanMatchingOdometry::state() const {
  if (!initialised_ || !globalMap() || !reference_) return std::nullopt;
  ScanMatchingOdometryState out;
  out.last_raw = last_raw_;
  out.last_corrected = last_corrected_;
  out.last_key_pose = last_key_pose_;
  out.last_stamp = last_stamp_;
  out.map_points = reference_->points();
  out.map_normals = reference_->normals();
  return out;
}

bool ScanMatchingOdometry::restore(const ScanMatchingOdometryState& state) {
  if (!globalMap() || state.map_points.size() != state.map_normals.size() ||
      state.map_points.empty()) {
    return false;
  }
  initialised_ = true;
  consecutive_refusals_ = 0;
  last_raw_ = state.last_raw;
  last_corrected_ = state.last_corrected;
  last_key_pose_ = state.last_key_pose;
  last_stamp_ = state.last_stamp;
  reference_.emplace(std::vector<Vector2>(), options_.normal_radius,
                     options_.initial_correspondence_distance);
  reference_->insert(state.map_points, state.map_normals, 0.0);
  return true;
}

void ScanMatchingOdometry::addKeyScan(const std::vector<Vector2>& points, const Pose2& pose) {
  std::vector<Vector2> placed;
  placed.reserve(points.size());
  for (const Vector2& p : points) placed.push_back(transformFrom(pose, p));
  ++counters_.key_scans;
  last_key_pose_ = pose;
  if (globalMap()) {
    // Normals from the key scan's own points, then merged into the map.
    const PointCloudReference scan(placed, options_.normal_radius,
                                   options_.initial_correspondence_distance);
    if (!reference_) {
      reference_.emplace(std::vector<Vector2>(), options_.normal_radius,
                         options_.initial_correspondence_distance);
    }
    reference_->insert(scan.points(), scan.normals(), options_.map_point_spacing);
    return;
  }
  // Local: the last local_map_scans key scans, every point kept, the
  // normals fitted over all of them.
  local_map_.push(placed);
  while (static_cast<int>(local_map_.scanCount()) > options_.local_map_scans) {
    local_map_.popOldest();
  }
  std::vector<Vector2> points_with_normals, normals;
  local_map_.fitted(&points_with_normals, &normals);
  // Several key scans lie over one another: cells of the normal radius
  // hold fewer points to compare than the global map's.
  reference_.emplace(std::vector<Vector2>(), options_.normal_radius, options_.normal_radius);
  reference_->insert(points_with_normals, normals, options_.map_point_spacing);
}

Pose2 ScanMatchingOdometry::process(const Scan& scan, const Pose2& raw_odometry,
                                    const Pose2& laser_pose, MatchResult* result) {
  return processPoints(scanPointsInRobotFrame(scan, laser_pose, options_), scan.stamp, raw_odometry,
                       result);
}

Pose2 ScanMatchingOdometry::processPoints(const std::vector<Vector2>& points, double stamp,
                                          const Pose2& raw_odometry, MatchResult* result) {
  MatchResult local;
  MatchResult& match = result ? *result : local;
  match = MatchResult();
  if (!initialised_) {
    // The corrected frame starts where the odometry frame is, so the output
    // is a drop-in replacement for the odometry pose.
    initialised_ = true;
    last_raw_ = raw_odometry;
    last_stamp_ = stamp;
    last_corrected_ = raw_odometry;
    addKeyScan(points, raw_odometry);
    match.ok = true;
    match.pose = raw_odometry;
    match.message = "first scan";
    return raw_odometry;
  }

  const Pose2 guess = compose(last_corrected_, between(last_raw_, raw_odometry));
  Pose2 corrected = guess;
  match = matchPoints(points, *reference_, guess, options_);
  if (!match.ok) ++counters_.refused_by_fit;
  if (match.ok) {
    const Pose2 correction = between(guess, match.pose);
    if (std::hypot(correction.x, correction.y) > options_.max_correction_translation ||
        std::abs(correction.theta) > options_.max_correction_rotation) {
      std::ostringstream m;
      m << "correction of the odometry guess (" << correction.x << " m, " << correction.y << " m, "
        << radToDeg(correction.theta) << " deg) beyond max_correction_*";
      match.ok = false;
      match.message = m.str();
      ++counters_.refused_by_correction;
    } else if (odometry_gate_ > 0.0 && !(stamp > last_stamp_)) {
      ++counters_.unchecked_by_odometry;  // the wheels' increment is not this step's
      corrected = match.pose;
    } else if (odometry_gate_ > 0.0) {
      const double d2 = odometryDisagreement(raw_odometry, match.pose, stamp - last_stamp_);
      if (d2 > odometry_gate_) {
        std::ostringstream m;
        m << "match disagrees with the wheels: squared Mahalanobis distance " << d2
          << " beyond the gate " << odometry_gate_ << " (correction " << correction.x << " m, "
          << correction.y << " m, " << radToDeg(correction.theta) << " deg)";
        match.ok = false;
        match.message = m.str();
        ++counters_.refused_by_odometry;
      } else {
        corrected = match.pose;
      }
    } else {
      corrected = match.pose;
    }
  }
  if (match.ok) {
    ++counters_.matched;
    consecutive_refusals_ = 0;
  } else {
    ++counters_.refused;
    ++consecutive_refusals_;
  }
  last_raw_ = raw_odometry;
  last_stamp_ = stamp;
  last_corrected_ = corrected;

  const Pose2 since_key = between(last_key_pose_, corrected);
  if (std::hypot(since_key.x, since_key.y) >= options_.keyscan_distance ||
      std::abs(since_key.theta) >= options_.keyscan_angle) {
    // Local map: a refused match still joins the reference when the robot
    // has moved, otherwise a long stretch of refusals would leave a stale
    // reference. Global map: a scan placed by dead reckoning only would stay
    // in the map for good, so only matched scans join it, unless the matches
    // keep failing (the robot entered space the map does not cover).
    constexpr int kRefusalsBeforeMapping = 3;
    if (match.ok || !globalMap() || consecutive_refusals_ >= kRefusalsBeforeMapping) {
      addKeyScan(points, corrected);
    }
  }
  return corrected;
}

}  // namespace ekf_slam
