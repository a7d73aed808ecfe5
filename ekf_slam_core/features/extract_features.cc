#include "ekf_slam_core/features/extract_features.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ekf_slam_core/features/split_and_merge.h"

namespace ekf_slam {
namespace {

// Adds the extraction's own uncertainty (options.point_model_sigma) to the
// covariance, then fills range, bearing and their covariance.
bool finishPoint(const FeatureOptions& options, PointFeature* feature) {
  feature->covariance +=
      options.point_model_sigma * options.point_model_sigma * Matrix2::Identity();
  Vector2 range_bearing;
  Matrix2 J_rb_xy;
  if (!pointToRangeBearing(feature->position, &range_bearing, &J_rb_xy)) return false;
  feature->range = range_bearing(0);
  feature->bearing = range_bearing(1);
  feature->range_bearing_covariance = J_rb_xy * feature->covariance * J_rb_xy.transpose();
  return true;
}

// Where beam `bearing` crosses the line (p, θ), as the along-line coordinate
// d·x; +inf when the beam runs (nearly) parallel to or away from the line.
double alongLineCrossing(const LineFit& line, double bearing) {
  const double cos_incidence = std::cos(bearing - line.theta);
  if (cos_incidence < 1e-3) return std::numeric_limits<double>::infinity();
  const double r = line.p / cos_incidence;
  return line.direction().dot(Vector2(r * std::cos(bearing), r * std::sin(bearing)));
}

struct FittedPiece {
  LineFit fit;
  std::vector<Matrix2> J_line_beam;  // ∂(p, θ)/∂(r_i, φ_i) per fitted point
  IndexSpan span;                    // fitted points
  bool trimmed_first = false;        // readings were dropped at the first end
  bool trimmed_last = false;         // ... at the last end
};

// True when `point` lies more than 3σ off `line`, a line fitted without it:
// the residual n·x − p has variance σ_r² cos²(φ − θ) + r² σ_φ² sin²(φ − θ)
// from the beam plus, from the line, [−1, d·x] Σ [−1, d·x]ᵀ.
bool offLine(const LineFit& line, const ScanPoint& point, const FeatureOptions& options) {
  // cos and sin of (φ − θ) from the unit vectors, no trig per reading.
  const Vector2 n = line.normal();
  const double c = point.direction.dot(n);
  const double s = point.direction.y() * n.x() - point.direction.x() * n.y();
  const double residual = n.dot(point.xy) - line.p;
  const double along = line.direction().dot(point.xy);
  const double variance =
      options.range_sigma * options.range_sigma * c * c +
      point.range * point.range * options.bearing_sigma * options.bearing_sigma * s * s +
      line.covariance(0, 0) - 2.0 * along * line.covariance(0, 1) +
      along * along * line.covariance(1, 1);
  return residual * residual > 9.0 * variance;
}

// Fits piece->span after dropping up to end_trim_points readings at each end
// that the line through the rest predicts badly (offLine). False when too few
// points remain or the fit is degenerate.
bool fitPiece(const std::vector<ScanPoint>& points, const FeatureOptions& options,
              FittedPiece* piece) {
  IndexSpan& span = piece->span;
  int trimmed_first = 0, trimmed_last = 0;
  LineFit rest;
  while (true) {
    if (span.size() < options.min_line_points ||
        !fitLine(points, span.first, span.last, options.range_sigma, options.bearing_sigma,
                 &piece->fit, &piece->J_line_beam)) {
      return false;
    }
    // Leave-one-out lines need only their geometry; the line's uncertainty
    // at the tested reading is taken from the full fit (n vs n − 1 readings).
    bool dropped = false;
    if (trimmed_first < options.end_trim_points && span.size() > options.min_line_points &&
        fitLineGeometry(points, span.first + 1, span.last, &rest)) {
      rest.covariance = piece->fit.covariance;
      if (offLine(rest, points[span.first], options)) {
        ++span.first;
        ++trimmed_first;
        dropped = true;
      }
    }
    if (trimmed_last < options.end_trim_points && span.size() > options.min_line_points &&
        fitLineGeometry(points, span.first, span.last - 1, &rest)) {
      rest.covariance = piece->fit.covariance;
      if (offLine(rest, points[span.last], options)) {
        --span.last;
        ++trimmed_last;
        dropped = true;
      }
    }
    if (!dropped) break;
  }
  piece->trimmed_first = trimmed_first > 0;
  piece->trimmed_last = trimmed_last > 0;
  return true;
}

// The outer end of a cluster's first (at_start) or last line: the extreme
// fitted point projected onto the line, classified by the beam beyond it.
PointFeature segmentEnd(const Scan& scan, const std::vector<ScanPoint>& points,
                        const FittedPiece& piece, bool at_start, int line_index,
                        const FeatureOptions& options) {
  const LineFit& line = piece.fit;
  const int extreme = at_start ? piece.span.first : piece.span.last;
  const ScanPoint& q_point = points[extreme];
  const Vector2 q = q_point.xy;
  const Vector2 n = line.normal(), d = line.direction();
  PointFeature end;
  end.kind = PointKind::kSegmentEnd;
  end.line = line_index;
  end.position = line.project(q);

  // e = p n + (d·q) d: ∂e/∂(p, θ) and ∂e/∂q, chained with every beam's
  // ∂(p, θ)/∂(r_i, φ_i) (the extreme point enters both ways).
  Matrix2 J_end_line;
  J_end_line.col(0) = n;
  J_end_line.col(1) = line.p * d - n.dot(q) * d - d.dot(q) * n;
  const Matrix2 J_end_q = d * d.transpose();
  const double var_r = options.range_sigma * options.range_sigma;
  const double var_phi = options.bearing_sigma * options.bearing_sigma;
  Matrix2 covariance = Matrix2::Zero();
  for (int i = 0; i < piece.span.size(); ++i) {
    Matrix2 J = J_end_line * piece.J_line_beam[i];
    if (piece.span.first + i == extreme) {
      const double cb = q_point.direction.x(), sb = q_point.direction.y();
      Matrix2 J_q_polar;
      J_q_polar << cb, -q_point.range * sb, sb, q_point.range * cb;
      J += J_end_q * J_q_polar;
    }
    covariance +=
        var_r * J.col(0) * J.col(0).transpose() + var_phi * J.col(1) * J.col(1).transpose();
  }
  end.covariance = covariance;

  const int neighbour = q_point.beam + (at_start ? -1 : 1);
  if (at_start ? piece.trimmed_first : piece.trimmed_last) {
    end.context = EndpointContext::kUnresolved;
  } else if (neighbour < 0 || neighbour >= scan.size()) {
    end.context = EndpointContext::kScanBoundary;
  } else if (!scan.isValid(neighbour)) {
    end.context = EndpointContext::kNoReturn;
  } else if (scan.ranges[neighbour] < q_point.range) {
    end.context = EndpointContext::kOccluded;
  } else if (scan.merged) {
    // The next beam's reading may come from another laser, which sees past
    // the object's end from elsewhere (parallax): the end is not placed.
    end.context = EndpointContext::kUnresolved;
  } else {
    // The object really ends between this beam and the next one, which
    // passes behind it. Place the end midway along that gap g with the
    // variance of a uniform spread, g²/12, along the line.
    const double s_end = d.dot(end.position);
    const double s_next = alongLineCrossing(line, scan.angle(neighbour));
    const double gap = std::abs(s_next - s_end);
    // A next reading on the line's extension (within hf) means the same wall
    // goes on past a sparse stretch (grazing incidence): no end at all.
    const double bearing_next = scan.angle(neighbour);
    const Vector2 next_point =
        scan.ranges[neighbour] * Vector2(std::cos(bearing_next), std::sin(bearing_next));
    const bool wall_continues = std::abs(n.dot(next_point) - line.p) <= options.split_threshold;
    if (!(gap <= options.endpoint_max_gap) || wall_continues) {
      end.context = EndpointContext::kUnresolved;
    } else {
      end.context = EndpointContext::kFrontEdge;
      end.landmark_candidate = true;
      end.position += 0.5 * (s_next - s_end) * d;
      end.covariance += (gap * gap / 12.0) * d * d.transpose();
    }
  }
  return end;
}

}  // namespace

double LineFeature::linearizationError() const {
  const double var_theta = covariance(1, 1);
  if (!(var_theta > 0.0)) return 0.0;
  const double var_p_given_theta =
      covariance(0, 0) - covariance(0, 1) * covariance(0, 1) / var_theta;
  if (!(var_p_given_theta > 0.0)) return std::numeric_limits<double>::infinity();
  return 0.5 * p * var_theta / std::sqrt(var_p_given_theta);
}

int FeatureSet::countCorners() const {
  int count = 0;
  for (const PointFeature& f : points_of_interest) count += f.kind == PointKind::kCorner ? 1 : 0;
  return count;
}

int FeatureSet::countLandmarkCandidates() const {
  int count = 0;
  for (const PointFeature& f : points_of_interest) count += f.landmark_candidate ? 1 : 0;
  return count;
}

namespace {

// Why a landmark candidate cannot go to the filter, or nullptr.
const char* unusableCandidate(const PointFeature& point) {
  const Matrix2& c = point.range_bearing_covariance;
  if (!(std::isfinite(point.range) && point.range > 0.0)) {
    return "range is not a positive finite number";
  }
  if (!std::isfinite(point.bearing)) return "bearing is not finite";
  if (!c.allFinite()) return "range-bearing covariance is not finite";
  if (std::abs(c(0, 1) - c(1, 0)) > 1e-9 * std::max(1e-12, c.diagonal().maxCoeff())) {
    return "range-bearing covariance is not symmetric";
  }
  if (!(c(0, 0) > 0.0 && c(1, 1) > 0.0 && c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0) > 0.0)) {
    return "range-bearing covariance is not positive definite";
  }
  return nullptr;
}

}  // namespace

std::string validateFeatureSet(const FeatureSet& features) {
  if (!features.error.empty()) return "the extraction failed: " + features.error;
  for (size_t i = 0; i < features.points_of_interest.size(); ++i) {
    const PointFeature& point = features.points_of_interest[i];
    if (!point.landmark_candidate) continue;  // never reaches the filter
    if (const char* why = unusableCandidate(point)) {
      return "point " + std::to_string(i) + ": " + why;
    }
  }
  return "";
}

FeatureSet extractFeatures(const Scan& scan, const FeatureOptions& laser_options) {
  FeatureSet out;
  out.error = validateFeatureOptions(laser_options);
  if (out.error.empty()) out.error = validateScan(scan);
  if (!out.error.empty()) return out;
  // Bearings rounded to beams (a merged scan) are off by up to half a beam,
  // uniformly: variance q² / 12 beside the beam's own jitter.
  FeatureOptions options = laser_options;
  if (scan.merged) {
    options.bearing_sigma =
        std::hypot(options.bearing_sigma, scan.angle_increment / std::sqrt(12.0));
  }

  out.points = scanToPoints(scan);
  out.clusters = clusterPoints(out.points, options);
  const int guard = options.break_guard_points;
  std::vector<FittedPiece> fitted;
  std::vector<int> line_of_piece;
  for (int c = 0; c < static_cast<int>(out.clusters.size()); ++c) {
    const std::vector<IndexSpan> pieces = splitAndMerge(out.points, out.clusters[c], options);
    const int num_pieces = static_cast<int>(pieces.size());
    fitted.assign(num_pieces, FittedPiece());
    line_of_piece.assign(num_pieces, -1);
    for (int k = 0; k < num_pieces; ++k) {
      out.pieces.push_back(pieces[k]);
      // Split points (and `guard` points beside them) belong to neither fit.
      IndexSpan span = pieces[k];
      if (k > 0) span.first += 1 + guard;
      if (k + 1 < num_pieces) span.last -= 1 + guard;
      FittedPiece& piece = fitted[k];
      piece.span = span;
      if (!fitPiece(out.points, options, &piece)) continue;
      span = piece.span;
      LineFeature line;
      line.p = piece.fit.p;
      line.theta = piece.fit.theta;
      line.covariance = piece.fit.covariance;
      line.start = piece.fit.project(out.points[span.first].xy);
      line.end = piece.fit.project(out.points[span.last].xy);
      line.first_beam = out.points[span.first].beam;
      line.last_beam = out.points[span.last].beam;
      line.num_points = piece.fit.num_points;
      line.rms_residual = piece.fit.rms_residual;
      line.cluster = c;
      if (line.length() < options.min_line_length) continue;
      line_of_piece[k] = static_cast<int>(out.lines.size());
      out.lines.push_back(line);
    }

    if (line_of_piece.front() >= 0) {
      PointFeature start = segmentEnd(scan, out.points, fitted.front(), /*at_start=*/true,
                                      line_of_piece.front(), options);
      if (finishPoint(options, &start)) out.points_of_interest.push_back(start);
    }
    for (int k = 0; k + 1 < num_pieces; ++k) {
      const int a = line_of_piece[k], b = line_of_piece[k + 1];
      if (a < 0 || b < 0) continue;
      const LineFit& la = fitted[k].fit;
      const LineFit& lb = fitted[k + 1].fit;
      double angle = std::abs(wrapAngle(la.theta - lb.theta));
      if (angle > kPi / 2.0) angle = kPi - angle;
      if (angle < options.corner_min_angle) continue;
      PointFeature corner;
      Matrix2 J_a, J_b;
      if (!intersectLines(la.p, la.theta, lb.p, lb.theta, &corner.position, &J_a, &J_b)) continue;
      const Vector2 split_point = out.points[pieces[k].last].xy;
      if ((corner.position - split_point).norm() > options.corner_max_distance) continue;
      corner.kind = PointKind::kCorner;
      corner.context = EndpointContext::kCorner;
      corner.landmark_candidate = true;
      // The two fits share no beam, so their errors are independent.
      corner.covariance =
          J_a * la.covariance * J_a.transpose() + J_b * lb.covariance * J_b.transpose();
      corner.line = a;
      corner.other_line = b;
      corner.corner_angle = angle;
      if (finishPoint(options, &corner)) out.points_of_interest.push_back(corner);
    }
    if (line_of_piece.back() >= 0) {
      PointFeature end = segmentEnd(scan, out.points, fitted.back(), /*at_start=*/false,
                                    line_of_piece.back(), options);
      if (finishPoint(options, &end)) out.points_of_interest.push_back(end);
    }
  }
  // A candidate the filter could not use (readings of 10³⁸ m under a
  // range_max of FLT_MAX give a covariance whose determinant rounds to
  // zero) stays a point of interest but is no landmark candidate: the
  // extractor never hands the filter what validateFeatureSet refuses.
  for (PointFeature& point : out.points_of_interest) {
    if (point.landmark_candidate && unusableCandidate(point) != nullptr) {
      point.landmark_candidate = false;
    }
  }
  return out;
}

}  // namespace ekf_slam
