#include "ekf_slam_core/sim/grid_world.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace ekf_slam {
namespace sim {
namespace {

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\"'");
  const size_t b = s.find_last_not_of(" \t\r\"'");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

// Reads the next whitespace-separated PGM header token, skipping # comments.
bool headerToken(std::istream& in, std::string* token) {
  token->clear();
  char c;
  while (in.get(c)) {
    if (c == '#') {
      std::string rest;
      std::getline(in, rest);
      continue;
    }
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (!token->empty()) return true;
      continue;
    }
    token->push_back(c);
  }
  return !token->empty();
}

}  // namespace

GridWorld::GridWorld(int width, int height, double resolution, const Vector2& origin,
                     std::vector<bool> occupied)
    : width_(width),
      height_(height),
      resolution_(resolution),
      origin_(origin),
      occupied_(std::move(occupied)) {}

std::string GridWorld::load(const std::string& yaml_path, GridWorld* out) {
  std::ifstream yaml(yaml_path);
  if (!yaml) return yaml_path + ": cannot open";
  std::string image;
  double resolution = 0.0, occupied_thresh = 0.65;
  int negate = 0;
  Vector2 origin = Vector2::Zero();
  bool have_origin = false;
  bool have_start = false;
  Pose2 start;
  std::string line;
  for (int number = 1; std::getline(yaml, line); ++number) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = trim(line.substr(0, colon)), value = trim(line.substr(colon + 1));
    std::istringstream v(value);
    if (key == "image") {
      image = value;
    } else if (key == "resolution") {
      v >> resolution;
    } else if (key == "negate") {
      v >> negate;
    } else if (key == "occupied_thresh") {
      v >> occupied_thresh;
    } else if (key == "origin") {
      char bracket, comma;
      double x, y;
      if (!(v >> bracket >> x >> comma >> y) || bracket != '[' || comma != ',') {
        return yaml_path + ":" + std::to_string(number) + ": origin must be [x, y, yaw]";
      }
      origin = Vector2(x, y);
      have_origin = true;
    } else if (key == "start_pose") {
      char bracket, comma1, comma2;
      double x, y, yaw;
      if (!(v >> bracket >> x >> comma1 >> y >> comma2 >> yaw) || bracket != '[') {
        return yaml_path + ":" + std::to_string(number) + ": start_pose must be [x, y, yaw]";
      }
      start = Pose2(x, y, yaw);
      have_start = true;
    }
  }
  if (image.empty()) return yaml_path + ": no 'image'";
  if (!(resolution > 0.0)) return yaml_path + ": 'resolution' must be > 0";
  if (!have_origin) return yaml_path + ": no 'origin'";
  if (image[0] != '/') {
    const size_t slash = yaml_path.find_last_of('/');
    if (slash != std::string::npos) image = yaml_path.substr(0, slash + 1) + image;
  }

  std::ifstream pgm(image, std::ios::binary);
  if (!pgm) return image + ": cannot open";
  std::string magic, w, h, maxval;
  if (!headerToken(pgm, &magic) || (magic != "P5" && magic != "P2") || !headerToken(pgm, &w) ||
      !headerToken(pgm, &h) || !headerToken(pgm, &maxval)) {
    return image + ": not a PGM image (P5 or P2)";
  }
  const int width = std::atoi(w.c_str()), height = std::atoi(h.c_str());
  const int max_value = std::atoi(maxval.c_str());
  if (width <= 0 || height <= 0 || max_value <= 0 || max_value > 255) {
    return image + ": unsupported PGM size or depth";
  }
  std::vector<int> pixels(static_cast<size_t>(width) * height);
  if (magic == "P5") {
    std::vector<unsigned char> raw(pixels.size());
    pgm.read(reinterpret_cast<char*>(raw.data()), raw.size());
    if (pgm.gcount() != static_cast<std::streamsize>(raw.size())) return image + ": truncated";
    for (size_t i = 0; i < raw.size(); ++i) pixels[i] = raw[i];
  } else {
    for (int& p : pixels) {
      if (!(pgm >> p)) return image + ": truncated";
    }
  }
  // map_server: occupancy = (max − value) / max, or value / max when negated;
  // image row 0 is the top (largest y).
  std::vector<bool> occupied(pixels.size());
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const double value = pixels[static_cast<size_t>(row) * width + col];
      const double occupancy = negate ? value / max_value : (max_value - value) / max_value;
      occupied[static_cast<size_t>(height - 1 - row) * width + col] = occupancy > occupied_thresh;
    }
  }
  *out = GridWorld(width, height, resolution, origin, std::move(occupied));
  out->has_start_pose_ = have_start;
  out->start_pose_ = start;
  return "";
}

bool GridWorld::occupiedAt(const Vector2& p) const {
  return occupied(static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_)),
                  static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_)));
}

double GridWorld::castRay(const Vector2& origin, double angle, double max_range) const {
  const double inf = std::numeric_limits<double>::infinity();
  if (width_ == 0) return inf;
  const double dx = std::cos(angle), dy = std::sin(angle);
  // Cell coordinates in units of cells.
  const double gx = (origin.x() - origin_.x()) / resolution_;
  const double gy = (origin.y() - origin_.y()) / resolution_;
  int ix = static_cast<int>(std::floor(gx)), iy = static_cast<int>(std::floor(gy));
  if (occupied(ix, iy)) return 0.0;
  const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
  // Distance along the ray (in cells) to the next vertical / horizontal cell border.
  double t_max_x = dx != 0.0 ? ((dx > 0 ? ix + 1 - gx : gx - ix) / std::abs(dx)) : inf;
  double t_max_y = dy != 0.0 ? ((dy > 0 ? iy + 1 - gy : gy - iy) / std::abs(dy)) : inf;
  const double t_delta_x = dx != 0.0 ? 1.0 / std::abs(dx) : inf;
  const double t_delta_y = dy != 0.0 ? 1.0 / std::abs(dy) : inf;
  const double limit = max_range / resolution_;
  while (true) {
    double t;
    if (t_max_x < t_max_y) {
      t = t_max_x;
      t_max_x += t_delta_x;
      ix += step_x;
    } else {
      t = t_max_y;
      t_max_y += t_delta_y;
      iy += step_y;
    }
    if (t > limit) return inf;
    if (ix < -1 || iy < -1 || ix > width_ || iy > height_) return inf;  // left the map
    if (occupied(ix, iy)) return t * resolution_;
  }
}

}  // namespace sim
}  // namespace ekf_slam
